#include <libquadex/quad_metrics.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>

namespace quadify::quadex {
namespace {

// Tolerance on quantities exact up to a few roundings (unitless or × bbox diagonal).
constexpr double kExactTol = 1e-9;

// A flat n×n grid of unit quads, CCW seen from +z.
core::PolyMesh quad_grid(int n) {
  core::PolyMesh out;
  out.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) out.V.row(j * (n + 1) + i) << i, j, 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      out.add_face({a, a + 1, a + n + 2, a + n + 1});
    }
  return out;
}

// The cube [0,1]³ + offset as 6 quads, outward CCW; vertex id x + 2y + 4z.
constexpr std::array<std::array<int, 4>, 6> kCubeQuads = {
    {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};

core::PolyMesh cube_quads(const Eigen::Vector3d& offset = Eigen::Vector3d::Zero(), bool reversed = false) {
  core::PolyMesh out;
  out.V.resize(8, 3);
  for (int v = 0; v < 8; ++v) out.V.row(v) = Eigen::RowVector3d(v & 1, (v >> 1) & 1, (v >> 2) & 1) + offset.transpose();
  for (const auto& q : kCubeQuads)
    reversed ? out.add_face({q[3], q[2], q[1], q[0]}) : out.add_face({q[0], q[1], q[2], q[3]});
  return out;
}

core::TriMesh cube_triangles() { return core::to_trimesh(cube_quads()); }

// An open ring of `sides` planar quads around the z axis (a coarse cylinder of radius 1, height 1),
// each side split into m×m quads. Vertex (s, i, j): side s, position i along it, height j.
core::PolyMesh prism_ring(int sides, int m, int shifted_edge = -1, double shift = 0) {
  core::PolyMesh out;
  std::vector<Eigen::Vector3d> corners(sides);
  for (int s = 0; s < sides; ++s) {
    const double a = 2 * std::numbers::pi * s / sides;
    corners[s] = Eigen::Vector3d(std::cos(a), std::sin(a), 0);
  }
  if (shifted_edge >= 0) {
    const Eigen::Vector3d next = corners[(shifted_edge + 1) % sides];
    corners[shifted_edge] += shift * (next - corners[shifted_edge]);
  }
  const int per_ring = sides * m;
  out.V.resize(per_ring * (m + 1), 3);
  for (int j = 0; j <= m; ++j)
    for (int s = 0; s < sides; ++s)
      for (int i = 0; i < m; ++i) {
        const Eigen::Vector3d p = corners[s] + (corners[(s + 1) % sides] - corners[s]) * (double(i) / m);
        out.V.row(j * per_ring + s * m + i) << p.x(), p.y(), double(j) / m;
      }
  for (int j = 0; j < m; ++j)
    for (int k = 0; k < per_ring; ++k) {
      const int a = j * per_ring + k, b = j * per_ring + (k + 1) % per_ring;
      out.add_face({a, b, b + per_ring, a + per_ring});
    }
  return out;
}

TEST(QuadMetrics, RegularGrid) {
  constexpr int kN = 6;
  const QuadMetrics m = compute_quad_metrics(quad_grid(kN));
  EXPECT_EQ(m.n_faces, kN * kN);
  EXPECT_EQ(m.n_vertices, (kN + 1) * (kN + 1));
  EXPECT_EQ(m.faces_by_degree.at(4), kN * kN);
  EXPECT_EQ(m.n_non_quads, 0);
  ASSERT_EQ(m.valence_histogram.size(), 1u);
  EXPECT_EQ(m.valence_histogram.at(4), (kN - 1) * (kN - 1));
  EXPECT_EQ(m.n_irregular, 0) << "boundary valence 3 and corners of valence 2 are regular";
  EXPECT_TRUE(m.manifold);
  EXPECT_EQ(m.n_components, 1);
  EXPECT_EQ(m.n_boundary_loops, 1);
  EXPECT_EQ(m.euler_characteristic, 1);
  EXPECT_EQ(m.genus, 0);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_NEAR(m.sj_min, 1.0, kExactTol);
  EXPECT_NEAR(m.sj_mean, 1.0, kExactTol);
  EXPECT_NEAR(m.angle_dev_max, 0.0, kExactTol);
  EXPECT_NEAR(m.edge_len_cv, 0.0, kExactTol);
  EXPECT_NEAR(m.edge_len_mean, 1.0, kExactTol);
  EXPECT_FALSE(m.has_reference);
  EXPECT_EQ(m.hausdorff_sym, -1);
}

TEST(QuadMetrics, BoundaryIrregularity) {
  // Removing the corner quad of a 3×3 grid: vertex (1,1) becomes a boundary vertex of valence 4
  // (irregular), (1,0) and (0,1) boundary corners of valence 2 (regular).
  core::PolyMesh grid = quad_grid(3);
  core::PolyMesh cut;
  cut.V = grid.V;
  for (int f = 1; f < grid.n_faces(); ++f)
    cut.add_face({grid.vertex(f, 0), grid.vertex(f, 1), grid.vertex(f, 2), grid.vertex(f, 3)});
  const QuadMetrics m = compute_quad_metrics(cut);
  EXPECT_EQ(m.n_irregular, 1);
  EXPECT_EQ(m.valence_histogram.at(4), 3);
  EXPECT_EQ(m.euler_characteristic, 1);
  EXPECT_EQ(m.genus, 0);
}

TEST(QuadMetrics, CubeHasEightValenceThreeVertices) {
  const QuadMetrics m = compute_quad_metrics(cube_quads());
  EXPECT_EQ(m.valence_histogram.at(3), 8);
  EXPECT_EQ(m.n_irregular, 8);
  EXPECT_EQ(m.euler_characteristic, 2);
  EXPECT_EQ(m.genus, 0);
  EXPECT_EQ(m.n_boundary_loops, 0);
  EXPECT_TRUE(m.manifold);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_NEAR(m.sj_min, 1.0, kExactTol);
}

TEST(QuadMetrics, ReflexAndBowtieQuadsAreFlipped) {
  core::PolyMesh mesh;
  mesh.V.resize(8, 3);
  mesh.V << 0, 0, 0, 2, 0, 0, 0.6, 0.6, 0, 0, 2, 0,  // dart: reflex corner at (0.6, 0.6)
      3, 0, 0, 4, 0, 0, 3, 1, 0, 4, 1, 0;             // bowtie: edges cross
  mesh.add_face({0, 1, 2, 3});
  mesh.add_face({4, 5, 6, 7});
  const QuadMetrics m = compute_quad_metrics(mesh);
  EXPECT_EQ(m.n_flipped, 2);
  EXPECT_LT(m.sj_min, 0.0);
  // The dart's sharp corner at (2,0) is atan(0.6/1.4) ≈ 23.2°: 66.8° from square.
  EXPECT_GT(m.angle_dev_max, 66.0);
  EXPECT_EQ(m.n_components, 2);
}

TEST(QuadMetrics, NonManifoldEdgeAndVertex) {
  core::PolyMesh fin;  // three quads on the edge (0,1)
  fin.V.resize(8, 3);
  fin.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, -1, 0, 0, -1, 0;
  fin.add_face({0, 1, 2, 3});
  fin.add_face({1, 0, 5, 4});
  fin.add_face({1, 0, 7, 6});
  const QuadMetrics edge = compute_quad_metrics(fin);
  EXPECT_FALSE(edge.manifold);
  EXPECT_EQ(edge.genus, -1);
  EXPECT_EQ(edge.n_components, 1);

  core::PolyMesh bowtie;  // two quads sharing only vertex 0
  bowtie.V.resize(7, 3);
  bowtie.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 0, 0, -1, -1, 0, 0, -1, 0;
  bowtie.add_face({0, 1, 2, 3});
  bowtie.add_face({0, 4, 5, 6});
  const QuadMetrics vertex = compute_quad_metrics(bowtie);
  EXPECT_FALSE(vertex.manifold);
  EXPECT_EQ(vertex.genus, -1);
  EXPECT_EQ(vertex.n_components, 2);

  EXPECT_TRUE(compute_quad_metrics(quad_grid(2)).manifold);
  EXPECT_EQ(compute_quad_metrics(quad_grid(2)).n_degenerate, 0);
}

// A quad that visits a vertex twice: an iso-line that closes on its own grid point (a handle one
// quad around) gives a loop edge (2, 2); a pinched quad visits its vertex at opposite corners.
TEST(QuadMetrics, FacesVisitingAVertexTwiceAreNotManifold) {
  core::PolyMesh loop = quad_grid(2);
  loop.add_face({8, 5, 2, 2});
  const QuadMetrics with_loop = compute_quad_metrics(loop);
  EXPECT_EQ(with_loop.n_degenerate, 1);
  EXPECT_FALSE(with_loop.manifold);
  EXPECT_EQ(with_loop.genus, -1);

  core::PolyMesh pinched = quad_grid(2);
  pinched.add_face({1, 4, 1, 5});
  const QuadMetrics with_pinch = compute_quad_metrics(pinched);
  EXPECT_EQ(with_pinch.n_degenerate, 1);
  EXPECT_FALSE(with_pinch.manifold);
}

TEST(QuadMetrics, HausdorffAgainstItselfIsZero) {
  QuadMetricsOptions options;
  options.hausdorff_samples = 2000;
  const core::TriMesh reference = cube_triangles();
  const QuadMetrics m = compute_quad_metrics(cube_quads(), &reference, options);
  EXPECT_TRUE(m.has_reference);
  EXPECT_LT(m.hausdorff_sym, kExactTol);
  EXPECT_LT(m.mean_dist_sym, kExactTol);
  EXPECT_EQ(m.n_flipped, 0);
}

TEST(QuadMetrics, HausdorffAgainstTranslatedCopy) {
  constexpr double kShift = 0.05;
  QuadMetricsOptions options;
  options.hausdorff_samples = 2000;
  const core::TriMesh reference = cube_triangles();
  const QuadMetrics m = compute_quad_metrics(cube_quads({kShift, 0, 0}), &reference, options);
  const double diag = std::sqrt(3.0);
  // The farthest points are on the ±x faces (distance kShift), reached at the vertices.
  EXPECT_NEAR(m.hausdorff_to_ref, kShift / diag, kExactTol);
  EXPECT_NEAR(m.hausdorff_from_ref, kShift / diag, kExactTol);
  EXPECT_NEAR(m.hausdorff_sym, kShift / diag, kExactTol);
  // Mean: the two x faces (1/6 of the area) are at distance kShift, points on the side faces
  // within kShift of the end are closer; the mean is positive and below the max.
  EXPECT_GT(m.mean_dist_sym, 0.1 * kShift / diag);
  EXPECT_LT(m.mean_dist_sym, kShift / diag);
}

TEST(QuadMetrics, FacingAgainstReferenceIsFlipped) {
  QuadMetricsOptions options;
  options.hausdorff_samples = 100;
  const core::TriMesh reference = cube_triangles();
  const QuadMetrics m = compute_quad_metrics(cube_quads({0, 0, 0}, true), &reference, options);
  EXPECT_NEAR(m.sj_min, 1.0, kExactTol) << "reversed quads are fine on their own";
  EXPECT_EQ(m.n_flipped, 6);
}

TEST(QuadMetrics, CubeCapturesAllFeatures) {
  QuadMetricsOptions options;
  options.hausdorff_samples = 100;
  const core::TriMesh reference = cube_triangles();
  const QuadMetrics m = compute_quad_metrics(cube_quads(), &reference, options);
  EXPECT_NEAR(m.feature_capture, 1.0, kExactTol);
  EXPECT_LT(m.feature_hausdorff, kExactTol);
}

TEST(QuadMetrics, NoSharpEdgesGivesNoFeatureCapture) {
  QuadMetricsOptions options;
  options.hausdorff_samples = 100;
  const core::TriMesh reference = core::to_trimesh(quad_grid(3));
  const QuadMetrics m = compute_quad_metrics(quad_grid(3), &reference, options);
  EXPECT_EQ(m.feature_capture, -1);
}

TEST(QuadMetrics, ShiftedRingEdgeIsNotCaptured) {
  constexpr double kShift = 0.2;  // of the side length (1 for a unit hexagon)
  QuadMetricsOptions options;
  options.hausdorff_samples = 1000;
  const core::TriMesh reference = core::to_trimesh(prism_ring(6, 4));
  const QuadMetrics exact = compute_quad_metrics(prism_ring(6, 1), &reference, options);
  EXPECT_NEAR(exact.feature_capture, 1.0, kExactTol);
  const QuadMetrics m = compute_quad_metrics(prism_ring(6, 1, 2, kShift), &reference, options);
  // 6 vertical edges at 60° dihedral (the rims are boundary): one of them has moved away.
  EXPECT_NEAR(m.feature_capture, 5.0 / 6.0, kExactTol);
  const double diag = std::sqrt(8.0);  // x ∈ [-1,1], y ∈ [-√3/2, √3/2], z ∈ [0,1]
  EXPECT_NEAR(m.feature_hausdorff, kShift / diag, kExactTol);
  EXPECT_GT(m.hausdorff_sym, 0.1 * kShift / diag);
}

TEST(QuadMetrics, SamplingIsDeterministic) {
  QuadMetricsOptions options;
  options.hausdorff_samples = 5000;
  const core::TriMesh reference = core::to_trimesh(prism_ring(6, 4));
  const core::PolyMesh quads = prism_ring(6, 2, 1, 0.1);
  const QuadMetrics a = compute_quad_metrics(quads, &reference, options);
  const QuadMetrics b = compute_quad_metrics(quads, &reference, options);
  EXPECT_EQ(a.hausdorff_sym, b.hausdorff_sym);
  EXPECT_EQ(a.mean_dist_sym, b.mean_dist_sym);
  options.seed = 7;
  const QuadMetrics c = compute_quad_metrics(quads, &reference, options);
  EXPECT_NE(a.mean_dist_sym, c.mean_dist_sym) << "a different seed samples other points";
}

}  // namespace
}  // namespace quadify::quadex

namespace quadify::quadex {
namespace {

// An open cylinder of radius 1 and height 4 as a quad grid (n_theta × n_z), its rows turned by
// `twist` radians per unit of height (a helical grid when twist ≠ 0).
core::PolyMesh cylinder_quads(int n_theta, int n_z, double twist) {
  core::PolyMesh m;
  m.V.resize(n_theta * (n_z + 1), 3);
  for (int j = 0; j <= n_z; ++j)
    for (int i = 0; i < n_theta; ++i) {
      const double z = 4.0 * j / n_z, a = 2 * std::numbers::pi * i / n_theta + twist * z;
      m.V.row(j * n_theta + i) << std::cos(a), std::sin(a), z;
    }
  for (int j = 0; j < n_z; ++j)
    for (int i = 0; i < n_theta; ++i) {
      const int a = j * n_theta + i, b = j * n_theta + (i + 1) % n_theta;
      m.add_face({a, b, b + n_theta, a + n_theta});
    }
  return m;
}

// The cylinder bends around (curvature 1) and not along its axis: a grid of rings and axial lines
// follows the principal directions; a helical one (axial lines at ~31°) does not.
TEST(QuadMetrics, PrincipalCurvatureAlignment) {
  const core::TriMesh reference = core::to_trimesh(cylinder_quads(96, 64, 0));
  const QuadMetrics aligned = compute_quad_metrics(cylinder_quads(32, 20, 0), &reference);
  EXPECT_GT(aligned.n_anisotropic_quads, 400);
  EXPECT_LT(aligned.principal_angle_mean, 3.0);
  const QuadMetrics helical = compute_quad_metrics(cylinder_quads(32, 20, 0.6), &reference);
  EXPECT_GT(helical.principal_angle_mean, 10.0);
  QuadMetricsOptions off;
  off.curvature_alignment = false;
  EXPECT_EQ(compute_quad_metrics(cylinder_quads(32, 20, 0), &reference, off).principal_angle_mean, -1);
}

}  // namespace
}  // namespace quadify::quadex
