// Stanford PLY, ascii and binary (little/big endian). The "vertex" element supplies x, y, z (any
// numeric type); the "face" element supplies a list property "vertex_indices" or "vertex_index"
// (any count and index types). Every other property and element is parsed and skipped.
#include "read_util.h"

#include <cstdint>
#include <vector>

namespace quadify::core::detail {
namespace {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool parse_type(std::string_view s, PlyType* type) {
  if (s == "char" || s == "int8") *type = PlyType::kInt8;
  else if (s == "uchar" || s == "uint8") *type = PlyType::kUint8;
  else if (s == "short" || s == "int16") *type = PlyType::kInt16;
  else if (s == "ushort" || s == "uint16") *type = PlyType::kUint16;
  else if (s == "int" || s == "int32") *type = PlyType::kInt32;
  else if (s == "uint" || s == "uint32") *type = PlyType::kUint32;
  else if (s == "float" || s == "float32") *type = PlyType::kFloat32;
  else if (s == "double" || s == "float64") *type = PlyType::kFloat64;
  else return false;
  return true;
}

int type_size(PlyType type) {
  switch (type) {
    case PlyType::kInt8: case PlyType::kUint8: return 1;
    case PlyType::kInt16: case PlyType::kUint16: return 2;
    case PlyType::kInt32: case PlyType::kUint32: case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 1;
}

bool is_integer(PlyType type) { return type != PlyType::kFloat32 && type != PlyType::kFloat64; }

struct Property {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
  PlyType value_type = PlyType::kFloat32;
};

struct Element {
  std::string name;
  long long count = 0;
  std::vector<Property> properties;
};

enum class Encoding { kAscii, kBinaryLE, kBinaryBE };

// Reads scalar values from the body, in either encoding.
class BodyReader {
 public:
  BodyReader(std::string_view body, Encoding encoding, const std::string& name)
      : body_(body), encoding_(encoding), name_(name) {}

  double read(PlyType type) {
    if (encoding_ == Encoding::kAscii) return read_ascii(type);
    const int size = type_size(type);
    if (pos_ + size > body_.size()) fail(name_, "truncated binary data");
    unsigned char b[8];
    std::memcpy(b, body_.data() + pos_, size);
    pos_ += size;
    const bool file_le = encoding_ == Encoding::kBinaryLE;
    if (file_le != host_is_little_endian())
      for (int i = 0; i < size / 2; ++i) std::swap(b[i], b[size - 1 - i]);
    switch (type) {
      case PlyType::kInt8: { int8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::kUint8: { uint8_t v; std::memcpy(&v, b, 1); return v; }
      case PlyType::kInt16: { int16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::kUint16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
      case PlyType::kInt32: { int32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kUint32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kFloat32: { float v; std::memcpy(&v, b, 4); return v; }
      case PlyType::kFloat64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0.0;
  }

  long long bytes_left() const { return static_cast<long long>(body_.size() - pos_); }

 private:
  double read_ascii(PlyType type) {
    while (pos_ < body_.size() && (is_space(body_[pos_]) || body_[pos_] == '\n')) ++pos_;
    size_t end = pos_;
    while (end < body_.size() && !is_space(body_[end]) && body_[end] != '\n') ++end;
    const std::string_view tok = body_.substr(pos_, end - pos_);
    pos_ = end;
    if (tok.empty()) fail(name_, "truncated ascii data");
    if (is_integer(type)) {
      long long v = 0;
      if (!parse_ll(tok, &v)) fail(name_, "bad integer " + quoted(tok));
      return static_cast<double>(v);
    }
    double v = 0.0;
    if (!parse_double(tok, &v)) fail(name_, "bad number " + quoted(tok));
    return v;
  }

  std::string_view body_;
  Encoding encoding_;
  const std::string& name_;
  size_t pos_ = 0;
};

}  // namespace

PolyMesh read_ply(const std::string& bytes, const std::string& name, const ReadOptions& options) {
  LineReader lines(bytes);
  std::string_view line;
  if (!lines.next(&line) || Tokens(line).next() != "ply") fail(name, "not a PLY file (no 'ply' magic)");
  Encoding encoding = Encoding::kAscii;
  bool have_format = false, have_end = false;
  std::vector<Element> elements;
  long long header_bytes = 0;
  while (lines.next(&line)) {
    Tokens tok(line);
    const std::string_view key = tok.next();
    const std::string at = "header line " + std::to_string(lines.line_number()) + ": ";
    if (key == "format") {
      const std::string_view f = tok.next();
      if (f == "ascii") encoding = Encoding::kAscii;
      else if (f == "binary_little_endian") encoding = Encoding::kBinaryLE;
      else if (f == "binary_big_endian") encoding = Encoding::kBinaryBE;
      else fail(name, at + "unknown format " + quoted(f));
      have_format = true;
    } else if (key == "element") {
      Element e;
      e.name = std::string(tok.next());
      const std::string_view c = tok.next();
      if (e.name.empty() || !parse_ll(c, &e.count)) fail(name, at + "bad element line");
      if (e.count < 0) fail(name, at + "negative element count " + std::to_string(e.count));
      elements.push_back(std::move(e));
    } else if (key == "property") {
      if (elements.empty()) fail(name, at + "property before any element");
      Property p;
      std::string_view t = tok.next();
      if (t == "list") {
        p.is_list = true;
        const std::string_view ct = tok.next(), vt = tok.next();
        if (!parse_type(ct, &p.count_type) || !parse_type(vt, &p.value_type) ||
            !is_integer(p.count_type))
          fail(name, at + "bad list property types");
      } else if (!parse_type(t, &p.value_type)) {
        fail(name, at + "unknown property type " + quoted(t));
      }
      p.name = std::string(tok.next());
      elements.back().properties.push_back(std::move(p));
    } else if (key == "end_header") {
      have_end = true;
      header_bytes = static_cast<long long>(bytes.size()) - lines.bytes_left();
      break;
    } else if (key == "comment" || key == "obj_info" || key.empty()) {
      continue;
    } else {
      fail(name, at + "unexpected header keyword " + quoted(key));
    }
  }
  if (!have_format) fail(name, "PLY header has no format line");
  if (!have_end) fail(name, "PLY header has no end_header (truncated)");

  BodyReader body(std::string_view(bytes).substr(header_bytes), encoding, name);
  // Validate every count against the bytes available, before allocating anything.
  {
    long long left = body.bytes_left();
    for (const Element& e : elements) {
      long long min_bytes = 0;
      for (const Property& p : e.properties)
        min_bytes += encoding == Encoding::kAscii ? 2 : type_size(p.is_list ? p.count_type : p.value_type);
      check_count(name, e.count, min_bytes, left, options, ("'" + e.name + "' element").c_str());
      left -= e.count * min_bytes;
    }
  }

  PolyMesh mesh;
  bool have_vertices = false;
  std::vector<int> face;
  for (const Element& e : elements) {
    if (e.properties.empty()) continue;  // nothing stored per element
    const bool is_vertex = e.name == "vertex" && !have_vertices;
    const bool is_face = e.name == "face";
    int coord_prop[3] = {-1, -1, -1}, index_prop = -1;
    for (int i = 0; i < static_cast<int>(e.properties.size()); ++i) {
      const Property& p = e.properties[i];
      if (is_vertex && !p.is_list) {
        if (p.name == "x") coord_prop[0] = i;
        if (p.name == "y") coord_prop[1] = i;
        if (p.name == "z") coord_prop[2] = i;
      }
      if (is_face && p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index"))
        index_prop = i;
    }
    if (is_vertex) {
      if (coord_prop[0] < 0 || coord_prop[1] < 0 || coord_prop[2] < 0)
        fail(name, "'vertex' element lacks an x, y or z property");
      mesh.V.resize(e.count, 3);
      have_vertices = true;
    }
    if (is_face && index_prop < 0) fail(name, "'face' element has no vertex_indices list");
    const long long nv = mesh.V.rows();
    for (long long i = 0; i < e.count; ++i) {
      for (int pi = 0; pi < static_cast<int>(e.properties.size()); ++pi) {
        const Property& p = e.properties[pi];
        if (!p.is_list) {
          const double value = body.read(p.value_type);
          if (is_vertex)
            for (int d = 0; d < 3; ++d)
              if (coord_prop[d] == pi) {
                if (!std::isfinite(value))
                  fail(name, "vertex " + std::to_string(i) + " has a non-finite coordinate");
                mesh.V(i, d) = value;
              }
          continue;
        }
        const double count_value = body.read(p.count_type);
        const long long min_item = encoding == Encoding::kAscii ? 2 : type_size(p.value_type);
        if (count_value < 0 || count_value > static_cast<double>(body.bytes_left() / min_item + 1))
          fail(name, "list of " + std::to_string(static_cast<long long>(count_value)) +
                         " items in element '" + e.name + "' " + std::to_string(i) +
                         " exceeds the file size");
        const long long count = static_cast<long long>(count_value);
        if (pi != index_prop) {
          for (long long k = 0; k < count; ++k) body.read(p.value_type);
          continue;
        }
        if (!is_face) continue;
        face.clear();
        for (long long k = 0; k < count; ++k) {
          const double idx = body.read(p.value_type);
          if (!(idx >= 0 && idx < static_cast<double>(nv)))
            fail(name, "face " + std::to_string(i) + ": index " +
                           std::to_string(static_cast<long long>(idx)) + " out of range (file has " +
                           std::to_string(nv) + " vertices)");
          face.push_back(static_cast<int>(idx));
        }
        if (face.size() < 3)
          fail(name, "face " + std::to_string(i) + " has " + std::to_string(face.size()) +
                         " vertices (at least 3 needed)");
        if (static_cast<long long>(mesh.face_vertex.size()) + count > 2'000'000'000LL)
          fail(name, "too many face corners");
        mesh.face_vertex.insert(mesh.face_vertex.end(), face.begin(), face.end());
        mesh.face_offset.push_back(static_cast<int>(mesh.face_vertex.size()));
      }
    }
  }
  if (!have_vertices) fail(name, "PLY file has no 'vertex' element");
  return mesh;
}

}  // namespace quadify::core::detail
