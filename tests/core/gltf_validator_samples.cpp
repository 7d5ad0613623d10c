// Writes the glTF samples that tests/core/validate_gltf.js checks with the Khronos validator:
// a quad mesh with UVs (seams split vertices), a triangle mesh without UVs, a polygon mesh with
// feature lines and an isolated vertex, each as .gltf (+ .bin) and .glb. Prints one file per line.
// Usage: gltf_validator_samples <output dir>
#include "writer_samples.h"

#include <libcore/status.h>
#include <libcore/write_mesh.h>

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

namespace {

quadify::core::PolyMesh pentagon_with_lines() {
  quadify::core::PolyMesh mesh;
  mesh.V.resize(7, 3);
  mesh.V << 0, 0, 0, 2, 0, 0, 3, 1.5, 0, 1, 3, 0, -1, 1.5, 0, 5, 5, 5,  // last but one: isolated
      1, 1.5, 1;                                                      // reached by a line only
  mesh.add_face({0, 1, 2, 3, 4});
  mesh.lines = {{0, 6}, {1, 0}};  // {1,0} repeats a polygon edge: must appear once
  return mesh;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: gltf_validator_samples <output dir>\n";
    return 2;
  }
  namespace fs = std::filesystem;
  const fs::path dir = argv[1];
  try {
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::vector<std::pair<std::string, quadify::core::PolyMesh>> samples = {
        {"cube quads uv", quadify::test::cube_quads(true)},  // a space: the .bin URI is escaped
        {"cube_quads", quadify::test::cube_quads(false)},
        {"octahedron", quadify::test::octahedron()},
        {"pentagon_lines", pentagon_with_lines()},
    };
    for (const auto& [name, mesh] : samples)
      for (const char* ext : {".gltf", ".glb"}) {
        const fs::path path = dir / (name + ext);
        quadify::core::write_mesh(path, mesh);
        std::cout << path.string() << "\n";
      }
  } catch (const std::exception& e) {
    std::cerr << "gltf_validator_samples: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
