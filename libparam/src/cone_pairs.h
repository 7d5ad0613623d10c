// Cancellation of close pairs of opposite cones by changing the matchings along a short seam
// path between them. Internal to libparam.
//
// Why: minimising τ with local estimation rounds some matchings so that a +1 and a −1 cone sit on
// the two ends of one or two short edges (a "dipole"). Such a pair lowers the distortion a little
// but cannot be placed on two distinct integer points of a quad grid whose cells are larger than
// its distance, which makes the integer quantization infeasible at a useful density, and it adds
// two irregular vertices to the quad mesh. Raising the matching of seam edge (v0→v1 in face_a) by
// one quarter turn lowers the index of v0 and raises the index of v1 by one (the rotation from
// face_a to face_b is a clockwise step around v0 and a counter-clockwise one around v1), so
// changing every seam of a path p → q by ±1 moves one unit of index from p to q and leaves the
// inner vertices of the path unchanged: a +1/−1 pair disappears.
#pragma once

#include "cut_layout.h"

#include <libcore/mesh.h>

#include <Eigen/Core>
#include <vector>

namespace quadify::param {

// A matching change: seam `seam` of the cut gets `delta` quarter turns more.
struct SeamChange {
  int seam = -1;
  int delta = 0;
};

// One pair of cones to cancel and the seam changes that cancel it.
struct ConePairCancellation {
  int positive_vertex = -1, negative_vertex = -1;
  double path_length = 0;  // 3D length of the seam path
  std::vector<SeamChange> changes;
};

// Index of every vertex of the seamless layout x (2·#copies): 4 − (UV angle sum)/(π/2), 0 at
// boundary vertices.
std::vector<int> vertex_indices(const core::TriMesh& mesh, const CutMesh& cut,
                                const Eigen::VectorXd& x);

// Disjoint pairs of interior cones of opposite sign (positive_vertex > 0 > negative_vertex)
// joined by a path of at most max_hops seam edges and 3D length at most max_length whose inner
// vertices are regular interior vertices; greedily by path length (shortest first, ties by
// vertex ids: deterministic). Applying a pair moves one unit of index from the positive to the
// negative cone, so cones of |index| > 1 may take part in several passes. Vertices flagged in
// `avoid` (#V, or empty) are neither ends nor inner vertices of a path (e.g. those of aligned
// features, whose u/v labels follow the matchings across the seams they touch).
std::vector<ConePairCancellation> find_cone_pair_cancellations(const core::TriMesh& mesh,
                                                               const CutMesh& cut,
                                                               const std::vector<int>& index,
                                                               double max_length, int max_hops,
                                                               const std::vector<char>& avoid = {});

// Disjoint pairs of interior cones of opposite sign whose shortest path over the mesh's edges
// (avoiding `avoid` and the boundary) is at most max_length, greedily by that length (ties by
// vertex ids); each with the changes along its shortest path over the seams, of any length. The
// seam path and the surface path bound a region of charts: changing the matchings along the seam
// path gives the map a cut along the surface path would give, up to a rotation of those charts,
// so the pair is as near as the surface says however far the cut's tree takes its seams (a
// dual-spanning-tree cut joins neighbouring vertices by seam paths 2-9 times longer: knot1).
// Inner vertices of the seam path may be cones (their index is unchanged); paths may share seams
// (their changes add up). path_length is the surface length.
std::vector<ConePairCancellation> find_surface_cone_pairs(const core::TriMesh& mesh,
                                                          const CutMesh& cut,
                                                          const std::vector<int>& index,
                                                          double max_length,
                                                          const std::vector<char>& avoid = {});

// Splits of cones of index above max_index (a quad vertex of valence 4 − index: index 2 gives a
// flat corner, index 3 a valence-1 vertex, which no quad mesh has; the rounding makes them at the
// tips of thin parts) and, with max_index 1, moves of +1 cones crowded by another positive cone
// closer than distance/2 (3D; one cone of such a group moves per call, the first chosen; the
// rounding leaves such clusters at tips, where the grid cannot put them on distinct points):
// for each such interior cone p, a path of at most max_hops seam edges to a regular interior
// vertex q, through regular interior vertices, whose 3D length is closest to `distance` (at
// most 2·distance, or a single edge), with q at least distance/2 from every other positive cone
// and from the other targets (a cone above max_index with no such target takes the one farthest
// from the positive cones). Applying it moves one unit of index from p to q (q becomes a +1
// cone). One move per cone per call, paths disjoint; greedily by |length − distance| (ties by
// vertex ids: deterministic). `avoid` as above. The result uses ConePairCancellation with
// negative_vertex = the target q.
std::vector<ConePairCancellation> find_cone_splits(const core::TriMesh& mesh, const CutMesh& cut,
                                                   const std::vector<int>& index, int max_index,
                                                   double distance, int max_hops,
                                                   const std::vector<char>& avoid = {});

// The face whose frame a matching change turns against the other face of its seam, which keeps
// its frame: raising the matching of seam (face a → face b) turns b, lowering it turns a (the
// same side of a path all along it, since the changes leave its inner vertices' indices alone);
// −1 for an even change, which turns no axis. A feature on a changed seam whose row lives in the
// turned face keeps its direction against the other side with its u/v label flipped, which is
// what the cancellation does (see path_closes_feature_sector).
int turned_face(const CutMesh& cut, const SeamChange& change);

// Whether the matching changes of a seam path would close a sector between aligned features, a
// check made before any solve. Round a vertex of the path, the aligned features split the map's
// angle into sectors of whole quarter turns (their rows keep each feature on its u or v axis in
// the frame of one face). The changes turn the frames beyond each path edge by its change: the
// angle at the path's positive end grows by a quarter, at its negative end it shrinks by one,
// and at an inner vertex one sector gains what another loses (nothing when the path's two edges
// lie in one sector). A sector left with no angle, or opened beyond 1.75 times its angle on the
// surface (a right-angled crease corner laid out flat), cannot be laid out: on fandisk, one such pair
// in a set of 24 left 791 flipped faces, and the halving that found it spent the failure budget
// before three other pairs were tried. x: the layout (2·#copies); feature_row_face: per
// EdgeTopology edge of cut.topo, the face whose half-edge carries its feature's row if it is an
// aligned feature, else −1. Features on the path's edges whose rows live in the turned face
// (turned_face) count with their rows in the other face: their labels flip with the change.
bool path_closes_feature_sector(const core::TriMesh& mesh, const CutMesh& cut,
                                const Eigen::VectorXd& x, const ConePairCancellation& pair,
                                const std::vector<int>& feature_row_face);

}  // namespace quadify::param
