// End-to-end param → quantize → extract on real meshes (slow): tests/data/spot.obj and the
// benchmark meshes of ../shared/meshes (skipped when absent). Prints one table row per run.
#include <gtest/gtest.h>
#include <libcore/read_mesh.h>

#include <cstdio>
#include <filesystem>

#include "quantize_test_util.h"
#include "test_util.h"

namespace quadify {
namespace {

constexpr double kQuadCountTolerance = 0.10;  // fraction of the target (see quantize_test.cpp)

void run_and_report(const std::string& name, const core::TriMesh& mesh, int target) {
  const test::PipelineRun run = test::run_pipeline(mesh, target);
  ASSERT_TRUE(run.param.status.is_ok()) << name << ": " << run.param.status.to_string();
  ASSERT_TRUE(run.quantized.status.is_ok()) << name << ": " << run.quantized.status.to_string();
  EXPECT_EQ(test::integer_seamless_violation(run.quantized.uv), "") << name;
  EXPECT_EQ(run.quantized.stats.n_flipped, 0) << name;
  ASSERT_TRUE(run.quads.status.is_ok()) << name << ": " << run.quads.status.to_string();
  const quadex::QuadMetrics qm = quadex::compute_quad_metrics(run.quads.quads, &mesh);
  const quantize::QuantizeStats& st = run.quantized.stats;
  std::printf("| %s | %d | %d | %d | %d | %d | %.2e | %d | %d | %.1f | %.1f | %.1f |\n",
              name.c_str(), target, qm.n_faces, qm.n_non_quads, qm.n_irregular, qm.n_flipped,
              qm.hausdorff_sym, st.n_reverted, st.n_scale_retries, run.seconds_param,
              run.seconds_quantize, run.seconds_extract);
  std::fflush(stdout);
  EXPECT_EQ(qm.n_non_quads, 0) << name;
  EXPECT_TRUE(qm.manifold) << name;
  EXPECT_EQ(qm.euler_characteristic, core::topology_stats(mesh).euler_characteristic) << name;
  // Near-scale restarts stay within the tolerance; a refined grid would not.
  EXPECT_NEAR(qm.n_faces, target, kQuadCountTolerance * target) << name;
}

TEST(QuantizeBenchmark, SpotFromTestData) {
  const core::TriMesh mesh = core::to_trimesh(core::read_mesh(test::data_path("spot.obj")));
  run_and_report("spot(test)", mesh, 2000);
}

TEST(QuantizeBenchmark, SharedMeshes) {
  const std::filesystem::path dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "no benchmark meshes";
  std::printf(
      "| mesh | target | quads | non-quads | irregular | flipped | Hausdorff | reverted "
      "| retries | s param | s quantize | s extract |\n");
  const std::pair<const char*, int> runs[] = {
      {"spot", 1000},      {"spot", 5000}, {"spot", 20000},   {"knot1", 5000},
      {"fertility", 5000}, {"elk", 5000},  {"fandisk", 5000}, {"rocker-arm", 5000}};
  for (const auto& [name, target] : runs) {
    const std::filesystem::path path = dir / (std::string(name) + ".obj");
    if (!std::filesystem::exists(path)) {
      ADD_FAILURE() << "missing benchmark mesh " << path;
      continue;
    }
    SCOPED_TRACE(name);
    run_and_report(name, core::to_trimesh(core::read_mesh(path)), target);
  }
}

}  // namespace
}  // namespace quadify
