// Repair of dirty but common input: welding, degenerate/duplicate faces, orientation,
// non-manifold vertices and edges.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>

#include <array>
#include <string>
#include <vector>

namespace quadify::core {

struct RepairOptions {
  // Weld vertices closer than this, relative to the bounding-box diagonal (binary STL stores
  // every triangle's corners separately; exporters round differently). 0 = exact duplicates only.
  double weld_tolerance = 1e-7;
  // A face whose area is below this, relative to diagonal², is degenerate and dropped.
  double degenerate_area_tolerance = 1e-14;
  // A "cap", a triangle with an angle of at least this (degrees), is removed like a zero-area
  // one: the neighbour across its long edge is split at the cap's vertex, which lies almost on
  // that edge (the surface moves by the cap's height). CAD tessellations leave such slivers along
  // curves; their normals are noise, so their edges would look sharp and become false features
  // that fold back on the real ones. A cap is kept where the split would join two vertices that
  // are already joined (the result would not be manifold). 180 = off. (Wider wedges between
  // two feature edges: flip_feature_wedges.)
  double cap_angle_deg = 178;
  // A folded sliver, a triangle with an angle of at least this (degrees) whose far vertex lies
  // within 5% of its longest edge's length from that edge and which is folded back over the
  // neighbours across both its shorter edges (normals more than 120° apart), is removed
  // like a cap: its two short edges look like creases beside the real one on its long edge (block
  // has nine between 142° and 178°, wingnut three). 180 = off.
  double folded_sliver_angle_deg = 120;
  // A fold: two triangles on an edge that lie almost on top of each other, face to face (their
  // normals more than this apart, degrees, and one's far vertex within 2% of the edge length
  // of the other's plane). CAD tessellations leave slivers folded over a neighbour along
  // curves. The edge is flipped when the two new triangles agree (normals within 30°): the
  // double-covered sliver disappears and the surface is as before. 180 = off.
  double fold_angle_deg = 150;
  // Fins: patches of at most this many faces (connected through manifold edges) that hang on
  // non-manifold edges with a free boundary, and without which those edges have exactly two
  // faces, are removed (a flap of a scan glued to the surface, a stray triangle across a corner);
  // larger ones are detached by split_nonmanifold_edges. 0 = detach them all.
  int max_fin_faces = 16;
  bool orient_components = true;          // make each component consistently oriented
  bool split_nonmanifold_vertices = true;  // give each fan of a non-manifold vertex its own copy
  bool split_nonmanifold_edges = true;     // detach faces beyond a consistent pair on an edge
};

// Counts of every repair made; reported in the JSON report under "repair".
struct RepairReport {
  int input_vertices = 0;
  int input_faces = 0;                  // polygons as read
  int polygons_triangulated = 0;        // faces of degree > 3 split into triangles
  int invalid_faces_removed = 0;        // degree < 3 or repeated vertex ids
  int welded_vertices = 0;              // vertices merged into another
  int degenerate_faces_removed = 0;     // zero-area (collinear or collapsed) triangles
  int caps_removed = 0;                 // caps (see RepairOptions::cap_angle_deg)
  int folds_flipped = 0;                // edges of folded triangle pairs flipped
  int fin_faces_removed = 0;            // faces of fins (see RepairOptions::max_fin_faces)
  int duplicate_faces_removed = 0;      // same vertex set as an earlier face
  int unreferenced_vertices_removed = 0;
  int faces_reoriented = 0;             // flipped to agree with their component
  int nonmanifold_edges_split = 0;
  int nonmanifold_vertices_split = 0;
  int output_vertices = 0;
  int output_faces = 0;
  int n_components = 0;
  int n_boundary_loops = 0;
  bool changed() const;
};

struct RepairResult {
  Status status;                 // InvalidInput when the mesh cannot be made usable (names why)
  TriMesh mesh;                  // manifold, consistently oriented, no degenerate faces
  RepairReport report;
  std::vector<int> vertex_origin;  // #V of mesh: input vertex id each output vertex came from
};

// Repairs a polygon mesh into a clean triangle mesh. Never throws on bad geometry; returns
// InvalidInput with a message naming the problem (e.g. "no faces left after removing 12
// degenerate faces") when nothing usable remains.
RepairResult repair_mesh(const PolyMesh& input, const RepairOptions& options = {});

// A feature curve's vertex w whose single triangle (a, b, w) spans the chord a-b, with an angle
// of at least min_angle_deg at w between the feature edges w-a and b-w: no seamless map can lay
// both features along one iso-line (one triangle corner cannot open to 180°), so one of them
// would be disabled. Where the neighbour across a-b is flat with the triangle (w within 1% of
// |ab| of its plane) and the two new triangles face like it, a-b is flipped: w gets a second
// corner and the surface does not move. Vertex ids and the face count stay; only faces change.
// Returns the number of flips. Precondition: an edge-manifold, consistently oriented mesh.
int flip_feature_wedges(TriMesh* mesh, const std::vector<std::array<int, 2>>& feature_edges,
                        double min_angle_deg = 150);

}  // namespace quadify::core
