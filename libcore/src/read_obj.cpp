// Wavefront OBJ: v, vt, f (v, v/vt, v//vn, v/vt/vn; negative = relative), l. Other statements
// (vn, o, g, s, usemtl, mtllib, ...) are skipped.
#include "read_util.h"

#include <vector>

namespace quadify::core::detail {
namespace {

// Resolves an OBJ index (1-based, or negative relative to the current count) to 0-based.
int resolve_index(long long raw, long long count, const std::string& name, int line,
                  const char* what) {
  const long long idx = raw > 0 ? raw - 1 : count + raw;
  if (raw == 0 || idx < 0 || idx >= count)
    fail(name, "line " + std::to_string(line) + ": " + what + " index " + std::to_string(raw) +
                   " out of range (file has " + std::to_string(count) + " " +
                   (std::string(what) == "face" || std::string(what) == "line" ? "vertices"
                                                                               : "texture coordinates") +
                   " so far)");
  return static_cast<int>(idx);
}

}  // namespace

PolyMesh read_obj(const std::string& bytes, const std::string& name, const ReadOptions& options) {
  std::vector<double> positions, texcoords;
  PolyMesh mesh;
  std::vector<int> face, face_tex;
  bool faces_have_uv = false;
  long long n_corners = 0;
  LineReader lines(bytes);
  std::string_view line;
  while (lines.next(&line)) {
    const int ln = lines.line_number();
    Tokens tok(line);
    const std::string_view key = tok.next();
    if (key == "v") {
      double xyz[3];
      for (double& x : xyz) {
        const std::string_view t = tok.next();
        if (!parse_double(t, &x))
          fail(name, "line " + std::to_string(ln) + ": bad vertex coordinate " + quoted(t));
        if (!std::isfinite(x))
          fail(name, "line " + std::to_string(ln) + ": non-finite vertex coordinate " + quoted(t));
      }
      if (static_cast<long long>(positions.size() / 3) >= options.max_elements)
        fail(name, "line " + std::to_string(ln) + ": more than " +
                       std::to_string(options.max_elements) + " vertices");
      positions.insert(positions.end(), xyz, xyz + 3);
    } else if (key == "vt") {
      double uv[2];
      for (double& x : uv) {
        const std::string_view t = tok.next();
        if (!parse_double(t, &x) || !std::isfinite(x))
          fail(name, "line " + std::to_string(ln) + ": bad texture coordinate " + quoted(t));
      }
      if (static_cast<long long>(texcoords.size() / 2) >= options.max_elements)
        fail(name, "line " + std::to_string(ln) + ": too many texture coordinates");
      texcoords.insert(texcoords.end(), uv, uv + 2);
    } else if (key == "f" || key == "fo") {
      face.clear();
      face_tex.clear();
      const long long nv = static_cast<long long>(positions.size() / 3);
      const long long nt = static_cast<long long>(texcoords.size() / 2);
      bool corner_has_uv = false, corner_missing_uv = false;
      for (std::string_view t = tok.next(); !t.empty(); t = tok.next()) {
        const size_t slash = t.find('/');
        long long raw = 0;
        if (!parse_ll(t.substr(0, slash), &raw))
          fail(name, "line " + std::to_string(ln) + ": bad face index " + quoted(t));
        face.push_back(resolve_index(raw, nv, name, ln, "face"));
        if (slash != std::string_view::npos) {
          std::string_view rest = t.substr(slash + 1);
          const std::string_view vt = rest.substr(0, rest.find('/'));
          if (!vt.empty()) {
            long long raw_t = 0;
            if (!parse_ll(vt, &raw_t))
              fail(name, "line " + std::to_string(ln) + ": bad texture index " + quoted(t));
            face_tex.push_back(resolve_index(raw_t, nt, name, ln, "texture"));
            corner_has_uv = true;
          } else {
            corner_missing_uv = true;
          }
        } else {
          corner_missing_uv = true;
        }
      }
      if (face.size() < 3)
        fail(name, "line " + std::to_string(ln) + ": face with " + std::to_string(face.size()) +
                       " vertices (at least 3 needed)");
      if (corner_has_uv && corner_missing_uv)
        fail(name, "line " + std::to_string(ln) + ": face mixes corners with and without texture "
                   "coordinates");
      if (mesh.n_faces() >= options.max_elements)
        fail(name, "line " + std::to_string(ln) + ": too many faces");
      if (mesh.n_faces() == 0) {
        faces_have_uv = corner_has_uv;
      } else if (faces_have_uv != corner_has_uv) {
        // Keep UVs only when every face has them (the PolyMesh stores them per corner).
        if (faces_have_uv) {
          mesh.face_uv.clear();
          faces_have_uv = false;
        }
      }
      n_corners += static_cast<long long>(face.size());
      if (n_corners > options.max_elements || n_corners > 2'000'000'000LL)
        fail(name, "line " + std::to_string(ln) + ": too many face corners");
      mesh.face_vertex.insert(mesh.face_vertex.end(), face.begin(), face.end());
      if (faces_have_uv) mesh.face_uv.insert(mesh.face_uv.end(), face_tex.begin(), face_tex.end());
      mesh.face_offset.push_back(static_cast<int>(mesh.face_vertex.size()));
    } else if (key == "l") {
      const long long nv = static_cast<long long>(positions.size() / 3);
      int prev = -1;
      for (std::string_view t = tok.next(); !t.empty(); t = tok.next()) {
        long long raw = 0;
        if (!parse_ll(t.substr(0, t.find('/')), &raw))
          fail(name, "line " + std::to_string(ln) + ": bad line index " + quoted(t));
        const int v = resolve_index(raw, nv, name, ln, "line");
        if (prev >= 0) mesh.lines.push_back({prev, v});
        if (static_cast<long long>(mesh.lines.size()) > options.max_elements)
          fail(name, "line " + std::to_string(ln) + ": too many line segments");
        prev = v;
      }
    }
  }
  const long long nv = static_cast<long long>(positions.size() / 3);
  mesh.V.resize(nv, 3);
  for (long long v = 0; v < nv; ++v)
    for (int d = 0; d < 3; ++d) mesh.V(v, d) = positions[3 * v + d];
  if (faces_have_uv) {
    const long long nt = static_cast<long long>(texcoords.size() / 2);
    mesh.uv.resize(nt, 2);
    for (long long t = 0; t < nt; ++t)
      for (int d = 0; d < 2; ++d) mesh.uv(t, d) = texcoords[2 * t + d];
  } else {
    mesh.face_uv.clear();
  }
  return mesh;
}

}  // namespace quadify::core::detail
