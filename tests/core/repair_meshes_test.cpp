// Slow: every benchmark mesh of /work/shared/meshes read and repaired, one line per file.
#include <libcore/read_mesh.h>
#include <libcore/repair.h>
#include <libcore/topology.h>

#include <gtest/gtest.h>

#include "test_util.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace quadify::core {
namespace {

// Slow: every benchmark mesh is read and repaired; each ends ok or with a named InvalidInput.
TEST(RepairSlow, EveryBenchmarkMesh) {
  const auto dir = test::shared_meshes_dir();
  if (dir.empty()) GTEST_SKIP() << "no benchmark meshes";
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (format_from_extension(entry.path()) != MeshFormat::kUnknown) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const auto& path : files) {
    const auto t0 = std::chrono::steady_clock::now();
    PolyMesh in;
    try {
      in = read_mesh(path);
    } catch (const InputError& e) {
      std::printf("%-28s read error: %s\n", path.filename().c_str(), e.what());
      continue;
    }
    const RepairResult r = repair_mesh(in);
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const RepairReport& p = r.report;
    if (!r.status.is_ok()) {
      EXPECT_EQ(r.status.code(), StatusCode::kInvalidInput) << path;
      std::printf("%-28s %s\n", path.filename().c_str(), r.status.to_string().c_str());
      continue;
    }
    const TopologyStats s = topology_stats(r.mesh);
    EXPECT_TRUE(s.is_manifold()) << path;
    EXPECT_NO_THROW((void)build_edge_topology(r.mesh)) << path;
    std::printf("%-28s V %d->%d F %d->%d weld %d degen %d dup %d invalid %d unref %d flip %d "
                "fins %d nmE %d nmV %d | comps %d loops %d chi %d genus %d | %.2fs\n",
                path.filename().c_str(), p.input_vertices, p.output_vertices, p.input_faces,
                p.output_faces, p.welded_vertices, p.degenerate_faces_removed,
                p.duplicate_faces_removed, p.invalid_faces_removed,
                p.unreferenced_vertices_removed, p.faces_reoriented, p.fin_faces_removed, p.nonmanifold_edges_split,
                p.nonmanifold_vertices_split, s.n_components, s.n_boundary_loops,
                s.euler_characteristic, s.genus, sec);
    if (path.filename() == "fandisk_degenerate.obj") {
      EXPECT_EQ(s.n_boundary_loops, 0) << "fandisk_degenerate must stay closed";
      EXPECT_EQ(s.genus, 0);
      EXPECT_EQ(s.n_components, 1);
    }
    // Fins (flaps and stray triangles on non-manifold edges) are removed, not detached: the
    // surfaces stay closed and whole.
    if (path.filename() == "dragon.obj" || path.filename() == "crank.obj") {
      EXPECT_GT(p.fin_faces_removed, 0) << path;
      EXPECT_EQ(s.n_boundary_loops, 0) << path;
      EXPECT_EQ(s.n_components, 1) << path;
    }
    if (path.filename() == "spot_nonmanifold.obj") {
      EXPECT_EQ(p.fin_faces_removed, 3);
      EXPECT_EQ(s.n_boundary_loops, 0);
      EXPECT_EQ(s.n_components, 2) << "spot and the tetrahedron at its non-manifold vertex";
    }
  }
}

}  // namespace
}  // namespace quadify::core
