// Small meshes built in code for the writer tests and the glTF validator samples.
#pragma once

#include <libcore/mesh.h>

namespace quadify::test {

// Unit cube as 6 CCW quads, vertex v at (v&1, (v>>1)&1, (v>>2)&1). With `with_uv`, face i is the
// grid cell (i%3, i/3) of a 3×2 atlas over [0,1]², so the UV table holds the 12 grid points and
// charts are cut apart along every cube edge that is not a shared cell border.
inline core::PolyMesh cube_quads(bool with_uv) {
  core::PolyMesh mesh;
  mesh.V.resize(8, 3);
  for (int v = 0; v < 8; ++v) mesh.V.row(v) << (v & 1), ((v >> 1) & 1), ((v >> 2) & 1);
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  if (with_uv) {
    mesh.uv.resize(12, 2);
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 4; ++i) mesh.uv.row(4 * j + i) << i / 3.0, j / 2.0;
  }
  for (int f = 0; f < 6; ++f) {
    std::vector<int> vertices(quads[f], quads[f] + 4), uvs;
    if (with_uv) {
      const int ci = f % 3, cj = f / 3;
      auto grid = [](int i, int j) { return 4 * j + i; };
      uvs = {grid(ci, cj), grid(ci + 1, cj), grid(ci + 1, cj + 1), grid(ci, cj + 1)};
    }
    mesh.add_face(vertices, uvs);
  }
  return mesh;
}

// Regular octahedron (6 vertices, 8 CCW triangles), no UVs.
inline core::PolyMesh octahedron() {
  core::PolyMesh mesh;
  mesh.V.resize(6, 3);
  mesh.V << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  const int tris[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (const auto& t : tris) mesh.add_face({t[0], t[1], t[2]});
  return mesh;
}

}  // namespace quadify::test
