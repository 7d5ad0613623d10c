// Local repair of badly shaped quads after extraction: vertices of quads with a corner whose
// scaled Jacobian is below a threshold (typically a reflex corner at a valence-3 cone, where the
// integer map is most anisotropic) are moved towards the centroid of their edge neighbours and
// projected back onto the input surface, one vertex at a time, keeping a move only when it raises
// the worst scaled Jacobian of the quads around that vertex. Topology, UVs and boundary vertices
// are unchanged.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>

#include <array>
#include <vector>

namespace quadify::quadex {

struct RelaxOptions {
  // Quads whose worst corner scaled Jacobian (corner cross product against the quad's area
  // vector, over the product of the edge lengths; 1 = right angle, ≤ 0 = reflex or flipped)
  // is below this are repaired.
  double min_scaled_jacobian = 0.2;
  // Rounds over the vertices to repair (each round visits them in index order).
  int max_rounds = 20;
  // Vertex rings around the bad quads' vertices that may move too (room to spread the fix).
  int rings = 1;
  // Feature edges of the surface (vertex-id pairs): quad vertices on them (within 1e-9 of the
  // bounding-box diagonal) stay fixed, so that feature curves keep their quad-edge chains
  // (but see release_features_for_flips).
  std::vector<std::array<int, 2>> feature_edges;
  // Snapping to creases missed by the quads: a vertex (not on a feature or boundary, and only
  // of quads) whose closest point p on a feature edge that is not on the surface's boundary lies
  // within snap_reach of its mean quad edge length, where the quads around it do not already
  // have p on one of their edges (a crease crossing a quad or running beside a chain of quad
  // edges), moves onto p, if every quad around it keeps a worst corner of at least
  // snap_min_quality (or does not get worse) and gets no farther from the surface than it was
  // or than 0.75 of the largest distance of any quad. A crease missed by a row of quads (a
  // disabled or released feature edge, a label switch) is then cut by them only between snapped
  // vertices, instead of being cut off by up to half a quad. 0 = off. (Reach 0.5 until
  // 2026-12-05: fandisk's Hausdorff 0.0035 -> 0.0031 and feature capture 0.984 -> 0.986, block
  // 0.944 -> 0.949, wingnut 0.935 -> 0.945 at 5,000 quads.)
  double snap_reach = 0.75;
  double snap_min_quality = 0.1;
  // Tentative snaps: where, after the repair, the quads leave the surface farthest (a surface
  // sample within snap_reach of the feature point of a snap refused only for the quality of
  // its quads, at least 0.75 of the largest distance), such a snap is tried without the quality
  // check, and the repair is run again from the snapping on: the two best such snaps alone, then
  // up to four together. A result is kept if it has no more flipped quads and no more quads
  // below min_scaled_jacobian, a worst quad no worse (or at least snap_min_quality) and a smaller
  // largest two-sided distance to the surface samples; the repair then often moves the
  // neighbours so that the quad the snap folded opens again (fandisk at 5,000 quads: a crease
  // corner cut off by 0.0031 of the diagonal, the largest distance, is met: 0.0031 -> 0.0019).
  // Costs up to three more repairs where there are such snaps.
  bool tentative_snaps = true;
  // Quads still flipped after that may move their vertices on features and boundaries too (off
  // the curve: a flipped or flat quad is worse than a crease or boundary missed by a fraction of
  // a quad), as a last resort.
  bool release_features_for_flips = true;
  // (Then, for quads still flipped or below 0.05: a local pass around them, from their extracted
  // positions, with raised thresholds; see RelaxStats::n_unfolded.)
  // Sample jumps, before the steps above (and again after them, and after the last resort for
  // the quads still flipped): a vertex of a quad below min_scaled_jacobian moves to a surface
  // sample (a vertex of the surface or a point inside one of its triangles) within jump_reach of
  // its mean quad edge length: the nearest that lifts every quad around it to the threshold,
  // else the one that raises their worst quality most, never making a good quad bad. The steps
  // slide a vertex by a fraction of its edges and move its neighbours too, which cannot untwist
  // a quad folded around a knife edge thinner than a quad (a screwdriver's blade) and pulls the
  // quads off a thin tip. 0 = off.
  double jump_reach = 1.0;
  // Shape fitting, last: the quads are moved closer to the surface where they are farthest from
  // it. A vertex (not fixed, not on a feature, only of quads) whose local distance (the largest
  // two-sided distance between its quads and the surface under them) exceeds fit_fraction of the
  // largest local distance of the vertices that may move, before fitting, moves to the surface
  // sample (a vertex of the surface or a point inside one of its triangles) under its quads,
  // within half its mean quad edge length, that lowers its local distance most, if every quad
  // around it keeps its quality or stays at least fit_min_quality; farthest vertices first, up to
  // fit_rounds rounds. Vertices stay on the surface. It brings in tips and ridges that the quads
  // cut off. fit_fraction 0 = off.
  double fit_fraction = 0.8;
  double fit_min_quality = 0.2;
  int fit_rounds = 3;
  // Diagonal choice, before the shape fitting and after it: a quad is a bilinear patch for some
  // consumers, but OBJ viewers, glTF (written as triangles) and the metrics split it along its
  // diagonal from its first corner, (0,1,2) and (0,2,3). A quad whose other diagonal gives two
  // triangles closer to the surface (by more than 1%; largest distance of a grid of samples), and
  // not overlapping, starts at its next corner instead: the same quad, orientation and UVs, a
  // closer triangulated surface. On a curved surface the split along the diagonal that follows
  // the direction of lesser curvature deviates less.
  bool choose_diagonals = true;
};

struct RelaxStats {
  int n_bad_before = 0;  // quads below min_scaled_jacobian before
  int n_bad_after = 0;   // and after
  // Quads with a corner scaled Jacobian ≤ 0 or facing away from the surface (their area vector
  // against the normal of the surface triangle closest to their centroid, as quad_metrics counts
  // flips); the repair treats such a quad's cosine to that normal as its quality.
  int n_flipped_before = 0, n_flipped_after = 0;
  int n_moves = 0;       // accepted vertex moves
  int n_jumps = 0;       // sample jumps (see jump_reach)
  int n_feature_vertices_moved = 0;  // vertices on features or boundaries moved by the last resort
  // Quads lifted from below 0.05 (flipped or slivers: a fold) by the local pass with raised
  // thresholds.
  int n_unfolded = 0;
  int n_snapped = 0;     // vertices moved onto a feature they were near (see snap_reach)
  int n_tentative_snaps = 0;  // of those, snaps kept by a second repair (see tentative_snaps)
  int n_fitted = 0;      // moves of the shape fitting (see fit_fraction)
  int n_diagonals_turned = 0;  // quads that start at their next corner (see choose_diagonals)
  // Largest two-sided distance between the faces and the surface samples (× bounding-box
  // diagonal) before and after the shape fitting, as it measures it (0 when it did not run).
  double fit_distance_before = 0, fit_distance_after = 0;
  double seconds = 0;
};

struct RelaxResult {
  core::Status status;
  core::PolyMesh quads;
  RelaxStats stats;
};

// Repairs the quads of `quads` (faces of degree ≠ 4 are left alone and do not count) whose worst
// corner is below options.min_scaled_jacobian, moving vertices on `surface` (the input triangle
// mesh: moved vertices are its closest points to the neighbour centroids). Deterministic.
// Returns kInvalidInput for bad options, an empty surface or vertex ids out of range.
[[nodiscard]] RelaxResult relax_bad_quads(const core::PolyMesh& quads, const core::TriMesh& surface,
                                          const RelaxOptions& options = {});

}  // namespace quadify::quadex
