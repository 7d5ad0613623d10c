// glTF 2.0 writer (.gltf + .bin, or .glb). The JSON is written with nlohmann_json and the binary
// buffer by hand, so that output works without tinygltf (QUADIFY_WITH_GLTF off) too.
#include "write_util.h"

#include <libcore/atomic_file.h>
#include <libcore/status.h>
#include <libcore/write_mesh.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace quadify::core {
namespace fs = std::filesystem;
namespace {

using Json = nlohmann::ordered_json;

// glTF 2.0 enumerations (specification §3.6.2, §3.7.2).
constexpr int kComponentFloat = 5126;
constexpr int kComponentUnsignedInt = 5125;
constexpr int kTargetArrayBuffer = 34962;
constexpr int kTargetElementArrayBuffer = 34963;
constexpr int kModeLines = 1;
constexpr int kModeTriangles = 4;
// GLB container (specification §4.4).
constexpr uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr uint32_t kGlbVersion = 2;
constexpr uint32_t kGlbChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kGlbChunkBin = 0x004E4942;   // "BIN\0"
// 0xFFFFFFFF is the primitive-restart value, which glTF forbids as an index.
constexpr uint64_t kMaxVertexCount = 0xFFFFFFFFull;

// The geometry as glTF wants it: float attributes per output vertex, 32-bit indices.
struct GltfGeometry {
  std::vector<float> position;  // 3 per output vertex
  std::vector<float> normal;    // 3 per output vertex, unit length
  std::vector<float> texcoord;  // 2 per output vertex; empty without UVs
  std::vector<uint32_t> triangles;  // 3 per triangle
  std::vector<uint32_t> lines;      // 2 per segment
  size_t n_vertices() const { return position.size() / 3; }
};

// Area-weighted vertex normals: each polygon adds its vector area (sum of its fan triangles'
// cross products) to each of its vertices. A vertex without a (non-degenerate) face gets +z.
Eigen::MatrixX3d vertex_normals(const PolyMesh& mesh) {
  Eigen::MatrixX3d N = Eigen::MatrixX3d::Zero(mesh.n_vertices(), 3);
  for (int f = 0; f < mesh.n_faces(); ++f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.vertex(f, 0));
    Eigen::Vector3d area = Eigen::Vector3d::Zero();
    for (int k = 1; k + 1 < mesh.degree(f); ++k) {
      const Eigen::Vector3d p1 = mesh.V.row(mesh.vertex(f, k));
      const Eigen::Vector3d p2 = mesh.V.row(mesh.vertex(f, k + 1));
      area += (p1 - p0).cross(p2 - p0);
    }
    for (int k = 0; k < mesh.degree(f); ++k) N.row(mesh.vertex(f, k)) += area.transpose();
  }
  for (Eigen::Index v = 0; v < N.rows(); ++v) {
    const double len = N.row(v).norm();
    // Exact zero (isolated vertex, or normals cancelling) has no direction; fall back to +z.
    if (std::isfinite(len) && len > 0.0)
      N.row(v) /= len;
    else
      N.row(v) << 0.0, 0.0, 1.0;
  }
  return N;
}

struct CornerKey {
  int vertex;
  double u, w;
  bool operator==(const CornerKey& o) const { return vertex == o.vertex && u == o.u && w == o.w; }
};
struct CornerKeyHash {
  size_t operator()(const CornerKey& k) const {
    auto bits = [](double x) {
      if (x == 0.0) x = 0.0;  // -0.0 equals +0.0, so it must hash equally
      uint64_t b;
      std::memcpy(&b, &x, sizeof b);
      return b;
    };
    uint64_t h = static_cast<uint64_t>(k.vertex) * 0x9E3779B97F4A7C15ull;
    h ^= bits(k.u) + 0x7F4A7C159E3779B9ull + (h << 6) + (h >> 2);
    h ^= bits(k.w) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    return std::hash<uint64_t>()(h);
  }
};

GltfGeometry build_geometry(const fs::path& path, const PolyMesh& mesh, bool with_uv) {
  const int nv = mesh.n_vertices();
  const Eigen::MatrixX3d N = vertex_normals(mesh);
  GltfGeometry g;
  std::vector<int64_t> out_of_vertex(nv, -1);  // one output copy of each vertex (for lines)
  std::vector<uint32_t> corner_out(mesh.face_vertex.size());
  auto add_vertex = [&](int v, double u, double w) {
    for (int d = 0; d < 3; ++d) g.position.push_back(static_cast<float>(mesh.V(v, d)));
    for (int d = 0; d < 3; ++d) g.normal.push_back(static_cast<float>(N(v, d)));
    if (with_uv) {
      g.texcoord.push_back(static_cast<float>(u));
      g.texcoord.push_back(static_cast<float>(w));
    }
    const uint32_t id = static_cast<uint32_t>(g.n_vertices() - 1);
    if (out_of_vertex[v] < 0) out_of_vertex[v] = id;
    return id;
  };
  if (with_uv) {
    // A vertex with k distinct UVs (a seam vertex) becomes k output vertices.
    std::unordered_map<CornerKey, uint32_t, CornerKeyHash> out_of_key;
    out_of_key.reserve(mesh.face_vertex.size());
    for (size_t c = 0; c < mesh.face_vertex.size(); ++c) {
      const int v = mesh.face_vertex[c], t = mesh.face_uv[c];
      const CornerKey key{v, mesh.uv(t, 0), mesh.uv(t, 1)};
      const auto it = out_of_key.find(key);
      corner_out[c] = it != out_of_key.end() ? it->second : out_of_key[key] = add_vertex(v, key.u, key.w);
    }
    for (int v = 0; v < nv; ++v)
      if (out_of_vertex[v] < 0) add_vertex(v, 0.0, 0.0);  // isolated or line-only vertex
  } else {
    for (int v = 0; v < nv; ++v) add_vertex(v, 0.0, 0.0);
    for (size_t c = 0; c < mesh.face_vertex.size(); ++c) corner_out[c] = static_cast<uint32_t>(mesh.face_vertex[c]);
  }
  if (g.n_vertices() >= kMaxVertexCount)
    throw OutputError(path.string() + ": " + std::to_string(g.n_vertices()) +
                      " vertices exceed glTF's 32-bit index range");

  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 1; k + 1 < mesh.degree(f); ++k)
      for (int j : {0, k, k + 1}) g.triangles.push_back(corner_out[mesh.face_corner(f, j)]);

  // Every undirected polygon edge and feature line once, in order of first appearance.
  std::unordered_set<uint64_t> seen;
  auto add_segment = [&](int a, int b) {
    if (a == b) return;
    const uint64_t key = (static_cast<uint64_t>(std::min(a, b)) << 32) | static_cast<uint32_t>(std::max(a, b));
    if (!seen.insert(key).second) return;
    g.lines.push_back(static_cast<uint32_t>(out_of_vertex[a]));
    g.lines.push_back(static_cast<uint32_t>(out_of_vertex[b]));
  };
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < mesh.degree(f); ++k) add_segment(mesh.vertex(f, k), mesh.vertex(f, (k + 1) % mesh.degree(f)));
  for (const auto& line : mesh.lines) add_segment(line[0], line[1]);
  return g;
}

// Appends little-endian values to the binary buffer, one buffer view per array.
class BinaryBuffer {
 public:
  // Returns the index of the new buffer view holding `values`.
  template <typename T>
  int add_view(Json& views, const std::vector<T>& values, int target) {
    static_assert(sizeof(T) == 4, "glTF views here hold 4-byte components");
    const size_t offset = bytes_.size();  // always a multiple of 4: every component has 4 bytes
    for (const T x : values) {
      const uint32_t word = std::bit_cast<uint32_t>(x);
      for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<char>((word >> (8 * i)) & 0xFFu));
    }
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * 4}, {"target", target}});
    return static_cast<int>(views.size()) - 1;
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

// Component-wise min and max of a float VEC3 array (required on POSITION by the spec §3.7.2.1).
std::pair<Json, Json> min_max3(const std::vector<float>& xyz) {
  std::array<float, 3> lo, hi;
  lo.fill(std::numeric_limits<float>::infinity());
  hi.fill(-std::numeric_limits<float>::infinity());
  for (size_t i = 0; i < xyz.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], xyz[i]);
    hi[i % 3] = std::max(hi[i % 3], xyz[i]);
  }
  // Written as the exact double of each float, so a reader's comparison with the data is exact.
  return {Json::array({double(lo[0]), double(lo[1]), double(lo[2])}),
          Json::array({double(hi[0]), double(hi[1]), double(hi[2])})};
}

// Percent-encodes everything but RFC 3986 unreserved characters (the .bin name goes in a URI).
std::string uri_encode(const std::string& name) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const unsigned char ch : name) {
    if (std::isalnum(ch) || ch == '-' || ch == '_' || ch == '.' || ch == '~') {
      out.push_back(static_cast<char>(ch));
    } else {
      out.push_back('%');
      out.push_back(kHex[ch >> 4]);
      out.push_back(kHex[ch & 15]);
    }
  }
  return out;
}

void put_u32(std::ostream& out, uint32_t x) {
  char b[4];
  for (int i = 0; i < 4; ++i) b[i] = static_cast<char>((x >> (8 * i)) & 0xFFu);
  out.write(b, 4);
}

bool is_glb(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
  return ext == ".glb";
}

}  // namespace

void write_gltf(const fs::path& path, const PolyMesh& mesh, const WriteOptions& options) {
  const bool with_uv = options.write_uv && mesh.has_uv();
  detail::check_polymesh_for_output(path, mesh, with_uv);
  const GltfGeometry g = build_geometry(path, mesh, with_uv);
  if (g.triangles.empty() && g.lines.empty())
    throw OutputError(path.string() + ": nothing to write (no faces and no lines)");

  Json views = Json::array(), accessors = Json::array();
  BinaryBuffer buffer;
  const auto [pos_min, pos_max] = min_max3(g.position);
  const auto n_out = g.n_vertices();
  accessors.push_back({{"bufferView", buffer.add_view(views, g.position, kTargetArrayBuffer)},
                       {"componentType", kComponentFloat}, {"count", n_out}, {"type", "VEC3"},
                       {"min", pos_min}, {"max", pos_max}});
  Json attributes = {{"POSITION", 0}};
  accessors.push_back({{"bufferView", buffer.add_view(views, g.normal, kTargetArrayBuffer)},
                       {"componentType", kComponentFloat}, {"count", n_out}, {"type", "VEC3"}});
  attributes["NORMAL"] = accessors.size() - 1;
  if (with_uv) {
    accessors.push_back({{"bufferView", buffer.add_view(views, g.texcoord, kTargetArrayBuffer)},
                         {"componentType", kComponentFloat}, {"count", n_out}, {"type", "VEC2"}});
    attributes["TEXCOORD_0"] = accessors.size() - 1;
  }
  Json primitives = Json::array();
  auto add_primitive = [&](const std::vector<uint32_t>& indices, int mode, const Json& prim_attributes) {
    if (indices.empty()) return;
    accessors.push_back({{"bufferView", buffer.add_view(views, indices, kTargetElementArrayBuffer)},
                         {"componentType", kComponentUnsignedInt}, {"count", indices.size()},
                         {"type", "SCALAR"}});
    primitives.push_back({{"attributes", prim_attributes}, {"indices", accessors.size() - 1}, {"mode", mode}});
  };
  add_primitive(g.triangles, kModeTriangles, attributes);
  // The wireframe shares the vertex data; it is never textured, so it leaves out TEXCOORD_0.
  Json line_attributes = attributes;
  line_attributes.erase("TEXCOORD_0");
  add_primitive(g.lines, kModeLines, line_attributes);

  const bool glb = is_glb(path);
  const std::string& bin = buffer.bytes();
  Json gltf = {
      {"asset", {{"version", "2.0"}, {"generator", "quadify"}}},
      {"scene", 0},
      {"scenes", Json::array({{{"nodes", Json::array({0})}}})},
      {"nodes", Json::array({{{"mesh", 0}}})},
      {"meshes", Json::array({{{"primitives", primitives}}})},
      {"accessors", accessors},
      {"bufferViews", views},
  };
  const fs::path bin_path = fs::path(path).replace_extension(".bin");
  Json buffer_json = {{"byteLength", bin.size()}};
  if (!glb) buffer_json["uri"] = uri_encode(bin_path.filename().string());
  gltf["buffers"] = Json::array({buffer_json});
  std::string json_text = gltf.dump(glb ? -1 : 1);

  if (!glb) {
    json_text.push_back('\n');
    write_files_atomically({{path, [&](std::ostream& out) { out.write(json_text.data(), json_text.size()); }},
                            {bin_path, [&](std::ostream& out) { out.write(bin.data(), bin.size()); }}});
    return;
  }
  // GLB chunks are 4-byte aligned: JSON padded with spaces, BIN with zeros (spec §4.4.3).
  while (json_text.size() % 4) json_text.push_back(' ');
  std::string bin_padded = bin;
  while (bin_padded.size() % 4) bin_padded.push_back('\0');
  const uint64_t total = 12 + 8 + json_text.size() + 8 + bin_padded.size();
  if (total > std::numeric_limits<uint32_t>::max())
    throw OutputError(path.string() + ": " + std::to_string(total) + " bytes exceed the GLB size limit (4 GiB)");
  write_file_atomically(path, [&](std::ostream& out) {
    put_u32(out, kGlbMagic);
    put_u32(out, kGlbVersion);
    put_u32(out, static_cast<uint32_t>(total));
    put_u32(out, static_cast<uint32_t>(json_text.size()));
    put_u32(out, kGlbChunkJson);
    out.write(json_text.data(), static_cast<std::streamsize>(json_text.size()));
    put_u32(out, static_cast<uint32_t>(bin_padded.size()));
    put_u32(out, kGlbChunkBin);
    out.write(bin_padded.data(), static_cast<std::streamsize>(bin_padded.size()));
  });
}

}  // namespace quadify::core
