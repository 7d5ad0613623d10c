// End-to-end tests of compute_seamless_param on procedural and tests/data meshes: zero flips
// (exact predicate), seam residual ≤ seam_tol × bbox diagonal, integer matchings, cone indices
// satisfying Gauss–Bonnet (Σ index = 4χ in quarter turns).
#include <libparam/seamless_param.h>

#include <libcore/predicates.h>
#include <libcore/read_mesh.h>
#include <libcore/topology.h>
#include <libcore/uv_metrics.h>

#include <gtest/gtest.h>

#include <filesystem>

#include "../test_meshes.h"
#include "test_meshes.h"
#include "test_util.h"

namespace quadify::param {
namespace {

// Seam residual bound of the API contract, relative to the bbox diagonal.
constexpr double kSeamTol = 1e-9;
// Gauss–Bonnet error of the UV angle sums (radians): round-off of a few thousand atan2 calls.
constexpr double kGaussBonnetTol = 1e-6;

struct Checked {
  int flips = 0;
  int cone_sum = 0;
  double residual = 0;
};

// Recomputes the properties from the output alone (independently of ParamStats).
Checked check_result(const std::string& name, const core::TriMesh& mesh, const ParamResult& r) {
  Checked c;
  EXPECT_TRUE(r.status.is_ok()) << name << ": " << r.status.to_string();
  const auto& uv = r.uv.corner_uv;
  EXPECT_EQ(uv.rows(), 3 * mesh.n_faces()) << name;
  for (int f = 0; f < mesh.n_faces(); ++f)
    if (core::orient2d(uv.row(3 * f), uv.row(3 * f + 1), uv.row(3 * f + 2)) <= 0) ++c.flips;
  auto corner_of = [&](int f, int v) {
    for (int k = 0; k < 3; ++k)
      if (mesh.F(f, k) == v) return 3 * f + k;
    return -1;
  };
  for (const SeamMatching& s : r.seams) {
    EXPECT_GE(s.matching, 0) << name;
    EXPECT_LE(s.matching, 3) << name;
    const Eigen::Vector2d ea =
        uv.row(corner_of(s.face_a, s.edge_vertex1)) - uv.row(corner_of(s.face_a, s.edge_vertex0));
    const Eigen::Vector2d eb =
        uv.row(corner_of(s.face_b, s.edge_vertex1)) - uv.row(corner_of(s.face_b, s.edge_vertex0));
    Eigen::Vector2d re = ea;
    for (int i = 0; i < s.matching; ++i) re = Eigen::Vector2d(-re.y(), re.x());
    c.residual = std::max(c.residual, (eb - re).norm());
  }
  for (const ConeInfo& k : r.cones) c.cone_sum += k.index;
  EXPECT_EQ(c.flips, 0) << name << ": flipped faces";
  EXPECT_LE(c.residual, kSeamTol * core::bbox_diagonal(mesh.V)) << name << ": seam residual";
  EXPECT_EQ(r.stats.n_flipped, c.flips) << name;
  // Independent check with core::compute_uv_metrics.
  const core::UVMetrics um = core::compute_uv_metrics(r.uv);
  EXPECT_EQ(um.n_flipped, 0) << name;
  EXPECT_EQ(um.n_degenerate, 0) << name;
  EXPECT_TRUE(um.matchings_integer) << name;
  EXPECT_TRUE(um.cone_indices_integer) << name;
  EXPECT_LT(um.gauss_bonnet_error, kGaussBonnetTol) << name;
  EXPECT_LE(um.seam_residual_abs, kSeamTol * core::bbox_diagonal(mesh.V)) << name;
  EXPECT_EQ(um.n_cones, r.stats.n_cones) << name;
  EXPECT_NEAR(um.tau, r.stats.tau, 1e-9 * r.stats.tau) << name;
  return c;
}

ParamOptions fast_options(Energy e = Energy::kSymmetricDirichlet) {
  ParamOptions o;
  o.energy = e;
  return o;
}

TEST(SeamlessParam, SphereConesSumToEight) {
  const core::TriMesh mesh = test::make_icosphere(2);
  const ParamResult r = compute_seamless_param(mesh, fast_options());
  const Checked c = check_result("icosphere2", mesh, r);
  EXPECT_EQ(c.cone_sum, 8) << "icosphere: Σ cone index (quarter turns) must be 4χ = 8";
  EXPECT_GT(r.stats.n_cones, 0);
  EXPECT_EQ(r.stats.n_flipped, 0);
}

TEST(SeamlessParam, TorusConesSumToZero) {
  const core::TriMesh mesh = test::make_torus(24, 10);
  const ParamResult r = compute_seamless_param(mesh, fast_options());
  const Checked c = check_result("torus", mesh, r);
  EXPECT_EQ(c.cone_sum, 0) << "torus: Σ cone index must be 4χ = 0";
}

TEST(SeamlessParam, OpenDiskIsFlipFreeAndSeamless) {
  const core::TriMesh mesh = test::make_disk(8, 24);
  const ParamResult r = compute_seamless_param(mesh, fast_options());
  check_result("disk", mesh, r);
}

TEST(SeamlessParam, TauEnergyReportsTau) {
  const core::TriMesh mesh = test::make_icosphere(2);
  const ParamResult r = compute_seamless_param(mesh, fast_options(Energy::kTau));
  check_result("icosphere2/tau", mesh, r);
  EXPECT_GE(r.stats.tau, 1.0);
  EXPECT_LT(r.stats.tau, 3.0) << "τ of a subdivided icosahedron should be moderate";
}

// A caller that only needs the cones stops before τ's continuation: asked once with the cone
// count of the full run, the map is seamless and flip-free with the same cones and matchings,
// and its τ is not below the continued map's. With two components it is not asked.
TEST(SeamlessParam, CallerCanStopBeforeTheTauContinuation) {
  const core::TriMesh mesh = test::make_icosphere(2);
  const ParamResult full = compute_seamless_param(mesh, fast_options(Energy::kTau));
  ParamOptions o = fast_options(Energy::kTau);
  std::vector<int> asked;
  o.continue_before_tau = [&](int n_cones) {
    asked.push_back(n_cones);
    return false;
  };
  const ParamResult stopped = compute_seamless_param(mesh, o);
  check_result("icosphere2/stopped", mesh, stopped);
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0], full.stats.n_cones);
  EXPECT_TRUE(stopped.stats.stopped_before_tau);
  EXPECT_FALSE(full.stats.stopped_before_tau);
  EXPECT_EQ(stopped.stats.n_cones, full.stats.n_cones);
  ASSERT_EQ(stopped.seams.size(), full.seams.size());
  for (size_t i = 0; i < full.seams.size(); ++i) EXPECT_EQ(stopped.seams[i].matching, full.seams[i].matching);
  EXPECT_GT(stopped.stats.tau, full.stats.tau) << "the continuation lowers τ";
  EXPECT_EQ(stopped.stats.n_tau_iterations, 0);
  // Continuing gives the full run.
  o.continue_before_tau = [](int) { return true; };
  EXPECT_TRUE(compute_seamless_param(mesh, o).uv.corner_uv == full.uv.corner_uv);
  // Two components: not asked.
  core::TriMesh a = test::make_icosphere(1), b = test::make_icosphere(1);
  core::TriMesh two;
  two.V.resize(a.V.rows() + b.V.rows(), 3);
  two.V << a.V, (b.V.array() + 3.0).matrix();
  two.F.resize(a.F.rows() + b.F.rows(), 3);
  two.F << a.F, (b.F.array() + static_cast<int>(a.V.rows())).matrix();
  asked.clear();
  o.continue_before_tau = [&](int n_cones) {
    asked.push_back(n_cones);
    return false;
  };
  const ParamResult r2 = compute_seamless_param(two, o);
  EXPECT_TRUE(asked.empty());
  EXPECT_FALSE(r2.stats.stopped_before_tau);
}

TEST(SeamlessParam, TwoComponentsAreDeterministicAcrossThreadCounts) {
  core::TriMesh a = test::make_icosphere(1), b = test::make_torus(16, 8);
  core::TriMesh m;
  m.V.resize(a.V.rows() + b.V.rows(), 3);
  m.V << a.V, b.V;
  m.F.resize(a.F.rows() + b.F.rows(), 3);
  m.F << a.F, (b.F.array() + static_cast<int>(a.V.rows())).matrix();
  ParamOptions o1 = fast_options(), o2 = fast_options();
  o1.threads = 1;
  o2.threads = 2;
  const ParamResult r1 = compute_seamless_param(m, o1), r2 = compute_seamless_param(m, o2);
  const Checked c = check_result("sphere+torus", m, r1);
  EXPECT_EQ(c.cone_sum, 8) << "sphere + torus: 4χ = 8";
  EXPECT_EQ(r1.stats.n_components, 2);
  EXPECT_TRUE(r1.uv.corner_uv == r2.uv.corner_uv) << "result depends on the thread count";
}

TEST(SeamlessParam, RejectsDegenerateFace) {
  core::TriMesh m = test::make_icosphere(0);
  m.V.row(m.F(0, 2)) = 0.5 * (m.V.row(m.F(0, 0)) + m.V.row(m.F(0, 1)));
  const ParamResult r = compute_seamless_param(m);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput) << r.status.to_string();
}

TEST(SeamlessParam, RejectsBadOptions) {
  ParamOptions o;
  o.threshold_step = 0;
  const ParamResult r = compute_seamless_param(test::make_icosphere(0), o);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput);
}

// Cone-pair cancellation on a real organic mesh (τ with local estimation makes +1/−1 pairs a
// few edges apart): the map stays flip-free and seamless, every cancelled pair removes exactly
// two cones, Gauss–Bonnet still holds, and no +1/−1 pair is left within the distance along one
// seam edge.
TEST(SeamlessParam, ConePairCancellationRemovesClosePairs) {
  const core::TriMesh mesh = core::to_trimesh(core::read_mesh(test::data_path("spot.obj")));
  ParamOptions plain;
  const ParamResult before = compute_seamless_param(mesh, plain);
  check_result("spot", mesh, before);
  ParamOptions cancel = plain;
  cancel.cone_pair_distance = 0.3;  // model units: spot's mean edge length is about 0.04
  cancel.cone_pair_max_hops = 6;
  const ParamResult after = compute_seamless_param(mesh, cancel);
  const Checked c = check_result("spot (cancelled)", mesh, after);
  EXPECT_EQ(c.cone_sum, 8) << "Σ cone index must stay 4χ";
  EXPECT_GT(after.stats.n_cancelled_pairs, 0);
  EXPECT_EQ(before.stats.n_cancelled_pairs, 0);
  // The seams' matchings differ from the plain run only through the cancellations, which run
  // after the same batches: each removes one +1 and one −1 cone.
  EXPECT_EQ(after.stats.n_cones, before.stats.n_cones - 2 * after.stats.n_cancelled_pairs);
  std::vector<int> index(mesh.n_vertices(), 0);
  for (const ConeInfo& k : after.cones) index[k.vertex] = k.index;
  for (const SeamMatching& s : after.seams) {
    const double len = (mesh.V.row(s.edge_vertex0) - mesh.V.row(s.edge_vertex1)).norm();
    if (len <= cancel.cone_pair_distance) {
      EXPECT_FALSE(index[s.edge_vertex0] * index[s.edge_vertex1] == -1)
          << "opposite cones left on seam edge " << s.edge_vertex0 << "-" << s.edge_vertex1;
    }
  }
}

// Pairs near over the surface (cone_pair_surface): after the seam-path cancellation the map is
// still flip-free and seamless with Σ index 4χ; every pair removed over the surface removes two
// cones, and none is left that the seam-path cancellation alone would have removed. The second
// wave (cone_pair_far_factor) runs after the first one is done: the first wave's cancellations
// are the same, and each far pair removes two more cones.
TEST(SeamlessParam, SurfaceConePairsKeepTheMapValid) {
  const core::TriMesh mesh = core::to_trimesh(core::read_mesh(test::data_path("spot.obj")));
  ParamOptions seams;
  seams.cone_pair_distance = 0.3;  // model units: spot's mean edge length is about 0.04
  seams.cone_pair_max_hops = 6;
  const ParamResult before = compute_seamless_param(mesh, seams);
  check_result("spot (seam pairs)", mesh, before);
  ParamOptions surface = seams;
  surface.cone_pair_surface = true;
  surface.cone_pair_far_factor = 1;  // the first wave only
  const ParamResult after = compute_seamless_param(mesh, surface);
  const Checked c = check_result("spot (surface pairs)", mesh, after);
  EXPECT_EQ(c.cone_sum, 8) << "Σ cone index must stay 4χ";
  EXPECT_EQ(before.stats.n_surface_pairs, 0);
  EXPECT_GT(after.stats.n_surface_pairs, 0);
  EXPECT_EQ(after.stats.n_far_pairs, 0);
  EXPECT_EQ(after.stats.n_cancelled_pairs - after.stats.n_surface_pairs, before.stats.n_cancelled_pairs);
  EXPECT_EQ(after.stats.n_cones, before.stats.n_cones - 2 * after.stats.n_surface_pairs);

  ParamOptions far = surface;
  far.cone_pair_far_factor = 4;
  const ParamResult after_far = compute_seamless_param(mesh, far);
  const Checked cf = check_result("spot (far surface pairs)", mesh, after_far);
  EXPECT_EQ(cf.cone_sum, 8) << "Σ cone index must stay 4χ";
  EXPECT_GT(after_far.stats.n_far_pairs, 0);
  EXPECT_EQ(after_far.stats.n_surface_pairs - after_far.stats.n_far_pairs, after.stats.n_surface_pairs);
  EXPECT_EQ(after_far.stats.n_cones, after.stats.n_cones - 2 * after_far.stats.n_far_pairs);
}

// Cone splitting: the thin spike's apex gets a cone of index 3 (UV angle π/2, a quad vertex of
// valence 1); with cone_split_distance no cone keeps an index above cone_split_max_index, the
// map stays flip-free and seamless, Σ index stays 4χ, and the units moved off the apex are new
// +1 cones.
TEST(SeamlessParam, ConeSplittingLeavesNoConeAboveTheMaxIndex) {
  const core::TriMesh mesh = test::spike();
  auto max_index = [](const ParamResult& r) {
    int m = 0;
    for (const ConeInfo& k : r.cones) m = std::max(m, k.index);
    return m;
  };
  const ParamResult plain = compute_seamless_param(mesh, ParamOptions{});
  check_result("spike", mesh, plain);
  ASSERT_GE(max_index(plain), 3) << "the test needs a cone of index 3 without splitting";
  EXPECT_EQ(plain.stats.n_split_cones, 0);
  for (const int most : {2, 1}) {
    ParamOptions split;
    split.cone_split_distance = 1.5;  // model units: the spike is 8 high, its base of radius 1
    split.cone_split_max_index = most;
    const ParamResult r = compute_seamless_param(mesh, split);
    const std::string name = "spike (split to " + std::to_string(most) + ")";
    const Checked c = check_result(name, mesh, r);
    EXPECT_EQ(c.cone_sum, 8) << name;
    EXPECT_LE(max_index(r), most) << name;
    EXPECT_GE(r.stats.n_split_cones, max_index(plain) - most) << name;
    EXPECT_EQ(r.stats.n_cones, plain.stats.n_cones + r.stats.n_split_cones) << name;
  }
}

TEST(SeamlessParam, TestDataMeshes) {
  for (const char* name : {"tet.obj", "cube.obj", "sphere.obj", "disk.obj", "torus.obj"}) {
    const auto path = test::data_path(name);
    if (!std::filesystem::exists(path)) continue;
    const core::TriMesh mesh = core::to_trimesh(core::read_mesh(path));
    const ParamResult r = compute_seamless_param(mesh, fast_options());
    const Checked c = check_result(name, mesh, r);
    const int chi = core::topology_stats(mesh).euler_characteristic;
    const int n_boundary = core::topology_stats(mesh).n_boundary_loops;
    if (n_boundary == 0) {
      EXPECT_EQ(c.cone_sum, 4 * chi) << name;
    }
  }
}

}  // namespace
}  // namespace quadify::param

namespace quadify::param {
namespace {

// Every energy yields an exactly seamless map with integer matchings; the line search keeps
// layouts flip-free even for the energies without a barrier.
TEST(SeamlessParam, AllEnergiesAreSeamless) {
  const core::TriMesh mesh = test::make_torus(16, 8);
  for (Energy e : {Energy::kArap, Energy::kLinfArap, Energy::kConformal}) {
    ParamOptions o;
    o.energy = e;
    const ParamResult r = compute_seamless_param(mesh, o);
    const std::string name = "torus/energy " + std::to_string(static_cast<int>(e));
    const Checked c = check_result(name, mesh, r);
    EXPECT_EQ(c.cone_sum, 0) << name;
  }
}

TEST(SeamlessParam, TopDownOrderIsSeamless) {
  const core::TriMesh mesh = test::make_icosphere(1);
  ParamOptions o = fast_options();
  o.order = RoundingOrder::kTopDown;
  const ParamResult r = compute_seamless_param(mesh, o);
  const Checked c = check_result("icosphere1/top-down", mesh, r);
  EXPECT_EQ(c.cone_sum, 8);
}

}  // namespace
}  // namespace quadify::param

namespace quadify::param {
namespace {

TEST(SeamlessParam, ProgressAndLocalEstimationCounters) {
  const core::TriMesh mesh = test::make_icosphere(2);
  ParamOptions o = fast_options();
  std::vector<int> rounds;
  o.progress = [&](const std::string& stage, int step, int n_steps) {
    if (stage == "round") rounds.push_back(step);
    EXPECT_GT(n_steps, 0);
  };
  const ParamResult r = compute_seamless_param(mesh, o);
  check_result("icosphere2/progress", mesh, r);
  EXPECT_EQ(rounds, (std::vector<int>{0, 1, 2, 3, 4})) << "one call per batch (ε = 0.1 … 0.5)";
  EXPECT_GT(r.stats.n_patches, 0) << "a sphere needs cones, so some matchings are uncertain";
  EXPECT_LE(r.stats.n_improved, r.stats.n_patches);
  EXPECT_LE(r.stats.n_batches, 5);
  ParamOptions no_le = fast_options();
  no_le.local_estimation = false;
  const ParamResult r2 = compute_seamless_param(mesh, no_le);
  check_result("icosphere2/no-le", mesh, r2);
  EXPECT_EQ(r2.stats.n_patches, 0);
}

// Feature alignment (paper section 6): every feature half-edge keeps its labeled coordinate, and
// the other side of an interior feature edge is aligned through its seam.
double feature_misalignment(const core::TriMesh& mesh, const ParamResult& r) {
  double worst = 0;
  const auto& uv = r.uv.corner_uv;
  for (const FeatureAlignment& fa : r.features) {
    const int a = 3 * fa.face + fa.corner, b = 3 * fa.face + (fa.corner + 1) % 3;
    worst = std::max(worst, std::abs(uv(b, fa.constant_coord) - uv(a, fa.constant_coord)) /
                                (uv.row(b) - uv.row(a)).norm());
  }
  (void)mesh;
  return worst;
}

std::vector<std::array<int, 2>> sharp_edge_pairs(const core::TriMesh& mesh, double angle) {
  const core::EdgeTopology topo = core::build_edge_topology(mesh);
  std::vector<std::array<int, 2>> pairs;
  for (const int e : core::sharp_edges(mesh, topo, angle))
    pairs.push_back({topo.edge_vertex(e, 0), topo.edge_vertex(e, 1)});
  return pairs;
}

TEST(FeatureAlignment, BoxEdgesAreAlignedAndCornersAreCones) {
  const core::TriMesh mesh = core::to_trimesh(core::read_mesh(test::data_path("box.obj")));
  ParamOptions o = fast_options();
  o.feature_edges = sharp_edge_pairs(mesh, 40);
  ASSERT_EQ(o.feature_edges.size(), 72u) << "12 box edges of 8, 6 and 4 segments";
  const ParamResult r = compute_seamless_param(mesh, o);
  const Checked c = check_result("box", mesh, r);
  EXPECT_EQ(c.cone_sum, 8);
  EXPECT_EQ(r.stats.n_feature_edges, 72);
  EXPECT_EQ(r.stats.n_aligned_features, 72);
  EXPECT_EQ(r.stats.n_disabled_features, 0);
  EXPECT_LT(feature_misalignment(mesh, r), 1e-9);
  EXPECT_LT(r.stats.feature_alignment_error, 1e-9);
  // Aligned creases make each side a rectangle: the map is an isometry, the corners +1 cones.
  EXPECT_LT(r.stats.tau, 1.001);
  ASSERT_EQ(r.cones.size(), 8u);
  for (const ConeInfo& k : r.cones) EXPECT_EQ(k.index, 1);
}

// Whole-curve labels on the box: its twelve edges are straight curves, every edge aligned, the
// corners +1 cones, the map an isometry as without them.
TEST(FeatureAlignment, BoxEdgesLabeledAsWholeCurves) {
  const core::TriMesh mesh = core::to_trimesh(core::read_mesh(test::data_path("box.obj")));
  ParamOptions o = fast_options();
  o.feature_edges = sharp_edge_pairs(mesh, 40);
  o.feature_curve_labels = true;
  const ParamResult r = compute_seamless_param(mesh, o);
  const Checked c = check_result("box curves", mesh, r);
  EXPECT_EQ(c.cone_sum, 8);
  EXPECT_EQ(r.stats.n_aligned_features, 72);
  EXPECT_EQ(r.stats.n_disabled_features, 0);
  EXPECT_LT(feature_misalignment(mesh, r), 1e-9);
  EXPECT_LT(r.stats.tau, 1.001);
  ASSERT_EQ(r.cones.size(), 8u);
}

// Alg. 3: the same box with the features labeled after the matchings and pulled in by a
// penalty: aligned within the tolerance (not exactly), every box edge kept, flip-free; the box's
// sides still become rectangles, so the corners are the eight +1 cones and τ stays near 1.
TEST(FeatureAlignment, SoftFeaturesAfterRoundingAreAlignedWithinTolerance) {
  const core::TriMesh mesh = core::to_trimesh(core::read_mesh(test::data_path("box.obj")));
  ParamOptions o = fast_options();
  o.feature_edges = sharp_edge_pairs(mesh, 40);
  o.feature_mode = FeatureMode::kAfterRounding;
  const ParamResult r = compute_seamless_param(mesh, o);
  const Checked c = check_result("box soft", mesh, r);
  EXPECT_EQ(c.cone_sum, 8);
  EXPECT_EQ(r.stats.n_aligned_features, 72);
  const double measured = feature_misalignment(mesh, r);
  EXPECT_LE(measured, o.soft_feature_tolerance);
  EXPECT_NEAR(r.stats.feature_alignment_error, measured, 1e-12);
  EXPECT_LT(r.stats.tau, 1.05);
  // Twelve arbitrary edges of a torus as features: those labeled are aligned softly, flip-free.
  const core::TriMesh torus = core::to_trimesh(core::read_mesh(test::data_path("torus.obj")));
  ParamOptions ot = fast_options();
  ot.feature_mode = FeatureMode::kAfterRounding;
  ot.feature_edges = sharp_edge_pairs(torus, 1e-3);
  ot.feature_edges.resize(std::min<size_t>(ot.feature_edges.size(), 12));
  const ParamResult rt = compute_seamless_param(torus, ot);
  check_result("torus soft", torus, rt);
  EXPECT_LE(feature_misalignment(torus, rt), ot.soft_feature_tolerance);
  EXPECT_GT(rt.stats.n_aligned_features, 0);
}

TEST(FeatureAlignment, DiskBoundaryIsAligned) {
  const core::TriMesh mesh = test::make_disk(8, 24);
  ParamOptions o = fast_options();
  o.align_boundaries = true;
  const ParamResult r = compute_seamless_param(mesh, o);
  check_result("disk", mesh, r);
  EXPECT_EQ(r.stats.n_feature_edges, 24);
  EXPECT_EQ(r.stats.n_aligned_features + r.stats.n_disabled_features, 24);
  EXPECT_EQ(r.stats.n_disabled_features, 0);
  EXPECT_LT(feature_misalignment(mesh, r), 1e-9);
}

TEST(FeatureAlignment, WedgeOfTwoCloseFeaturesKeepsOne) {
  // Two radial edges of a disk 15° apart cannot both run along one axis, and they cannot turn by
  // 90° without a large distortion: the wedge check disables one of them, and the map stays
  // flip-free.
  const core::TriMesh mesh = test::make_disk(4, 24);
  const core::EdgeTopology topo = core::build_edge_topology(mesh);
  // The centre vertex has the highest valence; take two consecutive spokes of it.
  std::vector<int> valence(mesh.n_vertices(), 0);
  for (int e = 0; e < topo.n_edges(); ++e) ++valence[topo.edge_vertex(e, 0)], ++valence[topo.edge_vertex(e, 1)];
  const int centre = static_cast<int>(std::max_element(valence.begin(), valence.end()) - valence.begin());
  int spoke0 = -1, spoke1 = -1;
  for (int f = 0; f < mesh.n_faces() && spoke0 < 0; ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.F(f, k) == centre) {
        spoke0 = mesh.F(f, (k + 1) % 3);
        spoke1 = mesh.F(f, (k + 2) % 3);
      }
  ASSERT_GE(spoke0, 0);
  ParamOptions o = fast_options();
  o.feature_edges = {{centre, spoke0}, {centre, spoke1}};
  const ParamResult r = compute_seamless_param(mesh, o);
  check_result("disk wedge", mesh, r);
  EXPECT_EQ(r.stats.n_feature_edges, 2);
  EXPECT_EQ(r.stats.n_aligned_features, 1);
  EXPECT_EQ(r.stats.n_disabled_features, 1);
  EXPECT_EQ(r.stats.n_disabled_by_wedge, 1);
  EXPECT_EQ(r.stats.n_disabled_by_tau + r.stats.n_disabled_by_flips, 0);
}

TEST(FeatureAlignment, RejectsAPairThatIsNotAnEdge) {
  const core::TriMesh mesh = test::make_disk(4, 12);
  ParamOptions o = fast_options();
  o.feature_edges = {{0, 0}};
  EXPECT_EQ(compute_seamless_param(mesh, o).status.code(), core::StatusCode::kInvalidInput);
  o.feature_edges = {{0, mesh.n_vertices()}};
  const ParamResult r = compute_seamless_param(mesh, o);
  EXPECT_EQ(r.status.code(), core::StatusCode::kInvalidInput);
  EXPECT_NE(r.status.message().find("feature edge"), std::string::npos) << r.status.message();
}

// Coarse cones (ParamOptions::cone_scale): the matchings rounded on a copy of spot smoothed at a
// length of several mesh edges carry over to spot itself as a flip-free seamless map whose cones
// satisfy Gauss–Bonnet, with fewer cones than the map of spot's own curvature; with features the
// option is ignored (their labels belong to the original layout).
TEST(SeamlessParam, ConeScaleGivesFewerConesAndAFlipFreeSeamlessMap) {
  const core::TriMesh mesh = core::to_trimesh(core::read_mesh(test::data_path("spot.obj")));
  ParamOptions plain;
  plain.energy = Energy::kSymmetricDirichlet;
  const ParamResult fine = compute_seamless_param(mesh, plain);
  check_result("spot", mesh, fine);
  EXPECT_FALSE(fine.stats.coarse_cones);
  ParamOptions coarse_options = plain;
  coarse_options.cone_scale = 0.2;  // model units: spot's mean edge length is about 0.04
  const ParamResult coarse = compute_seamless_param(mesh, coarse_options);
  const Checked c = check_result("spot (coarse cones)", mesh, coarse);
  EXPECT_TRUE(coarse.stats.coarse_cones) << coarse.stats.coarse_cones_fallback_reason;
  EXPECT_EQ(c.cone_sum, 8) << "Σ cone index must be 4χ";
  EXPECT_LT(coarse.stats.n_cones, fine.stats.n_cones);
  // The map is of spot's own triangles: same faces, finite distortion.
  EXPECT_EQ(coarse.uv.mesh.V, mesh.V);
  EXPECT_TRUE(std::isfinite(coarse.stats.tau));
  ParamOptions with_features = coarse_options;
  with_features.feature_edges = {{mesh.F(0, 0), mesh.F(0, 1)}};
  const ParamResult ignored = compute_seamless_param(mesh, with_features);
  EXPECT_FALSE(ignored.stats.coarse_cones);
  ParamOptions negative = plain;
  negative.cone_scale = -1;
  EXPECT_EQ(compute_seamless_param(mesh, negative).status.code(), core::StatusCode::kInvalidInput);
  // With τ, the carried map also gets τ's L^p continuation: same cones, lower τ than symmetric
  // Dirichlet alone (spot at 1,000 quads through the CLI: 2.59 → 1.63).
  ParamOptions tau_options = coarse_options;
  tau_options.energy = Energy::kTau;
  const ParamResult tau = compute_seamless_param(mesh, tau_options);
  check_result("spot (coarse cones, tau)", mesh, tau);
  EXPECT_TRUE(tau.stats.coarse_cones) << tau.stats.coarse_cones_fallback_reason;
  EXPECT_LT(tau.stats.tau, coarse.stats.tau);
}

}  // namespace
}  // namespace quadify::param
