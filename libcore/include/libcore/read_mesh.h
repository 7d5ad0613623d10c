// Mesh input: OBJ, OFF, PLY (ASCII/binary), STL (ASCII/binary), glTF/GLB.
#pragma once

#include <libcore/mesh.h>

#include <filesystem>
#include <string>

namespace quadify::core {

enum class MeshFormat { kUnknown, kObj, kOff, kPly, kStl, kGltf, kGlb };

// Format from the file extension (case-insensitive), kUnknown if not recognised.
MeshFormat format_from_extension(const std::filesystem::path& path);
const char* format_name(MeshFormat format);

struct ReadOptions {
  // Hard cap on the number of vertices/faces a header may announce, so that a corrupted count
  // cannot trigger a runaway allocation (elements, not bytes). Also capped by the file size.
  long long max_elements = 200'000'000;
};

// Reads a polygon mesh as stored in the file: no repair, polygons kept as polygons, OBJ `vt`
// and `l` kept. glTF/GLB: every triangle primitive of every mesh node, node transforms applied.
// Throws InputError("<path>: <problem>") for a missing, unreadable, truncated or malformed file,
// non-finite coordinates, out-of-range indices, or a file without faces. Never crashes or hangs
// on any byte sequence.
PolyMesh read_mesh(const std::filesystem::path& path, const ReadOptions& options = {});

// Same, from bytes in memory (for tests and fuzzing); `name` stands for the file in messages.
PolyMesh read_mesh_from_memory(const std::string& bytes, MeshFormat format, const std::string& name,
                               const ReadOptions& options = {});

}  // namespace quadify::core
