// Quad extraction from an integer-seamless parametrization (Levi 2021, Def. 3.2; extraction in
// the spirit of QEx, Ebke et al. 2013): the integer iso-lines u ∈ Z and v ∈ Z of the map, traced
// across seams, are the edges of the quad mesh and their crossings its vertices.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>

#include <vector>

namespace quadify::quadex {

struct ExtractOptions {
  // Largest allowed seam residual, × the UV bounding-box diagonal. Across every interior edge the
  // two sides' UVs must satisfy (u',v') = R_90^r (u,v) + (s,t) with (s,t) ∈ Z²; the residual is
  // the largest distance |R^r x + (s,t) − x'| over the edge's two endpoints, with the best-fit r
  // and the best-fit translation rounded to Z².
  // Above it the map is rejected (kInvalidInput naming the edge). Relative to the UV size
  // because seam errors of a solver scale with the magnitudes it handles.
  double max_transition_residual = 1e-6;
  // Largest distance (× UV bounding-box diagonal) of a cone vertex from the integer point it is
  // snapped to; farther cones are rejected (Def. 3.2 requires integer cones).
  double max_cone_offset = 1e-6;
  // UV coordinates within this distance (× UV bounding-box diagonal) of an integer are snapped to
  // it, so that vertices meant to lie on an iso-line do exactly (no sliver grid crossings).
  // All other coordinates are rounded to the dyadic grid 2^-k, k = min(40, 50 − ⌈log2(4·max|uv|
  // + 4)⌉) (2^-40 for |uv| < 60), on which adding integer translations is exact in double.
  double integer_snap_tolerance = 1e-9;
  // Refuse maps whose UV triangles' bounding boxes hold more integer points than this in total:
  // a too-fine map is a bad input, not a reason to exhaust memory.
  long long max_grid_points = 50'000'000;
  // Fill quads.uv / quads.face_uv with UVs per face corner, one chart per face: integer at grid
  // points, the crossing's UV at boundary crossings.
  bool output_uv = true;
};

struct ExtractStats {
  int n_vertices = 0;  // quad-mesh vertices: grid points plus boundary crossings
  int n_faces = 0;
  int n_non_quads = 0;                 // output faces of degree ≠ 4
  int n_grid_points_on_vertices = 0;   // grid points at a triangle-mesh vertex
  int n_grid_points_on_edges = 0;      // grid points inside a triangle-mesh edge
  int n_grid_points_in_faces = 0;      // grid points inside a triangle
  int n_cones = 0;                     // interior vertices whose holonomy is a nonzero rotation
  int n_seam_edges = 0;                // interior edges with a non-identity transition
  int n_boundary_crossings = 0;  // quad vertices where an iso-line crosses the boundary
  // Boundary vertices lying exactly on an iso-line that touches the boundary there (e.g. a reflex
  // corner snapped onto it), moved off it by 16 dyadic units so the extraction stays consistent.
  int n_unsnapped_boundary_vertices = 0;
  // Half-edge chains that did not close into a face (not expected), and closed chains with fewer
  // than three distinct vertices (slivers between an iso-line and the boundary).
  int n_dropped_faces = 0;
  double max_transition_residual = 0;  // measured, in UV units
  double seconds = 0;
};

struct ExtractResult {
  core::Status status;
  core::PolyMesh quads;  // CCW faces; uv/face_uv hold per-corner integer UVs when requested
  std::vector<int> vertex_face;  // per quad vertex: the input face it was placed in
  ExtractStats stats;
};

// Extracts the quad mesh of an integer-seamless map.
//
// Input: map.mesh is a manifold, consistently oriented triangle mesh (boundary allowed);
// map.corner_uv is (#F·3)×2, row 3f+k the UV of corner k of face f (libcore/mesh.h).
// Preconditions checked (each failure returns kInvalidInput naming the element):
//  - sizes match, coordinates finite, mesh edge-manifold and consistently oriented;
//  - every interior edge's transition is a rotation by r·90° plus an integer translation
//    (residual ≤ max_transition_residual); every cone (vertex with non-trivial rotational
//    holonomy) lies on an integer point; no interior vertex has a pure-translation holonomy;
//  - after snapping, every UV triangle is strictly positively oriented (exact orient2d).
// Method: every integer point of a (closed) UV triangle becomes a vertex, created once (by the
// owning face, half-edge or vertex corner), placed by barycentric interpolation of V. From each
// vertex, the iso-lines in the ±u/±v directions are traced through triangles, applying the
// seam transitions, until the next integer point. Point location and tracing use exact
// predicates with a symbolic perturbation (each iso-line is shifted infinitesimally to its
// left), so iso-lines through mesh vertices or along mesh edges need no special case. Faces
// are the cycles of "turn left at the end vertex"; valence follows the cones (3 at a +π/2 cone).
// Open meshes: the quad-mesh boundary follows the mesh boundary. Its vertices are the grid points
// on the boundary plus the points where an iso-line crosses the boundary (positions interpolated
// along the boundary edge, non-integer UVs); consecutive ones are joined by a quad edge. A
// boundary made of iso-line pieces (a boundary-aligned map) thus yields only quads; a boundary
// cutting through cells yields cut faces of degree ≠ 4, counted in n_non_quads. Mesh boundary
// vertices between crossings are not quad vertices (the corner they make is cut off). A
// non-integer boundary vertex lying exactly on an iso-line that touches the boundary there
// (a reflex corner) is first moved off the line by 16 dyadic units (n_unsnapped_boundary_vertices).
// Returns kOk, kInvalidInput (see above) or kInternal (a tracing invariant failed: a bug).
[[nodiscard]] ExtractResult extract_quads(const core::UVMesh& map, const ExtractOptions& options = {});

}  // namespace quadify::quadex
