// Pure quads from a quad-dominant mesh. Where the extraction meets a boundary that the map does
// not follow (a feature the parametrization had to give up), the grid is cut into polygons that
// are not quads: a pentagon or triangle where a boundary cuts a quad's corner off. In order:
//  1. an edge of such a polygon shorter than a quarter of the mean edge length, with an end on
//     the boundary, is collapsed onto that end (a sliver where the boundary passes a grid point);
//  2. a polygon of more than 4 corners loses its nearly flat corners that no other face has
//     (turn ≤ 15° between two boundary edges), down to 4 or an even degree;
//  3. two faces of odd degree side by side merge (their shared edge goes);
//  4. an odd face of degree ≥ 5 on the boundary gets a midpoint on the boundary edge whose split
//     is best, if that split has no flat corner;
//  5. any other odd face is joined by a path of faces to the nearest other odd face (merged if
//     adjacent) or face on the boundary (which gets a boundary midpoint), a midpoint on every
//     edge the path crosses (faces whose split keeps its corners off flat first);
//  6. every face now has an even number of vertices and is split into quads: along diagonals
//     (the split whose worst corner is best), or, where that worst corner is poor (a path
//     turning inside a quad), around a new vertex at its centroid;
//  7. an inner midpoint left as a flat corner (a triangle's) moves 0.3 of the way to its spokes'
//     far ends, and a vertex inside the surface left with two quads (a doublet) goes.
// Quads untouched by all this stay as they are.
//
// Invariants: the result's faces are all quads where every odd face found a partner within
// max_path_faces; the boundary keeps its vertices' positions (new ones lie on boundary edges;
// a collapse moves an inner vertex onto the boundary); an edge-manifold, consistently oriented
// input stays so (a collapse or merge that would break it is not made); deterministic.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>

namespace quadify::quadex {

struct PureQuadOptions {
  // Longest path of faces searched from an odd face to its partner (faces visited in breadth-first
  // order); an odd face with none within it stays as it is.
  int max_path_faces = 256;
  // An even polygon is split along diagonals when the split's worst corner scaled Jacobian is at
  // least this (1 = right angle), else around its centroid if that is better (it adds a vertex of
  // valence degree/2).
  double min_diagonal_quality = 0.2;
};

struct PureQuadStats {
  int n_non_quads_before = 0;  // faces of degree ≠ 4 in the input
  int n_non_quads_after = 0;   // and in the result
  // Short edges collapsed first: an edge of a face that is not a quad, shorter than a quarter of
  // the mean edge length, with an end on the boundary (a sliver where the boundary passes a grid
  // point closely), its boundary end kept in place.
  int n_edges_collapsed = 0;
  // Flat corners removed: a vertex of one face only, between two of its boundary edges, where the
  // boundary turns by at most 15° (the extraction puts a vertex wherever a grid line crosses the
  // boundary), in a face of more than 4 corners, flattest first, down to 4 or an even degree.
  int n_vertices_removed = 0;
  int n_boundary_splits = 0;   // boundary edges split at their midpoint
  int n_merged = 0;            // pairs of odd faces side by side merged (their shared edge removed)
  int n_paths = 0;             // paths of faces joining two odd faces, or one and the boundary
  int n_edges_split = 0;       // interior edges split at their midpoint by those paths
  int n_centers = 0;           // polygons split around a new vertex at their centroid
  // Midpoints inside the surface that were a flat corner of a quad (a triangle's), moved 0.3 of
  // the way towards the far ends of their other edges.
  int n_midpoints_shifted = 0;
  // Vertices inside the surface left with two quads only (a midpoint both sides' splits kept as a
  // corner) removed, their two quads merged into one.
  int n_doublets_removed = 0;
  int n_faces_split = 0;       // faces replaced by quads
  int n_quads_added = 0;       // quads that replace them
  double worst_quality = 1;    // worst corner scaled Jacobian of those quads (1 when none)

};

struct PureQuadResult {
  core::Status status;
  core::PolyMesh quads;  // the input's faces in order, each split face replaced by its quads in place
  PureQuadStats stats;
};

// Unchanged (a copy) when every face is a quad. Otherwise unreferenced vertices (the collapsed
// and removed ones) go, the others keep their order, and new vertices come after them (lines are
// renumbered with them; a line at a vertex that went goes). When `mesh` carries UVs, the new
// corners get UVs interpolated from their face's corners. Faces with fewer than 3 or repeated
// vertices, and edges with more than two faces, are left alone.
// Returns kInvalidInput for vertex ids out of range or bad options.
[[nodiscard]] PureQuadResult make_pure_quads(const core::PolyMesh& mesh, const PureQuadOptions& options = {});

}  // namespace quadify::quadex
