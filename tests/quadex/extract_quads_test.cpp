// Tests of quad extraction on integer-seamless maps constructed in code: planar grids (with and
// without a rotated seam), a cube with 8 cones, a flat torus, failure modes and a speed check.
#include <libquadex/extract_quads.h>

#include <libcore/topology.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace quadify::quadex {
namespace {

using core::UVMesh;

// Combinatorial summary of a polygon mesh.
struct PolyCheck {
  int n_used_vertices = 0;
  int n_edges = 0;
  int n_boundary_edges = 0;
  int n_bad_edges = 0;  // a directed edge used twice (non-manifold or inconsistent orientation)
  int euler = 0;
  std::map<int, int> degrees;   // face degree → count
  std::map<int, int> valences;  // vertex valence (distinct neighbours) → count, used vertices
};

PolyCheck check_poly(const core::PolyMesh& m) {
  PolyCheck c;
  std::map<std::pair<int, int>, int> directed;
  std::vector<std::set<int>> nbrs(m.n_vertices());
  for (int f = 0; f < m.n_faces(); ++f) {
    ++c.degrees[m.degree(f)];
    for (int k = 0; k < m.degree(f); ++k) {
      const int a = m.vertex(f, k), b = m.vertex(f, (k + 1) % m.degree(f));
      ++directed[{a, b}];
      nbrs[a].insert(b);
      nbrs[b].insert(a);
    }
  }
  std::set<std::pair<int, int>> undirected;
  for (const auto& [e, n] : directed) {
    if (n > 1) ++c.n_bad_edges;
    undirected.insert({std::min(e.first, e.second), std::max(e.first, e.second)});
    if (!directed.count({e.second, e.first})) ++c.n_boundary_edges;
  }
  c.n_edges = static_cast<int>(undirected.size());
  for (const auto& n : nbrs)
    if (!n.empty()) {
      ++c.n_used_vertices;
      ++c.valences[static_cast<int>(n.size())];
    }
  c.euler = c.n_used_vertices - c.n_edges + m.n_faces();
  return c;
}

// Every output face's UVs must be a unit square, counter-clockwise, in one integer chart.
int count_bad_uv_faces(const core::PolyMesh& m) {
  int bad = 0;
  for (int f = 0; f < m.n_faces(); ++f) {
    if (m.degree(f) != 4) continue;
    bool ok = true;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d a = m.uv.row(m.face_uv[m.face_corner(f, k)]);
      const Eigen::Vector2d b = m.uv.row(m.face_uv[m.face_corner(f, (k + 1) % 4)]);
      const Eigen::Vector2d c = m.uv.row(m.face_uv[m.face_corner(f, (k + 2) % 4)]);
      const Eigen::Vector2d e0 = b - a, e1 = c - b;
      ok = ok && std::abs(e0.norm() - 1) == 0 && e0.x() * e1.y() - e0.y() * e1.x() == 1;
    }
    bad += !ok;
  }
  return bad;
}

// Triangulated planar grid of (n+1)² vertices over [0,side]², with jittered interior vertices
// (every other one) and pseudo-random diagonals; position (x,y,0), UV = scale·(x,y).
UVMesh planar_grid(int n, double side, double scale, unsigned seed, double jitter_amplitude = 0.3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-jitter_amplitude, jitter_amplitude);
  UVMesh m;
  m.mesh.V.resize((n + 1) * (n + 1), 3);
  const double h = side / n;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      double x = side * i / n, y = side * j / n;
      if (jitter_amplitude > 0 && i > 0 && i < n && j > 0 && j < n && (i + j) % 2 == 1) {
        x += jitter(rng) * h;
        y += jitter(rng) * h;
      }
      m.mesh.V.row(j * (n + 1) + i) << x, y, 0.0;
    }
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      if (rng() % 2) {
        tris.push_back({a, b, c});
        tris.push_back({a, c, d});
      } else {
        tris.push_back({a, b, d});
        tris.push_back({b, c, d});
      }
    }
  m.mesh.F.resize(static_cast<int>(tris.size()), 3);
  m.corner_uv.resize(3 * static_cast<int>(tris.size()), 2);
  for (size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      m.mesh.F(f, k) = tris[f][k];
      m.corner_uv.row(3 * f + k) = scale * m.mesh.V.row(tris[f][k]).head<2>();
    }
  return m;
}

// Applies uv ↦ R_90^r uv + t to the UVs of every face whose centroid has x < x_cut.
void add_seam(UVMesh& m, double x_cut, int r, Eigen::Vector2d t) {
  for (int f = 0; f < m.mesh.n_faces(); ++f) {
    const double cx = (m.mesh.V(m.mesh.F(f, 0), 0) + m.mesh.V(m.mesh.F(f, 1), 0) + m.mesh.V(m.mesh.F(f, 2), 0)) / 3;
    if (cx >= x_cut) continue;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector2d p = m.corner_uv.row(3 * f + k);
      for (int i = 0; i < r; ++i) p = Eigen::Vector2d(-p.y(), p.x());
      m.corner_uv.row(3 * f + k) = p + t;
    }
  }
}

// Unit cube, each face an m×m grid of squares (alternating diagonals), UV per face = n·(s,t)
// plus an integer offset: transitions are rotations by k·90° plus integer shifts, 8 cones.
UVMesh cube(int m, int n) {
  const Eigen::Vector3d O[6] = {{0, 0, 1}, {0, 0, 0}, {1, 0, 0}, {0, 0, 0}, {0, 1, 0}, {0, 0, 0}};
  const Eigen::Vector3d U[6] = {{1, 0, 0}, {0, 1, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 1}, {1, 0, 0}};
  const Eigen::Vector3d W[6] = {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}};
  std::map<std::array<long, 3>, int> index;
  std::vector<Eigen::Vector3d> verts;
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<Eigen::Vector2d, 3>> uvs;
  auto vid = [&](const Eigen::Vector3d& p) {
    const std::array<long, 3> key{std::lround(p.x() * m), std::lround(p.y() * m), std::lround(p.z() * m)};
    auto [it, inserted] = index.try_emplace(key, static_cast<int>(verts.size()));
    if (inserted) verts.push_back(p);
    return it->second;
  };
  for (int s = 0; s < 6; ++s) {
    const Eigen::Vector2d offset(10.0 * s, -3.0 * s);
    auto corner = [&](int i, int j) {
      const double a = double(i) / m, b = double(j) / m;
      return std::pair<int, Eigen::Vector2d>(vid(O[s] + a * U[s] + b * W[s]), Eigen::Vector2d(n * a, n * b) + offset);
    };
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        const auto a = corner(i, j), b = corner(i + 1, j), c = corner(i + 1, j + 1), d = corner(i, j + 1);
        if ((i + j) % 2) {
          tris.push_back({a.first, b.first, c.first}), uvs.push_back({a.second, b.second, c.second});
          tris.push_back({a.first, c.first, d.first}), uvs.push_back({a.second, c.second, d.second});
        } else {
          tris.push_back({a.first, b.first, d.first}), uvs.push_back({a.second, b.second, d.second});
          tris.push_back({b.first, c.first, d.first}), uvs.push_back({b.second, c.second, d.second});
        }
      }
  }
  UVMesh out;
  out.mesh.V.resize(static_cast<int>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) out.mesh.V.row(i) = verts[i];
  out.mesh.F.resize(static_cast<int>(tris.size()), 3);
  out.corner_uv.resize(3 * static_cast<int>(tris.size()), 2);
  for (size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      out.mesh.F(f, k) = tris[f][k];
      out.corner_uv.row(3 * f + k) = uvs[f][k];
    }
  return out;
}

// Torus from an a×b periodic grid; UV = (i·pu/a, j·pv/b) unwrapped, so faces across the wrap
// carry translation transitions (pu, 0) / (0, pv).
UVMesh torus(int a, int b, double pu, double pv) {
  UVMesh m;
  m.mesh.V.resize(a * b, 3);
  for (int j = 0; j < b; ++j)
    for (int i = 0; i < a; ++i) {
      const double th = 2 * M_PI * i / a, ph = 2 * M_PI * j / b;
      m.mesh.V.row(j * a + i) << (3 + std::cos(ph)) * std::cos(th), (3 + std::cos(ph)) * std::sin(th),
          std::sin(ph);
    }
  m.mesh.F.resize(2 * a * b, 3);
  m.corner_uv.resize(6 * a * b, 2);
  int f = 0;
  auto put = [&](std::array<std::pair<int, int>, 3> c) {
    for (int k = 0; k < 3; ++k) {
      const auto [i, j] = c[k];
      m.mesh.F(f, k) = (j % b) * a + (i % a);
      m.corner_uv.row(3 * f + k) << i * pu / a, j * pv / b;
    }
    ++f;
  };
  for (int j = 0; j < b; ++j)
    for (int i = 0; i < a; ++i) {
      if ((i * 7 + j * 3) % 5 < 2) {
        put({{{i, j}, {i + 1, j}, {i + 1, j + 1}}});
        put({{{i, j}, {i + 1, j + 1}, {i, j + 1}}});
      } else {
        put({{{i, j}, {i + 1, j}, {i, j + 1}}});
        put({{{i + 1, j}, {i + 1, j + 1}, {i, j + 1}}});
      }
    }
  return m;
}

// An open disk made of k quadrants [0,n]² (each an m×m grid, alternating diagonals) glued
// cyclically around the origin with 90° rotations: a cone of index 4 - k at the origin, a
// boundary aligned with the iso-lines. Positions squeeze the quadrants into a planar fan.
UVMesh cone_disk(int k, int m, int n) {
  std::map<std::array<int, 3>, int> index;
  std::vector<Eigen::Vector3d> verts;
  auto vid = [&](int q, int i, int j) {
    std::array<int, 3> key{q, i, j};
    if (i == 0 && j == 0) key = {-1, 0, 0};
    else if (i == 0) key = {(q + 1) % k, j, 0};
    auto [it, inserted] = index.try_emplace(key, static_cast<int>(verts.size()));
    if (inserted) {
      const double x = double(i) / m, y = double(j) / m;
      const double rho = std::hypot(x, y), phi = (q + std::atan2(y, x) / (M_PI / 2)) * 2 * M_PI / k;
      verts.emplace_back(rho * std::cos(phi), rho * std::sin(phi), 0.0);
    }
    return it->second;
  };
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<Eigen::Vector2d, 3>> uvs;
  for (int q = 0; q < k; ++q)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        auto uv = [&](int a, int b) { return Eigen::Vector2d(double(n) * a / m, double(n) * b / m); };
        const int a = vid(q, i, j), b = vid(q, i + 1, j), c = vid(q, i + 1, j + 1), d = vid(q, i, j + 1);
        if ((i + j) % 2) {
          tris.push_back({a, b, c}), uvs.push_back({uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)});
          tris.push_back({a, c, d}), uvs.push_back({uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)});
        } else {
          tris.push_back({a, b, d}), uvs.push_back({uv(i, j), uv(i + 1, j), uv(i, j + 1)});
          tris.push_back({b, c, d}), uvs.push_back({uv(i + 1, j), uv(i + 1, j + 1), uv(i, j + 1)});
        }
      }
  UVMesh out;
  out.mesh.V.resize(static_cast<int>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) out.mesh.V.row(i) = verts[i];
  out.mesh.F.resize(static_cast<int>(tris.size()), 3);
  out.corner_uv.resize(3 * static_cast<int>(tris.size()), 2);
  for (size_t f = 0; f < tris.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      out.mesh.F(f, c) = tris[f][c];
      out.corner_uv.row(3 * f + c) = uvs[f][c];
    }
  return out;
}

// Signed area of a polygon's projection to the xy plane (shoelace).
double xy_area(const core::PolyMesh& m, int f) {
  double a = 0;
  for (int k = 0; k < m.degree(f); ++k) {
    const int i = m.vertex(f, k), j = m.vertex(f, (k + 1) % m.degree(f));
    a += m.V(i, 0) * m.V(j, 1) - m.V(j, 0) * m.V(i, 1);
  }
  return 0.5 * a;
}

// Moves every triangle to its own chart: uv ↦ R_90^r uv + t with random r and integer t per
// face, so that every interior edge becomes a seam with a random transition.
void scramble_charts(UVMesh& m, unsigned seed) {
  std::mt19937 rng(seed);
  for (int f = 0; f < m.mesh.n_faces(); ++f) {
    const int r = static_cast<int>(rng() % 4);
    const Eigen::Vector2d t(static_cast<int>(rng() % 11) - 5, static_cast<int>(rng() % 11) - 5);
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector2d p = m.corner_uv.row(3 * f + k);
      for (int i = 0; i < r; ++i) p = Eigen::Vector2d(-p.y(), p.x());
      m.corner_uv.row(3 * f + k) = p + t;
    }
  }
}

// Adds independent noise of magnitude ≤ amplitude to every corner UV (seams stay within tolerance).
void add_uv_noise(UVMesh& m, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-amplitude, amplitude);
  for (int c = 0; c < m.corner_uv.rows(); ++c) m.corner_uv.row(c) += Eigen::Vector2d(noise(rng), noise(rng));
}

// A disk of radius 1: centre plus `rings` rings of `sectors` vertices, UV = scale·(x,y) + offset.
UVMesh polar_disk(int rings, int sectors, double scale, Eigen::Vector2d offset) {
  UVMesh m;
  m.mesh.V.resize(1 + rings * sectors, 3);
  m.mesh.V.row(0) << 0, 0, 0;
  for (int i = 1; i <= rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      const double r = double(i) / rings, phi = 2 * M_PI * (j + 0.5 * (i % 2)) / sectors;
      m.mesh.V.row(1 + (i - 1) * sectors + j) << r * std::cos(phi), r * std::sin(phi), 0;
    }
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j < sectors; ++j) tris.push_back({0, 1 + j, 1 + (j + 1) % sectors});
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      const int a = 1 + (i - 1) * sectors + j, b = 1 + (i - 1) * sectors + (j + 1) % sectors;
      const int c = 1 + i * sectors + j, d = 1 + i * sectors + (j + 1) % sectors;
      // Odd rings are rotated by half a sector: pick the diagonal that keeps triangles CCW.
      if (i % 2) {
        tris.push_back({a, d, b}), tris.push_back({a, c, d});
      } else {
        tris.push_back({a, c, b}), tris.push_back({b, c, d});
      }
    }
  m.mesh.F.resize(static_cast<int>(tris.size()), 3);
  m.corner_uv.resize(3 * static_cast<int>(tris.size()), 2);
  for (size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      m.mesh.F(f, k) = tris[f][k];
      m.corner_uv.row(3 * f + k) = scale * m.mesh.V.row(tris[f][k]).head<2>().transpose() + offset;
    }
  return m;
}

// Keeps the faces whose centroid satisfies keep(x, y).
template <class Keep>
UVMesh select_faces(const UVMesh& m, Keep keep) {
  std::vector<int> kept;
  for (int f = 0; f < m.mesh.n_faces(); ++f) {
    const Eigen::Vector3d c =
        (m.mesh.V.row(m.mesh.F(f, 0)) + m.mesh.V.row(m.mesh.F(f, 1)) + m.mesh.V.row(m.mesh.F(f, 2))) / 3;
    if (keep(c.x(), c.y())) kept.push_back(f);
  }
  UVMesh out;
  out.mesh.V = m.mesh.V;
  out.mesh.F.resize(static_cast<int>(kept.size()), 3);
  out.corner_uv.resize(3 * static_cast<int>(kept.size()), 2);
  for (size_t i = 0; i < kept.size(); ++i) {
    out.mesh.F.row(i) = m.mesh.F.row(kept[i]);
    for (int k = 0; k < 3; ++k) out.corner_uv.row(3 * i + k) = m.corner_uv.row(3 * kept[i] + k);
  }
  return out;
}

void expect_all_quads(const ExtractResult& r, int n_quads, const std::string& name) {
  ASSERT_TRUE(r.status.is_ok()) << name << ": " << r.status.to_string();
  EXPECT_EQ(r.quads.n_faces(), n_quads) << name;
  EXPECT_EQ(r.stats.n_non_quads, 0) << name;
  EXPECT_EQ(r.stats.n_dropped_faces, 0) << name;
  EXPECT_EQ(count_bad_uv_faces(r.quads), 0) << name << ": faces whose UVs are not unit CCW squares";
}

// Quad vertex positions of a planar map with UV = scale·(x,y) must be the integer points / scale.
void expect_planar_lattice(const core::PolyMesh& q, int side, double scale, const std::string& name) {
  const int n = static_cast<int>(std::lround(side * scale));
  ASSERT_EQ(q.n_vertices(), (n + 1) * (n + 1)) << name;
  std::set<std::pair<long, long>> seen;
  double max_err = 0;
  for (int i = 0; i < q.n_vertices(); ++i) {
    const double u = q.V(i, 0) * scale, v = q.V(i, 1) * scale;
    max_err = std::max({max_err, std::abs(u - std::round(u)), std::abs(v - std::round(v)), std::abs(q.V(i, 2))});
    seen.insert({std::lround(u), std::lround(v)});
  }
  EXPECT_LT(max_err, 1e-9) << name << ": quad vertices off the lattice";
  EXPECT_EQ(static_cast<int>(seen.size()), (n + 1) * (n + 1)) << name << ": duplicated lattice points";
}

TEST(ExtractQuads, PlanarIrregularGrid) {
  for (const double scale : {1.0, 2.0, 2.5}) {
    const std::string name = "planar scale " + std::to_string(scale);
    const UVMesh map = planar_grid(6, 4.0, scale, 7);
    const ExtractResult r = extract_quads(map);
    const int n = static_cast<int>(std::lround(4 * scale));
    expect_all_quads(r, n * n, name);
    PolyCheck c = check_poly(r.quads);
    EXPECT_EQ(c.n_bad_edges, 0) << name;
    EXPECT_EQ(c.euler, 1) << name;
    EXPECT_EQ(c.n_boundary_edges, 4 * n) << name;
    EXPECT_EQ(c.valences[2], 4) << name << ": corners";
    EXPECT_EQ(c.valences[4], (n - 1) * (n - 1)) << name << ": interior vertices";
    EXPECT_GT(r.stats.n_grid_points_on_vertices, 0) << name;
    expect_planar_lattice(r.quads, 4, scale, name);
    const core::TopologyStats t = core::topology_stats(core::to_trimesh(r.quads));
    EXPECT_TRUE(t.is_manifold()) << name;
    EXPECT_EQ(t.n_boundary_loops, 1) << name;
  }
}

TEST(ExtractQuads, PlanarGridWithRotatedSeam) {
  for (int r = 1; r < 4; ++r) {
    const std::string name = "seam rotation " + std::to_string(90 * r);
    UVMesh map = planar_grid(6, 4.0, 2.0, 11);
    add_seam(map, 2.1, r, Eigen::Vector2d(7, -3));
    const ExtractResult res = extract_quads(map);
    expect_all_quads(res, 64, name);
    EXPECT_GT(res.stats.n_seam_edges, 0) << name;
    PolyCheck c = check_poly(res.quads);
    EXPECT_EQ(c.n_bad_edges, 0) << name;
    EXPECT_EQ(c.euler, 1) << name;
    EXPECT_EQ(c.valences[4], 49) << name;
    expect_planar_lattice(res.quads, 4, 2.0, name);
  }
}

TEST(ExtractQuads, CubeHasEightValenceThreeVertices) {
  for (const auto& [m, n] : std::vector<std::pair<int, int>>{{3, 2}, {3, 3}, {2, 5}, {4, 1}}) {
    const std::string name = "cube m=" + std::to_string(m) + " n=" + std::to_string(n);
    const ExtractResult r = extract_quads(cube(m, n));
    expect_all_quads(r, 6 * n * n, name);
    EXPECT_EQ(r.stats.n_cones, 8) << name;
    PolyCheck c = check_poly(r.quads);
    EXPECT_EQ(c.n_bad_edges, 0) << name;
    EXPECT_EQ(c.n_boundary_edges, 0) << name;
    EXPECT_EQ(c.euler, 2) << name;
    EXPECT_EQ(c.valences[3], 8) << name;
    EXPECT_EQ(c.valences[4], 6 * n * n - 6) << name;
    EXPECT_EQ(c.n_used_vertices, 6 * n * n + 2) << name;
    const core::TopologyStats t = core::topology_stats(core::to_trimesh(r.quads));
    EXPECT_TRUE(t.is_manifold()) << name;
    EXPECT_EQ(t.genus, 0) << name;
  }
}

TEST(ExtractQuads, FlatTorusIsRegular) {
  const ExtractResult r = extract_quads(torus(7, 5, 6.0, 4.0));
  expect_all_quads(r, 24, "torus");
  PolyCheck c = check_poly(r.quads);
  EXPECT_EQ(c.n_bad_edges, 0);
  EXPECT_EQ(c.n_boundary_edges, 0);
  EXPECT_EQ(c.euler, 0);
  EXPECT_EQ(c.valences[4], 24) << "every vertex must have valence 4";
  EXPECT_EQ(r.stats.n_cones, 0);
}

TEST(ExtractQuads, OpenDiskConesHaveValenceThreeAndFive) {
  for (const auto& [k, m, n] : std::vector<std::array<int, 3>>{{5, 3, 2}, {3, 3, 2}, {5, 2, 2}, {6, 4, 3}}) {
    const std::string name = "cone disk with " + std::to_string(k) + " quadrants, m=" +
                             std::to_string(m) + " n=" + std::to_string(n);
    const ExtractResult r = extract_quads(cone_disk(k, m, n));
    expect_all_quads(r, k * n * n, name);
    EXPECT_EQ(r.stats.n_cones, 1) << name;
    PolyCheck c = check_poly(r.quads);
    EXPECT_EQ(c.n_bad_edges, 0) << name;
    EXPECT_EQ(c.euler, 1) << name;
    EXPECT_EQ(c.n_boundary_edges, 2 * k * n) << name;
    // Interior: the cone (valence k) and valence-4 vertices; boundary: 2kn vertices, the k
    // outer corners of valence 2, the others of valence 3.
    const int n_boundary_valence3 = 2 * k * n - k;
    EXPECT_EQ(c.valences[k], 1 + (k == 3 ? n_boundary_valence3 : 0)) << name;
    EXPECT_EQ(c.valences[2], k) << name;
    EXPECT_EQ(c.valences[3], n_boundary_valence3 + (k == 3 ? 1 : 0)) << name;
    EXPECT_EQ(c.valences[4], k * (n - 1) * (n - 1) + k * (n - 1)) << name;
  }
}

// Cones of index 2 (UV angle π: two quadrants) are quad vertices of valence 2: a tetrahedron
// (4 cones of index 2) folded from the rectangle [0,8]×[0,4] whose bottom side is cut through
// its midpoint M = (4,0) along the slanted segment X' = (3,2) → M → X = (5,−2) (glued to itself
// by the half-turn about M), so that M's fan spans −63°…117° and one face, (M, P, Q), spans
// −9°…99°. The iso-line v = 0 arrives at M inside that face, and its left turn (the quadrant
// below +u, beyond the fan's end) lies in the same face seen once around the cone, turned by
// the holonomy: that turn used to be missed, and the trace walked a boundary the closed fan does
// not have (octopus with thin-part sizing: "boundary walk … does not terminate").
TEST(ExtractQuads, ConesOfIndexTwoAreVerticesOfValenceTwo) {
  // Vertices: 0 A≡B, 1 M, 2 N, 3 D≡C, 4 X≡X', 5 P, 6 Q.
  const double net[10][3][2] = {{{4, 0}, {5, -2}, {7, -0.5}},  {{4, 0}, {7, -0.5}, {3.5, 3}},
                                {{4, 0}, {3.5, 3}, {3, 2}},    {{5, -2}, {8, 0}, {7, -0.5}},
                                {{7, -0.5}, {8, 0}, {8, 4}},   {{7, -0.5}, {8, 4}, {4, 4}},
                                {{7, -0.5}, {4, 4}, {3.5, 3}}, {{3.5, 3}, {4, 4}, {0, 4}},
                                {{3.5, 3}, {0, 4}, {3, 2}},    {{3, 2}, {0, 4}, {0, 0}}};
  const int faces[10][3] = {{1, 4, 5}, {1, 5, 6}, {1, 6, 4}, {4, 0, 5}, {5, 0, 3},
                            {5, 3, 2}, {5, 2, 6}, {6, 2, 3}, {6, 3, 4}, {4, 3, 0}};
  for (unsigned seed = 0; seed < 6; ++seed) {
    const std::string name = "folded tetrahedron, seed " + std::to_string(seed);
    UVMesh tet;
    tet.mesh.V.resize(7, 3);
    tet.mesh.V << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1, 1.2, -0.9, 0.2, 0.3, 0.2, -1.1, -0.8, 0.1, -0.2;
    tet.mesh.F.resize(10, 3);
    tet.corner_uv.resize(30, 2);
    for (int f = 0; f < 10; ++f)
      for (int k = 0; k < 3; ++k) {
        tet.mesh.F(f, k) = faces[f][k];
        tet.corner_uv.row(3 * f + k) << net[f][k][0], net[f][k][1];
      }
    if (seed > 0) scramble_charts(tet, seed);
    const ExtractResult r = extract_quads(tet);
    expect_all_quads(r, 32, name);
    EXPECT_EQ(r.stats.n_cones, 4) << name;
    PolyCheck c = check_poly(r.quads);
    EXPECT_EQ(c.n_bad_edges, 0) << name;
    EXPECT_EQ(c.n_boundary_edges, 0) << name;
    EXPECT_EQ(c.euler, 2) << name;
    EXPECT_EQ(c.valences[2], 4) << name;
  }
}

// A hat of four triangles around an apex whose UV fan spans one quadrant, [0,2]², closed by a
// 90° rotation: a cone of index 3, which would be a quad vertex of valence 1. Refused with a
// message naming it (it used to fail later, in the tracing, as an internal error).
TEST(ExtractQuads, ConeOfIndexThreeIsRejected) {
  UVMesh hat;
  hat.mesh.V.resize(5, 3);
  hat.mesh.V << 0, 0, 1, 1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0;
  hat.mesh.F.resize(4, 3);
  hat.mesh.F << 0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1;
  const Eigen::Vector2d ring[5] = {{2, 0}, {2, 1}, {2, 2}, {1, 2}, {0, 2}};
  hat.corner_uv.resize(12, 2);
  for (int f = 0; f < 4; ++f) {
    hat.corner_uv.row(3 * f) = Eigen::Vector2d(0, 0).transpose();
    hat.corner_uv.row(3 * f + 1) = ring[f].transpose();
    hat.corner_uv.row(3 * f + 2) = ring[f + 1].transpose();
  }
  const ExtractResult r = extract_quads(hat);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput) << r.status.to_string();
  EXPECT_NE(r.status.message().find("cone vertex 0 has index 3"), std::string::npos) << r.status.message();
  EXPECT_NE(r.status.message().find("valence 1"), std::string::npos) << r.status.message();
}

TEST(ExtractQuads, BoundaryCrossingIsoLinesMakeBoundaryVertices) {
  // [0,4]² with UV = (x + 0.5, y + 0.3): the boundary cuts cells. Lines u = 1..4 and v = 1..4
  // give 5×5 cells: 9 interior unit quads, 12 cut quads along the sides, 4 corner triangles.
  for (const bool seam : {false, true}) {
    const std::string name = seam ? "offset map with seam" : "offset map";
    UVMesh map = planar_grid(6, 4.0, 1.0, 13);
    for (int c = 0; c < map.corner_uv.rows(); ++c) map.corner_uv.row(c) += Eigen::Vector2d(0.5, 0.3);
    if (seam) add_seam(map, 2.1, 3, Eigen::Vector2d(-2, 5));
    const ExtractResult r = extract_quads(map);
    ASSERT_TRUE(r.status.is_ok()) << name << ": " << r.status.to_string();
    EXPECT_EQ(r.quads.n_faces(), 25) << name;
    EXPECT_EQ(r.stats.n_non_quads, 4) << name;
    EXPECT_EQ(r.stats.n_boundary_crossings, 16) << name;
    EXPECT_EQ(r.stats.n_dropped_faces, 0) << name;
    PolyCheck c = check_poly(r.quads);
    EXPECT_EQ(c.degrees[3], 4) << name;
    EXPECT_EQ(c.degrees[4], 21) << name;
    EXPECT_EQ(c.n_bad_edges, 0) << name;
    EXPECT_EQ(c.euler, 1) << name;
    EXPECT_EQ(c.n_boundary_edges, 16) << name;
    EXPECT_EQ(c.n_used_vertices, 32) << name;
    double total = 0, min_area = 1e300, max_uv_area_error = 0;
    for (int f = 0; f < r.quads.n_faces(); ++f) {
      total += xy_area(r.quads, f);
      min_area = std::min(min_area, xy_area(r.quads, f));
      // The face's UVs (one chart per face) must span the same area as its positions.
      double uv_area = 0;
      for (int k = 0; k < r.quads.degree(f); ++k) {
        const Eigen::Vector2d a = r.quads.uv.row(r.quads.face_uv[r.quads.face_corner(f, k)]);
        const Eigen::Vector2d b =
            r.quads.uv.row(r.quads.face_uv[r.quads.face_corner(f, (k + 1) % r.quads.degree(f))]);
        uv_area += 0.5 * (a.x() * b.y() - b.x() * a.y());
      }
      max_uv_area_error = std::max(max_uv_area_error, std::abs(uv_area - xy_area(r.quads, f)));
    }
    EXPECT_LT(max_uv_area_error, 1e-9) << name << ": face UVs not in one consistent chart";
    // The domain minus the four corners cut off by the first iso-lines: 16 - 2·0.175 - 2·0.075.
    EXPECT_NEAR(total, 15.5, 1e-9) << name;
    EXPECT_GT(min_area, 0.07) << name << ": a face is inverted or degenerate";
  }
}

TEST(ExtractQuads, EveryTriangleInItsOwnChart) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const std::string tag = " (seed " + std::to_string(seed) + ")";
    UVMesh planar = planar_grid(7, 4.0, 2.0, seed);
    scramble_charts(planar, seed);
    const ExtractResult p = extract_quads(planar);
    expect_all_quads(p, 64, "scrambled planar" + tag);
    expect_planar_lattice(p.quads, 4, 2.0, "scrambled planar" + tag);
    EXPECT_EQ(check_poly(p.quads).n_bad_edges, 0);

    UVMesh box = cube(3, 2);
    scramble_charts(box, seed);
    const ExtractResult c = extract_quads(box);
    expect_all_quads(c, 24, "scrambled cube" + tag);
    EXPECT_EQ(c.stats.n_cones, 8) << tag;
    PolyCheck pc = check_poly(c.quads);
    EXPECT_EQ(pc.euler, 2) << tag;
    EXPECT_EQ(pc.valences[3], 8) << tag;

    UVMesh cut = planar_grid(6, 4.0, 1.0, seed);
    for (int i = 0; i < cut.corner_uv.rows(); ++i) cut.corner_uv.row(i) += Eigen::Vector2d(0.5, 0.3);
    scramble_charts(cut, seed);
    const ExtractResult b = extract_quads(cut);
    ASSERT_TRUE(b.status.is_ok()) << b.status.to_string() << tag;
    EXPECT_EQ(b.quads.n_faces(), 25) << tag;
    EXPECT_EQ(b.stats.n_non_quads, 4) << tag;
    EXPECT_EQ(check_poly(b.quads).euler, 1) << tag;
  }
}

TEST(ExtractQuads, ToleratesSeamNoiseBelowTolerance) {
  // Noise of 1e-12 UV units per corner: seams, cones and on-vertex grid points are snapped.
  UVMesh box = cube(3, 3);  // every grid point on a mesh vertex, iso-lines along mesh edges
  add_uv_noise(box, 1e-12, 4);
  const ExtractResult c = extract_quads(box);
  expect_all_quads(c, 54, "noisy cube");
  EXPECT_EQ(c.stats.n_grid_points_on_vertices, 56);
  EXPECT_GT(c.stats.max_transition_residual, 0);
  EXPECT_LT(c.stats.max_transition_residual, 1e-11);
  PolyCheck pc = check_poly(c.quads);
  EXPECT_EQ(pc.euler, 2);
  EXPECT_EQ(pc.valences[3], 8);
}

TEST(ExtractQuads, RoundDiskBoundaryCutsCells) {
  int case_id = 0;
  for (const double scale : {3.7, 6.0, 10.3})
    for (const Eigen::Vector2d& offset : {Eigen::Vector2d(0.25, 0.61), Eigen::Vector2d(0, 0)}) {
      const std::string name = "disk case " + std::to_string(case_id++);
      UVMesh map = polar_disk(5, 24, scale, offset);
      scramble_charts(map, 17 + case_id);
      const ExtractResult r = extract_quads(map);
      ASSERT_TRUE(r.status.is_ok()) << name << ": " << r.status.to_string();
      EXPECT_EQ(r.stats.n_dropped_faces, 0) << name;
      PolyCheck c = check_poly(r.quads);
      EXPECT_EQ(c.n_bad_edges, 0) << name;
      EXPECT_EQ(c.euler, 1) << name;
      EXPECT_EQ(c.n_used_vertices, r.quads.n_vertices()) << name << ": unused vertices";
      // Every lattice point strictly inside the disk is a vertex of valence 4.
      const double radius = scale * std::cos(M_PI / 24);  // inscribed circle of the polygon
      int inner = 0;
      for (int x = -20; x <= 20; ++x)
        for (int y = -20; y <= 20; ++y)
          inner += std::hypot(x - offset.x(), y - offset.y()) < radius - 1e-9;
      EXPECT_GE(c.valences[4], inner) << name;
      double min_area = 1e300;
      for (int f = 0; f < r.quads.n_faces(); ++f) min_area = std::min(min_area, xy_area(r.quads, f));
      EXPECT_GT(min_area, 0) << name << ": an output face is inverted or degenerate";
      EXPECT_GE(c.n_boundary_edges, r.stats.n_boundary_crossings) << name;
      const core::TopologyStats t = core::topology_stats(core::to_trimesh(r.quads));
      EXPECT_TRUE(t.is_manifold()) << name;
      EXPECT_EQ(t.n_boundary_loops, 1) << name;
    }
}

TEST(ExtractQuads, RandomSimilarityMapsGiveValidMeshes) {
  // UV = scale·R_θ·(x,y) + offset on jittered planar grids, every triangle in its own chart:
  // iso-lines cut the boundary at arbitrary angles, some pass exactly through vertices.
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const std::string name = "similarity trial " + std::to_string(trial);
    UVMesh map = planar_grid(8, 4.0, 1.0, 100 + trial);
    const double theta = trial % 4 == 0 ? 0.0 : 2 * M_PI * unit(rng);
    const double scale = trial % 4 == 0 ? 1.0 + trial / 4 : 0.7 + 2.5 * unit(rng);
    const Eigen::Vector2d offset = trial % 4 == 0 ? Eigen::Vector2d(0, 0)
                                                  : Eigen::Vector2d(unit(rng) * 3, unit(rng) * 3);
    for (int c = 0; c < map.corner_uv.rows(); ++c) {
      const Eigen::Vector2d p = map.corner_uv.row(c);
      map.corner_uv.row(c) = scale * Eigen::Vector2d(std::cos(theta) * p.x() - std::sin(theta) * p.y(),
                                                     std::sin(theta) * p.x() + std::cos(theta) * p.y()) +
                             offset;
    }
    scramble_charts(map, trial);
    const ExtractResult r = extract_quads(map);
    ASSERT_TRUE(r.status.is_ok()) << name << ": " << r.status.to_string();
    EXPECT_EQ(r.stats.n_dropped_faces, 0) << name;
    PolyCheck c = check_poly(r.quads);
    EXPECT_EQ(c.n_bad_edges, 0) << name;
    EXPECT_EQ(c.euler, 1) << name;
    EXPECT_EQ(c.n_used_vertices, r.quads.n_vertices()) << name;
    double total = 0, min_area = 1e300;
    for (int f = 0; f < r.quads.n_faces(); ++f) {
      total += xy_area(r.quads, f);
      min_area = std::min(min_area, xy_area(r.quads, f));
    }
    EXPECT_GT(min_area, 0) << name << ": an output face is inverted or degenerate";
    EXPECT_LE(total, 16.0 + 1e-9) << name;
    // Only the 4 domain corners are cut off (boundary vertices are the crossings), each within
    // one UV cell of xy area 1/scale².
    EXPECT_GE(total, 16.0 - 4.0 / (scale * scale) - 1e-9) << name << ": faces missing";
  }
}

TEST(ExtractQuads, ReflexBoundaryCornerOnAnIsoLine) {
  // L-shaped domain [0,4]² \ [2,4]², UV = (x + 0.5, y + dy): for dy = 0 the reflex corner
  // (2,2) ↦ (2.5, 2) lies on the iso-line v = 2, which runs along the boundary on one side of
  // it and through the interior on the other; dy = 0.5 is the generic control.
  for (const double dy : {0.0, 0.5}) {
    const std::string name = "L shape dy=" + std::to_string(dy);
    UVMesh map = select_faces(planar_grid(8, 4.0, 1.0, 3, 0.0), [](double x, double y) { return x < 2 || y < 2; });
    for (int c = 0; c < map.corner_uv.rows(); ++c) map.corner_uv.row(c) += Eigen::Vector2d(0.5, dy);
    const ExtractResult r = extract_quads(map);
    ASSERT_TRUE(r.status.is_ok()) << name << ": " << r.status.to_string();
    EXPECT_EQ(r.stats.n_dropped_faces, 0) << name;
    EXPECT_EQ(r.stats.n_unsnapped_boundary_vertices, dy == 0 ? 1 : 0) << name;
    PolyCheck c = check_poly(r.quads);
    EXPECT_EQ(c.n_bad_edges, 0) << name;
    EXPECT_EQ(c.euler, 1) << name;
    EXPECT_EQ(c.n_used_vertices, r.quads.n_vertices()) << name;
    const core::TopologyStats t = core::topology_stats(core::to_trimesh(r.quads));
    EXPECT_TRUE(t.is_manifold()) << name;
    EXPECT_EQ(t.n_boundary_loops, 1) << name << ": a crack (T-junction) in the output";
    double total = 0, min_area = 1e300;
    for (int f = 0; f < r.quads.n_faces(); ++f) {
      total += xy_area(r.quads, f);
      min_area = std::min(min_area, xy_area(r.quads, f));
    }
    EXPECT_GT(min_area, 0) << name;
    EXPECT_LE(total, 12.0 + 1e-9) << name;
    EXPECT_GE(total, 12.0 - 5 * 0.5 - 1e-9) << name << ": faces missing (5 corners, each ≤ half a cell)";
  }
}

TEST(ExtractQuads, RejectsNonSeamlessMap) {
  UVMesh map = planar_grid(6, 4.0, 2.0, 3);
  add_seam(map, 2.1, 1, Eigen::Vector2d(7.3, -3));
  const ExtractResult r = extract_quads(map);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput) << r.status.to_string();
  EXPECT_NE(r.status.message().find("not integer-seamless"), std::string::npos) << r.status.message();
  EXPECT_NE(r.status.message().find("residual"), std::string::npos) << r.status.message();
  EXPECT_EQ(r.quads.n_faces(), 0);

  const ExtractResult t = extract_quads(torus(7, 5, 6.3, 4.0));
  EXPECT_EQ(t.status.code(), core::StatusCode::kInvalidInput) << t.status.to_string();
}

TEST(ExtractQuads, RejectsFlippedTriangle) {
  UVMesh map = planar_grid(6, 4.0, 2.0, 5);
  const int f = 17;
  const Eigen::Vector2d tmp = map.corner_uv.row(3 * f);
  map.corner_uv.row(3 * f) = map.corner_uv.row(3 * f + 1);
  map.corner_uv.row(3 * f + 1) = tmp;
  const ExtractResult r = extract_quads(map);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput) << r.status.to_string();
  EXPECT_NE(r.status.message().find("face 17 is flipped"), std::string::npos) << r.status.message();
}

TEST(ExtractQuads, RejectsConeOffTheLattice) {
  UVMesh map = cube(2, 2);
  map.corner_uv.array() += 0.5;  // shifts every chart: rotations then need half-integer shifts
  const ExtractResult r = extract_quads(map);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput) << r.status.to_string();
}

TEST(ExtractQuads, RejectsBadSizes) {
  UVMesh map = planar_grid(2, 1.0, 1.0, 1);
  map.corner_uv.conservativeResize(5, 2);
  const ExtractResult r = extract_quads(map);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput) << r.status.to_string();
}

TEST(ExtractQuads, RejectsBadOptionsAndTooFineMaps) {
  const UVMesh map = planar_grid(4, 4.0, 1.0, 2);
  ExtractOptions bad;
  bad.max_transition_residual = -1;
  EXPECT_EQ(extract_quads(map, bad).status.code(), core::StatusCode::kInvalidInput);
  ExtractOptions small;
  small.max_grid_points = 10;  // the map spans 25 + points
  const ExtractResult r = extract_quads(map, small);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput) << r.status.to_string();
  EXPECT_NE(r.status.message().find("max_grid_points"), std::string::npos) << r.status.message();
}

TEST(ExtractQuads, LargeTorusSpeed) {
  // 250×200 grid → 100K triangles, 200×100 = 20K quads.
  const UVMesh map = torus(250, 200, 200.0, 100.0);
  const ExtractResult r = extract_quads(map);
  expect_all_quads(r, 20000, "large torus");
  PolyCheck c = check_poly(r.quads);
  EXPECT_EQ(c.euler, 0);
  EXPECT_EQ(c.valences[4], 20000);
  std::printf("[ stats    ] 100K-triangle torus: %d quads, %d vertices (%d on vertices, %d on edges, "
              "%d in faces), %.3f s\n",
              r.stats.n_faces, r.stats.n_vertices, r.stats.n_grid_points_on_vertices,
              r.stats.n_grid_points_on_edges, r.stats.n_grid_points_in_faces, r.stats.seconds);
#if !defined(__SANITIZE_ADDRESS__)
  EXPECT_LT(r.stats.seconds, 5.0) << "target: ≤ 5 s for 100K triangles";
#endif

  // An open 224² grid (100K triangles) mapped by a rotation of 30°, 20K cells, cut boundary.
  UVMesh planar = planar_grid(224, 1.0, 1.0, 5);
  const double c30 = std::cos(M_PI / 6), s30 = std::sin(M_PI / 6), scale = std::sqrt(20000.0);
  for (int c = 0; c < planar.corner_uv.rows(); ++c) {
    const Eigen::Vector2d p = planar.corner_uv.row(c);
    planar.corner_uv.row(c) = scale * Eigen::Vector2d(c30 * p.x() - s30 * p.y(), s30 * p.x() + c30 * p.y());
  }
  const ExtractResult b = extract_quads(planar);
  ASSERT_TRUE(b.status.is_ok()) << b.status.to_string();
  EXPECT_EQ(b.stats.n_dropped_faces, 0);
  EXPECT_EQ(check_poly(b.quads).euler, 1);
  EXPECT_NEAR(b.quads.n_faces(), 20000, 4 * scale) << "interior cells plus cut cells along the boundary";
  std::printf("[ stats    ] 100K-triangle rotated open grid: %d faces (%d non-quads), %d boundary "
              "crossings, %.3f s\n",
              b.stats.n_faces, b.stats.n_non_quads, b.stats.n_boundary_crossings, b.stats.seconds);
#if !defined(__SANITIZE_ADDRESS__)
  EXPECT_LT(b.stats.seconds, 5.0) << "target: ≤ 5 s for 100K triangles";
#endif
}

}  // namespace
}  // namespace quadify::quadex
