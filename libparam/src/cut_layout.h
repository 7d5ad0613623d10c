// Cutting a connected mesh along a dual spanning tree and laying it out isometrically
// (paper section 4, "Initialization"). Internal to libparam.
#pragma once

#include <libcore/mesh.h>
#include <libcore/topology.h>

#include <Eigen/Core>

#include <array>
#include <utility>
#include <vector>

namespace quadify::param {

// A seam edge of the cut: an interior edge that is not in the dual spanning tree. Its twin
// half-edges are he_a (in face he_a/3, running v0→v1) and he_b (in face he_b/3, running v1→v0).
struct CutSeam {
  int he_a = -1, he_b = -1;
  int edge = -1;  // EdgeTopology edge id
};

struct CutMesh {
  core::EdgeTopology topo;
  std::vector<int> tree_parent_halfedge;  // #F, half-edge of the parent face across the tree edge
                                          // (-1 at the root face)
  std::vector<int> face_order;            // #F, BFS order of the faces (root first)
  std::vector<int> corner_copy;           // #F·3, vertex copy of each corner
  std::vector<int> copy_vertex;           // #copies, mesh vertex of each copy
  int n_copies() const { return static_cast<int>(copy_vertex.size()); }
  std::vector<CutSeam> seams;             // every non-tree interior edge
  int root_copy = 0;                      // a copy of the root face, kept fixed (translation gauge)
  // Rest shape of each face in an isometric 2D frame of its 3D triangle: the 2×2 matrix
  // Dm = [p1−p0, p2−p0] with p0 = 0 and p1 on the positive x axis.
  // With a size field (cut_along_dual_tree's face_size) the frame is that of the triangle scaled
  // by 1/size: the target shape of the face in the map (paper section 7).
  std::vector<Eigen::Matrix2d> rest;      // #F
  std::vector<double> area;               // #F, area of the rest shape
  bool sized = false;                     // rest shapes of different scales (a size field)
};

// The rest frame of face f (columns p1−p0, p2−p0 in a 2D frame of the triangle, p1 on the
// positive x axis) and its area, for the triangle scaled by `scale`, mapped by the face's target
// metric (face_metric[f], 3×3 on the 3D edge vectors, if given) and scaled by 1/face_size[f] (if
// given): the target shape of the face in the map (paper section 7).
Eigen::Matrix2d sized_rest_frame(const core::TriMesh& mesh, int f, double scale,
                                 const std::vector<double>& face_size,
                                 const std::vector<Eigen::Matrix3d>& face_metric, double* area);

// Cuts a connected, manifold, consistently oriented mesh along a BFS dual spanning tree rooted at
// face `seed_face`. Vertex copies are the corners merged across the tree edges (in BFS order, so
// copy ids grow away from the root). face_size (#F positive values, or empty): the target edge
// length of each face relative to its 3D size; rest frames are the triangles scaled by 1/size.
CutMesh cut_along_dual_tree(const core::TriMesh& mesh, int seed_face = 0,
                            const std::vector<double>& face_size = {},
                            const std::vector<Eigen::Matrix3d>& face_metric = {});

// Isometric layout of the cut mesh, face by face in BFS order: (#copies)×2 positions. With a size
// field (cut.sized) each face is placed by the similarity that maps its rest edge onto the edge
// already placed (conforming, with the scale changing from face to face).
Eigen::MatrixX2d isometric_unfold(const core::TriMesh& mesh, const CutMesh& cut);

// The vertex copies at the ends of seam s: v0 and v1 in face a (a0, a1) and in face b (b0, b1).
struct SeamEnds {
  int a0, a1, b0, b1;
};
SeamEnds seam_ends(const CutMesh& cut, int seam);

// Continuous matching of each seam, in quarter turns in (−2, 2]: the rotation from
// e_a = x(v1 in face a) − x(v0 in face a) to e_b = x(v1 in face b) − x(v0 in face b).
std::vector<double> measure_matchings(const CutMesh& cut, const Eigen::MatrixX2d& x);

// The two scalar rows of the constraint e_b − R^r e_a = 0 of seam s, as (variable, coefficient)
// triplets over the 2·#copies scalar variables (variable 2·copy + d). Duplicates are summed.
struct SparseRow {
  std::vector<std::pair<int, double>> entries;
};
// A row from (variable, coefficient) terms: sorted by variable, equal variables summed, zero
// coefficients dropped.
SparseRow make_row(std::vector<std::pair<int, double>> terms);
// The rotation by r quarter turns (r in 0..3) on the coordinates:
// (R^r e)[d] = kRotationSign[r][d] · e[kRotationSource[r][d]].
inline constexpr int kRotationSource[4][2] = {{0, 1}, {1, 0}, {0, 1}, {1, 0}};
inline constexpr double kRotationSign[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
std::array<SparseRow, 2> seam_constraint_rows(const CutMesh& cut, int seam, int matching);

// 3D length of the edge of seam s.
double seam_length(const CutMesh& cut, int seam);

// Applies R_90^r to a 2-vector.
inline Eigen::Vector2d rotate_quarter(const Eigen::Vector2d& e, int r) {
  switch (((r % 4) + 4) % 4) {
    case 0: return e;
    case 1: return {-e.y(), e.x()};
    case 2: return -e;
    default: return {e.y(), -e.x()};
  }
}

}  // namespace quadify::param
