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

}  // namespace quadify::test
