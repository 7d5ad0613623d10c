#include <libcore/read_mesh.h>

#include "read_util.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <system_error>

namespace quadify::core {
namespace {

PolyMesh read_dispatch(const std::string& bytes, MeshFormat format, const std::string& name,
                       const std::string& base_dir, const ReadOptions& options) {
  if (bytes.empty()) detail::fail(name, "file is empty");
  PolyMesh mesh;
  switch (format) {
    case MeshFormat::kObj: mesh = detail::read_obj(bytes, name, options); break;
    case MeshFormat::kOff: mesh = detail::read_off(bytes, name, options); break;
    case MeshFormat::kPly: mesh = detail::read_ply(bytes, name, options); break;
    case MeshFormat::kStl: mesh = detail::read_stl(bytes, name, options); break;
    case MeshFormat::kGltf: mesh = detail::read_gltf(bytes, false, name, base_dir, options); break;
    case MeshFormat::kGlb: mesh = detail::read_gltf(bytes, true, name, base_dir, options); break;
    case MeshFormat::kUnknown:
      detail::fail(name, "unknown mesh format (expected .obj, .off, .ply, .stl, .gltf or .glb)");
  }
  detail::validate_read_mesh(mesh, name);
  return mesh;
}

}  // namespace

MeshFormat format_from_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".obj") return MeshFormat::kObj;
  if (ext == ".off") return MeshFormat::kOff;
  if (ext == ".ply") return MeshFormat::kPly;
  if (ext == ".stl") return MeshFormat::kStl;
  if (ext == ".gltf") return MeshFormat::kGltf;
  if (ext == ".glb") return MeshFormat::kGlb;
  return MeshFormat::kUnknown;
}

const char* format_name(MeshFormat format) {
  switch (format) {
    case MeshFormat::kObj: return "OBJ";
    case MeshFormat::kOff: return "OFF";
    case MeshFormat::kPly: return "PLY";
    case MeshFormat::kStl: return "STL";
    case MeshFormat::kGltf: return "glTF";
    case MeshFormat::kGlb: return "GLB";
    case MeshFormat::kUnknown: break;
  }
  return "unknown";
}

PolyMesh read_mesh(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string name = path.string();
  const MeshFormat format = format_from_extension(path);
  if (format == MeshFormat::kUnknown)
    detail::fail(name, "unknown mesh format '" + path.extension().string() +
                           "' (expected .obj, .off, .ply, .stl, .gltf or .glb)");
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) detail::fail(name, "file does not exist");
  if (std::filesystem::is_directory(status)) detail::fail(name, "is a directory, not a mesh file");
  if (!std::filesystem::is_regular_file(status)) detail::fail(name, "is not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) detail::fail(name, "cannot open for reading");
  std::string bytes;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) detail::fail(name, "cannot determine the file size");
  in.seekg(0, std::ios::beg);
  bytes.resize(static_cast<size_t>(size));
  if (size > 0 && !in.read(bytes.data(), size)) detail::fail(name, "read error");
  const std::string base_dir = path.parent_path().empty() ? std::string(".")
                                                          : path.parent_path().string();
  return read_dispatch(bytes, format, name, base_dir, options);
}

PolyMesh read_mesh_from_memory(const std::string& bytes, MeshFormat format, const std::string& name,
                               const ReadOptions& options) {
  return read_dispatch(bytes, format, name, std::string(), options);
}

namespace detail {

void validate_read_mesh(const PolyMesh& mesh, const std::string& name) {
  const int nv = mesh.n_vertices();
  for (int v = 0; v < nv; ++v)
    for (int d = 0; d < 3; ++d)
      if (!std::isfinite(mesh.V(v, d)))
        fail(name, "vertex " + std::to_string(v + 1) + " has a non-finite coordinate");
  if (mesh.n_faces() == 0) fail(name, "file has no faces");
  for (size_t c = 0; c < mesh.face_vertex.size(); ++c)
    if (mesh.face_vertex[c] < 0 || mesh.face_vertex[c] >= nv)
      fail(name, "face index " + std::to_string(mesh.face_vertex[c]) + " out of range (file has " +
                     std::to_string(nv) + " vertices)");
  for (const auto& line : mesh.lines)
    for (int v : line)
      if (v < 0 || v >= nv)
        fail(name, "line index " + std::to_string(v) + " out of range (file has " +
                       std::to_string(nv) + " vertices)");
  if (mesh.has_uv()) {
    if (mesh.face_uv.size() != mesh.face_vertex.size()) fail(name, "inconsistent texture indices");
    for (int t : mesh.face_uv)
      if (t < 0 || t >= mesh.uv.rows()) fail(name, "texture index out of range");
    for (int t = 0; t < mesh.uv.rows(); ++t)
      if (!std::isfinite(mesh.uv(t, 0)) || !std::isfinite(mesh.uv(t, 1)))
        fail(name, "texture coordinate " + std::to_string(t + 1) + " is not finite");
  }
}

}  // namespace detail
}  // namespace quadify::core
