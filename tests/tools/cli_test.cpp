// The CLI as a user meets it: exit codes, one-line errors that name the file, reports, and no
// partial output on failure.
#include "cli_run.h"

#include <libcore/read_mesh.h>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include <sys/wait.h>

namespace fs = std::filesystem;
using quadify::test::cli_path;
using quadify::test::data_path;
using quadify::test::make_temp_dir;

namespace {

using quadify::test::CliRun;
using quadify::test::quadify;
using quadify::test::slurp;
using quadify::test::write_text;

// Unit cube, 8 vertices, 12 triangles, outward CCW.
const char* kCubeTriObj = R"(v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
)";

// The same cube as 6 quads.
const char* kCubeQuadObj = R"(v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

// A flat 2×1 strip of 4 triangles with UVs equal to the positions (an isometry, no seams).
const char* kStripUvObj = R"(v 0 0 0
v 1 0 0
v 2 0 0
v 0 1 0
v 1 1 0
v 2 1 0
vt 0 0
vt 1 0
vt 2 0
vt 0 1
vt 1 1
vt 2 1
f 1/1 2/2 5/5
f 1/1 5/5 4/4
f 2/2 3/3 6/6
f 2/2 6/6 5/5
)";

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (cli_path().empty()) GTEST_SKIP() << "quadify CLI not built";
    dir_ = make_temp_dir("cli");
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  // `quadify IN -o dir_/q.obj --target-faces N --quiet --json dir_/r.json EXTRA`: expects exit 0
  // and returns the report.
  nlohmann::json remesh_report(const fs::path& in, int target_faces, const std::string& extra) {
    std::string args;
    args.append("'").append(in.string()).append("' -o '").append((dir_ / "q.obj").string());
    args.append("' --target-faces ").append(std::to_string(target_faces));
    args.append(" --quiet --json '").append((dir_ / "r.json").string()).append("' ").append(extra);
    const CliRun r = quadify(args, dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(slurp(dir_ / "r.json"));
  }
  fs::path dir_;
};

TEST_F(CliTest, HelpListsCommandsAndExitCodes) {
  const CliRun r = quadify("--help", dir_);
  EXPECT_EQ(r.exit_code, 0);
  for (const char* word : {"info", "check", "--json", "--threads", "--quiet", "Exit codes"})
    EXPECT_NE(r.out.find(word), std::string::npos) << "help lacks " << word << ":\n" << r.out;
}

TEST_F(CliTest, VersionPrintsVersion) {
  const CliRun r = quadify("--version", dir_);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("quadify"), std::string::npos);
}

TEST_F(CliTest, UnknownOptionIsBadInput) {
  const CliRun r = quadify("info --no-such-option x.obj", dir_);
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(CliTest, InfoReportsTopologyAndRepairs) {
  write_text(dir_ / "cube.obj", kCubeTriObj);
  const CliRun r = quadify("info '" + (dir_ / "cube.obj").string() + "' --json '" + (dir_ / "r.json").string() + "'", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(j["mesh"]["faces"], 12);
  EXPECT_EQ(j["mesh"]["genus"], 0);
  EXPECT_EQ(j["mesh"]["euler_characteristic"], 2);
  EXPECT_EQ(j["repair"]["welded_vertices"], 0);
  EXPECT_TRUE(j["timings"].contains("read"));
  EXPECT_EQ(j["mesh"]["sharp_edges"], 12) << "the cube's edges";
  EXPECT_EQ(j["mesh"]["crease_edges"], 12);
  EXPECT_NE(r.out.find("12 sharp edges"), std::string::npos) << r.out;
  // spot's sharp edges are mostly not creases (coarse ears and horns).
  std::string spot_args;  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "'" + string
  spot_args.append("info '").append(data_path("spot.obj").string()).append("' --json '");
  spot_args.append((dir_ / "r.json").string()).append("'");
  const CliRun spot = quadify(spot_args, dir_);
  ASSERT_EQ(spot.exit_code, 0) << spot.err;
  const auto s = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(s["mesh"]["sharp_edges"], 73);
  EXPECT_LT(s["mesh"]["crease_edges"].get<int>(), 20);
}

TEST_F(CliTest, MissingFileIsBadInputNamingTheFileWithoutReport) {
  const fs::path missing = dir_ / "does_not_exist.obj";
  const CliRun r = quadify("info '" + missing.string() + "' --json '" + (dir_ / "r.json").string() + "'", dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("does_not_exist.obj"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one error line expected:\n" << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "r.json"));
}

TEST_F(CliTest, TruncatedBinaryStlIsBadInput) {
  std::string bytes(80, ' ');
  const unsigned n = 1000;  // announces 1000 triangles, holds none
  bytes.append(reinterpret_cast<const char*>(&n), 4);
  write_text(dir_ / "trunc.stl", bytes);
  const CliRun r = quadify("info '" + (dir_ / "trunc.stl").string() + "' --json '" + (dir_ / "r.json").string() + "'", dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("trunc.stl"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "r.json"));
}

TEST_F(CliTest, UnwritableReportIsInternalFailure) {
  write_text(dir_ / "cube.obj", kCubeTriObj);
  const CliRun r = quadify("info '" + (dir_ / "cube.obj").string() + "' --json '" + (dir_ / "no/such/dir/r.json").string() + "'", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("r.json"), std::string::npos) << r.err;
}

// An output folder that does not exist is reported before any work (the remesh would otherwise
// run to the end first), naming the file; the report beside it is not written either.
TEST_F(CliTest, UnwritableOutputFailsBeforeTheRun) {
  const std::string spot = data_path("spot.obj").string();
  const fs::path out = dir_ / "no/such/dir/q.obj";
  for (const std::string sub : {"", "param "}) {
    const CliRun r = quadify(sub + "'" + spot + "' -o '" + out.string() + "' --json '" +
                                 (dir_ / "r.json").string() + "'",
                             dir_);
    EXPECT_EQ(r.exit_code, 1) << sub;
    EXPECT_NE(r.err.find(out.string() + ": cannot create file"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line, no stage ran: " << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "r.json"));
  }
}

TEST_F(CliTest, CheckQuadCubeAgainstTriangleCube) {
  write_text(dir_ / "cube.obj", kCubeTriObj);
  write_text(dir_ / "quads.obj", kCubeQuadObj);
  const CliRun r = quadify("check '" + (dir_ / "quads.obj").string() + "' --reference '" + (dir_ / "cube.obj").string() +
                            "' --samples 5000 --json '" + (dir_ / "c.json").string() + "'",
                        dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "c.json"))["check"];
  EXPECT_EQ(j["kind"], "quad");
  EXPECT_EQ(j["faces"], 6);
  EXPECT_EQ(j["non_quads"], 0);
  EXPECT_EQ(j["irregular_vertices"], 8);
  EXPECT_EQ(j["flipped_quads"], 0);
  EXPECT_EQ(j["manifold"], true);
  EXPECT_EQ(j["genus"], 0);
  EXPECT_LT(j["hausdorff_sym"].get<double>(), 1e-9);
  EXPECT_NEAR(j["feature_capture"].get<double>(), 1.0, 1e-9);
}

TEST_F(CliTest, CheckUvMapOfIsometricStrip) {
  write_text(dir_ / "strip.obj", kStripUvObj);
  const CliRun r = quadify("check '" + (dir_ / "strip.obj").string() + "' --json '" + (dir_ / "c.json").string() + "'", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "c.json"))["check"];
  EXPECT_EQ(j["kind"], "uv");
  EXPECT_EQ(j["flipped"], 0);
  EXPECT_NEAR(j["tau"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(j["seam_edges"], 0);
  EXPECT_EQ(j["cones"], 0);
  EXPECT_LT(j["gauss_bonnet_error"].get<double>(), 1e-9);
}

TEST_F(CliTest, CheckWithMissingReferenceIsBadInput) {
  write_text(dir_ / "quads.obj", kCubeQuadObj);
  const CliRun r = quadify("check '" + (dir_ / "quads.obj").string() + "' --reference '" + (dir_ / "nope.stl").string() + "'", dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nope.stl"), std::string::npos) << r.err;
}

}  // namespace

namespace {

TEST_F(CliTest, ParamWritesSeamlessFlipFreeUvObj) {
  const fs::path out = dir_ / "sphere_uv.obj";
  const CliRun r = quadify("param '" + data_path("sphere.obj").string() + "' -o '" + out.string() + "' --json '" +
                               (dir_ / "p.json").string() + "'",
                           dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(out));
  // Measure the written file independently of the param report.
  const CliRun c = quadify("check '" + out.string() + "' --json '" + (dir_ / "c.json").string() + "'", dir_);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "c.json"))["check"];
  EXPECT_EQ(j["kind"], "uv");
  EXPECT_EQ(j["flipped"], 0);
  EXPECT_EQ(j["matchings_integer"], true);
  EXPECT_EQ(j["cone_indices_integer"], true);
  EXPECT_EQ(j["cone_index_sum"], 8) << "sphere: cone indices (quarter turns) sum to 4*chi";
  EXPECT_LT(j["gauss_bonnet_error"].get<double>(), 1e-9);
  EXPECT_LT(j["seam_residual_abs"].get<double>(), 1e-9 * 2.0);  // sphere.obj has diagonal ~2√3
  EXPECT_LT(j["tau"].get<double>(), 3.0);
}

// --feature-mode after (Alg. 3): the cube's edges are aligned softly, within 1e-5, and the
// written map is still seamless and flip-free; a mode that does not exist is bad input.
TEST_F(CliTest, SoftFeatureModeAlignsWithinTolerance) {
  write_text(dir_ / "cube.obj", kCubeTriObj);
  std::string args;
  args.append("param '").append((dir_ / "cube.obj").string()).append("' -o '");
  args.append((dir_ / "c_uv.obj").string()).append("' --json '").append((dir_ / "p.json").string());
  const CliRun r = quadify(args + "' --feature-mode after", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto f = nlohmann::json::parse(slurp(dir_ / "p.json"))["param"]["features"];
  EXPECT_EQ(f["mode"], "after");
  EXPECT_EQ(f["aligned"], 12);
  EXPECT_EQ(f["disabled"], 0);
  EXPECT_EQ(f["disabled_by_tau"].get<int>() + f["disabled_by_wedge"].get<int>() + f["disabled_by_flips"].get<int>(), 0);
  EXPECT_EQ(f["components_without_features"], 0);
  EXPECT_EQ(f["fallback_reason"], "");
  EXPECT_LE(f["alignment_error"].get<double>(), 1e-5);
  const CliRun c = quadify("check '" + (dir_ / "c_uv.obj").string() + "' --json '" + (dir_ / "c.json").string() + "'", dir_);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "c.json"))["check"];
  EXPECT_EQ(j["flipped"], 0);
  EXPECT_EQ(j["cone_index_sum"], 8);
  EXPECT_LT(j["seam_residual_abs"].get<double>(), 1e-9);
  const CliRun bad = quadify(args + "' --feature-mode sometimes", dir_);
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
}

// The default command end to end, measured by `check --reference` on the written file.
TEST_F(CliTest, RemeshWritesManifoldPureQuadMesh) {
  const fs::path out = dir_ / "spot_quads.obj";
  const std::string spot = data_path("spot.obj").string();
  std::string args;  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "'" + string
  args.append("'").append(spot).append("' -o '").append(out.string());
  args.append("' --target-faces 1500 --json '").append((dir_ / "r.json").string()).append("'");
  const CliRun r = quadify(args, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(out));
  const auto report = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(report["command"], "remesh");
  EXPECT_EQ(report["quantize"]["flipped"], 0);
  // The count adjustment is on by default below 60,000 triangles: spot's rounding gives 1,585
  // quads for 1,500 (see RemeshCountAdjustmentsMoveTheCountToTheTarget).
  EXPECT_GT(report["quantize"]["count_adjustments"].get<int>(), 0) << "on by default";
  EXPECT_EQ(report["quantize"]["count_adjustment_undone"], false);
  EXPECT_NEAR(report["quads"]["faces"].get<int>(), 1500, 0.005 * 1500);
  // Where the parametrization's time went, as `quadify param` reports it.
  const auto& profile = report["param"]["profile"];
  EXPECT_GT(profile["seconds_factorize"].get<double>(), 0);
  EXPECT_LE(profile["seconds_factorize"].get<double>(), report["param"]["seconds"].get<double>());
  EXPECT_GT(profile["transition_iterations"].get<int>() + profile["tau_iterations"].get<int>(), 0);
  const CliRun c = quadify("check '" + out.string() + "' --reference '" + spot + "' --json '" +
                               (dir_ / "c.json").string() + "'",
                           dir_);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "c.json"))["check"];
  EXPECT_EQ(j["kind"], "quad");
  EXPECT_EQ(j["non_quads"], 0);
  EXPECT_EQ(j["manifold"], true);
  EXPECT_EQ(j["components"], 1);
  EXPECT_EQ(j["euler_characteristic"], 2) << "spot is a sphere";
  EXPECT_NEAR(j["faces"].get<int>(), 1500, 150) << "face count within 10% of the target";
  // About 1% of the diagonal at this coarse density (0.66% at 5,000 quads).
  EXPECT_LT(j["hausdorff_sym"].get<double>(), 0.02);
  // The summary line; spot's few creases are too short to align (stray), so no feature capture.
  EXPECT_NE(r.out.find(" -> "), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("feature capture"), std::string::npos) << r.out;
}

// A boundary the quads do not follow (the disk with --no-boundary-alignment) cuts the grid into
// pentagons and triangles; by default they become quads (midpoints on boundary edges or along
// paths of faces, merges, splits), and the outline and distance stay; --no-pure-quads keeps them.
TEST_F(CliTest, RemeshMakesPureQuadsWhereTheGridMeetsAnUnalignedBoundary) {
  const fs::path disk = data_path("disk.obj");
  const nlohmann::json kept = remesh_report(disk, 300, "--no-boundary-alignment --no-pure-quads");
  const nlohmann::json pure = remesh_report(disk, 300, "--no-boundary-alignment");
  EXPECT_GT(kept["quads"]["non_quads"].get<int>(), 10);
  EXPECT_FALSE(kept.contains("pure_quads"));
  EXPECT_EQ(pure["quads"]["non_quads"], 0);
  EXPECT_EQ(pure["pure_quads"]["non_quads_before"], kept["quads"]["non_quads"]);
  EXPECT_EQ(pure["pure_quads"]["non_quads_after"], 0);
  EXPECT_EQ(pure["quads"]["flipped_quads"], 0);
  EXPECT_EQ(pure["quads"]["manifold"], true);
  EXPECT_EQ(pure["quads"]["genus"], 0);
  EXPECT_GT(pure["quads"]["sj_min"].get<double>(), 0.1);
  EXPECT_LE(pure["quads"]["hausdorff_sym"].get<double>(), kept["quads"]["hausdorff_sym"].get<double>() * 1.05);
  EXPECT_NEAR(pure["quads"]["faces"].get<int>(), kept["quads"]["faces"].get<int>(),
              0.2 * kept["quads"]["faces"].get<int>());
}

// The summary names the feature capture where features were aligned, and a result farther from
// the input than 1% of its diagonal gets a warning that says what helps (the washer at 150 quads:
// about 1.5%); --quiet prints neither.
TEST_F(CliTest, RemeshSummaryGivesTheCaptureAndWarnsWhenCoarse) {
  const std::string washer = data_path("washer.obj").string();
  std::string args;
  args.append("'").append(washer).append("' -o '").append((dir_ / "w.obj").string());
  args.append("' --target-faces 150 --json '").append((dir_ / "w.json").string()).append("'");
  const CliRun r = quadify(args, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto quads = nlohmann::json::parse(slurp(dir_ / "w.json"))["quads"];
  const double hausdorff = quads["hausdorff_sym"].get<double>();
  EXPECT_GT(hausdorff, 0.01) << "the test needs a coarse result";
  EXPECT_NE(r.err.find("washer.obj: the quads leave the input by up to"), std::string::npos) << r.err;
  char capture[64];
  std::snprintf(capture, sizeof capture, "feature capture %.3f", quads["feature_capture"].get<double>());
  EXPECT_NE(r.out.find(capture), std::string::npos) << r.out;
  const CliRun quiet = quadify(args + " --quiet", dir_);
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.err.find("leave the input"), std::string::npos) << quiet.err;
  EXPECT_EQ(quiet.out, "");
}

// --count-tolerance: spot at 500 quads comes out with 526 without it (the rounding grows the
// map), near 500 with it; the report counts the roundings run again.
TEST_F(CliTest, RemeshCountToleranceBringsTheCountToTheTarget) {
  // (The count adjustment, on by default, is left out: it would move both counts.)
  const nlohmann::json off = remesh_report(data_path("spot.obj"), 500, "--count-adjustments 0");
  EXPECT_EQ(off["quantize"]["count_corrections"], 0);
  const nlohmann::json on =
      remesh_report(data_path("spot.obj"), 500, "--count-tolerance 0.015 --count-adjustments 0");
  EXPECT_EQ(on["quads"]["non_quads"], 0);
  EXPECT_EQ(on["quads"]["flipped_quads"], 0);
  const int before = off["quads"]["faces"].get<int>(), after = on["quads"]["faces"].get<int>();
  EXPECT_LT(std::abs(after - 500), std::abs(before - 500)) << before << " -> " << after << " quads";
  EXPECT_LE(on["quantize"]["count_corrections_kept"].get<int>(),
            on["quantize"]["count_corrections"].get<int>());
  // Without a count to aim at (an edge length) it is refused, not ignored, as is the count
  // adjustment.
  for (const char* option : {"--count-tolerance 0.015", "--count-adjustments 8"}) {
    std::string args;
    args.append("'").append(data_path("spot.obj").string()).append("' -o '").append((dir_ / "e.obj").string());
    args.append("' --edge-length 0.05 ").append(option);
    const CliRun bad = quadify(args, dir_);
    EXPECT_EQ(bad.exit_code, 2) << option << ": " << bad.err;
    EXPECT_NE(bad.err.find("--edge-length"), std::string::npos) << bad.err;
    EXPECT_FALSE(fs::exists(dir_ / "e.obj"));
  }
}

// --count-adjustments: spot at 1,500 quads comes out with 1,585 without it; moving a few integer
// unknowns by a unit each (the count known before each move) brings it within 0.5% of 1,500,
// flip-free, on the same rounding.
TEST_F(CliTest, RemeshCountAdjustmentsMoveTheCountToTheTarget) {
  const nlohmann::json off = remesh_report(data_path("spot.obj"), 1500, "--count-adjustments 0");
  EXPECT_EQ(off["quantize"]["count_adjustments"], 0);
  EXPECT_GT(std::abs(off["quads"]["faces"].get<int>() - 1500), 0.005 * 1500) << "nothing to adjust";
  const nlohmann::json on = remesh_report(data_path("spot.obj"), 1500, "--count-adjustments 8");
  EXPECT_GT(on["quantize"]["count_adjustments"].get<int>(), 0);
  EXPECT_LE(on["quantize"]["count_adjustments"].get<int>(), 8);
  EXPECT_EQ(on["quantize"]["count_corrections"], 0);
  EXPECT_NEAR(on["quads"]["faces"].get<int>(), 1500, 7);
  EXPECT_EQ(on["quads"]["non_quads"], 0);
  EXPECT_EQ(on["quads"]["flipped_quads"], 0);
  EXPECT_EQ(on["quads"]["manifold"], true);
}

// At 800 quads spot's map has 44 cones (36 more than a sphere needs, one per 22 quads): by default
// the matchings are rounded on a smoothed copy, which leaves fewer cones and still a valid mesh;
// --cone-scale 0 keeps the paper's map, which then also loses the cone pairs near over the surface
// (--surface-cone-pairs; the map the smoothed copy replaces skips them): fewer cones than 44.
TEST_F(CliTest, RemeshUsesCoarseConesWhereTheMapHasTooManyCones) {
  const std::string spot = data_path("spot.obj").string();
  auto run = [&](const std::string& extra) {
    std::string args;
    args.append("'").append(spot).append("' -o '").append((dir_ / "o.obj").string());
    args.append("' --target-faces 800 --samples 20000 --json '").append((dir_ / "r.json").string());
    args.append("' ").append(extra);
    const CliRun r = quadify(args, dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(slurp(dir_ / "r.json"));
  };
  const auto coarse = run("");
  EXPECT_EQ(coarse["param"]["coarse_cones"], true) << coarse["param"].dump();
  ASSERT_TRUE(coarse["param"]["fine_cones"].is_number()) << coarse["param"].dump();
  const int fine_cones = coarse["param"]["fine_cones"];
  EXPECT_LT(coarse["param"]["cones"].get<int>(), fine_cones);
  const auto q = coarse["quads"];
  EXPECT_EQ(q["non_quads"], 0);
  EXPECT_EQ(q["manifold"], true);
  EXPECT_EQ(q["flipped_quads"], 0);
  EXPECT_EQ(q["genus"], 0);
  EXPECT_LT(q["irregular_vertices"].get<int>(), fine_cones);
  EXPECT_NEAR(q["faces"].get<int>(), 800, 80);
  EXPECT_LT(q["hausdorff_sym"].get<double>(), 0.02);
  const auto plain = run("--cone-scale 0");
  EXPECT_EQ(plain["param"]["coarse_cones"], false);
  EXPECT_TRUE(plain["param"]["fine_cones"].is_null());
  EXPECT_LT(plain["param"]["cones"].get<int>(), fine_cones);
  EXPECT_GT(plain["param"]["surface_pairs"].get<int>(), 0);
  const auto seams_only = run("--cone-scale 0 --surface-cone-pairs off");
  EXPECT_EQ(seams_only["param"]["cones"], fine_cones);
  EXPECT_EQ(seams_only["param"]["surface_pairs"], 0);
  EXPECT_EQ(seams_only["param"]["far_pairs"], 0);
  EXPECT_LE(plain["param"]["far_pairs"].get<int>(), plain["param"]["surface_pairs"].get<int>());
  std::string bad_args;
  bad_args.append("'").append(spot).append("' -o o.obj --cone-scale sometimes");
  const CliRun bad = quadify(bad_args, dir_);
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--cone-scale: 'sometimes' is neither a non-negative number nor auto"), std::string::npos)
      << bad.err;
  EXPECT_EQ(bad.err.find("179769"), std::string::npos) << "no DBL_MAX range: " << bad.err;
  std::string bad_pairs;
  bad_pairs.append("'").append(spot).append("' -o o.obj --surface-cone-pairs sometimes");
  const CliRun bad_pairs_run = quadify(bad_pairs, dir_);
  EXPECT_EQ(bad_pairs_run.exit_code, 2) << bad_pairs_run.err;
  EXPECT_NE(bad_pairs_run.err.find("--surface-cone-pairs"), std::string::npos) << bad_pairs_run.err;
}

// A run that fails after the input was read writes no mesh, but its report says what failed and
// has the figures of the stages that ran.
TEST_F(CliTest, FailedRemeshStillWritesTheReport) {
  const fs::path out = dir_ / "o.obj";
  const std::string spot = data_path("spot.obj").string();
  std::string args;
  args.append("'").append(spot).append("' -o '").append(out.string());
  args.append("' --cone-scale 0 --time-budget 0.001 --json '").append((dir_ / "r.json").string()).append("'");
  const CliRun r = quadify(args, dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("spot.obj"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  ASSERT_TRUE(fs::exists(dir_ / "r.json"));
  const auto report = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(report["status"], "error");
  EXPECT_NE(report["error"].get<std::string>().find("time budget"), std::string::npos) << report["error"];
  EXPECT_FALSE(report.contains("output"));
  EXPECT_GT(report["param"]["cones"].get<int>(), 0);
  EXPECT_GT(report["quantize"]["integer_dofs"].get<int>(), 0);
  EXPECT_FALSE(report.contains("quads"));
}

// The box's creases are detected at the default 40° and end up as quad edges; the report says so.
TEST_F(CliTest, RemeshCapturesTheBoxCreases) {
  const fs::path out = dir_ / "box_quads.obj";
  const std::string box = data_path("box.obj").string();
  std::string args;
  args.append("'").append(box).append("' -o '").append(out.string());
  args.append("' --target-faces 200 --json '").append((dir_ / "r.json").string()).append("'");
  const CliRun r = quadify(args, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(report["param"]["features"]["detected_sharp_edges"], 72);
  EXPECT_EQ(report["param"]["features"]["sharp_edges_not_creases"], 0) << "flat sides: all creases";
  EXPECT_EQ(report["param"]["features"]["aligned"], 72);
  EXPECT_EQ(report["param"]["features"]["stray_creases"], 0) << "one network of 72 edges: not stray";
  EXPECT_EQ(report["quantize"]["features_dropped"], false);
  EXPECT_GE(report["quads"]["feature_capture"].get<double>(), 0.999);
  EXPECT_EQ(report["quads"]["flipped_quads"], 0);
  EXPECT_EQ(report["quads"]["non_quads"], 0);
  // Every crease is on quad edges: nothing to snap (with or without --no-feature-snap).
  EXPECT_EQ(report["relax"]["snapped"], 0);
  const CliRun off = quadify(args + " --no-feature-snap", dir_);
  ASSERT_EQ(off.exit_code, 0) << off.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "r.json"))["relax"]["snapped"], 0);
  EXPECT_EQ(report["param"]["features"]["curve_labels"], false);
  // The box's twelve edges are straight curves: labeled as whole curves they are all kept too.
  std::string curve_args = args;
  curve_args.append(" --feature-curve-labels");
  const CliRun curves = quadify(curve_args, dir_);
  ASSERT_EQ(curves.exit_code, 0) << curves.err;
  const auto with_curves = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(with_curves["param"]["features"]["curve_labels"], true);
  EXPECT_EQ(with_curves["param"]["features"]["aligned"], 72);
  EXPECT_GE(with_curves["quads"]["feature_capture"].get<double>(), 0.999);
  EXPECT_EQ(with_curves["quads"]["flipped_quads"], 0);
  EXPECT_EQ(with_curves["quads"]["non_quads"], 0);
}

// --map writes the integer-seamless triangle map the quads come from: `quadify check` reads it as
// a flip-free seamless map with integer matchings, 8 cones of index 1 at the box's corners, and a
// UV area equal to the number of quads (each quad is a unit square of the grid).
TEST_F(CliTest, RemeshWritesTheIntegerMapOnRequest) {
  const fs::path map = dir_ / "box_map.obj";
  const auto report = remesh_report(data_path("box.obj"), 200, "--map '" + map.string() + "'");
  ASSERT_TRUE(fs::exists(map));
  EXPECT_EQ(report["map_output"], map.string());
  const CliRun c = quadify("check '" + map.string() + "' --json '" + (dir_ / "c.json").string() + "'", dir_);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "c.json"))["check"];
  EXPECT_EQ(j["kind"], "uv");
  EXPECT_EQ(j["flipped"], 0);
  EXPECT_EQ(j["matchings_integer"], true);
  EXPECT_EQ(j["seam_residual_abs"].get<double>(), 0.0) << "integer-seamless to the bit";
  EXPECT_EQ(j["cones"], 8);
  EXPECT_EQ(j["cone_index_sum"], 8);
  const quadify::core::PolyMesh read = quadify::core::read_mesh(map);
  ASSERT_TRUE(read.has_uv());
  double uv_area = 0;
  for (int f = 0; f < read.n_faces(); ++f) {
    const Eigen::Vector2d a = read.uv.row(read.face_uv[read.face_corner(f, 0)]);
    const Eigen::Vector2d b = read.uv.row(read.face_uv[read.face_corner(f, 1)]);
    const Eigen::Vector2d c = read.uv.row(read.face_uv[read.face_corner(f, 2)]);
    uv_area += 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  }
  EXPECT_NEAR(uv_area, report["quads"]["faces"].get<double>(), 1e-6);
  // Without --map no map is written, and an unwritable map path fails before the run.
  const fs::path bad = dir_ / "missing_dir" / "m.obj";
  std::string args;  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "'" + string
  args.append("'").append(data_path("box.obj").string()).append("' -o '").append((dir_ / "b.obj").string());
  args.append("' --quiet --map '").append(bad.string()).append("'");
  const CliRun r = quadify(args, dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(bad.string() + ": cannot create file"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "b.obj"));
}

// Creases that are all short (--min-crease-quads above the box's network, 72 edges in one
// curve) are left out as stray fragments, and the remesher says so; at the default they are
// aligned (above).
TEST_F(CliTest, RemeshLeavesOutCreasesThatAreAllShort) {
  const std::string box = data_path("box.obj").string();
  std::string args;  // appended piecewise (GCC 12's false -Wrestrict on "'" + string)
  args.append("'").append(box).append("' -o '").append((dir_ / "o.obj").string());
  args.append("' --target-faces 200 --min-crease-quads 1000 --json '").append((dir_ / "r.json").string()).append("'");
  const CliRun r = quadify(args, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("the 72 crease edges form only short curves"), std::string::npos) << r.err;
  const auto report = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(report["param"]["features"]["stray_creases"], 72);
  EXPECT_EQ(report["param"]["features"]["feature_edges"], 0);
  EXPECT_EQ(report["param"]["features"]["aligned"], 0);
  EXPECT_EQ(report["quads"]["flipped_quads"], 0);
  EXPECT_EQ(report["quads"]["non_quads"], 0);
}

// The torus and a flat flake far from it, 0.02 wide, with n×n vertices: far smaller than a quad
// at 400 quads, so the flake gets no grid point.
fs::path write_torus_and_flake(const fs::path& dir, int n) {
  std::ostringstream obj;
  obj << slurp(data_path("torus.obj"));
  int nv = 0;
  {
    std::istringstream in(slurp(data_path("torus.obj")));
    for (std::string line; std::getline(in, line);)
      if (line.rfind("v ", 0) == 0) ++nv;
  }
  obj << "\n";
  const double step = 0.02 / (n - 1);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) obj << "v " << 10 + step * i << " " << step * j << " 0\n";
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = nv + 1 + n * j + i, b = a + 1, c = a + n, d = c + 1;
      obj << "f " << a << " " << b << " " << d << "\nf " << a << " " << d << " " << c << "\n";
    }
  const fs::path in = dir / ("torus_flake" + std::to_string(n) + ".obj");
  write_text(in, obj.str());
  return in;
}

// quadify on write_torus_and_flake(n) at 400 quads, the report in dir/r.json.
CliRun remesh_torus_and_flake(const fs::path& dir, int n) {
  const fs::path in = write_torus_and_flake(dir, n);
  std::string args;  // appended piecewise (GCC 12's false -Wrestrict on "'" + string)
  args.append("'").append(in.string()).append("' -o '").append((dir / "o.obj").string());
  args.append("' --target-faces 400 --json '").append((dir / "r.json").string()).append("'");
  return quadify(args, dir);
}

// A flake of 8 triangles is split into 24 quads of its own (three per triangle): the output
// keeps both components and stays pure quad.
TEST_F(CliTest, RemeshSplitsAComponentTooSmallForTheGrid) {
  const CliRun r = remesh_torus_and_flake(dir_, 3);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 component(s) too small for the quad grid"), std::string::npos) << r.err;
  const auto report = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(report["mesh"]["components"], 2);
  EXPECT_EQ(report["quads"]["components"], 2);
  EXPECT_EQ(report["quads"]["components_lost"], 0);
  EXPECT_EQ(report["quads"]["non_quads"], 0);
  EXPECT_EQ(report["quads"]["flipped_quads"], 0);
  EXPECT_EQ(report["small_components"]["replaced"], 1);
  EXPECT_EQ(report["small_components"]["quads_added"], 24);
  // The flake's own faces are no reason to refine the torus's grid.
  EXPECT_EQ(report["quantize"]["refinements"], 0);
}

// A flake of 162 triangles is more than the split takes (64): it gets no quads, and the
// remesher says so.
TEST_F(CliTest, RemeshWarnsAboutComponentsThatGetNoQuads) {
  const CliRun r = remesh_torus_and_flake(dir_, 10);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 of 2 components got no quads"), std::string::npos) << r.err;
  const auto report = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_EQ(report["mesh"]["components"], 2);
  EXPECT_EQ(report["quads"]["components"], 1);
  EXPECT_EQ(report["quads"]["components_lost"], 1);
  EXPECT_EQ(report["small_components"]["replaced"], 0);
}

// At 10 quads the torus's tube is about one quad around: the first grid has a loop of a single
// quad around it (quads that meet themselves, not manifold). The remesher quantizes again on a
// finer grid until the quads are manifold, says so, and counts the refinements in the report.
TEST_F(CliTest, RemeshRefinesAGridThatPinchesAHandle) {
  const std::string torus = data_path("torus.obj").string();
  const fs::path out = dir_ / "torus_quads.obj";
  std::string args;  // appended piecewise (GCC 12's false -Wrestrict on "'" + string)
  args.append("'").append(torus).append("' -o '").append(out.string());
  args.append("' --target-faces 10 --json '").append((dir_ / "r.json").string()).append("'");
  const CliRun r = quadify(args, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("are not manifold"), std::string::npos) << r.err;
  const auto report = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_GE(report["quantize"]["refinements"].get<int>(), 1);
  EXPECT_EQ(report["quads"]["manifold"], true);
  EXPECT_EQ(report["quads"]["genus"], 1) << "the handle is kept";
  EXPECT_EQ(report["quads"]["non_quads"], 0);
}

// tests/data/sphere.obj stretched to the ellipsoid (3, 1, 1), written to `path`.
void write_ellipsoid(const fs::path& path) {
  std::ostringstream obj;
  {
    std::istringstream in(slurp(data_path("sphere.obj")));
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("v ", 0) == 0) {
        std::istringstream ls(line.substr(2));
        double x = 0, y = 0, z = 0;
        ls >> x >> y >> z;
        obj << "v " << 3 * x << " " << y << " " << z << "\n";
      } else if (line.rfind("f ", 0) == 0) {
        obj << line << "\n";
      }
    }
  }
  write_text(path, obj.str());
}

// --adaptive: on an ellipsoid (3, 1, 1) the quads at the tips (curvature 3) come out smaller
// than around the middle (curvature 1), more so than the map's own distortion makes them;
// --anisotropic: quads around the middle stretch along the axis.
TEST_F(CliTest, AdaptiveSizingFollowsTheCurvature) {
  const fs::path in = dir_ / "ellipsoid.obj";
  write_ellipsoid(in);
  // Mean quad edge at the tips (|x| > 2.5) over the middle (|x| < 0.5), and in the middle, mean
  // edge along the long axis over around it.
  struct Shape {
    double tip_over_middle, along_over_around;
  };
  // The uniform map has no reason to follow the axis: around the middle its grid winds
  // helically at most targets (a cylinder's helical grid is as isometric as the straight one),
  // so only its tip-to-middle size ratio is used.
  auto remesh = [&](const std::string& extra, bool axis_aligned = true) {
    const fs::path out = dir_ / "q.obj";
    const auto report = remesh_report(in, 600, extra);
    EXPECT_EQ(report["quads"]["non_quads"], 0);
    EXPECT_EQ(report["quads"]["flipped_quads"], 0);
    EXPECT_NEAR(report["quads"]["faces"].get<int>(), 600, 60) << "the count stays near the target";
    std::vector<Eigen::Vector3d> v;
    double tip = 0, middle = 0, along = 0, around = 0;
    int n_tip = 0, n_middle = 0, n_along = 0, n_around = 0;
    std::istringstream qs(slurp(out));
    for (std::string line; std::getline(qs, line);) {
      std::istringstream ls(line.substr(std::min<size_t>(2, line.size())));
      if (line.rfind("v ", 0) == 0) {
        Eigen::Vector3d p;
        ls >> p.x() >> p.y() >> p.z();
        v.push_back(p);
      } else if (line.rfind("f ", 0) == 0) {
        std::vector<int> ids;
        for (std::string t; ls >> t;) ids.push_back(std::stoi(t.substr(0, t.find('/'))) - 1);
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        double len = 0;
        for (size_t i = 0; i < ids.size(); ++i) {
          const Eigen::Vector3d e = v[ids[(i + 1) % ids.size()]] - v[ids[i]];
          c += v[ids[i]] / static_cast<double>(ids.size());
          len += e.norm() / static_cast<double>(ids.size());
        }
        if (std::abs(c.x()) > 2.5) tip += len, ++n_tip;
        if (std::abs(c.x()) < 0.5) {
          middle += len, ++n_middle;
          for (size_t i = 0; i < ids.size(); ++i) {
            const Eigen::Vector3d e = v[ids[(i + 1) % ids.size()]] - v[ids[i]];
            if (std::abs(e.x()) > 0.8 * e.norm()) along += e.norm(), ++n_along;
            if (std::abs(e.x()) < 0.3 * e.norm()) around += e.norm(), ++n_around;
          }
        }
      }
    }
    EXPECT_GT(n_tip, 0);
    EXPECT_GT(n_middle, 0);
    if (axis_aligned) {
      EXPECT_GT(n_along, 0);
      EXPECT_GT(n_around, 0);
    }
    return Shape{(tip / std::max(n_tip, 1)) / (middle / std::max(n_middle, 1)),
                 (along / std::max(n_along, 1)) / (around / std::max(n_around, 1))};
  };
  const Shape uniform = remesh("", false);
  const Shape adaptive = remesh("--adaptive");
  EXPECT_LT(adaptive.tip_over_middle, uniform.tip_over_middle - 0.08)
      << "uniform " << uniform.tip_over_middle << ", adaptive " << adaptive.tip_over_middle;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "r.json"))["param"]["sizing"]["mode"], "adaptive");
  EXPECT_NEAR(adaptive.along_over_around, 1, 0.2) << "isotropic: square quads";
  // Anisotropic: around the middle the surface bends 9× less along x (curvature 1/9 against 1),
  // so quads stretch along x (up to the ratio 4 of the lengths: 2× along, ½× around).
  const Shape anisotropic = remesh("--adaptive --anisotropic");
  EXPECT_GT(anisotropic.along_over_around, 1.4) << "along/around " << anisotropic.along_over_around;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "r.json"))["param"]["sizing"]["mode"], "adaptive-anisotropic");
}

// bench/capture_breakdown.py reads the integer map (--map) and the quads: its capture is the
// report's (the same sharp edges, samples and tolerance; the washer needs no repair), the length
// it counts as missed adds up to what the capture leaves, and the washer's rims lie on integer
// iso-lines. A map without UVs is refused with a message naming the file.
TEST_F(CliTest, CaptureBreakdownAccountsForTheMissedFeatureLength) {
  if (quadify::test::exit_code_of(std::system("python3 --version >/dev/null 2>&1")) != 0)
    GTEST_SKIP() << "python3 not found";
  const fs::path map = dir_ / "washer_map.obj";
  const auto report = remesh_report(data_path("washer.obj"), 300, "--map '" + map.string() + "'");
  ASSERT_TRUE(fs::exists(map));
  const fs::path script =
      data_path("washer.obj").parent_path().parent_path().parent_path() / "bench" / "capture_breakdown.py";
  ASSERT_TRUE(fs::exists(script)) << script;
  auto run = [&](const fs::path& map_file, const fs::path& json) {
    std::string cmd = "python3 ";
    cmd.append(quadify::test::shell_quoted(script)).append(" ").append(quadify::test::shell_quoted(map_file));
    cmd.append(" ").append(quadify::test::shell_quoted(dir_ / "q.obj")).append(" --json ");
    cmd.append(quadify::test::shell_quoted(json)).append(" >'").append((dir_ / "b.out").string());
    cmd.append("' 2>'").append((dir_ / "b.err").string()).append("'");
    return quadify::test::exit_code_of(std::system(cmd.c_str()));
  };
  ASSERT_EQ(run(map, dir_ / "b.json"), 0) << slurp(dir_ / "b.err");
  const auto b = nlohmann::json::parse(slurp(dir_ / "b.json"));
  EXPECT_GT(b["sharp_edges"].get<int>(), 0);
  EXPECT_NEAR(b["capture"].get<double>(), report["quads"]["feature_capture"].get<double>(), 1e-9);
  double missed = 0, length = 0;
  for (const auto& [kind, share] : b["missed"].items()) missed += share.get<double>();
  for (const auto& [kind, share] : b["length"].items()) length += share.get<double>();
  EXPECT_NEAR(missed, 1 - b["capture"].get<double>(), 1e-9);
  EXPECT_NEAR(length, 1, 1e-9);
  EXPECT_GT(b["length"]["aligned"].get<double>(), 0.9) << "the rims on integer iso-lines";
  // The rims are circles about a dozen quad edges around: what the quads miss of them is mostly
  // cut off by the chords (a chord of a twelfth of the inner rim misses it by 3.4% of its radius,
  // above 0.1% of the diagonal).
  const auto& m = b["missed"];
  EXPECT_GT(m["chord"].get<double>(), m["unaligned"].get<double>() + m["parallel"].get<double>() +
                                          m["chain end"].get<double>() + m["other"].get<double>());
  // The quads as the map: no UVs.
  EXPECT_EQ(run(dir_ / "q.obj", dir_ / "bad.json"), 1);
  EXPECT_NE(slurp(dir_ / "b.err").find("q.obj: no per-corner UVs"), std::string::npos) << slurp(dir_ / "b.err");
  EXPECT_FALSE(fs::exists(dir_ / "bad.json"));
}

// Feature-loop sizing: the washer's inner rims (circles of radius 0.1, 0.63 long) are about
// 8 quad edges around at 300 quads; by default the remesher gives them about 12, and
// --no-feature-sizing keeps the size uniform.
TEST_F(CliTest, RemeshGivesShortFeatureLoopsMoreQuads) {
  auto remesh = [&](const std::string& extra) {
    const fs::path out = dir_ / "q.obj";
    const auto report = remesh_report(data_path("washer.obj"), 300, extra);
    EXPECT_EQ(report["quads"]["non_quads"], 0);
    EXPECT_EQ(report["quads"]["flipped_quads"], 0);
    EXPECT_EQ(report["quads"]["manifold"], true);
    EXPECT_EQ(report["quads"]["genus"], 1);
    EXPECT_NEAR(report["quads"]["faces"].get<int>(), 300, 30) << "the count stays near the target";
    // Quad vertices on the inner top rim (r = 0.1, z = 0.1).
    int on_rim = 0;
    std::istringstream qs(slurp(out));
    for (std::string line; std::getline(qs, line);) {
      if (line.rfind("v ", 0) != 0) continue;
      std::istringstream ls(line.substr(2));
      Eigen::Vector3d p;
      ls >> p.x() >> p.y() >> p.z();
      if (std::abs(std::hypot(p.x(), p.y()) - 0.1) < 1e-3 && std::abs(p.z() - 0.1) < 1e-9) ++on_rim;
    }
    return std::make_pair(on_rim, report["param"]["sizing"]);
  };
  const auto [sized_rim, sized] = remesh("");
  EXPECT_EQ(sized["mode"], "feature-loops");
  EXPECT_GT(sized["sized_vertices"].get<int>(), 0);
  EXPECT_NEAR(sized["smallest_relative_edge"].get<double>(), 0.66, 0.1) << "about 8 of the 12 edges wanted";
  const auto [uniform_rim, uniform] = remesh("--no-feature-sizing");
  EXPECT_EQ(uniform["mode"], "uniform");
  EXPECT_GE(sized_rim, 11) << "quad vertices around the small hole's rim";
  EXPECT_GT(sized_rim, uniform_rim + 2) << "with " << sized_rim << ", without " << uniform_rim;
}

// --align-curvature (paper 6.1): around the middle of the ellipsoid the quad edges follow the
// principal directions (rings and meridians); without it they lie at about the random 22.5°.
TEST_F(CliTest, CurvatureAlignmentTurnsQuadsOntoPrincipalDirections) {
  const fs::path in = dir_ / "ellipsoid.obj";
  write_ellipsoid(in);
  auto remesh = [&](const std::string& extra) {
    const auto report = remesh_report(in, 600, extra);
    EXPECT_EQ(report["quads"]["non_quads"], 0);
    EXPECT_EQ(report["quads"]["flipped_quads"], 0);
    EXPECT_GT(report["quads"]["anisotropic_quads"].get<int>(), 100);
    return report;
  };
  const auto plain = remesh("");
  EXPECT_TRUE(plain["param"]["curvature_alignment"].is_null());
  const auto aligned = remesh("--align-curvature");
  const double before = plain["quads"]["principal_angle_mean"].get<double>();
  const double after = aligned["quads"]["principal_angle_mean"].get<double>();
  EXPECT_GT(before, 12);
  EXPECT_LT(after, 8) << "without the mode: " << before;
  const auto& ca = aligned["param"]["curvature_alignment"];
  EXPECT_GT(ca["faces"].get<int>(), 500);
  EXPECT_LT(ca["angle_deg"].get<double>(), ca["angle_initial_deg"].get<double>());
  std::string bad_args;  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "'" + string
  bad_args.append("'").append(in.string()).append("' -o '").append((dir_ / "b.obj").string());
  bad_args.append("' --align-curvature --curvature-weight -1");
  const CliRun bad = quadify(bad_args, dir_);
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_FALSE(fs::exists(dir_ / "b.obj"));
}

// A size field file: one positive number per input vertex; a bad line or count is bad input.
TEST_F(CliTest, SizeFieldFileIsReadOrRejectedNamingTheLine) {
  const fs::path cube = dir_ / "cube.obj";
  write_text(cube, kCubeTriObj);
  auto run = [&](const std::string& sizes) {
    write_text(dir_ / "sizes.txt", sizes);
    std::string args;
    args.append("'").append(cube.string()).append("' -o '").append((dir_ / "o.obj").string());
    args.append("' --target-faces 24 --size-field '").append((dir_ / "sizes.txt").string()).append("'");
    return quadify(args, dir_);
  };
  const CliRun word = run("1\n1\nbig\n");
  EXPECT_EQ(word.exit_code, 2);
  EXPECT_NE(word.err.find("sizes.txt: line 3"), std::string::npos) << word.err;
  const CliRun negative = run("1\n-1\n");
  EXPECT_EQ(negative.exit_code, 2);
  EXPECT_NE(negative.err.find("line 2: sizes must be positive"), std::string::npos) << negative.err;
  const CliRun count = run("1\n1\n1\n");
  EXPECT_EQ(count.exit_code, 2);
  EXPECT_NE(count.err.find("3 sizes for an input of 8 vertices"), std::string::npos) << count.err;
  EXPECT_FALSE(fs::exists(dir_ / "o.obj")) << "no output after bad input";
  const CliRun ok = run("# sizes\n1\n1\n1\n1\n2\n2\n2\n2\n");
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_TRUE(fs::exists(dir_ / "o.obj"));
}

// A feature-edge file with a malformed line or a pair that is not an edge is bad input, named.
TEST_F(CliTest, BadFeatureEdgeFileIsBadInputNamingTheLine) {
  const fs::path out = dir_ / "o.obj";
  const std::string box = data_path("box.obj").string();
  auto run_with = [&](const std::string& text) {
    write_text(dir_ / "edges.txt", text);
    std::string args;
    args.append("param '").append(box).append("' -o '").append(out.string());
    args.append("' --feature-edges '").append((dir_ / "edges.txt").string()).append("'");
    return quadify(args, dir_);
  };
  CliRun r = run_with("# box edge\n0 1\n0 1 2\n");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("edges.txt: line 3"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  r = run_with("0 209\n");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("is not an edge"), std::string::npos) << r.err;
  r = run_with("0 100000\n");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("out of range"), std::string::npos) << r.err;
  r = run_with("0 1\n");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(CliTest, RemeshOnBrokenInputWritesNothing) {
  write_text(dir_ / "bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n");  // truncated
  const fs::path out = dir_ / "out.glb";
  std::string args;
  args.append("'").append((dir_ / "bad.stl").string()).append("' -o '").append(out.string()).append("'");
  const CliRun r = quadify(args, dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("bad.stl"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// A path that spells a subcommand stays a path: only the first word names the subcommand.
TEST_F(CliTest, OutputNamedLikeASubcommandIsAPath) {
  std::string args;
  args.append("'").append((dir_ / "nope.obj").string()).append("' -o info --quiet");
  const CliRun r = quadify(args, dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("nope.obj"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "info"));
}

TEST_F(CliTest, ParamOnBrokenInputWritesNothing) {
  write_text(dir_ / "bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n");  // truncated
  const fs::path out = dir_ / "out.obj";
  const CliRun r = quadify("param '" + (dir_ / "bad.off").string() + "' -o '" + out.string() + "'", dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.off"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
}

}  // namespace
