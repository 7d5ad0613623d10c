// Reads a mesh with an installed quadify and prints its element counts and topology:
//   quadify_consumer <mesh file>
// Output (one line): "<V> vertices <F> faces <Q> quads chi <χ> genus <g>"
#include <libcore/mesh.h>
#include <libcore/read_mesh.h>
#include <libcore/topology.h>
#include <libquadex/quad_metrics.h>

#include <exception>
#include <iostream>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: quadify_consumer <mesh file>\n";
    return 2;
  }
  try {
    const quadify::core::PolyMesh mesh = quadify::core::read_mesh(argv[1]);
    const quadify::core::TopologyStats topo = quadify::core::topology_stats(quadify::core::to_trimesh(mesh));
    quadify::quadex::QuadMetricsOptions options;
    options.hausdorff_samples = 0;  // no reference mesh: only counts are needed
    const quadify::quadex::QuadMetrics metrics = quadify::quadex::compute_quad_metrics(mesh, nullptr, options);
    const auto quads = metrics.faces_by_degree.find(4);
    std::cout << mesh.n_vertices() << " vertices " << mesh.n_faces() << " faces "
              << (quads == metrics.faces_by_degree.end() ? 0 : quads->second) << " quads chi "
              << topo.euler_characteristic << " genus " << topo.genus << "\n";
  } catch (const std::exception& e) {
    std::cerr << "quadify_consumer: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
