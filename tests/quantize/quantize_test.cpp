// Tests of quantize_seamless: param → quantize → extract on the small meshes of tests/data.
#include <gtest/gtest.h>
#include <libcore/read_mesh.h>
#include <libparam/constrained_layout.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <tuple>
#include <utility>
#include <vector>

#include "quantize_test_util.h"
#include "test_meshes.h"
#include "test_util.h"

namespace quadify {
namespace {

// Quad count within this fraction of the target (the scale is set from the UV area; the
// flip-free re-optimization changes the area only slightly).
constexpr double kQuadCountTolerance = 0.10;
// A coarse target for tests/data/plate.obj, where its creases do not all fit the grid.
constexpr int kPlateTarget = 120;

core::TriMesh load(const std::string& name) {
  return core::to_trimesh(core::read_mesh(test::data_path(name)));
}

// Asserts every property of a successful pipeline run on `mesh`.
void expect_valid_quads(const std::string& name, const core::TriMesh& mesh, int target,
                        bool check_count) {
  const test::PipelineRun run = test::run_pipeline(mesh, target);
  ASSERT_TRUE(run.param.status.is_ok()) << name << ": " << run.param.status.to_string();
  ASSERT_TRUE(run.quantized.status.is_ok()) << name << ": " << run.quantized.status.to_string();
  const quantize::QuantizeStats& st = run.quantized.stats;
  EXPECT_EQ(st.n_flipped, 0) << name;
  EXPECT_EQ(st.n_rounded, st.n_candidates) << name;
  EXPECT_GT(st.scale, 0) << name;
  EXPECT_EQ(test::integer_seamless_violation(run.quantized.uv), "") << name;
  const core::UVMetrics um = core::compute_uv_metrics(run.quantized.uv);
  EXPECT_EQ(um.n_flipped, 0) << name;
  EXPECT_EQ(um.n_degenerate, 0) << name;
  ASSERT_TRUE(run.quads.status.is_ok()) << name << ": " << run.quads.status.to_string();
  EXPECT_EQ(run.quads.stats.n_non_quads, 0) << name;
  const quadex::QuadMetrics qm = quadex::compute_quad_metrics(run.quads.quads);
  EXPECT_GT(qm.n_faces, 0) << name;
  EXPECT_TRUE(qm.manifold) << name;
  EXPECT_EQ(qm.n_non_quads, 0) << name;
  EXPECT_EQ(qm.euler_characteristic, core::topology_stats(mesh).euler_characteristic) << name;
  if (check_count) {
    EXPECT_NEAR(qm.n_faces, target, kQuadCountTolerance * target)
        << name << ": " << qm.n_faces << " quads for target " << target << ", scale retries "
        << st.n_scale_retries;
  }
}

TEST(QuantizeSeamless, SphereIsIntegerSeamlessAndExtracts) {
  expect_valid_quads("sphere", load("sphere.obj"), 300, true);
}

TEST(QuantizeSeamless, TorusIsIntegerSeamlessAndExtracts) {
  expect_valid_quads("torus", load("torus.obj"), 400, true);
}

TEST(QuantizeSeamless, CubeIsIntegerSeamlessAndExtracts) {
  // Eight cones on 12 triangles: the quad count is dictated by the cone lattice.
  expect_valid_quads("cube", load("cube.obj"), 54, false);
}

// Feature alignment end to end: the box's creases (or a disk's boundary) are aligned by the
// parametrization; quantization must put them on integer iso-lines exactly, and extraction then
// has them as chains of quad edges.
struct FeatureRun {
  param::ParamResult param;
  quantize::QuantizeResult quantized;
  quadex::ExtractResult quads;
};
FeatureRun run_with_features(const core::TriMesh& mesh, int target, bool boundaries,
                             const quantize::QuantizeOptions& base = {}) {
  FeatureRun run;
  param::ParamOptions po;
  po.energy = param::Energy::kSymmetricDirichlet;
  const core::EdgeTopology topo = core::build_edge_topology(mesh);
  for (const int e : core::sharp_edges(mesh, topo, 40))
    po.feature_edges.push_back({topo.edge_vertex(e, 0), topo.edge_vertex(e, 1)});
  po.align_boundaries = boundaries;
  run.param = param::compute_seamless_param(mesh, po);
  if (!run.param.status.is_ok()) return run;
  quantize::QuantizeOptions qo = base;
  qo.target_faces = target;
  run.quantized = quantize::quantize_seamless(mesh, run.param, qo);
  if (run.quantized.status.is_ok()) run.quads = quadex::extract_quads(run.quantized.uv);
  return run;
}

// A thin spike: the rounding gives its apex a cone of index 3 (a quad vertex of valence 1, which
// extraction rejects); cone splitting as the CLI does it (one quad edge, index 2 kept) moves one
// unit off it, and the pipeline gives a valid pure-quad mesh of the spike.
TEST(QuantizeSeamless, ThinSpikeExtractsWithItsApexConeSplit) {
  expect_valid_quads("spike", test::spike(), 300, true);
}

// Without cone splitting the spike's apex keeps its index-3 cone: quantization refuses the map at
// once (no rounding can make a quad vertex of valence 1) and names the cone.
TEST(QuantizeSeamless, ConeOfIndexThreeIsRefusedBeforeRounding) {
  const core::TriMesh mesh = test::spike();
  quantize::QuantizeOptions qo;
  qo.target_faces = 300;
  param::ParamOptions po;
  po.energy = param::Energy::kSymmetricDirichlet;
  const param::ParamResult map = param::compute_seamless_param(mesh, po);
  ASSERT_TRUE(map.status.is_ok()) << map.status.to_string();
  int apex_index = 0;
  for (const param::ConeInfo& c : map.cones)
    if (c.vertex == mesh.n_vertices() - 2) apex_index = c.index;
  ASSERT_EQ(apex_index, 3) << "the spike's apex (see test::spike)";
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, map, qo);
  EXPECT_EQ(q.status.code(), core::StatusCode::kInvalidInput);
  EXPECT_NE(q.status.message().find("cone vertex " + std::to_string(mesh.n_vertices() - 2) + " has index 3"),
            std::string::npos)
      << q.status.message();
  EXPECT_EQ(q.stats.n_rounded, 0);
  EXPECT_TRUE(q.stats.faces_with_unresolved_cones.empty()) << "refused, not let through";
  // Below 16 quads (kMinQuadsForCones) the grid cannot resolve the spike anyway: the map is not
  // refused, and its faces (one component: all of them) are named for the extraction to leave out.
  qo.target_faces = 8;
  const quantize::QuantizeResult tiny = quantize::quantize_seamless(mesh, map, qo);
  EXPECT_NE(tiny.status.code(), core::StatusCode::kInvalidInput) << tiny.status.to_string();
  std::vector<int> all_faces(mesh.n_faces());
  std::iota(all_faces.begin(), all_faces.end(), 0);
  EXPECT_EQ(tiny.stats.faces_with_unresolved_cones, all_faces);
}

TEST(QuantizeSeamless, BoxCreasesBecomeQuadEdges) {
  const core::TriMesh mesh = load("box.obj");
  const FeatureRun run = run_with_features(mesh, 200, false);
  ASSERT_TRUE(run.param.status.is_ok()) << run.param.status.to_string();
  ASSERT_EQ(run.param.stats.n_aligned_features, 72);
  ASSERT_TRUE(run.quantized.status.is_ok()) << run.quantized.status.to_string();
  EXPECT_FALSE(run.quantized.stats.features_dropped);
  EXPECT_EQ(run.quantized.stats.n_aligned_features, 72);
  EXPECT_EQ(run.quantized.stats.n_released_feature_lines, 0);
  EXPECT_EQ(run.quantized.stats.n_rounded, run.quantized.stats.n_candidates);
  EXPECT_EQ(test::integer_seamless_violation(run.quantized.uv), "");
  // Exactly on integer iso-lines.
  const Eigen::MatrixX2d& uv = run.quantized.uv.corner_uv;
  for (const param::FeatureAlignment& fa : run.param.features) {
    const int a = 3 * fa.face + fa.corner, b = 3 * fa.face + (fa.corner + 1) % 3;
    const double ua = uv(a, fa.constant_coord), ub = uv(b, fa.constant_coord);
    EXPECT_EQ(ua, ub) << "face " << fa.face;
    EXPECT_EQ(ua, std::round(ua)) << "face " << fa.face;
  }
  ASSERT_TRUE(run.quads.status.is_ok()) << run.quads.status.to_string();
  const quadex::QuadMetrics qm = quadex::compute_quad_metrics(run.quads.quads, &mesh);
  EXPECT_EQ(qm.n_non_quads, 0);
  EXPECT_TRUE(qm.manifold);
  EXPECT_EQ(qm.n_flipped, 0);
  EXPECT_EQ(qm.n_irregular, 8) << "one valence-3 vertex per box corner";
  EXPECT_GE(qm.feature_capture, 0.999);
  EXPECT_LT(qm.hausdorff_sym, 1e-9) << "quads on the box's flat sides";
}

// The features' own time budget: when it runs out they count as not fitting (dropped, with the
// reason), and the map is quantized without them, or the quantization stops for a caller that
// parametrizes again without them.
TEST(QuantizeSeamless, FeatureTimeBudgetDropsTheFeaturesNotTheMap) {
  const core::TriMesh mesh = load("box.obj");
  quantize::QuantizeOptions qo;
  qo.feature_time_budget_seconds = 1e-9;
  const FeatureRun run = run_with_features(mesh, 200, false, qo);
  ASSERT_TRUE(run.param.status.is_ok()) << run.param.status.to_string();
  ASSERT_GT(run.param.stats.n_aligned_features, 0);
  ASSERT_TRUE(run.quantized.status.is_ok()) << run.quantized.status.to_string();
  EXPECT_TRUE(run.quantized.stats.features_dropped);
  EXPECT_NE(run.quantized.stats.features_dropped_reason.find("time budget"), std::string::npos)
      << run.quantized.stats.features_dropped_reason;
  EXPECT_EQ(test::integer_seamless_violation(run.quantized.uv), "");
  EXPECT_EQ(run.quantized.stats.n_flipped, 0);
  qo.target_faces = 200;
  qo.quantize_without_features = false;
  const quantize::QuantizeResult stopped = quantize::quantize_seamless(mesh, run.param, qo);
  EXPECT_EQ(stopped.status.code(), core::StatusCode::kNotConverged) << stopped.status.to_string();
  EXPECT_TRUE(stopped.stats.features_dropped);
  qo.feature_time_budget_seconds = -1;
  EXPECT_EQ(quantize::quantize_seamless(mesh, run.param, qo).status.code(),
            core::StatusCode::kInvalidInput);
}

// A map whose re-optimization with the features' rows cannot be set up (the elimination above
// max_element_entries, as dragon's feature map at 5,000 quads) counts as the features not
// fitting: the attempts without them follow (here refused too, below one entry per face), the
// reason is kept for the caller (the remesher then parametrizes without the features), and the
// status is the last attempt's.
TEST(QuantizeSeamless, FeatureRowsTooLargeToSetUpCountAsNotFitting) {
  const core::TriMesh mesh = load("box.obj");
  const FeatureRun kept = run_with_features(mesh, 200, false);
  ASSERT_TRUE(kept.quantized.status.is_ok()) << kept.quantized.status.to_string();
  ASSERT_FALSE(kept.quantized.stats.features_dropped);
  EXPECT_TRUE(kept.quantized.stats.features_dropped_reason.empty());
  quantize::QuantizeOptions qo;
  qo.target_faces = 200;
  qo.max_element_entries = 0.5 * mesh.n_faces();
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, kept.param, qo);
  EXPECT_EQ(q.status.code(), core::StatusCode::kNumericalFailure) << q.status.to_string();
  EXPECT_NE(q.status.message().find("unknowns in one triangle"), std::string::npos) << q.status.message();
  EXPECT_NE(q.stats.features_dropped_reason.find("unknowns in one triangle"), std::string::npos)
      << "the features' layout was refused first: " << q.stats.features_dropped_reason;
  EXPECT_GE(q.stats.n_scale_retries, 2) << "the attempts without the features were tried";
  // Without the fallback (quantize_without_features = false) the refusal is the answer at once.
  qo.quantize_without_features = false;
  const quantize::QuantizeResult stopped = quantize::quantize_seamless(mesh, kept.param, qo);
  EXPECT_EQ(stopped.status.code(), core::StatusCode::kNumericalFailure);
  EXPECT_EQ(stopped.stats.n_scale_retries, 0);
}

// A plate with five square holes at a coarse grid: the holes are about a quad wide, and with
// every crease aligned some translation around a hole has no flip-free integer. Only the
// alignment rows near that dead end are released; the rest of the creases stay on iso-lines.
TEST(QuantizeSeamless, FeaturesNearADeadEndAreReleasedTheRestKept) {
  const core::TriMesh mesh = load("plate.obj");
  quantize::QuantizeOptions all_or_nothing;
  all_or_nothing.feature_release_rounds = 0;
  const FeatureRun dropped = run_with_features(mesh, kPlateTarget, false, all_or_nothing);
  ASSERT_TRUE(dropped.param.status.is_ok()) << dropped.param.status.to_string();
  ASSERT_TRUE(dropped.quantized.status.is_ok()) << dropped.quantized.status.to_string();
  ASSERT_TRUE(dropped.quantized.stats.features_dropped)
      << "the plate must dead-end with all its creases";
  // A caller that parametrizes again without the features can have the quantization stop there.
  quantize::QuantizeOptions stop = all_or_nothing;
  stop.target_faces = kPlateTarget;
  stop.quantize_without_features = false;
  const quantize::QuantizeResult stopped = quantize::quantize_seamless(mesh, dropped.param, stop);
  EXPECT_EQ(stopped.status.code(), core::StatusCode::kNotConverged);
  EXPECT_TRUE(stopped.stats.features_dropped);
  EXPECT_FALSE(stopped.stats.features_dropped_reason.empty());

  const FeatureRun run = run_with_features(mesh, kPlateTarget, false);
  ASSERT_TRUE(run.quantized.status.is_ok()) << run.quantized.status.to_string();
  const quantize::QuantizeStats& st = run.quantized.stats;
  const int n_rows = static_cast<int>(run.param.features.size());
  EXPECT_FALSE(st.features_dropped) << st.features_dropped_reason;
  EXPECT_GT(st.n_released_feature_edges, 0);
  EXPECT_LT(st.n_released_feature_edges, n_rows / 2);
  EXPECT_GE(st.n_aligned_features, n_rows / 2);
  EXPECT_EQ(st.n_flipped, 0);
  EXPECT_EQ(test::integer_seamless_violation(run.quantized.uv), "");
  ASSERT_TRUE(run.quads.status.is_ok()) << run.quads.status.to_string();
  const quadex::QuadMetrics qm = quadex::compute_quad_metrics(run.quads.quads, &mesh);
  EXPECT_EQ(qm.n_non_quads, 0);
  EXPECT_TRUE(qm.manifold);
  EXPECT_EQ(qm.n_flipped, 0);
  EXPECT_EQ(qm.euler_characteristic, core::topology_stats(mesh).euler_characteristic);
  const quadex::QuadMetrics dropped_qm =
      quadex::compute_quad_metrics(dropped.quads.quads, &mesh);
  EXPECT_GT(qm.feature_capture, dropped_qm.feature_capture + 0.2)
      << "kept: " << qm.feature_capture << ", all dropped: " << dropped_qm.feature_capture;
}

TEST(QuantizeSeamless, AlignedDiskBoundaryGivesPureQuads) {
  const core::TriMesh mesh = load("disk.obj");
  const FeatureRun run = run_with_features(mesh, 120, true);
  ASSERT_TRUE(run.param.status.is_ok()) << run.param.status.to_string();
  ASSERT_TRUE(run.quantized.status.is_ok()) << run.quantized.status.to_string();
  EXPECT_FALSE(run.quantized.stats.features_dropped);
  EXPECT_EQ(test::integer_seamless_violation(run.quantized.uv), "");
  ASSERT_TRUE(run.quads.status.is_ok()) << run.quads.status.to_string();
  const quadex::QuadMetrics qm = quadex::compute_quad_metrics(run.quads.quads, &mesh);
  EXPECT_EQ(qm.n_non_quads, 0) << "an aligned boundary is made of iso-line pieces";
  EXPECT_TRUE(qm.manifold);
  EXPECT_EQ(qm.n_boundary_loops, 1);
  EXPECT_EQ(qm.n_flipped, 0);
  EXPECT_NEAR(qm.n_faces, 120, 0.15 * 120);
}

TEST(QuantizeSeamless, EdgeLengthSetsTheScale) {
  const core::TriMesh mesh = load("sphere.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok()) << p.status.to_string();
  quantize::QuantizeOptions qo;
  qo.edge_length = 0.2;  // sphere of radius 1: area 4π ≈ 12.6 → about 314 quads
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p, qo);
  ASSERT_TRUE(q.status.is_ok()) << q.status.to_string();
  double area3d = 0;
  for (int f = 0; f < mesh.n_faces(); ++f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)),
                          p2 = mesh.V.row(mesh.F(f, 2));
    area3d += 0.5 * (p1 - p0).cross(p2 - p0).norm();
  }
  const double expected = area3d / (qo.edge_length * qo.edge_length);
  EXPECT_NEAR(q.stats.uv_area, expected, kQuadCountTolerance * expected)
      << "UV area " << q.stats.uv_area << " vs 3D area / h² " << expected << ", scale retries "
      << q.stats.n_scale_retries << ", reverted " << q.stats.n_reverted;
  EXPECT_EQ(test::integer_seamless_violation(q.uv), "");
  EXPECT_EQ(q.stats.n_count_corrections, 0) << "an edge length asks for no count";
}

// Without a target count or an edge length: at least 5,000 quads (a triangulated CAD part has few
// triangles for its features), one per six triangles above 30,000 triangles.
TEST(QuantizeSeamless, DefaultDensityIsAtLeastFiveThousandQuads) {
  auto area_of = [](const core::TriMesh& m) {
    double a = 0;
    for (int f = 0; f < m.n_faces(); ++f) {
      const Eigen::Vector3d p0 = m.V.row(m.F(f, 0)), p1 = m.V.row(m.F(f, 1)), p2 = m.V.row(m.F(f, 2));
      a += 0.5 * (p1 - p0).cross(p2 - p0).norm();
    }
    return a;
  };
  const core::TriMesh box = load("box.obj");
  const quantize::QuantizeOptions defaults;
  EXPECT_NEAR(quantize::target_edge_length(box, defaults), std::sqrt(area_of(box) / 5000), 1e-12);
  // A flat 120 × 130 grid of 31,200 triangles: 5,200 quads.
  core::TriMesh grid;
  const int nx = 120, ny = 130;
  grid.V.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) grid.V.row(j * (nx + 1) + i) << 0.01 * i, 0.01 * j, 0;
  grid.F.resize(2 * nx * ny, 3);
  for (int j = 0, f = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int v = j * (nx + 1) + i;
      grid.F.row(f++) << v, v + 1, v + nx + 2;
      grid.F.row(f++) << v, v + nx + 2, v + nx + 1;
    }
  EXPECT_NEAR(quantize::target_edge_length(grid, defaults), std::sqrt(area_of(grid) / 5200), 1e-12);
  // The box quantized at the default density: about 5,000 quads.
  const param::ParamResult p = param::compute_seamless_param(box);
  ASSERT_TRUE(p.status.is_ok()) << p.status.to_string();
  const quantize::QuantizeResult q = quantize::quantize_seamless(box, p, defaults);
  ASSERT_TRUE(q.status.is_ok()) << q.status.to_string();
  EXPECT_NEAR(q.stats.uv_area, 5000, kQuadCountTolerance * 5000);
  EXPECT_EQ(test::integer_seamless_violation(q.uv), "");
  // The count adjustment aims at the default density's count as at a target's (it moves while
  // the count is more than 0.5% off, and only closer), and at none with an edge length.
  quantize::QuantizeOptions adjusting = defaults;
  adjusting.max_count_adjustments = 8;
  const quantize::QuantizeResult a = quantize::quantize_seamless(box, p, adjusting);
  ASSERT_TRUE(a.status.is_ok()) << a.status.to_string();
  const double off_before = std::abs(q.stats.uv_area - 5000);
  EXPECT_LE(std::abs(a.stats.uv_area - 5000), std::max(0.005 * 5000, off_before)) << q.stats.uv_area;
  EXPECT_EQ(a.stats.n_count_adjustments > 0, off_before > 0.005 * 5000) << q.stats.uv_area;
  EXPECT_EQ(a.stats.n_flipped, 0);
  EXPECT_EQ(test::integer_seamless_violation(a.uv), "");
  adjusting.edge_length = quantize::target_edge_length(box, defaults);
  const quantize::QuantizeResult e = quantize::quantize_seamless(box, p, adjusting);
  ASSERT_TRUE(e.status.is_ok()) << e.status.to_string();
  EXPECT_EQ(e.stats.n_count_adjustments, 0);
}

// The parametrization the remesher makes for a quantization at qo's density: symmetric Dirichlet,
// cone pairs within a few quads cancelled, cones of index 3 split.
param::ParamResult remesher_param(const core::TriMesh& mesh, const quantize::QuantizeOptions& qo) {
  param::ParamOptions po;
  po.energy = param::Energy::kSymmetricDirichlet;
  po.cone_pair_distance = quantize::recommended_cone_pair_distance(mesh, qo);
  po.cone_pair_max_hops = quantize::kRecommendedConePairHops;
  po.cone_split_distance = quantize::target_edge_length(mesh, qo);
  return param::compute_seamless_param(mesh, po);
}

// The re-optimizations grow the map by a few percent, differently from mesh to mesh and scale to
// scale; the count correction runs the rounding again at a corrected scale while the count is
// off by more than count_tolerance and keeps the map closest to the target. Without a target
// count (an edge length) it does nothing (EdgeLengthSetsTheScale).
TEST(QuantizeSeamless, CountCorrectionBringsTheQuadsCloserToTheTarget) {
  const core::TriMesh mesh = load("spot.obj");
  int n_improved = 0;
  for (const int target : {500, 600}) {  // spot at 500: UV area 551 before; at 600: 596
    quantize::QuantizeOptions qo;
    qo.target_faces = target;
    qo.count_tolerance = 0.015;
    const param::ParamResult p = remesher_param(mesh, qo);
    ASSERT_TRUE(p.status.is_ok()) << p.status.to_string();
    qo.max_count_corrections = 0;
    const quantize::QuantizeResult plain = quantize::quantize_seamless(mesh, p, qo);
    ASSERT_TRUE(plain.status.is_ok()) << target << ": " << plain.status.to_string();
    EXPECT_EQ(plain.stats.n_count_corrections, 0);
    qo.max_count_corrections = quantize::QuantizeOptions{}.max_count_corrections;
    const quantize::QuantizeResult corrected = quantize::quantize_seamless(mesh, p, qo);
    ASSERT_TRUE(corrected.status.is_ok()) << target << ": " << corrected.status.to_string();
    const double plain_error = std::abs(plain.stats.uv_area - target);
    const double error = std::abs(corrected.stats.uv_area - target);
    SCOPED_TRACE("target " + std::to_string(target) + ": UV area " + std::to_string(plain.stats.uv_area) +
                 " -> " + std::to_string(corrected.stats.uv_area));
    EXPECT_LE(error, plain_error) << target << ": the closest map is kept";
    EXPECT_EQ(corrected.stats.n_count_corrections > 0, plain_error > qo.count_tolerance * target) << target;
    EXPECT_EQ(corrected.stats.n_count_corrections_kept > 0, error < plain_error) << target;
    n_improved += error < plain_error;
    EXPECT_EQ(corrected.stats.n_flipped, 0) << target;
    EXPECT_EQ(test::integer_seamless_violation(corrected.uv), "") << target;
  }
  EXPECT_GE(n_improved, 1) << "no target came out closer";
}

// The count adjustment: once the rounding is done, the quad count (the UV area) depends on the
// integers alone, and moving one integer column by a unit where that brings the count closer
// (flip-free, energy within 1%) gets it to the target or near it, on the map the rounding made.
TEST(QuantizeSeamless, CountAdjustmentMovesTheCountToTheTarget) {
  const core::TriMesh mesh = load("spot.obj");
  int n_adjusted = 0;
  for (const int target : {500, 800}) {  // spot at 500: 526 quads without the adjustment
    quantize::QuantizeOptions qo;
    qo.target_faces = target;
    const param::ParamResult p = remesher_param(mesh, qo);
    ASSERT_TRUE(p.status.is_ok()) << p.status.to_string();
    const quantize::QuantizeResult plain = quantize::quantize_seamless(mesh, p, qo);  // off by default
    ASSERT_TRUE(plain.status.is_ok()) << target << ": " << plain.status.to_string();
    EXPECT_EQ(plain.stats.n_count_adjustments, 0);
    qo.max_count_adjustments = 8;
    const quantize::QuantizeResult adjusted = quantize::quantize_seamless(mesh, p, qo);
    ASSERT_TRUE(adjusted.status.is_ok()) << target << ": " << adjusted.status.to_string();
    SCOPED_TRACE("target " + std::to_string(target) + ": UV area " + std::to_string(plain.stats.uv_area) +
                 " -> " + std::to_string(adjusted.stats.uv_area));
    // Both are integer-seamless closed maps: the area is the quad count, an integer.
    EXPECT_NEAR(adjusted.stats.uv_area, std::round(adjusted.stats.uv_area), 1e-6);
    EXPECT_LE(std::abs(adjusted.stats.uv_area - target), std::abs(plain.stats.uv_area - target));
    EXPECT_EQ(adjusted.stats.n_count_adjustments > 0, adjusted.stats.uv_area != plain.stats.uv_area);
    // The map before the adjustment comes along, exact: the plain rounding's to the bit.
    if (adjusted.stats.n_count_adjustments > 0) {
      EXPECT_TRUE(adjusted.uv_unadjusted.corner_uv == plain.uv.corner_uv);
      EXPECT_EQ(adjusted.stats.uv_area_unadjusted, plain.stats.uv_area);
      EXPECT_EQ(test::integer_seamless_violation(adjusted.uv_unadjusted), "");
    }
    EXPECT_EQ(plain.uv_unadjusted.corner_uv.rows(), 0);
    EXPECT_LE(adjusted.stats.n_count_adjustments, qo.max_count_adjustments);
    n_adjusted += adjusted.stats.n_count_adjustments > 0;
    EXPECT_EQ(adjusted.stats.n_flipped, 0);
    EXPECT_EQ(test::integer_seamless_violation(adjusted.uv), "");
    const quadex::ExtractResult quads = quadex::extract_quads(adjusted.uv);
    ASSERT_TRUE(quads.status.is_ok()) << quads.status.to_string();
    EXPECT_EQ(quads.quads.n_faces(), std::lround(adjusted.stats.uv_area));
  }
  EXPECT_GE(n_adjusted, 1) << "the count moved at neither target";
}

TEST(QuantizeCurves, LongestCurveInQuadEdgesAndKnifeEdges) {
  // The fold line of 4 unit edges at quad edge 0.5 is 8 quad edges long; split into two pieces
  // of one edge each, 2. A fold of 150° (opening 30°) is a knife edge, one of 60° is not.
  quantize::QuantizeOptions qo;
  qo.edge_length = 0.5;
  const std::vector<std::array<int, 2>> line = {{0, 1}, {1, 2}, {2, 3}, {3, 4}};
  const std::vector<std::array<int, 2>> pieces = {{0, 1}, {2, 3}};
  const core::TriMesh knife = test::folded_strips(4, 30), fold = test::folded_strips(4, 120);
  const quantize::CurveSummary a = quantize::summarize_curves(knife, line, qo);
  EXPECT_NEAR(a.longest_quad_edges, 8, 1e-12);
  EXPECT_TRUE(a.has_knife_edge);
  const quantize::CurveSummary b = quantize::summarize_curves(fold, line, qo);
  EXPECT_NEAR(b.longest_quad_edges, 8, 1e-12);
  EXPECT_FALSE(b.has_knife_edge);
  const quantize::CurveSummary c = quantize::summarize_curves(fold, pieces, qo);
  EXPECT_NEAR(c.longest_quad_edges, 2, 1e-12);
  EXPECT_FALSE(c.has_knife_edge);
  EXPECT_TRUE(quantize::summarize_curves(knife, pieces, qo, 149).has_knife_edge);
  EXPECT_FALSE(quantize::summarize_curves(knife, pieces, qo, 151).has_knife_edge);
  const quantize::CurveSummary none = quantize::summarize_curves(fold, {}, qo);
  EXPECT_EQ(none.longest_quad_edges, 0);
  EXPECT_FALSE(none.has_knife_edge);
}

TEST(QuantizeCoarseCones, OnlyConesBeyondTheTopologysNeedCount) {
  // sphere.obj (closed, χ = 2) needs 8 cones: at 100 target quads, 8 + 2 cones (2 × 40 ≤ 100) keep
  // the map; 8 + 3 ask for coarse cones at 1.4 quad edges. The open disk needs none.
  const core::TriMesh sphere = core::to_trimesh(core::read_mesh(test::data_path("sphere.obj")));
  quantize::QuantizeOptions qo;
  qo.target_faces = 100;
  const double h = quantize::target_edge_length(sphere, qo);
  EXPECT_EQ(quantize::recommended_cone_scale(sphere, qo, 8), 0);
  EXPECT_EQ(quantize::recommended_cone_scale(sphere, qo, 10), 0);
  EXPECT_NEAR(quantize::recommended_cone_scale(sphere, qo, 11), quantize::kCoarseConeQuadEdges * h, 1e-12 * h);
  qo.target_faces = 1000;
  EXPECT_EQ(quantize::recommended_cone_scale(sphere, qo, 11), 0);
  const core::TriMesh disk = core::to_trimesh(core::read_mesh(test::data_path("disk.obj")));
  quantize::QuantizeOptions dq;
  dq.target_faces = 80;
  EXPECT_EQ(quantize::recommended_cone_scale(disk, dq, 2), 0);
  EXPECT_GT(quantize::recommended_cone_scale(disk, dq, 3), 0);
}

TEST(QuantizeSeamless, RejectsNonSeamlessInput) {
  const core::TriMesh mesh = load("sphere.obj");
  param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  ASSERT_FALSE(p.seams.empty());
  // Break one seam: move one corner of a seam face along its edge.
  p.uv.corner_uv.row(3 * p.seams[0].face_b) += Eigen::RowVector2d(0.01, 0.003);
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p);
  EXPECT_EQ(q.status.code(), core::StatusCode::kInvalidInput) << q.status.to_string();
  EXPECT_NE(q.status.message().find("not seamless"), std::string::npos) << q.status.message();
}

TEST(QuantizeSeamless, RejectsMismatchedSizesAndBadOptions) {
  const core::TriMesh mesh = load("cube.obj");
  param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  quantize::QuantizeOptions bad;
  bad.target_faces = -5;
  EXPECT_EQ(quantize::quantize_seamless(mesh, p, bad).status.code(),
            core::StatusCode::kInvalidInput);
  p.uv.corner_uv.conservativeResize(5, 2);
  EXPECT_EQ(quantize::quantize_seamless(mesh, p).status.code(), core::StatusCode::kInvalidInput);
}

TEST(QuantizeSeamless, TimeBudgetStopsWithAMessage) {
  const core::TriMesh mesh = load("sphere.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  quantize::QuantizeOptions qo;
  qo.target_faces = 300;
  qo.time_budget_seconds = 1e-9;
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p, qo);
  EXPECT_EQ(q.status.code(), core::StatusCode::kNotConverged) << q.status.to_string();
  EXPECT_NE(q.status.message().find("time budget"), std::string::npos) << q.status.message();
  EXPECT_NE(q.status.message().find("scale"), std::string::npos) << q.status.message();
  EXPECT_TRUE(q.stats.out_of_time);
  EXPECT_FALSE(q.stats.stopped_at_dead_end);
  qo.time_budget_seconds = -1;
  EXPECT_EQ(quantize::quantize_seamless(mesh, p, qo).status.code(),
            core::StatusCode::kInvalidInput);
}

// The caller's say at a dead end: a sphere's eight cones on a grid of two quads cannot all find
// grid points, so the attempts dead-end; continue_after_dead_end sees each dead end before the
// next scale (the cone and the faces in the way) and can stop the quantization there.
TEST(QuantizeSeamless, CallerCanStopAtADeadEnd) {
  const core::TriMesh mesh = load("torus.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok()) << p.status.to_string();
  quantize::QuantizeOptions qo;
  qo.target_faces = 2;
  std::vector<quantize::DeadEnd> seen;
  qo.continue_after_dead_end = [&](const quantize::DeadEnd& de) {
    seen.push_back(de);
    return seen.size() < 3;
  };
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p, qo);
  ASSERT_EQ(q.status.code(), core::StatusCode::kNotConverged) << q.status.to_string();
  EXPECT_TRUE(q.stats.stopped_at_dead_end);
  EXPECT_FALSE(q.stats.out_of_time);
  ASSERT_EQ(seen.size(), 3u) << "asked at each dead end until it said stop";
  EXPECT_NE(q.status.message().find("stopped after 3 of"), std::string::npos) << q.status.message();
  EXPECT_NE(q.status.message().find(seen[2].reason), std::string::npos) << q.status.message();
  for (size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].attempt, static_cast<int>(i) + 1);
    EXPECT_EQ(seen[i].attempts_without_features, static_cast<int>(i) + 1) << "the map has no features";
    EXPECT_FALSE(seen[i].reason.empty());
    EXPECT_FALSE(seen[i].faces.empty()) << "the faces in the way";
    if (seen[i].cone_vertex >= 0) {
      EXPECT_LT(seen[i].cone_vertex, mesh.n_vertices());
      EXPECT_NE(seen[i].reason.find("cone vertex " + std::to_string(seen[i].cone_vertex)), std::string::npos)
          << seen[i].reason;
    }
  }
  EXPECT_EQ(seen[0].scale, 1.0);
  EXPECT_NE(seen[1].scale, 1.0) << "the next attempt is at another scale";
  EXPECT_NE(seen[2].scale, seen[1].scale);
}

// The sphere's map (14 cones) asked into two quads: whichever cones are pinned first take the
// grid points the others need, and without backtracking all eight attempts (the target's scale,
// its jitters, then ×1.25 twice) dead-ended, as at four quads (checked on 2026-12-07). Freeing the
// pinned neighbours of a blocked cone and rounding them again with it gets through: 14 cones on
// 14 distinct grid points, at least 12 quads on a sphere.
TEST(QuantizeSeamless, ConesBlockedByTheirNeighboursAreRoundedAgainWithThem) {
  const core::TriMesh mesh = load("sphere.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok()) << p.status.to_string();
  quantize::QuantizeOptions qo;
  qo.target_faces = 2;
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p, qo);
  ASSERT_TRUE(q.status.is_ok()) << q.status.to_string();
  EXPECT_GT(q.stats.n_unstuck_cones, 0) << "the test no longer reaches a blocked cone";
  EXPECT_EQ(q.stats.n_flipped, 0);
  EXPECT_EQ(q.stats.n_rounded, q.stats.n_candidates);
  EXPECT_EQ(test::integer_seamless_violation(q.uv), "");
  const quadex::ExtractResult ex = quadex::extract_quads(q.uv);
  ASSERT_TRUE(ex.status.is_ok()) << ex.status.to_string();
  const quadex::QuadMetrics qm = quadex::compute_quad_metrics(ex.quads);
  EXPECT_GE(qm.n_faces, p.stats.n_cones - 2);
  EXPECT_LE(qm.n_faces, 2 * p.stats.n_cones) << "far more quads than asked";
  EXPECT_EQ(qm.n_non_quads, 0);
  EXPECT_TRUE(qm.manifold);
  EXPECT_EQ(qm.euler_characteristic, 2);
}

TEST(QuantizeSeamless, ProgressReportsRoundedUnknownsAndScale) {
  const core::TriMesh mesh = load("torus.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  quantize::QuantizeOptions qo;
  qo.target_faces = 400;
  std::vector<std::tuple<std::string, int, int>> calls;
  qo.progress = [&](const std::string& stage, int step, int n) { calls.push_back({stage, step, n}); };
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p, qo);
  ASSERT_TRUE(q.status.is_ok()) << q.status.to_string();
  ASSERT_FALSE(calls.empty());
  for (const auto& [stage, step, n] : calls) {
    EXPECT_EQ(stage.rfind("quantize x", 0), 0u) << stage;
    EXPECT_LE(step, n) << stage;
    EXPECT_EQ(n, q.stats.n_integer_dofs) << stage;
  }
  EXPECT_EQ(std::get<1>(calls.back()), std::get<2>(calls.back())) << "all unknowns rounded";
}

// Cones closer than a quad edge must still land on distinct grid points: at a density of a few
// quads per cone the sphere's eight cones sit about one unit apart and are rounded jointly.
TEST(QuantizeSeamless, ClusteredConesTakeDistinctGridPoints) {
  const core::TriMesh mesh = load("sphere.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  quantize::QuantizeOptions qo;
  qo.target_faces = 10;
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p, qo);
  ASSERT_TRUE(q.status.is_ok()) << q.status.to_string();
  EXPECT_GT(q.stats.n_clustered_cones, 0) << "the test no longer builds a cluster";
  EXPECT_EQ(q.stats.n_flipped, 0);
  EXPECT_EQ(test::integer_seamless_violation(q.uv), "");
  const core::UVMetrics um = core::compute_uv_metrics(q.uv);
  EXPECT_EQ(um.n_flipped, 0);
  EXPECT_EQ(um.n_degenerate, 0);
  const quadex::ExtractResult ex = quadex::extract_quads(q.uv);
  ASSERT_TRUE(ex.status.is_ok()) << ex.status.to_string();
  const quadex::QuadMetrics qm = quadex::compute_quad_metrics(ex.quads);
  EXPECT_EQ(qm.n_non_quads, 0);
  EXPECT_TRUE(qm.manifold);
  EXPECT_EQ(qm.euler_characteristic, 2);
}

// The lattice property the rounding relies on: with cone copies preferred free, every cone
// coordinate and seam translation is an integer combination of free integer unknowns.
// The torus's seamless map and its copies (for the PinnedLayout tests).
struct TorusCopies {
  core::TriMesh mesh = load("torus.obj");
  param::ParamResult p = param::compute_seamless_param(mesh);
  param::CopyLayout cl;
  bool ok = p.status.is_ok() && param::build_copy_layout(mesh, p.uv.corner_uv, p.seams, 1e-6, &cl).is_ok();
};

TEST(PinnedLayout, CandidatesAreIntegerCombinationsOfFreeIntegerUnknowns) {
  const TorusCopies torus;
  ASSERT_TRUE(torus.ok);
  const core::TriMesh& mesh = torus.mesh;
  const param::ParamResult& p = torus.p;
  const param::CopyLayout& cl = torus.cl;
  std::vector<char> cone_vertex(mesh.n_vertices(), 0), cone_copy(cl.n_copies(), 0);
  for (const param::ConeInfo& c : p.cones) cone_vertex[c.vertex] = 1;
  for (int k = 0; k < cl.n_copies(); ++k) cone_copy[k] = cone_vertex[cl.copy_vertex[k]];
  param::PinnedLayoutOptions po;
  po.prefer_free = cone_copy;
  Eigen::VectorXd x0 = 10 * cl.x;  // a few units per feature
  param::PinnedLayout layout;
  ASSERT_TRUE(layout.init(mesh, cl, x0, po).is_ok());
  const param::ConstrainedReduction& red = layout.reduction();
  const int n_copy_vars = 2 * cl.n_copies();
  std::vector<char> candidate(red.P.rows(), 0);
  for (int k = 0; k < cl.n_copies(); ++k)
    if (cone_copy[k]) candidate[2 * k] = candidate[2 * k + 1] = 1;
  for (int v = n_copy_vars; v < red.P.rows(); ++v) candidate[v] = 1;
  int n_checked = 0;
  for (int v = 0; v < red.P.rows(); ++v) {
    if (!candidate[v]) continue;
    ++n_checked;
    EXPECT_EQ(red.c[v], std::round(red.c[v])) << "variable " << v;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, v); it; ++it) {
      EXPECT_EQ(it.value(), std::round(it.value())) << "variable " << v;
      EXPECT_TRUE(candidate[red.free_vars[it.col()]]) << "variable " << v << " uses column "
                                                      << it.col();
    }
  }
  EXPECT_GT(n_checked, 0);
}

// The element Hessians' size is bounded: a layout whose elimination couples more than
// max_element_entries (Σ over faces of its free unknowns²) is refused with the figures, not built.
TEST(PinnedLayout, RefusesAnEliminationAboveTheEntryLimit) {
  const TorusCopies torus;
  ASSERT_TRUE(torus.ok);
  const core::TriMesh& mesh = torus.mesh;
  const param::CopyLayout& cl = torus.cl;
  param::PinnedLayoutOptions po;
  param::PinnedLayout layout;
  ASSERT_TRUE(layout.init(mesh, cl, 10 * cl.x, po).is_ok()) << "the default limit";
  // Every face depends on at least 2 free unknowns (4 entries): a limit below 4 per face fails.
  po.max_element_entries = 3.0 * mesh.n_faces();
  const core::Status st = layout.init(mesh, cl, 10 * cl.x, po);
  EXPECT_EQ(st.code(), core::StatusCode::kNumericalFailure);
  EXPECT_NE(st.message().find("unknowns in one triangle"), std::string::npos) << st.message();
}

// The sphere's seamless map at 10× scale in a PinnedLayout (for the PinnedLayout tests).
struct SphereLayout {
  core::TriMesh mesh = load("sphere.obj");
  param::CopyLayout cl;
  param::PinnedLayout layout;
  bool ok = false;  // the map, the copies and the layout were built
  SphereLayout() {
    const param::ParamResult p = param::compute_seamless_param(mesh);
    ok = p.status.is_ok() &&
         param::build_copy_layout(mesh, p.uv.corner_uv, p.seams, 1e-6, &cl).is_ok() &&
         layout.init(mesh, cl, 10 * cl.x, {}).is_ok();
  }
};

// Per variable of x = P·y + c: its free column, or -1.
std::vector<int> column_of_variable(const param::ConstrainedReduction& red) {
  std::vector<int> col_of(red.P.rows(), -1);
  for (size_t c = 0; c < red.free_vars.size(); ++c) col_of[red.free_vars[c]] = static_cast<int>(c);
  return col_of;
}

// The first vertex copy whose u coordinate is a free variable of the layout, and that variable's
// column ({-1, -1}: none).
std::pair<int, int> first_copy_with_free_u(const param::CopyLayout& cl, const param::PinnedLayout& layout) {
  const std::vector<int> col_of = column_of_variable(layout.reduction());
  for (int k = 0; k < cl.n_copies(); ++k)
    if (col_of[2 * k] >= 0) return {k, col_of[2 * k]};
  return {-1, -1};
}

TEST(PinnedLayout, PinsReachableTargetsAndRefusesDegenerateOnes) {
  SphereLayout sphere;
  auto& [mesh, cl, layout, ready] = sphere;
  ASSERT_TRUE(ready);
  ASSERT_EQ(layout.n_flipped(), 0);
  // A free variable a tenth of a unit away from where it is.
  const int j = layout.n_free() / 2;
  const double target = layout.y()[j] + 0.1;
  const param::PinReport ok = layout.pin({{j, target}}, {}, 5, 1e-4);
  ASSERT_TRUE(ok.status.is_ok()) << ok.status.to_string();
  ASSERT_EQ(ok.pinned.size(), 1u);
  EXPECT_EQ(ok.pinned[0], 1);
  EXPECT_TRUE(layout.is_pinned(j));
  EXPECT_EQ(layout.y()[j], target);
  EXPECT_EQ(layout.n_flipped(), 0);
  // Both coordinates of the three copies of one face onto one line: the face is determined by
  // its targets and degenerate, so the targets block and the layout stays flip-free.
  const param::ConstrainedReduction& red = layout.reduction();
  const std::vector<int> col_of = column_of_variable(red);
  int face = -1;
  for (int f = 0; f < mesh.n_faces() && face < 0; ++f) {
    bool all_free = true;
    for (int k = 0; k < 3; ++k) {
      const int copy = cl.corner_copy[3 * f + k];
      all_free = all_free && col_of[2 * copy] >= 0 && col_of[2 * copy + 1] >= 0 &&
                 !layout.is_pinned(col_of[2 * copy]) && !layout.is_pinned(col_of[2 * copy + 1]);
    }
    if (all_free) face = f;
  }
  ASSERT_GE(face, 0);
  std::vector<std::pair<int, double>> collinear;
  for (int k = 0; k < 3; ++k) {
    const int copy = cl.corner_copy[3 * face + k];
    collinear.push_back({col_of[2 * copy], 100.0 + k});
    collinear.push_back({col_of[2 * copy + 1], 100.0 + k});
  }
  const param::PinReport blocked = layout.pin(collinear, {}, 5, 1e-4);
  ASSERT_TRUE(blocked.status.is_ok()) << blocked.status.to_string();
  for (size_t i = 0; i < collinear.size(); ++i) {
    EXPECT_EQ(blocked.pinned[i], 0) << i;
    EXPECT_EQ(blocked.blocking[i], 1) << i;
  }
  EXPECT_EQ(layout.n_flipped(), 0);
}

TEST(PinnedLayout, AnAttemptThatPinsNothingLeavesTheLayoutAsItWas) {
  SphereLayout sphere;
  auto& [mesh, cl, layout, ready] = sphere;
  ASSERT_TRUE(ready);
  const auto [copy, j] = first_copy_with_free_u(cl, layout);
  ASSERT_GE(copy, 0);
  // A hundred units away: the steps move the layout towards it until the faces around the copy
  // stop them, and the target is dropped.
  const Eigen::VectorXd y0 = layout.y();
  const param::PinReport rep = layout.pin({{j, y0[j] + 100}}, {}, 30, 1e-4);
  ASSERT_TRUE(rep.status.is_ok()) << rep.status.to_string();
  EXPECT_EQ(rep.pinned[0], 0);
  EXPECT_EQ(rep.blocking[0], 1);
  EXPECT_GT(rep.iterations, 0) << "it did try";
  EXPECT_EQ(layout.y(), y0) << "bit for bit";
  EXPECT_FALSE(layout.is_pinned(j));
  EXPECT_EQ(layout.n_flipped(), 0);
  // With the penalty homotopy the attempt's layout is relaxed and kept (see pin()).
  param::PinSettings far;
  far.penalty_stages = 8;
  const param::PinReport held = layout.pin({{j, y0[j] + 100}}, far, 30, 1e-4);
  ASSERT_TRUE(held.status.is_ok()) << held.status.to_string();
  EXPECT_EQ(held.pinned[0], 0);
  EXPECT_FALSE(layout.is_pinned(j));
  EXPECT_EQ(layout.n_flipped(), 0);
  // Then a reachable target still pins, and the layout moves.
  const Eigen::VectorXd y1 = layout.y();
  const param::PinReport ok = layout.pin({{j, y1[j] + 0.05}}, {}, 5, 1e-4);
  ASSERT_TRUE(ok.status.is_ok());
  EXPECT_EQ(ok.pinned[0], 1);
  EXPECT_EQ(layout.y()[j], y1[j] + 0.05);
}

TEST(PinnedLayout, LimitingFacesAreAroundAMoveThatFolds) {
  SphereLayout sphere;
  auto& [mesh, cl, layout, ready] = sphere;
  ASSERT_TRUE(ready);
  // A copy whose u is a free variable; the faces around its vertex.
  const auto [copy, j] = first_copy_with_free_u(cl, layout);
  ASSERT_GE(copy, 0);
  const Eigen::VectorXd y0 = layout.y();
  // A hundredth of a unit: nothing limits it. A hundred units: the faces around the copy (and
  // no others, since the rest follows smoothly) fold first.
  EXPECT_TRUE(layout.limiting_faces({{j, y0[j] + 0.01}}).empty());
  const std::vector<int> limiting = layout.limiting_faces({{j, y0[j] + 100}});
  ASSERT_FALSE(limiting.empty());
  const int v = cl.copy_vertex[copy];
  bool around = false;
  for (const int f : limiting)
    for (int k = 0; k < 3; ++k) around = around || mesh.F(f, k) == v;
  EXPECT_TRUE(around);
  EXPECT_LT(limiting.size(), static_cast<size_t>(mesh.n_faces()));
  // The query moves nothing and pins nothing.
  EXPECT_EQ(layout.y(), y0);
  EXPECT_FALSE(layout.is_pinned(j));
  EXPECT_TRUE(layout.limiting_faces({{-1, 0.0}}).empty()) << "out of range: ignored";
}

// Wide faces (more free unknowns than wide_face_variables) are assembled in the copies'
// coordinates and mapped by the elimination: with every face wide, the same pins give the same
// layout (up to the order of the sums), the same limiting faces and the same Newton steps.
TEST(PinnedLayout, WideFacesThroughTheEliminationGiveTheSameSteps) {
  const core::TriMesh mesh = load("sphere.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  param::CopyLayout cl;
  ASSERT_TRUE(p.status.is_ok() && param::build_copy_layout(mesh, p.uv.corner_uv, p.seams, 1e-6, &cl).is_ok());
  ASSERT_FALSE(p.cones.empty());
  std::vector<char> cone_vertex(mesh.n_vertices(), 0), cone_copy(cl.n_copies(), 0);
  for (const param::ConeInfo& c : p.cones) cone_vertex[c.vertex] = 1;
  for (int k = 0; k < cl.n_copies(); ++k) cone_copy[k] = cone_vertex[cl.copy_vertex[k]];
  param::PinnedLayoutOptions narrow_options, wide_options;
  narrow_options.prefer_free = wide_options.prefer_free = cone_copy;
  wide_options.wide_face_variables = 0;
  param::PinnedLayout narrow, wide;
  ASSERT_TRUE(narrow.init(mesh, cl, 10 * cl.x, narrow_options).is_ok());
  ASSERT_TRUE(wide.init(mesh, cl, 10 * cl.x, wide_options).is_ok());
  ASSERT_EQ(narrow.n_free(), wide.n_free());
  // A cone coordinate half a unit away, and a copy a hundred units away (it folds its faces).
  const std::vector<int> col_of = column_of_variable(narrow.reduction());
  int cone_col = -1;
  for (int k = 0; k < cl.n_copies() && cone_col < 0; ++k)
    if (cone_copy[k] && col_of[2 * k] >= 0) cone_col = col_of[2 * k];
  ASSERT_GE(cone_col, 0);
  const auto [copy, j] = first_copy_with_free_u(cl, narrow);
  ASSERT_GE(copy, 0);
  EXPECT_EQ(narrow.limiting_faces({{j, narrow.y()[j] + 100}}), wide.limiting_faces({{j, wide.y()[j] + 100}}));
  const std::vector<std::pair<int, double>> targets = {{cone_col, narrow.y()[cone_col] + 0.5}};
  const param::PinReport a = narrow.pin(targets, {}, 5, 1e-6);
  const param::PinReport b = wide.pin(targets, {}, 5, 1e-6);
  ASSERT_TRUE(a.status.is_ok() && b.status.is_ok());
  EXPECT_EQ(a.pinned, b.pinned);
  EXPECT_EQ(a.pinned[0], 1);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_LT((narrow.y() - wide.y()).lpNorm<Eigen::Infinity>(), 1e-7 * narrow.y().lpNorm<Eigen::Infinity>());
  EXPECT_EQ(wide.n_flipped(), 0);
  core::Status st;
  const int it_a = narrow.minimize(20, 1e-10, &st);
  ASSERT_TRUE(st.is_ok());
  const int it_b = wide.minimize(20, 1e-10, &st);
  ASSERT_TRUE(st.is_ok());
  EXPECT_NEAR(it_a, it_b, 1);
  EXPECT_LT((narrow.y() - wide.y()).lpNorm<Eigen::Infinity>(), 1e-6 * narrow.y().lpNorm<Eigen::Infinity>());
}

TEST(ConstrainedLayout, CopiesAndAffineRowsOnTheSphere) {
  const core::TriMesh mesh = load("sphere.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  param::CopyLayout cl;
  ASSERT_TRUE(param::build_copy_layout(mesh, p.uv.corner_uv, p.seams, 1e-6, &cl).is_ok());
  EXPECT_EQ(cl.n_components, 1);
  EXPECT_GE(cl.n_copies(), mesh.n_vertices());
  // Pin a coordinate of one copy to a value, plus a duplicate (dependent) row.
  const int k = cl.n_copies() / 2;
  const double target = cl.x[2 * k] + 0.05;
  param::AffineRow row{{{2 * k, 1.0}}, target};
  const param::ConstrainedLayoutResult r =
      param::solve_constrained_layout(mesh, cl, cl.x, {}, {row, row});
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.n_flipped, 0);
  ASSERT_EQ(r.independent.size(), 2u);
  EXPECT_EQ(r.independent[0], 1);
  EXPECT_EQ(r.independent[1], 0);
  EXPECT_NEAR(r.x[2 * k], target, 1e-9) << "pinned coordinate";
  // Seams still hold.
  for (const param::CopySeam& s : cl.seams) {
    Eigen::Vector2d ea = r.x.segment<2>(2 * s.a1) - r.x.segment<2>(2 * s.a0);
    for (int i = 0; i < s.matching; ++i) ea = Eigen::Vector2d(-ea.y(), ea.x());
    EXPECT_LT((r.x.segment<2>(2 * s.b1) - r.x.segment<2>(2 * s.b0) - ea).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace quadify
