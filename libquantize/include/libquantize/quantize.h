// Quantization of a seamless parametrization into an integer-seamless one (Levi 2021, Def. 3.2):
// across every seam (u', v') = R_90^r (u, v) + (s, t) with (s, t) ∈ Z², and every cone at an
// integer point, flip-free, at a chosen density. The result feeds quadex::extract_quads.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>
#include <libparam/seamless_param.h>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace quadify::quantize {

// A dead end of the rounding (QuantizeOptions::continue_after_dead_end).
struct DeadEnd {
  int attempt = 0;         // attempts made so far (this one included), with and without features
  int attempts_without_features = 0;  // of those, without aligned features
  double scale = 1;        // this attempt's scale / the target scale
  int cone_vertex = -1;    // mesh vertex of the cone that reached no grid point, or -1
  std::vector<int> faces;  // mesh faces that resisted the blocked move
  std::string reason;
};

struct QuantizeOptions {
  // Number of quads wanted: each unit square of the scaled map is one quad, so the map is scaled
  // to a UV area of target_faces. 0: use edge_length; if both are 0 the default target is
  // max(5000, #F / 6) quads (about one quad per three triangle pairs, and at least 5,000: a
  // triangulated CAD part has few triangles for its features; see kMinDefaultQuads).
  int target_faces = 0;
  // Quad edge length in model units (used when target_faces = 0): the map, near-isometric up to
  // a global factor, is scaled so that one UV unit ≈ edge_length on the surface.
  double edge_length = 0;
  // Distortion minimised while moving into the integer constraints (kTau is optimized as
  // kSymmetricDirichlet). Barrier energies keep every step flip-free.
  param::Energy energy = param::Energy::kSymmetricDirichlet;
  // Increment of the rounding-error threshold between batches: batch i rounds the unknowns whose
  // distance to the nearest integer is below (i+1)·threshold_step; the last batch takes the rest.
  double threshold_step = 0.125;
  // Newton iterations of the flip-free re-optimization after each batch.
  int max_newton_iters = 30;
  // When the rounding dead-ends at the target scale, it restarts at the scales ×(1 ± k·
  // near_scale_step), k = 1, 1, 2, 2, … (near_scale_tries of them: the quad count stays within
  // about ±8% of the target), then at the refinements ×scale_growth^k, k = 1..max_scale_retries.
  int near_scale_tries = 4;
  double near_scale_step = 0.02;
  int max_scale_retries = 3;
  double scale_growth = 1.25;
  // Aligned features: when the rounding dead-ends on a cone, or on a seam translation with the
  // feature lines still free, the alignment rows on the faces that resist the blocked move (or
  // within a few vertex rings of them) are released and the rounding goes on; after this many
  // releases in one run the next attempt starts (features rounded last, then none). 0: any dead
  // end drops to the next attempt.
  int feature_release_rounds = 32;
  // Count correction (with target_faces or the default density, not with edge_length; 0 = off,
  // the default). The re-optimizations change the map's area (the quad count) by a few percent:
  // +2.7% on average at 5,000 quads, ±2% from mesh to mesh and scale to scale. With
  // count_tolerance > 0 the scale allows for the average growth, and while the count is further
  // than count_tolerance × target from the target, the
  // rounding is run again at a scale corrected by the growth measured, up to
  // max_count_corrections times (each costs about what the first rounding did), and the map
  // closest to the target is kept (a run that dead-ends, or keeps fewer feature lines, changes
  // nothing). 0.015 suits: below 1.5% a new rounding is about as likely to land further away as
  // closer. Off by default: every run lands on another rounding (as at another target), which
  // costs time where it collides cones (feline: 12 → 24 s) and moves the figures both ways.
  double count_tolerance = 0;
  int max_count_corrections = 2;
  // With target_faces, or the default density (not with edge_length, which asks for no count):
  // once the rounding is done, up to this many integer unknowns (a seam
  // translation, a cone coordinate, a feature line) are moved by one unit each, where the quad
  // count that gives (known exactly before the move on a closed map: the count depends on the
  // integers alone) is closer to the target; a move is kept only if the map stays flip-free and
  // its symmetric Dirichlet energy grows by at most the share of the target it gains (and 1%);
  // until the count is within 0.5% of the target. Each move tried is a whole-mesh solve. 0 (the
  // default here): off; the remesher asks for 8 up to 60,000 input triangles, which puts 18 of 20
  // bench meshes within 0.5% of 5,000 quads, the Hausdorff distance moving both ways like
  // another rounding would (see quantize.cpp).
  int max_count_adjustments = 0;
  // When the rounding with the aligned features dead-ends: true, quantize the same map without
  // them (at every scale); false, stop there with status kNotConverged and stats.features_dropped
  // set, for a caller that parametrizes again without the features (the map they shaped has
  // more cones and distortion; the remesher does this).
  bool quantize_without_features = true;
  // Allowed seam residual of the input |e_b − R^r e_a|, × its UV bounding-box diagonal.
  double input_seam_tol = 1e-6;
  // Bound on the re-optimizations' element Hessians, as param::PinnedLayoutOptions::
  // max_element_entries: a layout above it is refused (kNumericalFailure). With the aligned
  // features' rows it counts as the features not fitting (see quantize_without_features).
  double max_element_entries = 4e7;
  // Worker threads of the optimizer; 0 = all hardware threads. The result does not depend on it.
  int threads = 0;
  // Isotropic sizing: the same per-face sizes as param::ParamOptions::face_size (or empty). The
  // re-optimizations use the sized rest shapes, and the target count and edge length refer to the
  // sized area Σ area/size² (a size field normalized to keep that equal to the surface area, as
  // the CLI's are, leaves the quad count where the target puts it).
  std::vector<double> face_size;
  std::vector<Eigen::Matrix3d> face_metric;  // as param::ParamOptions::face_metric (or empty)
  // Direction alignment kept through the re-optimizations: as param::ParamOptions::face_direction
  // and direction_weight (or empty).
  std::vector<Eigen::Vector3d> face_direction;
  double direction_weight = 3;
  // Wall-clock limit of the quantization in seconds (0 = none). When it is exceeded the result
  // is kNotConverged with a message naming the scale, the stage and what to try.
  double time_budget_seconds = 0;
  // Wall-clock limit of the rounding with the aligned features in seconds (0 = none), counted
  // from the start of the quantization: when it is exceeded the features are treated as not
  // fitting (as a dead end: stats.features_dropped, then quantize_without_features decides).
  // The rounding of a map whose features cannot fit can spend many minutes in collisions and
  // releases before it dead-ends (dragon, 108K triangles: 708 s).
  double feature_time_budget_seconds = 0;
  // Optional progress callback, once per batch: stage "quantize x<scale factor> cones" or
  // "... translations", step = integer unknowns rounded so far of n_steps independent ones.
  std::function<void(const std::string& stage, int step, int n_steps)> progress;
  // Optional: asked after an attempt without aligned features dead-ends, before the next scale
  // is tried; false stops there (kNotConverged naming the dead end; stats.stopped_at_dead_end).
  // A caller that has a better next step than more scales for some dead ends uses it (the
  // remesher: a cone stuck in a part thinner than the quads, see DeadEnd).
  std::function<bool(const DeadEnd&)> continue_after_dead_end;
};

struct QuantizeStats {
  double scale = 0;         // final factor from the input UVs to the integer map's UVs
  int n_scale_retries = 0;  // restarts at another scale (near ones first, then refinements)
  int n_count_corrections = 0;       // roundings run again for the count (count_tolerance)
  int n_count_corrections_kept = 0;  // of those, closer to the target than the map before
  int n_count_adjustments = 0;       // integer unknowns moved by one unit for the count
  double seconds_count_adjustment = 0;
  int n_candidates = 0;     // integer quantities: cone-copy coordinates, seam translations and
                            // the constant coordinates of aligned feature ends
  int n_integer_dofs = 0;   // of those, independent ones (after exact elimination)
  int n_rounded = 0;        // candidates made integer (all but released feature ends on success)
  int n_reverted = 0;       // batch splits and roundings to the other neighbouring integer
  int n_batches = 0;        // constrained re-optimizations that succeeded
  int n_flipped = 0;        // flipped or degenerate faces of the result (exact predicate)
  int n_cones = 0;
  // Faces (increasing) of the components that keep a cone of index 3 or more: a component of
  // fewer than 16 quads at the target scale, which the grid cannot resolve, may keep one (a
  // larger one is refused, kInvalidInput). Such a cone would be a quad vertex of valence 1 or 0:
  // extract the quads without these faces (quadex::split_small_components replaces a component
  // with no quads by its split triangles).
  std::vector<int> faces_with_unresolved_cones;
  // Aligned features of the input map (param::FeatureAlignment) that the result has exactly on
  // integer iso-lines. Feature lines that reach no integer flip-free are released (left where
  // they are; n_released_feature_lines), unless a cone or translation depends on them. A cone or
  // translation that dead-ends releases the alignment of the feature edges in its way
  // (n_released_feature_edges); when the rounding still dead-ends at the target scale, all
  // features are dropped (features_dropped) and the map is quantized without them.
  int n_aligned_features = 0;
  int n_released_feature_lines = 0;
  // Aligned feature edges whose alignment was released near a dead end of the rounding (see
  // QuantizeOptions::feature_release_rounds; 0 when the features were dropped).
  int n_released_feature_edges = 0;
  bool features_dropped = false;
  std::string features_dropped_reason;  // why the rounding with the features dead-ended
  // The rounding stopped at a dead end because continue_after_dead_end said so.
  bool stopped_at_dead_end = false;
  // The quantization stopped at QuantizeOptions::time_budget_seconds (kNotConverged).
  bool out_of_time = false;
  int n_cone_collisions = 0;  // cones that their batch could not move to the chosen grid point
  int n_clustered_cones = 0;  // cones rounded jointly because another cone was within 1.5 units
  int n_unstuck_cones = 0;    // cones that reached a grid point only with their neighbours rounded again
  int n_iterations = 0;       // Newton iterations (one factorization each) in total
  double uv_area = 0;         // UV area of the result (≈ number of quads)
  double uv_area_unadjusted = 0;  // of QuantizeResult::uv_unadjusted, when it is kept
  double seconds = 0;
  double seconds_setup = 0;     // elimination, element maps and symbolic analysis (per scale)
  double seconds_rounding = 0;  // initial relaxation and the pinned batches
  double seconds_final = 0;     // final relaxation
};

struct QuantizeResult {
  core::Status status;
  core::UVMesh uv;  // the input mesh with integer-seamless corner UVs, (#F·3)×2
  // The same map before the count adjustment (QuantizeOptions::max_count_adjustments), exact and
  // flip-free as uv, when the adjustment moved it; else empty corner_uv. For a caller that
  // measures both (the remesher keeps the adjusted map unless its quads are 1.5 times as far from
  // the input, or beyond 1% of its diagonal where the others are not).
  core::UVMesh uv_unadjusted;
  QuantizeStats stats;
};

// The quad edge length in model units that `options` ask for on `mesh`: options.edge_length, or
// sqrt(3D area / target quads) with the target (or default target) face count. Used to size
// density-dependent choices before the map exists (e.g. param::ParamOptions::cone_pair_distance).
[[nodiscard]] double target_edge_length(const core::TriMesh& mesh, const QuantizeOptions& options);

// The param::ParamOptions::cone_pair_distance that suits quantization at `options`' density:
// quad_edges target quad edge lengths, and at least 8 mean edge lengths of the input (the pairs
// made by the rounding of matchings sit a few mesh edges apart whatever the density); 0 when
// quad_edges ≤ 0. Use with cone_pair_max_hops = kRecommendedConePairHops.
[[nodiscard]] double recommended_cone_pair_distance(const core::TriMesh& mesh,
                                                    const QuantizeOptions& options,
                                                    double quad_edges = 4);
inline constexpr int kRecommendedConePairHops = 6;

// The param::ParamOptions::cone_scale that suits quantization at `options`' density, for a
// feature-free map with n_cones cones: 0 (the paper's map as it is) while the cones beyond the
// 4|χ| a closed surface needs are at most one per quads_per_cone (kQuadsPerCone) target quads, else
// kCoarseConeQuadEdges target quad edge lengths
// (the matchings rounded on a smoothed copy). Measured at 5,000 quads: maps with one cone per
// 28 quads or more (mannequin-devil 177, dragon about 380) dead-end in the rounding, where the
// coarse map rounds in seconds; the bench meshes that quantize have one per 54 or fewer.
inline constexpr double kQuadsPerCone = 40;
inline constexpr double kCoarseConeQuadEdges = 1.4;
[[nodiscard]] double recommended_cone_scale(const core::TriMesh& mesh, const QuantizeOptions& options,
                                            int n_cones, double quads_per_cone = kQuadsPerCone);

// The feature edges (vertex-id pairs of `mesh`) that quantization at `options`' density can keep
// on integer iso-lines: a feature curve (a connected component of the feature edges) shorter
// than min_quad_edges target quad edges, or a closed one shorter than four times that, is dropped
// (it cannot hold distinct grid points; e.g. a tiny hole's boundary or a short crease of a scan).
[[nodiscard]] std::vector<std::array<int, 2>> features_for_density(
    const core::TriMesh& mesh, const std::vector<std::array<int, 2>>& feature_edges,
    const QuantizeOptions& options, double min_quad_edges = 1);

// The length of the longest curve (connected component) of `edges` (vertex-id pairs of `mesh`)
// in target quad edges at `options`' density, and whether some curve is a knife edge (the median
// dihedral angle of its edges, between their two faces, at least knife_deg degrees). The remesher
// leaves out creases that are all shorter than a few quad edges and no knife edge: an organic
// model's stray fragments (see RemeshArgs in the CLI).
struct CurveSummary {
  double longest_quad_edges = 0;
  bool has_knife_edge = false;
};
[[nodiscard]] CurveSummary summarize_curves(const core::TriMesh& mesh,
                                            const std::vector<std::array<int, 2>>& edges,
                                            const QuantizeOptions& options, double knife_deg = 120);

// Quantizes `seamless` (a result of param::compute_seamless_param for `mesh`, or any map with
// seams listed with their matchings and every cone in seamless.cones) into an integer-seamless
// map: greedy batch rounding of the independent integer unknowns, each batch followed by a
// flip-free re-optimization, then exact snapping (see quantize.cpp for the method).
// The result is integer-seamless bit-exactly: transitions and cone UVs are exact integers.
// Returns kInvalidInput for a mismatching or non-seamless input (naming the edge), flipped input
// faces, or bad options; kNotConverged when no tried scale could be made flip-free (uv holds
// the best integer-seamless attempt, stats.n_flipped > 0, or the input when none was found);
// kNumericalFailure when a factorization fails; kInternal if the exact verification fails.
[[nodiscard]] QuantizeResult quantize_seamless(const core::TriMesh& mesh,
                                               const param::ParamResult& seamless,
                                               const QuantizeOptions& options = {});

}  // namespace quadify::quantize
