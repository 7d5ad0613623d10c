// End-to-end remeshes of benchmark meshes of ../shared/meshes through the CLI (skipped when
// absent), asserting figures that a change of the pipeline must not lose.
#include "cli_run.h"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace quadify::test {
namespace {

namespace fs = std::filesystem;

// Runs `quadify MESH -o dir/q.obj --target-faces TARGET --quiet --json dir/r.json EXTRA` (TARGET
// 5000 unless given) on a mesh of ../shared/meshes (the test skips without it).
class CliSlow : public ::testing::Test {
 protected:
  void SetUp() override {
    if (cli_path().empty()) GTEST_SKIP() << "quadify CLI not built";
    meshes_ = shared_meshes_dir();
    if (meshes_.empty()) GTEST_SKIP() << "no shared meshes";
    dir_ = make_temp_dir("cli_slow");
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  // The report of a run that must succeed (a failed expectation and null otherwise).
  nlohmann::json remesh(const std::string& mesh, const std::string& extra = "", int target = 5000) {
    std::string args = "'";
    args.append((meshes_ / mesh).string()).append("' -o '").append((dir_ / "q.obj").string());
    args.append("' --target-faces ").append(std::to_string(target));
    args.append(" --quiet --json '").append((dir_ / "r.json").string()).append("' ");
    args.append(extra);
    const CliRun r = quadify(args, dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    if (r.exit_code != 0) return nullptr;
    return nlohmann::json::parse(slurp(dir_ / "r.json"));
  }
  bool has(const std::string& mesh) const { return fs::exists(meshes_ / mesh); }
  fs::path meshes_, dir_;
};

// plane_holes at 5,000 quads: its parametrization fails with its 1,282 feature and boundary
// edges (its last batch leaves faces flipped on the tail fin and a wing's knife edge); run again
// without the features near there, it keeps most of them, and the grid no longer cuts most of
// its 27 window holes (272 non-quads when all features were dropped; 49 where it still cuts them,
// which the pure-quad pass turns into quads).
TEST_F(CliSlow, PlaneHolesKeepsTheFeaturesAwayFromWhereItsMapFailed) {
  if (!has("plane_holes.obj")) GTEST_SKIP() << "no plane_holes";
  const nlohmann::json report = remesh("plane_holes.obj");
  ASSERT_FALSE(report.is_null());
  const nlohmann::json& features = report["param"]["features"];
  EXPECT_EQ(features["components_without_features_near_failure"], 1);
  EXPECT_EQ(features["components_without_features"], 0);
  EXPECT_GT(features["aligned"].get<int>(), features["feature_edges"].get<int>() / 2);
  EXPECT_EQ(report["quads"]["flipped_quads"], 0);
  EXPECT_EQ(report["quads"]["non_quads"], 0);
  EXPECT_GT(report["pure_quads"]["non_quads_before"].get<int>(), 0);
  EXPECT_GT(report["quads"]["feature_capture"].get<double>(), 0.7);
  EXPECT_LT(report["quads"]["hausdorff_sym"].get<double>(), 0.01);
}

// `quadify param plane_holes.obj`: its last batch of matchings stays flipped with its features.
// When every earlier feature was dropped first, the deferral of the batch's seams then left no
// face flipped: a flip-free map with 0 of its 1,282 feature edges. Now the deferral comes first,
// one face stays flipped, the component fails, and it is run again without the features near
// the flipped faces: most stay aligned.
TEST_F(CliSlow, PlaneHolesParamKeepsMostOfItsFeatures) {
  if (!has("plane_holes.obj")) GTEST_SKIP() << "no plane_holes";
  std::string args = "param '";
  args.append((meshes_ / "plane_holes.obj").string()).append("' -o '").append((dir_ / "p.obj").string());
  args.append("' --quiet --json '").append((dir_ / "p.json").string()).append("'");
  const CliRun r = quadify(args, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(dir_ / "p.json"));
  const nlohmann::json& features = report["param"]["features"];
  EXPECT_EQ(features["components_without_features"], 0);
  EXPECT_GT(features["aligned"].get<int>(), features["feature_edges"].get<int>() / 2);
  EXPECT_EQ(report["param"]["flipped"], 0);
}

// `quadify param fandisk.obj`: two creases meet at 22° at a wedge's tip. Labeled edge by edge
// (the paper's Alg. 2), both take one axis near the tip, whose edges the wedge check disables,
// and the wedge becomes a strip between two parallel iso-lines, squeezed where it is wide: τ 2.91.
// Labeled as whole curves (the default of `param`), the wedge opens to a quarter turn at its tip:
// τ 2.05.
TEST_F(CliSlow, FandiskAcuteWedgeOpensToAQuarterTurn) {
  if (!has("fandisk.obj")) GTEST_SKIP() << "no fandisk";
  auto param = [&](const std::string& extra) -> nlohmann::json {
    std::string args = "param '";
    args.append((meshes_ / "fandisk.obj").string()).append("' -o '").append((dir_ / "p.obj").string());
    args.append("' --quiet --json '").append((dir_ / "p.json").string()).append("' ").append(extra);
    const CliRun r = quadify(args, dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    if (r.exit_code != 0) return nullptr;
    return nlohmann::json::parse(slurp(dir_ / "p.json"));
  };
  const nlohmann::json on = param("");
  ASSERT_FALSE(on.is_null());
  EXPECT_EQ(on["param"]["features"]["acute_curves"], 2);
  EXPECT_EQ(on["param"]["flipped"], 0);
  const nlohmann::json off = param("--acute-curve-labels off");
  ASSERT_FALSE(off.is_null());
  EXPECT_EQ(off["param"]["features"]["acute_curves"], 0);
  EXPECT_EQ(off["param"]["flipped"], 0);
  EXPECT_LT(on["param"]["tau"].get<double>(), 2.3);
  EXPECT_GT(off["param"]["tau"].get<double>(), 2.6);
  EXPECT_GE(on["param"]["features"]["aligned"].get<int>(), off["param"]["features"]["aligned"].get<int>() - 5);
}

// fandisk at 5,000 quads: the largest distance to the surface sits at a crease corner that a row
// of quads cuts off (a crease edge left unaligned by the wedge check); the snap that meets it
// folds a quad, which the repair then opens again, and the tentative snap keeps it
// (RelaxOptions::tentative_snaps). Measured: 0.0031 → 0.0019 of the diagonal with the cone pairs
// of b13687e; with the feature-sector check of the cone pairs and the label flips along their
// paths (a map with 3 more pairs cancelled, 32 irregular vertices instead of 38), 0.0037 → 0.0020.
TEST_F(CliSlow, FandiskCreaseCornerIsMetByATentativeSnap) {
  if (!has("fandisk.obj")) GTEST_SKIP() << "no fandisk";
  const nlohmann::json report = remesh("fandisk.obj");
  ASSERT_FALSE(report.is_null());
  EXPECT_GE(report["relax"]["tentative_snaps"].get<int>(), 1);
  EXPECT_EQ(report["quads"]["non_quads"], 0);
  EXPECT_EQ(report["quads"]["flipped_quads"], 0);
  EXPECT_LT(report["quads"]["hausdorff_sym"].get<double>(), 0.0025);
  // Without them, the corner stays cut off.
  const nlohmann::json off_report = remesh("fandisk.obj", "--no-tentative-snaps");
  ASSERT_FALSE(off_report.is_null());
  EXPECT_EQ(off_report["relax"]["tentative_snaps"].get<int>(), 0);
  EXPECT_GT(off_report["quads"]["hausdorff_sym"].get<double>(),
            report["quads"]["hausdorff_sym"].get<double>() + 0.0005);
}

// wingnut at 5,000 quads: 6 of its 365 sharp edges are too short or too faceted for the crease
// filter, but 98% are creases (a CAD part: all kept, core::CreaseOptions::keep_all_share), and two
// narrow chamfer bands (0.03 wide, quads of 0.11) get quads as long as they are wide
// (param::feature_strip_vertex_size), so that both their creases are quad edges: feature capture
// 0.945 → 0.964. With --no-feature-sizing the bands lose a crease (0.934; compared without the
// cone pairs near over the surface, the pipeline the sizing was measured in: with them, the run
// without sizing lands on another rounding, 0.960). Since the repair removes folded slivers
// (three on wingnut), the run without sizing captures 0.957 against the default's 0.962: the
// margin is smaller, the order the same.
TEST_F(CliSlow, WingnutKeepsItsShortSharpEdgesAndItsNarrowBands) {
  if (!has("wingnut.obj")) GTEST_SKIP() << "no wingnut";
  const nlohmann::json report = remesh("wingnut.obj");
  ASSERT_FALSE(report.is_null());
  EXPECT_EQ(report["param"]["features"]["sharp_edges_not_creases"], 0);
  EXPECT_EQ(report["param"]["sizing"]["mode"], "feature-strips");
  EXPECT_GT(report["param"]["sizing"]["strip_vertices"].get<int>(), 0);
  EXPECT_EQ(report["quads"]["non_quads"], 0);
  EXPECT_EQ(report["quads"]["flipped_quads"], 0);
  EXPECT_NEAR(report["quads"]["faces"].get<double>(), 5000, 500);
  EXPECT_GE(report["quads"]["feature_capture"].get<double>(), 0.955);
  const nlohmann::json off_report = remesh("wingnut.obj", "--no-feature-sizing --surface-cone-pairs off");
  ASSERT_FALSE(off_report.is_null());
  EXPECT_LT(off_report["quads"]["feature_capture"].get<double>(),
            report["quads"]["feature_capture"].get<double>() - 0.002);
}

// mannequin-devil at 5,000 quads: its creases get feature-strip sizing, but the map they shape
// has a cone of index 3 at a horn tip, so the remesher drops them; the sizing goes with them
// (kept, the quads shrank along bands of creases no longer aligned: Hausdorff 0.0137, above 1%).
// The count adjustment then brings its 5,220 quads to 5,000, but those are farther from the
// input (Hausdorff 0.0132 against 0.0089: above 1%): the remesher keeps the quads before it.
TEST_F(CliSlow, MannequinDropsItsFeatureSizingWithItsFeatures) {
  if (!has("mannequin-devil.obj")) GTEST_SKIP() << "no mannequin-devil";
  const nlohmann::json report = remesh("mannequin-devil.obj");
  ASSERT_FALSE(report.is_null());
  EXPECT_EQ(report["quantize"]["features_dropped"], true);
  EXPECT_EQ(report["param"]["sizing"]["mode"], "uniform");
  EXPECT_EQ(report["param"]["sizing"]["feature_sizing_dropped"], "feature-strips");
  EXPECT_EQ(report["quads"]["non_quads"], 0);
  EXPECT_EQ(report["quads"]["flipped_quads"], 0);
  EXPECT_LT(report["quads"]["hausdorff_sym"].get<double>(), 0.01);
  EXPECT_GT(report["quantize"]["count_adjustments"].get<int>(), 0);
  EXPECT_EQ(report["quantize"]["count_adjustment_undone"], true);
}

// casting at 1,000 quads: one of its bars is about one quad around, and a rounding may close the
// integer iso-line round it on its own grid point: two faces with a loop edge, which the metrics
// used to count as manifold quads (and as 2 flipped quads, genus 8). They are degenerate now, the
// mesh not manifold, and the remesher refines the grid until every handle keeps its quads (the
// map of b13687e needed one refinement here; f6eee26's, with other cones, none:
// CliTest.RemeshRefinesAGridThatPinchesAHandle tests the refinement itself). Either way: no degenerate face, manifold, the input's genus.
TEST_F(CliSlow, CastingAtAThousandQuadsKeepsItsHandles) {
  if (!has("casting.obj")) GTEST_SKIP() << "no casting";
  const nlohmann::json report = remesh("casting.obj", "", 1000);
  ASSERT_FALSE(report.is_null());
  EXPECT_EQ(report["quads"]["degenerate_faces"], 0);
  EXPECT_EQ(report["quads"]["manifold"], true);
  EXPECT_EQ(report["quads"]["genus"], report["mesh"]["genus"]);
  EXPECT_EQ(report["quads"]["non_quads"], 0);
  EXPECT_EQ(report["quads"]["flipped_quads"], 0);
}

}  // namespace
}  // namespace quadify::test
