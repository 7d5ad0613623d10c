// Mesh containers and index conventions shared by every quadify library.
//
// Conventions (used everywhere, tested in tests/core/mesh_test.cpp):
//  - V is #V×3 double, F is #F×3 int, counter-clockwise seen from outside.
//  - Corner c = 3f + k is corner k of face f. Per-corner data (UVs: seams make them discontinuous)
//    is a (#F·3)×d matrix indexed by corner.
//  - Half-edge h = 3f + k runs from F(f,k) to F(f,(k+1)%3); it is the edge opposite corner
//    (k+2)%3. So half-edge ids equal the corner id of their tail.
#pragma once

#include <Eigen/Core>

#include <array>
#include <vector>

namespace quadify::core {

struct TriMesh {
  Eigen::MatrixX3d V;  // #V×3 positions
  Eigen::MatrixX3i F;  // #F×3 vertex ids, CCW

  int n_vertices() const { return static_cast<int>(V.rows()); }
  int n_faces() const { return static_cast<int>(F.rows()); }
};

// A general polygon mesh, as read from a file or produced by quad extraction.
struct PolyMesh {
  Eigen::MatrixX3d V;                  // #V×3 positions
  std::vector<int> face_offset{0};     // #faces+1; face f is face_vertex[face_offset[f] .. face_offset[f+1])
  std::vector<int> face_vertex;        // concatenated vertex ids of every face, CCW
  Eigen::MatrixX2d uv;                 // texture-coordinate table (OBJ `vt`), may be empty
  std::vector<int> face_uv;            // per face corner: row of `uv`; empty or face_vertex.size()
  std::vector<std::array<int, 2>> lines;  // line segments between vertex ids (OBJ `l`), e.g. features

  int n_vertices() const { return static_cast<int>(V.rows()); }
  int n_faces() const { return static_cast<int>(face_offset.size()) - 1; }
  int degree(int f) const { return face_offset[f + 1] - face_offset[f]; }
  int face_corner(int f, int k) const { return face_offset[f] + k; }
  int vertex(int f, int k) const { return face_vertex[face_offset[f] + k]; }
  bool has_uv() const { return !face_uv.empty(); }
  // Appends a face (vertex ids, and uv rows if the mesh carries UVs).
  void add_face(const std::vector<int>& vertices, const std::vector<int>& uvs = {});
};

// A triangle mesh with per-corner UVs: the form of every parametrization in quadify.
struct UVMesh {
  TriMesh mesh;
  Eigen::MatrixX2d corner_uv;  // (#F·3)×2, row 3f+k is the UV of corner k of face f
};

// Conversions. to_poly keeps UVs (one uv row per corner). to_trimesh fan-triangulates polygons
// (no UVs); a face of degree < 3 is skipped.
PolyMesh to_poly(const TriMesh& mesh);
PolyMesh to_poly(const UVMesh& uv_mesh);
TriMesh to_trimesh(const PolyMesh& mesh);
// A triangle PolyMesh with UVs as a UVMesh; faces of degree != 3 are fan-triangulated.
UVMesh to_uvmesh(const PolyMesh& mesh);

// Length of the diagonal of the axis-aligned bounding box of V (0 for an empty V).
double bbox_diagonal(const Eigen::MatrixX3d& V);

}  // namespace quadify::core
