// Helpers shared by the mesh writers (write_mesh.cpp, write_gltf.cpp). Not installed.
#pragma once

#include <libcore/mesh.h>

#include <filesystem>

namespace quadify::core::detail {

// Throws OutputError("<path>: <problem>") unless the mesh can be written as a valid file:
// finite positions, every face with ≥ 3 vertex ids in range, lines in range, and — when
// `check_uv` — face_uv parallel to face_vertex with rows in range and finite UVs.
void check_polymesh_for_output(const std::filesystem::path& path, const PolyMesh& mesh, bool check_uv);

}  // namespace quadify::core::detail
