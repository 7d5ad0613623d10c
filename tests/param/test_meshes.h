// Procedural meshes for the libparam tests (no files needed).
#pragma once

#include <libcore/mesh.h>

#include <cmath>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

namespace quadify::test {

// Icosphere of radius 1 with `subdivisions` 4-to-1 splits (20·4^s faces, outward CCW).
inline core::TriMesh make_icosphere(int subdivisions) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t},  {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      mid[key] = static_cast<int>(v.size()) - 1;
      return static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f.swap(g);
  }
  core::TriMesh m;
  m.V.resize(v.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) m.V.row(i) = v[i].transpose();
  m.F.resize(f.size(), 3);
  for (size_t i = 0; i < f.size(); ++i) m.F.row(i) << f[i][0], f[i][1], f[i][2];
  return m;
}

// Torus (radii R, r) with an n×m grid, each quad split in two triangles.
inline core::TriMesh make_torus(int n, int m, double R = 2.0, double r = 0.7) {
  core::TriMesh t;
  t.V.resize(n * m, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = 2 * std::numbers::pi * i / n, w = 2 * std::numbers::pi * j / m;
      t.V.row(i * m + j) << (R + r * std::cos(w)) * std::cos(u), (R + r * std::cos(w)) * std::sin(u),
          r * std::sin(w);
    }
  t.F.resize(2 * n * m, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const int a = i * m + j, b = ((i + 1) % n) * m + j, c = ((i + 1) % n) * m + (j + 1) % m,
                d = i * m + (j + 1) % m;
      t.F.row(2 * (i * m + j)) << a, b, c;
      t.F.row(2 * (i * m + j) + 1) << a, c, d;
    }
  return t;
}

// A curved open disk: a polar grid (rings × sectors) lifted onto a paraboloid.
// Three faces of a cube meeting at the origin (angle defect π/2 at vertex 0), open.
inline core::TriMesh make_cube_corner() {
  core::TriMesh corner;
  corner.V.resize(4, 3);
  corner.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  corner.F.resize(3, 3);
  corner.F << 0, 2, 1, 0, 3, 2, 0, 1, 3;
  return corner;
}

inline core::TriMesh make_disk(int rings, int sectors) {
  core::TriMesh d;
  d.V.resize(1 + rings * sectors, 3);
  d.V.row(0) << 0, 0, 0;
  for (int i = 1; i <= rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      const double rad = static_cast<double>(i) / rings, a = 2 * std::numbers::pi * j / sectors;
      d.V.row(1 + (i - 1) * sectors + j) << rad * std::cos(a), rad * std::sin(a), 0.8 * rad * rad;
    }
  std::vector<std::array<int, 3>> f;
  for (int j = 0; j < sectors; ++j) f.push_back({0, 1 + j, 1 + (j + 1) % sectors});
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      const int a = 1 + (i - 1) * sectors + j, b = 1 + (i - 1) * sectors + (j + 1) % sectors;
      const int c = 1 + i * sectors + j, e = 1 + i * sectors + (j + 1) % sectors;
      f.push_back({a, c, e});
      f.push_back({a, e, b});
    }
  d.F.resize(f.size(), 3);
  for (size_t i = 0; i < f.size(); ++i) d.F.row(i) << f[i][0], f[i][1], f[i][2];
  return d;
}

}  // namespace quadify::test
