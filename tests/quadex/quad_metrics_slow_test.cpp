#include <libquadex/quad_metrics.h>

#include <libcore/read_mesh.h>

#include <gtest/gtest.h>

#include "test_util.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace quadify::quadex {
namespace {

// Spot by QuadriFlow against the input, beside ../shared/peers/results.tsv (same definitions:
// 100,000 area samples per side plus all vertices).
TEST(QuadMetricsSlow, SpotQuadriflowMatchesPeerTable) {
  const std::filesystem::path meshes = test::shared_meshes_dir();
  if (meshes.empty()) GTEST_SKIP() << "no shared meshes";
  const std::filesystem::path peers = meshes.parent_path() / "peers";
  const std::filesystem::path quad_path = peers / "quadriflow" / "spot.obj";
  const std::filesystem::path table_path = peers / "results.tsv";
  if (!std::filesystem::exists(quad_path) || !std::filesystem::exists(table_path) ||
      !std::filesystem::exists(meshes / "spot.obj"))
    GTEST_SKIP() << "no peer results";
  // The table's row: mesh peer status ... irregular(7) flipped(8) ... hausdorff_sym(15) mean(16).
  std::ifstream table(table_path);
  std::string line;
  std::vector<std::string> row;
  while (std::getline(table, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, '\t');) cells.push_back(cell);
    if (cells.size() > 16 && cells[0] == "spot" && cells[1] == "quadriflow") row = cells;
  }
  ASSERT_FALSE(row.empty()) << "no spot/quadriflow row in " << table_path;
  const int peer_irregular = std::stoi(row[7]), peer_flipped = std::stoi(row[8]);
  const double peer_sj_min = std::stod(row[9]), peer_sj_mean = std::stod(row[10]);
  const double peer_angle_dev = std::stod(row[11]), peer_cv = std::stod(row[12]);
  const double peer_hausdorff = std::stod(row[15]), peer_mean = std::stod(row[16]);

  const core::PolyMesh quads = core::read_mesh(quad_path);
  const core::TriMesh reference = core::to_trimesh(core::read_mesh(meshes / "spot.obj"));
  const auto start = std::chrono::steady_clock::now();
  const QuadMetrics m = compute_quad_metrics(quads, &reference);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  RecordProperty("seconds", std::to_string(seconds));
  std::cout << "spot/quadriflow: ours vs peers: irregular " << m.n_irregular << " / " << peer_irregular
            << ", flipped " << m.n_flipped << " / " << peer_flipped << ", sj_min " << m.sj_min << " / "
            << peer_sj_min << ", sj_mean " << m.sj_mean << " / " << peer_sj_mean << ", angle_dev "
            << m.angle_dev_mean << " / " << peer_angle_dev << ", cv " << m.edge_len_cv << " / " << peer_cv
            << ", hausdorff " << m.hausdorff_sym << " / " << peer_hausdorff << ", mean " << m.mean_dist_sym
            << " / " << peer_mean << " (" << seconds << " s)\n";
  EXPECT_EQ(m.n_irregular, peer_irregular);
  EXPECT_EQ(m.n_flipped, peer_flipped);
  // Topology and per-quad quality are exact functions of the mesh: 4 significant digits as printed.
  constexpr double kPrintedRelTol = 1e-3;
  EXPECT_NEAR(m.sj_min, peer_sj_min, kPrintedRelTol * std::abs(peer_sj_min));
  EXPECT_NEAR(m.sj_mean, peer_sj_mean, kPrintedRelTol * std::abs(peer_sj_mean));
  EXPECT_NEAR(m.angle_dev_mean, peer_angle_dev, kPrintedRelTol * peer_angle_dev);
  EXPECT_NEAR(m.edge_len_cv, peer_cv, kPrintedRelTol * peer_cv);
  // Sampled distances: other random points give a slightly different max/mean.
  constexpr double kSampledRelTol = 0.05;
  EXPECT_NEAR(m.hausdorff_sym, peer_hausdorff, kSampledRelTol * peer_hausdorff);
  EXPECT_NEAR(m.mean_dist_sym, peer_mean, kSampledRelTol * peer_mean);
}

}  // namespace
}  // namespace quadify::quadex
