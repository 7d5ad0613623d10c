// Example: read a mesh, repair it, print what repair did and the topology of the result.
//   example_repair_and_measure mesh.stl
#include <libcore/read_mesh.h>
#include <libcore/repair.h>
#include <libcore/topology.h>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s MESH\n", argv[0]);
    return 2;
  }
  try {
    const quadify::core::PolyMesh raw = quadify::core::read_mesh(argv[1]);
    const quadify::core::RepairResult repaired = quadify::core::repair_mesh(raw);
    if (!repaired.status.is_ok()) {
      std::fprintf(stderr, "%s: %s\n", argv[1], repaired.status.message().c_str());
      return 2;
    }
    const auto stats = quadify::core::topology_stats(repaired.mesh);
    std::printf("%d vertices, %d faces, %d components, genus %d, %d boundary loops; welded %d, dropped %d degenerate\n",
                stats.n_vertices, stats.n_faces, stats.n_components, stats.genus, stats.n_boundary_loops,
                repaired.report.welded_vertices, repaired.report.degenerate_faces_removed);
  } catch (const quadify::core::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
