// Direct seamless parametrization (Levi 2021, "Direct Seamless Parametrization", sections 3–5
// and 8.1): cut along a dual spanning tree, lay out isometrically, then round the seam matchings
// in batches of increasing rounding error while re-optimizing a flip-free layout subject to the
// seamlessness constraints e' = R_90^r e of the rounded edges.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>

#include <Eigen/Core>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace quadify::param {

// Distortion measure minimised by the layout optimization (paper section 8.5).
enum class Energy {
  kTau,                // max distortion τ = sqrt(σ1max/σ2min): symmetric Dirichlet, then an L^p
                       // continuation of it that drives the maximum down; flip-free
  kSymmetricDirichlet, // Σ area·(σ1² + σ1⁻² + σ2² + σ2⁻²); a barrier, flip-free
  kArap,               // Σ area·((σ1−1)² + (σ2−1)²); no barrier (flips are counted, not prevented)
  kLinfArap,           // L^p ARAP with a large p, approximating the max ARAP distortion
  kConformal,          // MIPS conformal energy Σ area·(σ1/σ2 + σ2/σ1); scale-free
};

// When feature edges get their alignment (paper section 6).
enum class FeatureMode {
  kDuringRounding,  // Alg. 2: labeled with the matchings, batch by batch, as hard constraints
  kAfterRounding,   // Alg. 3: after every matching is rounded, as soft constraints (a penalty
                    // raised until the alignment error is at most soft_feature_tolerance)
};

// Order of the batches of matching rounding (paper 8.1).
enum class RoundingOrder {
  kBottomUp,  // ε = step, 2·step, …, 0.5: round the most certain matchings first (default)
  kTopDown,   // ε = 0.5−step, …, 0: round matchings with rounding error ≥ ε first
};

struct ParamOptions {
  Energy energy = Energy::kTau;
  RoundingOrder order = RoundingOrder::kBottomUp;
  // Increment of the rounding-error threshold ε between batches, in quarter turns (paper: 0.1).
  double threshold_step = 0.1;
  // Choose floor/ceil of uncertain matchings by laying out a local patch both ways (paper §5).
  bool local_estimation = true;
  // Matchings with rounding error ≥ this (quarter turns) go through local estimation (paper: 0.3).
  double local_estimation_min_error = 0.3;
  // Size of a local-estimation patch: vertex-ring BFS levels around the edge (paper: 5).
  int patch_bfs_levels = 5;
  // Newton iterations per layout optimization (one per batch and per penalty stage).
  int max_newton_iters = 60;
  // Allowed seam residual |e' − R^r e| of the result, relative to the bounding-box diagonal.
  double seam_tol = 1e-9;
  // Cone-pair cancellation (not in the paper; for quad meshing): after the last batch, pairs of a
  // +1 and a −1 cone joined by a path of at most cone_pair_max_hops seam edges whose 3D length is
  // at most cone_pair_distance (model units) are removed by changing the matchings along the path
  // by one quarter turn, followed by a flip-free re-optimization (a set that cannot be made
  // flip-free is split and retried, then dropped). Such pairs cannot sit on two distinct integer
  // points of a grid coarser than their distance. 0 = off (the paper's method).
  double cone_pair_distance = 0;
  int cone_pair_max_hops = 3;
  // With cone_pair_distance > 0: then also the pairs within cone_pair_distance over the surface
  // (the shortest path over the mesh's edges) whose seam path is longer, by changing the matchings
  // along that seam path, however long (the map is the one a cut along the surface path would give,
  // up to a rotation of the charts between the two paths; a dual-spanning-tree cut joins
  // neighbouring vertices by seam paths 2-9 times longer than the surface's: knot1). Off the
  // aligned features' vertices; a set is kept when the map's τ at that stage stays within 1.25
  // times its τ before the surface pairs and it changes no face's singular values by more than
  // 1.75 times (else it goes again without the pairs nearest to the faces beyond that; a pair
  // that failed on its own is not tried again). Not on the smoothed copy of cone_scale, nor on a
  // map continue_before_tau rejects. Without the size bound, over 20 meshes at 5,000
  // quads: irregular vertices 903 → 711, but Hausdorff higher on 12 (spot 0.0037 → 0.0057,
  // mannequin-devil 0.0089 → 0.0174: a protrusion shrunk); see the README.
  bool cone_pair_surface = false;
  // With cone_pair_surface: once no near pair is left, a second wave over the pairs within this
  // many times cone_pair_distance over the surface, under the same τ and size bounds (≤ 1 = off).
  // Taking them in the first wave instead (a 4 times larger cone_pair_distance) lets far pairs
  // crowd out near ones whose sets then fail: over the 20-mesh regression at 5,000 quads,
  // irregular vertices rise on dilo 70 → 84, rocker-arm 18 → 26, spot_nonmanifold 34 → 44. As a
  // second wave: fertility 42 → 40, genus3 28 → 24, spot 26 → 22, three_components 40 → 36, the
  // 16 others unchanged (8 times: the same).
  double cone_pair_far_factor = 4;
  // Cone splitting (not in the paper; for quad meshing): after the cancellation, a cone of index
  // above cone_split_max_index (index 3: UV angle π/2, a quad vertex of valence 1, which no quad
  // mesh has; index 2: a flat quad corner; the rounding makes them at the tips of thin parts,
  // such as octopus's tentacles) gives one unit of index at a time to a regular vertex whose path
  // along the seams (≤ 64 edges, through regular vertices, off aligned features) is closest to
  // cone_split_distance (model units) and at most twice it, followed by the flip-free
  // re-optimization of the cancellation. With cone_split_max_index 1, +1 cones closer than half
  // the distance to another +1 cone move too. cone_split_distance 0 = off (the paper).
  double cone_split_distance = 0;
  int cone_split_max_index = 2;
  // Coarse cones (not in the paper; for quad meshing at coarse densities): when > 0, the
  // matchings are rounded (Alg. 1, with the cone-pair cancellation) on a copy of the mesh
  // smoothed at this length (model units; one implicit cotangent-Laplacian heat step of time
  // cone_scale²), where curvature details smaller than it do not make cones of their own, and
  // the layout is then optimized on the mesh itself under those matchings, flip-free (symmetric
  // Dirichlet for Energy::kTau). Ignored when features, boundary alignment or directions are
  // asked for (their labels belong to the original layout). If the smoothed copy collapses or
  // its map cannot be carried over flip-free, the mesh is parametrized as with 0 (the reason is
  // in ParamStats::coarse_cones_fallback_reason). 0 = off (the paper's method).
  double cone_scale = 0;
  // With cone_scale > 0: whether a coarse path that cannot be used falls back to the paper's map
  // (true), or returns its failure status (false; for a caller that already holds that map).
  bool cone_scale_fallback = true;
  // Feature alignment (paper section 6, Alg. 2): each of these mesh edges (pairs of vertex ids,
  // in either order) is made parallel to the u or the v axis of its chart, labeled together with
  // the matchings in the same batches (a label is rounded like a matching: the edge's angle to the
  // u axis in quarter turns, Def. 6.1), so that quantization can put it on an integer iso-line.
  // A pair that is not an edge of the mesh is an error (kInvalidInput). Boundary edges may be
  // listed; see also align_boundaries.
  std::vector<std::array<int, 2>> feature_edges;
  // Treat every boundary edge as a feature edge (boundary-aligned maps: open meshes then give
  // pure-quad boundaries).
  bool align_boundaries = false;
  // Labels of features with alignment error ≥ local_estimation_min_error are chosen by local
  // estimation (the patch laid out with the edge along u and along v); a feature whose better
  // patch layout still has τ above this is disabled (paper 8.4: 2.5). Features whose labels would
  // close a wedge between two features at a vertex (both along one direction) are disabled too.
  double feature_max_tau = 2.5;
  // Two features meeting at a vertex whose wedge would open or close by more than this factor
  // (its target angle, a multiple of 90°, against its angle on the surface) keep only the older
  // label (a wedge at a boundary, where open meshes need their corners, uses feature_max_tau).
  // Creases meeting almost straight (180° on the surface) would become 90° and 270° (a stretch
  // of 2, a flat quad corner counted as flipped): below 2, one of them is disabled instead.
  // Measured at 5,000 quads (with the wedge check fixed to use each label's own axis), 1.8
  // against 2.5: flipped quads fandisk 16 → 1, beetle 20 → 14, wingnut 1 → 0, for feature capture
  // fandisk 0.982 → 0.950 and beetle 0.980 → 0.932 (wingnut 0.807 → 0.846). 1.95 since
  // 2026-12-05 (still below the straight case's 2; the relaxation now unfolds what 1.8 avoided):
  // at 5,000 quads, 0 flipped on every CAD mesh either way, capture block 0.933 → 0.944,
  // wingnut 0.925 → 0.935, teapot 0.539 → 0.591, fandisk_degenerate 0.968 → 0.974, casting 0.858 →
  // 0.852; Hausdorff fandisk 0.0066 → 0.0035, fandisk_degenerate 0.0097 → 0.0060, casting 0.0085
  // → 0.0080, block 0.0079 → 0.0086; worst corner wingnut 0.135 → 0.090, fandisk_degenerate
  // 0.200 → 0.092.
  double feature_max_wedge_stretch = 1.95;
  // Alg. 2 with whole curves (ours, opt-in): the features of a smooth curve (consecutive edges
  // within 30° of straight on the surface) are to become one straight iso-line, followed along
  // the curve in the layout; an edge within 60° of it takes its label when that turn falls below
  // the batch threshold, the others are labeled edge by edge as in the paper. Edge by edge, a
  // curve that bends past 45° in the layout switches axes where it is straight on the surface,
  // and the wedge check disables the edges there (fandisk's curved rims at 5,000 quads:
  // Hausdorff 0.0066 → 0.0028 with it). Off by default: over 11 meshes at 5,000 quads and 4 at 2,000 and
  // 10,000, Hausdorff was worse in 10 runs of 16 (see the README's design notes).
  bool feature_curve_labels = false;
  // With feature_curve_labels: a smooth curve that turns by 60° or more within this arc length
  // (model units; a rounded corner at the scale of the quads: the remesher passes two target quad
  // edges) is split there, at the middle of the rounding, into curves labeled on their own. 0 = off.
  double feature_corner_length = 0;
  // Alg. 2 at acute corners (ours): where two creases meet at 15° to 45° on the surface (fandisk's
  // 22° wedge), labeled edge by edge both take the same axis near the corner, the wedge check
  // disables the edges at its tip, and the wedge is laid out as a strip of one width between two
  // parallel iso-lines, squeezed where it is wide (fandisk's τ 2.91). The smooth curves that end
  // at such a corner are labeled as whole curves (as with feature_curve_labels), their straight
  // run from the corner (edges within 45° of the first), so that each stays one straight
  // iso-line and the wedge opens to a quarter turn at its tip (τ 2.05). Narrower spurs
  // (wingnut's 4°-13°) are left to the edge-by-edge labels. The quad remesher turns it off by
  // default: at 5,000 quads fandisk's quads were farther from the input (Hausdorff 0.0020 ->
  // 0.0036; README, "Acute corners").
  bool feature_acute_curve_labels = true;
  FeatureMode feature_mode = FeatureMode::kDuringRounding;
  // Alg. 3: largest |Δ constant coordinate| / |edge| accepted for a soft-aligned feature (the
  // paper reports at most 1e-5).
  double soft_feature_tolerance = 1e-5;
  // Isotropic sizing (paper section 7): the target edge length of each face relative to its 3D
  // size (#F positive values; empty = uniform). The distortion energy compares the map with the
  // triangle scaled by 1/face_size (the "transformed source triangle"), so a face of size 2 asks
  // for quads twice as long as a face of size 1. libquantize must be given the same field
  // (QuantizeOptions::face_size); only ratios matter there, as the map is scaled to the target.
  std::vector<double> face_size;
  // Anisotropic sizing (paper section 7): per face a 3×3 matrix applied to its 3D edge vectors
  // before its rest shape is taken (#F, or empty), e.g. diag(1/s1, 1/s2, ·) in a principal
  // frame asks for quads of edge lengths s1 and s2 along the two directions; combined with
  // face_size when both are given. libquantize needs the same (QuantizeOptions::face_metric).
  std::vector<Eigen::Matrix3d> face_metric;
  // Direction alignment (paper section 6.1, e.g. principal curvature directions from
  // param::principal_face_directions): per face a 3D direction (#F, or empty; a zero vector
  // leaves the face free) that the map should send onto a UV axis, either one (a cross). Unlike
  // the paper, which aligns a reference edge with hard constraints through the feature
  // machinery, the alignment is soft: every layout optimization adds
  // direction_weight·Σ area·|J d|²·sin²(angle of J d to its nearest axis), so directions that no
  // seamless map can follow (non-integrable fields, noise) cost distortion instead of cones or
  // flips. Before the first batch the unconstrained layout is optimized with it, so the matchings
  // are rounded on the aligned layout. With face_metric, d is measured in the metric.
  std::vector<Eigen::Vector3d> face_direction;
  // Weight of the alignment against the distortion energy (SD at an isometry is 4 per unit area;
  // the L^p stages of kTau keep that balance). 3 against 1: mean quad-edge angle to the principal
  // directions at 5,000 quads rocker-arm 9.6° → 8.6°, elk 11.9° → 10.6°, fertility 13.7° → 11.7°
  // (22.5° = random; without alignment 23–25°).
  double direction_weight = 3;
  // Rotate the initial layout so that the largest group of feature directions lies along the u
  // axis (Alg. 4, k-means of the feature edge directions on the unit circle).
  bool feature_global_rotation = true;
  // TBB worker threads for components, local-estimation patches and per-face energy evaluation;
  // 0 = all hardware threads. The result does not depend on this number. (CHOLMOD's own
  // OpenMP/BLAS threads are not governed by it.)
  int threads = 0;
  // Optional progress callback (stage "round": batch step of n_steps; "cone pairs": pass of the
  // cone-pair cancellation, out of 4; stage "tau": exponent of the L^p continuation, out of 64).
  // Calls are serialized, but with several components they may come from worker threads.
  std::function<void(const std::string& stage, int step, int n_steps)> progress;
  // Optional: asked once the matchings are final (after the last batch, the cone-pair
  // cancellation and the cone splits), before τ's L^p continuation, with the number of cones;
  // only with Energy::kTau, on a mesh of one component (with several, the cones are known only
  // together) and without coarse cones (cone_scale 0 or its fallback). Returning false skips the continuation: the result keeps the last batch's
  // symmetric Dirichlet layout (seamless and flip-free, converged less tightly) and sets
  // ParamStats::stopped_before_tau. For a caller that only needs the cones to decide what to do
  // next (the remesher's coarse cones).
  std::function<bool(int n_cones)> continue_before_tau;
};

struct ParamStats {
  int n_components = 0;
  int n_seam_edges = 0;        // interior edges not in the dual spanning tree
  int n_cones = 0;             // interior vertices with a non-zero index
  int n_patches = 0;           // local-estimation patches laid out
  int n_improved = 0;          // patches whose choice differs from the nearest rounding
  int n_batches = 0;           // rounding batches that rounded at least one matching
  int n_cancelled_pairs = 0;   // cone pairs removed by cone-pair cancellation
  int n_surface_pairs = 0;     // of those: pairs near over the surface only (cone_pair_surface)
  int n_far_pairs = 0;         // of those: the second wave's (cone_pair_far_factor)
  int n_split_cones = 0;       // units of index moved off cones by cone splitting
  int n_deferred_matchings = 0;  // seams whose rounding a batch deferred (flips near them)
  bool coarse_cones = false;   // the matchings were rounded on the smoothed copy (cone_scale)
  bool stopped_before_tau = false;  // ParamOptions::continue_before_tau returned false
  std::string coarse_cones_fallback_reason;  // why cone_scale was asked for but not used
  int n_feature_edges = 0;     // feature edges asked for (listed, plus boundaries if aligned)
  int n_aligned_features = 0;  // feature edges aligned in the result (see ParamResult::features)
  int n_disabled_features = 0; // feature edges whose alignment was disabled (τ bound, wedge
                               // conflicts, or a batch that could not be made flip-free)
  int n_disabled_by_tau = 0;    // of those: local τ above feature_max_tau (or stretched, Alg. 3)
  int n_disabled_by_wedge = 0;  // of those: wedge conflicts with a neighbouring feature
  int n_disabled_by_flips = 0;  // of those: the batch could not be made flip-free with them
  int n_feature_patches = 0;   // local-estimation patches laid out for feature labels
  int n_acute_curves = 0;      // curves labeled whole at acute corners (feature_acute_curve_labels)
  int n_feature_fallbacks = 0; // components that failed with their features and were
                               // parametrized again without them (all counted as disabled)
  int n_feature_partial_fallbacks = 0;  // components that failed with their features and were
                                       // parametrized again without those within 2 vertex rings
                                       // of the faces their last batch left flipped (those
                                       // counted as disabled by flips)
  std::string feature_fallback_reason;  // why the first failed run of either failed ("" if none)
  double feature_alignment_error = 0;  // max |Δ constant coordinate| / |edge| over aligned ones
  int n_direction_faces = 0;   // faces with a direction to align (ParamOptions::face_direction)
  // Area-weighted mean angle (degrees, 0..45) between those directions' images and the nearest
  // UV axis, in the initial isometric layout (after the global rotation) and in the result.
  double direction_angle_initial = 0, direction_angle = 0;
  int total_iterations = 0;    // Newton iterations over all optimizations (global layout)
  int n_flipped = 0;           // faces with non-positive UV orientation (exact predicate)
  int n_free_variables = 0;    // reduced variables after all constraints (summed over components)
  int max_constraint_fill = 0; // longest dependent-variable expression of the elimination
  double tau = 0;              // sqrt(σ1max/σ2min) of the final map; +inf if flipped
  double sd_max = 0;           // max per-face symmetric Dirichlet energy (4 = isometry)
  double seam_residual = 0;    // max |e' − R^r e| over seam edges, in UV units
  double seconds_cut = 0, seconds_optimize = 0, seconds_local_estimation = 0,
         seconds_total = 0;
  // Profile of seconds_optimize (summed over components): constraint elimination, element maps
  // and Hessian pattern (setup), energy/gradient/Hessian evaluation (assembly), symbolic analysis,
  // numeric factorization + solve, line search, least-squares projections, and the part spent in
  // the τ continuation. Newton iterations split by phase.
  double seconds_elimination = 0, seconds_setup = 0, seconds_assembly = 0, seconds_analyze = 0,
         seconds_factorize = 0, seconds_line_search = 0, seconds_projection = 0, seconds_tau = 0;
  long long max_hessian_nonzeros = 0;  // largest reduced Hessian of the global layout
  int max_element_variables = 0;       // reduced variables of the widest face element
  long long max_sum_sq_element_variables = 0;  // largest Σ_f k_f² (k_f: a face's reduced variables)
  int n_transition_iterations = 0, n_batch_iterations = 0, n_tau_iterations = 0;
};

// One seam edge of the result: the edge (edge_vertex0, edge_vertex1) shared by face_a and face_b.
// With e_a = uv_a(v1) − uv_a(v0) in face_a and e_b likewise in face_b: e_b = R_90^matching e_a.
struct SeamMatching {
  int face_a = -1, face_b = -1;
  int edge_vertex0 = -1, edge_vertex1 = -1;
  int matching = 0;  // quarter turns, 0..3
};

// An interior vertex where the UV angle sum differs from 2π: index = 4 − angle_sum/(π/2)
// (quarter turns; +1 at a valence-3-like cone, −1 at a valence-5-like cone).
struct ConeInfo {
  int vertex = -1;
  int index = 0;
};

// An aligned feature edge: the half-edge of `face` from corner k to corner (k+1)%3 keeps UV
// coordinate `constant_coord` (0: u, 1: v) constant, i.e. it runs along the other axis. The other
// side of an interior feature edge is aligned too (through its seam's matching).
struct FeatureAlignment {
  int face = -1;
  int corner = 0;
  int constant_coord = 0;
};

struct ParamResult {
  core::Status status;
  core::UVMesh uv;                 // the input mesh with (#F·3)×2 corner UVs
  std::vector<SeamMatching> seams;
  std::vector<ConeInfo> cones;
  std::vector<FeatureAlignment> features;
  ParamStats stats;
};

// Computes a seamless parametrization of every connected component of `mesh` (Alg. 1 of the
// paper, with local estimation of §5). Components are processed independently (in parallel
// when built with TBB) and are laid out in separate UV charts that may overlap.
// Preconditions: manifold, consistently oriented, finite V, non-degenerate triangles.
// Returns kInvalidInput on a violated precondition or bad options, kNumericalFailure when a
// factorization fails, kNotConverged when the seamless layout could not be made flip-free
// (the result is still returned, with stats.n_flipped > 0).
[[nodiscard]] ParamResult compute_seamless_param(const core::TriMesh& mesh,
                                                 const ParamOptions& options = {});

}  // namespace quadify::param
