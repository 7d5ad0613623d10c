// Mesh output: OBJ (polygons, optional per-corner UVs), glTF 2.0 (.gltf + .bin) and .glb.
// Every write is atomic (temporary file in the target folder, then rename): a failed write
// leaves no partial file. Failures throw OutputError("<path>: <problem>").
#pragma once

#include <libcore/mesh.h>

#include <filesystem>

namespace quadify::core {

struct WriteOptions {
  bool write_uv = true;   // write texture coordinates when the mesh has them
  int precision = 17;     // significant digits of text coordinates (17: round-trips doubles)
};

// OBJ: `v`, optional `vt` + `f v/vt`, `l` lines. Quads stay 4-vertex faces.
void write_obj(const std::filesystem::path& path, const PolyMesh& mesh, const WriteOptions& = {});

// OBJ of a parametrization: one `vt` per distinct UV, so corners across a seam have different
// `vt` rows and the seams are visible in any UV viewer.
void write_uv_obj(const std::filesystem::path& path, const UVMesh& uv_mesh, const WriteOptions& = {});

// glTF 2.0: polygons fan-triangulated as a TRIANGLES primitive (TEXCOORD_0 when UVs are present,
// NORMAL per vertex), polygon edges as a LINES primitive (the quad wireframe).
// `.glb` → binary container; `.gltf` → JSON + `<stem>.bin` beside it.
void write_gltf(const std::filesystem::path& path, const PolyMesh& mesh, const WriteOptions& = {});

// Dispatch on the extension (.obj, .gltf, .glb); other extensions throw OutputError.
void write_mesh(const std::filesystem::path& path, const PolyMesh& mesh, const WriteOptions& = {});

}  // namespace quadify::core
