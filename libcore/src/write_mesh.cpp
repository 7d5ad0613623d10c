// OBJ writers and the extension dispatch (glTF lives in write_gltf.cpp).
#include "write_util.h"

#include <libcore/atomic_file.h>
#include <libcore/status.h>
#include <libcore/write_mesh.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <unordered_map>

namespace quadify::core {
namespace fs = std::filesystem;

namespace detail {

void check_polymesh_for_output(const fs::path& path, const PolyMesh& mesh, bool check_uv) {
  auto fail = [&](const std::string& problem) { throw OutputError(path.string() + ": " + problem); };
  const int nv = mesh.n_vertices();
  if (!mesh.V.allFinite()) {
    for (int v = 0; v < nv; ++v)
      if (!mesh.V.row(v).allFinite()) fail("vertex " + std::to_string(v) + " has a non-finite coordinate");
  }
  if (mesh.face_offset.empty() || mesh.face_offset.front() != 0 ||
      mesh.face_offset.back() != static_cast<int>(mesh.face_vertex.size()))
    fail("face_offset does not describe face_vertex (" + std::to_string(mesh.face_vertex.size()) + " ids)");
  for (int f = 0; f < mesh.n_faces(); ++f) {
    if (mesh.degree(f) < 3)
      fail("face " + std::to_string(f) + " has " + std::to_string(mesh.degree(f)) +
           " vertices (a face needs at least 3)");
    for (int k = 0; k < mesh.degree(f); ++k) {
      const int v = mesh.vertex(f, k);
      if (v < 0 || v >= nv)
        fail("face " + std::to_string(f) + " references vertex " + std::to_string(v) + " of " +
             std::to_string(nv));
    }
  }
  for (size_t l = 0; l < mesh.lines.size(); ++l)
    for (int v : mesh.lines[l])
      if (v < 0 || v >= nv)
        fail("line " + std::to_string(l) + " references vertex " + std::to_string(v) + " of " +
             std::to_string(nv));
  if (!check_uv || !mesh.has_uv()) return;
  if (mesh.face_uv.size() != mesh.face_vertex.size())
    fail("face_uv has " + std::to_string(mesh.face_uv.size()) + " entries, face_vertex " +
         std::to_string(mesh.face_vertex.size()));
  const int n_uv = static_cast<int>(mesh.uv.rows());
  for (size_t c = 0; c < mesh.face_uv.size(); ++c)
    if (mesh.face_uv[c] < 0 || mesh.face_uv[c] >= n_uv)
      fail("face corner " + std::to_string(c) + " references uv " + std::to_string(mesh.face_uv[c]) +
           " of " + std::to_string(n_uv));
  for (int t = 0; t < n_uv; ++t)
    if (!mesh.uv.row(t).allFinite()) fail("uv " + std::to_string(t) + " is not finite");
}

}  // namespace detail

namespace {

// Significant digits beyond 17 carry no information for a double (17 round-trips every value).
constexpr int kMaxDoubleDigits = 17;
// Text is assembled in memory and handed to the stream in blocks of this many bytes.
constexpr size_t kFlushBytes = size_t{1} << 20;

// Buffered, locale-independent text output (std::to_chars never uses the global locale).
class ObjText {
 public:
  ObjText(std::ostream& out, int precision)
      : out_(out), precision_(std::clamp(precision, 1, kMaxDoubleDigits)) {
    text_.reserve(kFlushBytes + 256);
  }

  void put(std::string_view s) { text_.append(s); }
  void put(char c) { text_.push_back(c); }
  void put_int(long long x) {
    std::array<char, 24> buf;
    const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), x);
    text_.append(buf.data(), r.ptr);
  }
  void put_double(double x) {
    std::array<char, 64> buf;
    const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), x, std::chars_format::general, precision_);
    text_.append(buf.data(), r.ptr);
  }
  // Ends a line; hands the buffer to the stream when it is large.
  void end_line() {
    text_.push_back('\n');
    if (text_.size() >= kFlushBytes) flush();
  }
  void flush() {
    out_.write(text_.data(), static_cast<std::streamsize>(text_.size()));
    text_.clear();
  }

 private:
  std::ostream& out_;
  int precision_;
  std::string text_;
};

void put_vertices(ObjText& text, const Eigen::MatrixX3d& V) {
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    text.put("v");
    for (int d = 0; d < 3; ++d) {
      text.put(' ');
      text.put_double(V(v, d));
    }
    text.end_line();
  }
}

void put_uv_row(ObjText& text, double u, double w) {
  text.put("vt ");
  text.put_double(u);
  text.put(' ');
  text.put_double(w);
  text.end_line();
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
  return ext;
}

// Key of an exact UV value; -0.0 and +0.0 are one value (they compare equal).
struct UvKey {
  double u, w;
  bool operator==(const UvKey& o) const { return u == o.u && w == o.w; }
};
struct UvKeyHash {
  size_t operator()(const UvKey& k) const {
    auto bits = [](double x) {
      if (x == 0.0) x = 0.0;  // fold -0.0 onto +0.0 so that equal keys hash equally
      unsigned long long b;
      std::memcpy(&b, &x, sizeof b);
      return b;
    };
    return std::hash<unsigned long long>()(bits(k.u) * 0x9E3779B97F4A7C15ull ^ bits(k.w));
  }
};

}  // namespace

void write_obj(const fs::path& path, const PolyMesh& mesh, const WriteOptions& options) {
  const bool with_uv = options.write_uv && mesh.has_uv();
  detail::check_polymesh_for_output(path, mesh, with_uv);
  write_file_atomically(path, [&](std::ostream& out) {
    ObjText text(out, options.precision);
    text.put("# quadify OBJ: ");
    text.put_int(mesh.n_vertices());
    text.put(" vertices, ");
    text.put_int(mesh.n_faces());
    text.put(" faces");
    text.end_line();
    put_vertices(text, mesh.V);
    if (with_uv)
      for (Eigen::Index t = 0; t < mesh.uv.rows(); ++t) put_uv_row(text, mesh.uv(t, 0), mesh.uv(t, 1));
    for (int f = 0; f < mesh.n_faces(); ++f) {
      text.put('f');
      for (int k = 0; k < mesh.degree(f); ++k) {
        text.put(' ');
        text.put_int(mesh.vertex(f, k) + 1);
        if (with_uv) {
          text.put('/');
          text.put_int(mesh.face_uv[mesh.face_corner(f, k)] + 1);
        }
      }
      text.end_line();
    }
    for (const auto& line : mesh.lines) {
      text.put("l ");
      text.put_int(line[0] + 1);
      text.put(' ');
      text.put_int(line[1] + 1);
      text.end_line();
    }
    text.flush();
  });
}

void write_uv_obj(const fs::path& path, const UVMesh& uv_mesh, const WriteOptions& options) {
  const TriMesh& mesh = uv_mesh.mesh;
  const int nf = mesh.n_faces();
  if (uv_mesh.corner_uv.rows() != 3 * static_cast<Eigen::Index>(nf))
    throw OutputError(path.string() + ": corner_uv has " + std::to_string(uv_mesh.corner_uv.rows()) +
                      " rows, expected 3·#F = " + std::to_string(3 * static_cast<long long>(nf)));
  if (!uv_mesh.corner_uv.allFinite()) {
    for (Eigen::Index c = 0; c < uv_mesh.corner_uv.rows(); ++c)
      if (!uv_mesh.corner_uv.row(c).allFinite())
        throw OutputError(path.string() + ": corner " + std::to_string(c) + " has a non-finite UV");
  }
  // The polygon checks (indices, finiteness) are the same for a triangle mesh.
  detail::check_polymesh_for_output(path, to_poly(mesh), false);

  // One vt row per distinct UV value, numbered in order of first appearance; corners across a seam
  // differ in value and so get different rows.
  std::vector<int> corner_row;
  std::vector<UvKey> rows;
  if (options.write_uv) {
    std::unordered_map<UvKey, int, UvKeyHash> row_of;
    row_of.reserve(3 * static_cast<size_t>(nf));
    corner_row.resize(3 * static_cast<size_t>(nf));
    for (int c = 0; c < 3 * nf; ++c) {
      const UvKey key{uv_mesh.corner_uv(c, 0), uv_mesh.corner_uv(c, 1)};
      const auto [it, inserted] = row_of.try_emplace(key, static_cast<int>(rows.size()));
      if (inserted) rows.push_back(key);
      corner_row[c] = it->second;
    }
  }
  write_file_atomically(path, [&](std::ostream& out) {
    ObjText text(out, options.precision);
    text.put("# quadify UV OBJ: one vt per distinct UV; seams separate vt rows");
    text.end_line();
    put_vertices(text, mesh.V);
    for (const UvKey& key : rows) put_uv_row(text, key.u, key.w);
    for (int f = 0; f < nf; ++f) {
      text.put('f');
      for (int k = 0; k < 3; ++k) {
        text.put(' ');
        text.put_int(mesh.F(f, k) + 1);
        if (options.write_uv) {
          text.put('/');
          text.put_int(corner_row[3 * f + k] + 1);
        }
      }
      text.end_line();
    }
    text.flush();
  });
}

void write_mesh(const fs::path& path, const PolyMesh& mesh, const WriteOptions& options) {
  const std::string ext = lower_extension(path);
  if (ext == ".obj") return write_obj(path, mesh, options);
  if (ext == ".gltf" || ext == ".glb") return write_gltf(path, mesh, options);
  throw OutputError(path.string() + ": unsupported output format '" + ext + "' (use .obj, .gltf or .glb)");
}

}  // namespace quadify::core
