// Small constructed meshes shared by the test suites.
#pragma once

#include <libcore/mesh.h>

#include <cmath>
#include <numbers>

namespace quadify::test {

// Two flat strips of n unit squares along x meeting at the edge y = z = 0 (its n + 1 vertices
// come first): the top (y from 0 to 1, z = 0) and one opening by `opening` degrees below it (a
// blade's edge for a small opening); the edge's dihedral angle is 180° − opening.
inline core::TriMesh folded_strips(int n, double opening) {
  const double a = opening * std::numbers::pi / 180;
  core::TriMesh m;
  m.V.resize(3 * (n + 1), 3);
  for (int i = 0; i <= n; ++i) {
    m.V.row(i) << i, 0, 0;                                        // edge
    m.V.row(n + 1 + i) << i, 1, 0;                                // top
    m.V.row(2 * (n + 1) + i) << i, std::cos(a), -std::sin(a);     // underside
  }
  m.F.resize(4 * n, 3);
  for (int i = 0; i < n; ++i) {
    const int e = i, t = n + 1 + i, u = 2 * (n + 1) + i;
    m.F.row(4 * i) << e, e + 1, t + 1;
    m.F.row(4 * i + 1) << e, t + 1, t;
    m.F.row(4 * i + 2) << e + 1, e, u;
    m.F.row(4 * i + 3) << e + 1, u, u + 1;
  }
  return m;
}

// A closed thin cone ("spike"): a base disk of radius 1 at z = 0 (a centre vertex and a ring of
// n) and `rings` rings of n vertices up to an apex at z = height, each ring turned by half a
// sector. With height 8 the apex's angle sum is about 0.78 rad, below π/2: the rounding of the
// matchings gives it index 3 (a quad vertex of valence 1), as at the tips of tentacles.
inline core::TriMesh spike(int n = 16, int rings = 12, double height = 8) {
  core::TriMesh m;
  const int apex = n * rings, base = apex + 1;
  m.V.resize(n * rings + 2, 3);
  for (int k = 0; k < rings; ++k)
    for (int i = 0; i < n; ++i) {
      const double r = 1 - static_cast<double>(k) / rings;
      const double a = 2 * std::numbers::pi * (i + 0.5 * k) / n;
      m.V.row(k * n + i) << r * std::cos(a), r * std::sin(a), height * k / rings;
    }
  m.V.row(apex) << 0, 0, height;
  m.V.row(base) << 0, 0, 0;
  m.F.resize(2 * n * (rings - 1) + 2 * n, 3);
  int f = 0;
  for (int k = 0; k + 1 < rings; ++k)
    for (int i = 0; i < n; ++i) {
      const int a = k * n + i, b = k * n + (i + 1) % n, c = (k + 1) * n + i, d = (k + 1) * n + (i + 1) % n;
      m.F.row(f++) << a, b, c;
      m.F.row(f++) << b, d, c;
    }
  for (int i = 0; i < n; ++i) {
    m.F.row(f++) << (rings - 1) * n + i, (rings - 1) * n + (i + 1) % n, apex;
    m.F.row(f++) << base, (i + 1) % n, i;
  }
  return m;
}

}  // namespace quadify::test
