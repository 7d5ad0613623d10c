#include <libcore/uv_metrics.h>

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <numbers>
#include <queue>
#include <stdexcept>

namespace quadify::core {
namespace {

// Tolerance on quantities that are exact up to a few floating-point roundings (unitless).
constexpr double kExactTol = 1e-9;

// A flat n×n grid of unit cells in the z=0 plane (or lifted by `height`), split along diagonals,
// with per-corner UVs given by `map`.
UVMesh grid_map(int n, const std::function<Eigen::Vector2d(double, double)>& map,
                const std::function<double(double, double)>& height = nullptr) {
  UVMesh out;
  const int nv = (n + 1) * (n + 1);
  out.mesh.V.resize(nv, 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      out.mesh.V.row(j * (n + 1) + i) << i, j, height ? height(i, j) : 0.0;
  out.mesh.F.resize(2 * n * n, 3);
  int f = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      out.mesh.F.row(f++) << a, b, c;
      out.mesh.F.row(f++) << a, c, d;
    }
  out.corner_uv.resize(3 * out.mesh.n_faces(), 2);
  for (int g = 0; g < out.mesh.n_faces(); ++g)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = out.mesh.V.row(out.mesh.F(g, k));
      out.corner_uv.row(3 * g + k) = map(p.x(), p.y()).transpose();
    }
  return out;
}

// The unit cube cut open along 7 edges and unfolded into a cross: its six faces are unit squares
// placed by a breadth-first unfolding from the bottom face, each square split into 2 triangles.
UVMesh cube_cross() {
  const std::array<std::array<int, 4>, 6> quads = {{{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                                     {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
  UVMesh out;
  out.mesh.V.resize(8, 3);
  for (int v = 0; v < 8; ++v) out.mesh.V.row(v) << (v & 1), ((v >> 1) & 1), ((v >> 2) & 1);
  std::vector<std::array<Eigen::Vector2d, 4>> quad_uv(6);
  std::vector<char> placed(6, 0);
  quad_uv[0] = {Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0), Eigen::Vector2d(1, 1), Eigen::Vector2d(0, 1)};
  placed[0] = 1;
  std::queue<int> queue;
  queue.push(0);
  auto rot90 = [](const Eigen::Vector2d& d) { return Eigen::Vector2d(-d.y(), d.x()); };
  while (!queue.empty()) {
    const int q = queue.front();
    queue.pop();
    for (int k = 0; k < 4; ++k) {
      const int a = quads[q][k], b = quads[q][(k + 1) % 4];
      for (int r = 0; r < 6; ++r) {
        if (placed[r]) continue;
        for (int i = 0; i < 4; ++i) {
          if (quads[r][i] != b || quads[r][(i + 1) % 4] != a) continue;
          // r runs b → a along the shared edge; it lies on the other side of it in the plane.
          const Eigen::Vector2d ub = quad_uv[q][(k + 1) % 4], ua = quad_uv[q][k];
          const Eigen::Vector2d d = ua - ub;
          quad_uv[r][i] = ub;
          quad_uv[r][(i + 1) % 4] = ua;
          quad_uv[r][(i + 2) % 4] = ua + rot90(d);
          quad_uv[r][(i + 3) % 4] = ub + rot90(d);
          placed[r] = 1;
          queue.push(r);
        }
      }
    }
  }
  out.mesh.F.resize(12, 3);
  out.corner_uv.resize(36, 2);
  for (int q = 0; q < 6; ++q)
    for (int t = 0; t < 2; ++t) {
      const std::array<int, 3> local = t == 0 ? std::array<int, 3>{0, 1, 2} : std::array<int, 3>{0, 2, 3};
      for (int k = 0; k < 3; ++k) {
        out.mesh.F(2 * q + t, k) = quads[q][local[k]];
        out.corner_uv.row(3 * (2 * q + t) + k) = quad_uv[q][local[k]].transpose();
      }
    }
  return out;
}

TEST(UVMetrics, IsometricFlatGridIsPerfect) {
  const UVMesh grid = grid_map(8, [](double x, double y) { return Eigen::Vector2d(x, y); });
  const UVMetrics m = compute_uv_metrics(grid);
  EXPECT_EQ(m.n_faces, 128);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_EQ(m.n_degenerate, 0);
  EXPECT_NEAR(m.tau, 1.0, kExactTol);
  EXPECT_NEAR(m.sigma1_max, 1.0, kExactTol);
  EXPECT_NEAR(m.sigma2_min, 1.0, kExactTol);
  EXPECT_NEAR(m.sd_mean, 4.0, kExactTol);
  EXPECT_NEAR(m.sd_max, 4.0, kExactTol);
  EXPECT_NEAR(m.conformal_max, 1.0, kExactTol);
  EXPECT_NEAR(m.area_max, 1.0, kExactTol);
  EXPECT_EQ(m.n_seam_edges, 0);
  EXPECT_EQ(m.n_cones, 0);
  EXPECT_TRUE(m.cone_indices_integer);
  EXPECT_EQ(m.n_boundary_vertices, 32);
  EXPECT_EQ(m.euler_characteristic, 1);
  EXPECT_LT(m.gauss_bonnet_error, kExactTol);
}

TEST(UVMetrics, AxisScaledMapHasAnalyticSingularValues) {
  const UVMesh grid = grid_map(4, [](double x, double y) { return Eigen::Vector2d(2 * x, 3 * y); });
  const UVMetrics m = compute_uv_metrics(grid);
  for (int f = 0; f < m.n_faces; ++f) {
    EXPECT_NEAR(m.singular_values(f, 0), 3.0, kExactTol) << "face " << f;
    EXPECT_NEAR(m.singular_values(f, 1), 2.0, kExactTol) << "face " << f;
  }
  EXPECT_NEAR(m.tau, std::sqrt(3.0 / 2.0), kExactTol);
  EXPECT_NEAR(m.conformal_max, 1.5, kExactTol);
  // Scale-normalised: σ·sqrt(1/6) gives σ1σ2 = 1, so no area distortion remains.
  EXPECT_NEAR(m.area_max, 1.0, kExactTol);
  const double s1 = 3 / std::sqrt(6.0), s2 = 2 / std::sqrt(6.0);
  EXPECT_NEAR(m.sd_mean, s1 * s1 + 1 / (s1 * s1) + s2 * s2 + 1 / (s2 * s2), kExactTol);
}

TEST(UVMetrics, ShearedMapHasAnalyticSingularValues) {
  constexpr double kShear = 0.7;
  const UVMesh grid = grid_map(3, [](double x, double y) { return Eigen::Vector2d(x + kShear * y, y); });
  const UVMetrics m = compute_uv_metrics(grid);
  // Singular values of [[1,k],[0,1]]: sqrt((2 + k² ± k·sqrt(k² + 4)) / 2).
  const double root = kShear * std::sqrt(kShear * kShear + 4);
  const double s1 = std::sqrt((2 + kShear * kShear + root) / 2), s2 = std::sqrt((2 + kShear * kShear - root) / 2);
  EXPECT_NEAR(s1 * s2, 1.0, kExactTol);
  EXPECT_NEAR(m.sigma1_max, s1, kExactTol);
  EXPECT_NEAR(m.sigma2_min, s2, kExactTol);
  EXPECT_NEAR(m.area_max, 1.0, kExactTol);
  EXPECT_EQ(m.n_flipped, 0);
}

TEST(UVMetrics, FlippedTriangleIsCountedAndTauInfinite) {
  constexpr int kN = 4;
  UVMesh grid = grid_map(kN, [](double x, double y) { return Eigen::Vector2d(x, y); });
  // Vertex (n,0) is in one triangle only, (n-1,0),(n,0),(n,1); moving its UV to (n-1,1)
  // reverses exactly that triangle.
  const int corner_vertex = kN;
  int n_moved = 0;
  for (int c = 0; c < 3 * grid.mesh.n_faces(); ++c)
    if (grid.mesh.F(c / 3, c % 3) == corner_vertex) {
      grid.corner_uv.row(c) << kN - 1, 1;
      ++n_moved;
    }
  ASSERT_EQ(n_moved, 1);
  const UVMetrics m = compute_uv_metrics(grid);
  EXPECT_EQ(m.n_flipped, 1);
  EXPECT_EQ(m.n_degenerate, 0);
  EXPECT_TRUE(std::isinf(m.tau)) << "tau " << m.tau;
  EXPECT_TRUE(std::isinf(m.sd_max));
  EXPECT_LT(m.sigma2_min, 0.0);
  // Each flipped triangle adds 2π to the Gauss–Bonnet sum (signed corner angles).
  EXPECT_NEAR(m.gauss_bonnet_error, 2 * std::numbers::pi, kExactTol);
}

TEST(UVMetrics, DegenerateTriangleIsCounted) {
  UVMesh grid = grid_map(2, [](double x, double y) { return Eigen::Vector2d(x, y); });
  // Collapse the single triangle at vertex (2,0) onto a line.
  for (int c = 0; c < 3 * grid.mesh.n_faces(); ++c)
    if (grid.mesh.F(c / 3, c % 3) == 2) grid.corner_uv.row(c) << 1.5, 0.5;
  const UVMetrics m = compute_uv_metrics(grid);
  EXPECT_EQ(m.n_degenerate, 1);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_TRUE(std::isinf(m.tau));
  EXPECT_LT(m.gauss_bonnet_error, kExactTol);
}

TEST(UVMetrics, MirroredMapHasNoFlips) {
  const UVMesh grid = grid_map(5, [](double x, double y) { return Eigen::Vector2d(-x, y); });
  const UVMetrics m = compute_uv_metrics(grid);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_NEAR(m.tau, 1.0, kExactTol);
  EXPECT_NEAR(m.sigma2_min, 1.0, kExactTol);
  EXPECT_EQ(m.n_cones, 0);
  EXPECT_LT(m.gauss_bonnet_error, kExactTol);
}

TEST(UVMetrics, CurvedOpenDiskByProjection) {
  constexpr int kN = 6;
  const UVMesh disk = grid_map(
      kN, [](double x, double y) { return Eigen::Vector2d(x, y); },
      [](double x, double y) { return 0.05 * ((x - 3) * (x - 3) + (y - 3) * (y - 3)); });
  const UVMetrics m = compute_uv_metrics(disk);
  EXPECT_EQ(m.euler_characteristic, 1);
  EXPECT_EQ(m.n_boundary_vertices, 4 * kN);
  EXPECT_EQ(m.n_cones, 0);
  EXPECT_EQ(m.n_seam_edges, 0);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_GT(m.tau, 1.0);  // projection shortens the tilted directions
  EXPECT_LT(m.sigma2_min, 1.0 - 1e-3);
  EXPECT_LT(m.gauss_bonnet_error, kExactTol);
}

TEST(UVMetrics, CubeCrossHasEightQuarterConesAndIntegerSeams) {
  const UVMesh cube = cube_cross();
  const UVMetrics m = compute_uv_metrics(cube);
  EXPECT_EQ(m.euler_characteristic, 2);
  EXPECT_EQ(m.n_boundary_vertices, 0);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_NEAR(m.tau, 1.0, kExactTol);
  // A spanning tree of the 6 faces keeps 5 of the 12 cube edges; the other 7 are cut.
  EXPECT_EQ(m.n_seam_edges, 7);
  EXPECT_TRUE(m.matchings_integer);
  EXPECT_LT(m.seam_residual_max, kExactTol);
  bool has_rotation = false;
  for (const SeamEdge& s : m.seams) {
    EXPECT_NEAR(s.angle, std::round(s.angle), kExactTol) << "edge " << s.edge;
    has_rotation |= s.matching != 0;
  }
  EXPECT_TRUE(has_rotation) << "a cube net needs rotational seams";
  ASSERT_EQ(m.n_cones, 8);
  for (const Cone& c : m.cones) {
    EXPECT_NEAR(c.angle_sum, 1.5 * std::numbers::pi, kExactTol) << "vertex " << c.vertex;
    EXPECT_NEAR(c.index, 1.0, kExactTol) << "vertex " << c.vertex;
    EXPECT_FALSE(c.on_boundary);
  }
  EXPECT_TRUE(m.cone_indices_integer);
  EXPECT_LT(m.gauss_bonnet_error, kExactTol);
}

TEST(UVMetrics, NonIntegerSeamIsReported) {
  UVMesh cube = cube_cross();
  // Rotate the UVs of face 1 (top) and its sibling triangle by 10°: its seams stop being integer.
  const double a = 10.0 * std::numbers::pi / 180;
  Eigen::Matrix2d R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  for (int c = 6; c < 12; ++c) cube.corner_uv.row(c) = (R * cube.corner_uv.row(c).transpose()).transpose();
  const UVMetrics m = compute_uv_metrics(cube);
  EXPECT_FALSE(m.matchings_integer);
  EXPECT_GT(m.seam_residual_max, 0.1);
  EXPECT_LT(m.gauss_bonnet_error, kExactTol);  // angle sums are unchanged by a rigid motion
}

TEST(UVMetrics, WrongCornerUVSizeThrows) {
  UVMesh grid = grid_map(2, [](double x, double y) { return Eigen::Vector2d(x, y); });
  grid.corner_uv.conservativeResize(grid.corner_uv.rows() - 1, 2);
  EXPECT_THROW((void)compute_uv_metrics(grid), std::invalid_argument);
}

TEST(UVMetrics, LargeGridIsFast) {
  const UVMesh grid = grid_map(224, [](double x, double y) { return Eigen::Vector2d(x, y + 0.1 * x); });
  ASSERT_GT(grid.mesh.n_faces(), 100'000);
  const auto start = std::chrono::steady_clock::now();
  const UVMetrics m = compute_uv_metrics(grid);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(m.n_flipped, 0);
  // Generous bound (sanitizer builds are ~10× slower); Release takes well under 0.2 s.
  EXPECT_LT(seconds, 5.0) << m.n_faces << " faces";
}

}  // namespace
}  // namespace quadify::core
