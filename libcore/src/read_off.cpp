// Object File Format: "[ST][C][N]OFF" header, counts, vertex lines (x y z, then optional normal,
// colour or texture values, ignored), face lines (n i_1 .. i_n, optional colour). '#' starts a
// comment anywhere.
#include "read_util.h"

#include <vector>

namespace quadify::core::detail {
namespace {

// Next line with content (comments stripped); false at the end of the file.
bool next_content_line(LineReader& lines, std::string_view* line) {
  while (lines.next(line)) {
    const size_t hash = line->find('#');
    if (hash != std::string_view::npos) *line = line->substr(0, hash);
    Tokens probe(*line);
    if (!probe.next().empty()) return true;
  }
  return false;
}

std::string at_line(const LineReader& lines) { return "line " + std::to_string(lines.line_number()) + ": "; }

}  // namespace

PolyMesh read_off(const std::string& bytes, const std::string& name, const ReadOptions& options) {
  LineReader lines(bytes);
  std::string_view line;
  if (!next_content_line(lines, &line)) fail(name, "no OFF header");
  Tokens header(line);
  std::string_view magic = header.next();
  // Accept the variants that only add per-vertex attributes we ignore: ST (texture), C (colour),
  // N (normal). 4OFF / nOFF change the dimension and are rejected.
  {
    std::string_view m = magic;
    if (m.substr(0, 2) == "ST") m.remove_prefix(2);
    if (!m.empty() && m.front() == 'C') m.remove_prefix(1);
    if (!m.empty() && m.front() == 'N') m.remove_prefix(1);
    if (m != "OFF") fail(name, "not an OFF file (header " + quoted(magic) + ")");
  }
  std::string_view count_tok = header.next();
  if (count_tok == "BINARY") fail(name, "binary OFF is not supported");
  if (count_tok.empty()) {
    if (!next_content_line(lines, &line)) fail(name, "missing vertex/face counts");
    header = Tokens(line);
    count_tok = header.next();
  }
  long long nv = 0, nf = 0;
  const std::string_view nf_tok = header.next();
  if (!parse_ll(count_tok, &nv) || !parse_ll(nf_tok, &nf))
    fail(name, at_line(lines) + "bad vertex/face counts " + quoted(count_tok) + " " + quoted(nf_tok));
  constexpr long long kMinVertexBytes = 6;  // "0 0 0\n"
  constexpr long long kMinFaceBytes = 8;    // "3 0 1 2\n"
  check_count(name, nv, kMinVertexBytes, lines.bytes_left(), options, "vertex");
  check_count(name, nf, kMinFaceBytes, lines.bytes_left() - nv * kMinVertexBytes, options, "face");

  PolyMesh mesh;
  mesh.V.resize(nv, 3);
  for (long long v = 0; v < nv; ++v) {
    if (!next_content_line(lines, &line))
      fail(name, "truncated: " + std::to_string(v) + " of " + std::to_string(nv) + " vertices read");
    Tokens tok(line);
    for (int d = 0; d < 3; ++d) {
      const std::string_view t = tok.next();
      double x = 0.0;
      if (!parse_double(t, &x) || !std::isfinite(x))
        fail(name, at_line(lines) + "bad vertex coordinate " + quoted(t));
      mesh.V(v, d) = x;
    }
  }
  mesh.face_offset.reserve(nf + 1);
  std::vector<int> face;
  for (long long f = 0; f < nf; ++f) {
    if (!next_content_line(lines, &line))
      fail(name, "truncated: " + std::to_string(f) + " of " + std::to_string(nf) + " faces read");
    Tokens tok(line);
    long long degree = 0;
    const std::string_view t0 = tok.next();
    if (!parse_ll(t0, &degree)) fail(name, at_line(lines) + "bad face size " + quoted(t0));
    if (degree < 3 || degree > static_cast<long long>(line.size()))
      fail(name, at_line(lines) + "face size " + std::to_string(degree) + " is invalid");
    face.clear();
    for (long long k = 0; k < degree; ++k) {
      const std::string_view t = tok.next();
      long long idx = 0;
      if (!parse_ll(t, &idx)) fail(name, at_line(lines) + "bad face index " + quoted(t));
      if (idx < 0 || idx >= nv)
        fail(name, at_line(lines) + "face index " + std::to_string(idx) +
                       " out of range (file has " + std::to_string(nv) + " vertices)");
      face.push_back(static_cast<int>(idx));
    }
    if (static_cast<long long>(mesh.face_vertex.size()) + degree > 2'000'000'000LL)
      fail(name, "too many face corners");
    mesh.face_vertex.insert(mesh.face_vertex.end(), face.begin(), face.end());
    mesh.face_offset.push_back(static_cast<int>(mesh.face_vertex.size()));
  }
  return mesh;
}

}  // namespace quadify::core::detail
