#include <libcore/mesh.h>
#include <libcore/status.h>

namespace quadify::core {

void PolyMesh::add_face(const std::vector<int>& vertices, const std::vector<int>& uvs) {
  QUADIFY_CHECK(uvs.empty() || uvs.size() == vertices.size(), "uv count differs from vertex count");
  QUADIFY_CHECK(uvs.empty() == face_uv.empty() || n_faces() == 0, "faces mix with and without UVs");
  face_vertex.insert(face_vertex.end(), vertices.begin(), vertices.end());
  face_uv.insert(face_uv.end(), uvs.begin(), uvs.end());
  face_offset.push_back(static_cast<int>(face_vertex.size()));
}

PolyMesh to_poly(const TriMesh& mesh) {
  PolyMesh out;
  out.V = mesh.V;
  out.face_vertex.reserve(mesh.F.size());
  out.face_offset.reserve(mesh.F.rows() + 1);
  for (int f = 0; f < mesh.n_faces(); ++f) {
    for (int k = 0; k < 3; ++k) out.face_vertex.push_back(mesh.F(f, k));
    out.face_offset.push_back(static_cast<int>(out.face_vertex.size()));
  }
  return out;
}

PolyMesh to_poly(const UVMesh& uv_mesh) {
  PolyMesh out = to_poly(uv_mesh.mesh);
  out.uv = uv_mesh.corner_uv;
  out.face_uv.resize(out.face_vertex.size());
  for (size_t c = 0; c < out.face_uv.size(); ++c) out.face_uv[c] = static_cast<int>(c);
  return out;
}

TriMesh to_trimesh(const PolyMesh& mesh) {
  TriMesh out;
  out.V = mesh.V;
  int n_tris = 0;
  for (int f = 0; f < mesh.n_faces(); ++f) n_tris += std::max(0, mesh.degree(f) - 2);
  out.F.resize(n_tris, 3);
  int t = 0;
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 1; k + 1 < mesh.degree(f); ++k)
      out.F.row(t++) << mesh.vertex(f, 0), mesh.vertex(f, k), mesh.vertex(f, k + 1);
  return out;
}

UVMesh to_uvmesh(const PolyMesh& mesh) {
  UVMesh out;
  out.mesh = to_trimesh(mesh);
  out.corner_uv.setZero(out.mesh.n_faces() * 3, 2);
  if (!mesh.has_uv()) return out;
  int t = 0;
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 1; k + 1 < mesh.degree(f); ++k, ++t) {
      const int corners[3] = {0, k, k + 1};
      for (int j = 0; j < 3; ++j)
        out.corner_uv.row(3 * t + j) = mesh.uv.row(mesh.face_uv[mesh.face_corner(f, corners[j])]);
    }
  return out;
}

double bbox_diagonal(const Eigen::MatrixX3d& V) {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

}  // namespace quadify::core
