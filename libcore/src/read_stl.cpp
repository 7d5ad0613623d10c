// STL, ascii and binary. A file is binary when its size is exactly 84 + 50·n for the triangle
// count n in its header, even if it starts with "solid" (many exporters write that). Corners are
// not welded here (STL stores each triangle separately): repair_mesh welds them.
#include "read_util.h"

#include <vector>

namespace quadify::core::detail {
namespace {

constexpr long long kBinaryHeaderBytes = 84;    // 80-byte comment + uint32 triangle count
constexpr long long kBinaryTriangleBytes = 50;  // normal, 3 corners (float32 ×12), attribute

float read_le_float(const unsigned char* p) {
  uint32_t bits = static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
                  (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
  float value;
  std::memcpy(&value, &bits, 4);
  return value;
}

PolyMesh read_binary(const std::string& bytes, long long n, const std::string& name,
                     const ReadOptions& options) {
  check_count(name, n, kBinaryTriangleBytes, static_cast<long long>(bytes.size()) - kBinaryHeaderBytes,
              options, "triangle");
  if (3 * n > options.max_elements) fail(name, "too many vertices");
  PolyMesh mesh;
  mesh.V.resize(3 * n, 3);
  mesh.face_vertex.resize(3 * n);
  mesh.face_offset.resize(n + 1);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data()) + kBinaryHeaderBytes;
  for (long long t = 0; t < n; ++t) {
    const unsigned char* tri = data + t * kBinaryTriangleBytes + 12;  // skip the normal
    for (int k = 0; k < 3; ++k) {
      for (int d = 0; d < 3; ++d) {
        const double x = read_le_float(tri + 12 * k + 4 * d);
        if (!std::isfinite(x))
          fail(name, "triangle " + std::to_string(t) + " has a non-finite coordinate");
        mesh.V(3 * t + k, d) = x;
      }
      mesh.face_vertex[3 * t + k] = static_cast<int>(3 * t + k);
    }
    mesh.face_offset[t + 1] = static_cast<int>(3 * t + 3);
  }
  return mesh;
}

PolyMesh read_ascii(const std::string& bytes, const std::string& name, const ReadOptions& options) {
  std::vector<double> positions;
  PolyMesh mesh;
  LineReader lines(bytes);
  std::string_view line;
  bool in_loop = false;
  int loop_start = 0;
  while (lines.next(&line)) {
    Tokens tok(line);
    const std::string_view key = tok.next();
    const std::string at = "line " + std::to_string(lines.line_number()) + ": ";
    if (key == "outer") {
      if (in_loop) fail(name, at + "nested 'outer loop'");
      in_loop = true;
      loop_start = static_cast<int>(positions.size() / 3);
    } else if (key == "vertex") {
      if (!in_loop) fail(name, at + "'vertex' outside 'outer loop'");
      for (int d = 0; d < 3; ++d) {
        const std::string_view t = tok.next();
        double x = 0.0;
        if (!parse_double(t, &x) || !std::isfinite(x))
          fail(name, at + "bad vertex coordinate " + quoted(t));
        positions.push_back(x);
      }
      if (static_cast<long long>(positions.size() / 3) > options.max_elements)
        fail(name, at + "too many vertices");
    } else if (key == "endloop") {
      if (!in_loop) fail(name, at + "'endloop' without 'outer loop'");
      in_loop = false;
      const int end = static_cast<int>(positions.size() / 3);
      if (end - loop_start < 3)
        fail(name, at + "facet with " + std::to_string(end - loop_start) + " vertices");
      for (int v = loop_start; v < end; ++v) mesh.face_vertex.push_back(v);
      mesh.face_offset.push_back(end);
    }
  }
  if (in_loop) fail(name, "truncated inside a facet");
  const long long nv = static_cast<long long>(positions.size() / 3);
  mesh.V.resize(nv, 3);
  for (long long v = 0; v < nv; ++v)
    for (int d = 0; d < 3; ++d) mesh.V(v, d) = positions[3 * v + d];
  return mesh;
}

}  // namespace

PolyMesh read_stl(const std::string& bytes, const std::string& name, const ReadOptions& options) {
  const long long size = static_cast<long long>(bytes.size());
  if (size >= kBinaryHeaderBytes) {
    const auto* p = reinterpret_cast<const unsigned char*>(bytes.data()) + 80;
    const long long n = static_cast<long long>(p[0]) | (static_cast<long long>(p[1]) << 8) |
                        (static_cast<long long>(p[2]) << 16) | (static_cast<long long>(p[3]) << 24);
    if (size == kBinaryHeaderBytes + kBinaryTriangleBytes * n) return read_binary(bytes, n, name, options);
  }
  Tokens first(std::string_view(bytes).substr(0, std::min<size_t>(bytes.size(), 256)));
  if (first.next() == "solid") return read_ascii(bytes, name, options);
  if (size < kBinaryHeaderBytes) fail(name, "too short for a binary STL (truncated)");
  fail(name, "binary STL size " + std::to_string(size) +
                 " does not match its triangle count (truncated or corrupt)");
}

}  // namespace quadify::core::detail
