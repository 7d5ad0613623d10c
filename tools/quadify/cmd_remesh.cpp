// quadify [remesh] IN -o OUT.{obj,gltf,glb}: the whole pipeline — read and repair, seamless
// parametrization (libparam), integer-seamless quantization (libquantize), quad extraction
// (libquadex), export — with progress per stage and the quad metrics in the report.
#include "commands.h"

#include <libcore/atomic_file.h>
#include <libcore/write_mesh.h>
#include <libparam/seamless_param.h>
#include <libparam/sizing.h>
#include <libquadex/extract_quads.h>
#include <libquadex/quad_metrics.h>
#include <libquadex/pure_quads.h>
#include <libquadex/relax_quads.h>
#include <libquadex/small_components.h>
#include <libquantize/quantize.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>

namespace quadify::cli {
namespace {

struct RemeshArgs {
  std::string input;
  std::string output;
  int target_faces = 0;
  double edge_length = 0;
  bool keep_uv = false;
  std::string map_output;  // the integer-seamless triangle map as a UV OBJ ("" = none)
  bool measure = true;
  bool relax = true;
  bool pure_quads = true;
  bool feature_snap = true;
  bool tentative_snaps = true;
  bool fit = true;
  bool thin_parts = true;  // retry a dead end with thin-part sizing (param::thin_part_vertex_size)
  bool feature_sizing = true;  // smaller quads around short closed feature curves (param::feature_loop_vertex_size)
  param::ParamOptions param;
  int samples = 100'000;
  double cone_pair_distance = 4;  // × the target quad edge length
  std::string surface_cone_pairs = "auto";  // param::ParamOptions::cone_pair_surface: on, off, auto
  double cone_split_distance = 1;  // × the target quad edge length
  double cone_scale = -1;         // × the target quad edge length, 0 = off, < 0 = auto
  double time_budget = 0;         // seconds for the quantization, 0 = none
  double count_tolerance = quantize::QuantizeOptions{}.count_tolerance;
  int count_adjustments = -1;  // quantize::QuantizeOptions::max_count_adjustments; < 0: auto
  // Detected creases that are all shorter than this many target quad edges (no knife edge among
  // them) are left out: an organic model's stray fragments. 0 = always aligned.
  double min_crease_quads = 8;
  FeatureArgs features;
  SizingArgs sizing;
};

// A handle thinner than about one quad can get a loop of a single quad around it: the extracted
// mesh then has quads that meet themselves (not manifold). The quantization is then run again on
// a grid with kRefineFactor times as many quads, at most kMaxRefinements times.
constexpr int kMaxRefinements = 3;
constexpr double kRefineFactor = 1.3;

// The rounding with aligned features gets at most max(kMinFeatureSeconds, kFeatureTimeFactor ×
// the parametrization's seconds) before the features count as not fitting and the map is
// parametrized again without them. Where they fit it takes far less (casting at 5,000 quads: 61 s
// after a 12 s parametrization; at 20,000 quads 20 s in all); dragon's (108K triangles, scanned
// creases) dead-ended after 708 s.
constexpr double kMinFeatureSeconds = 120;
constexpr double kFeatureTimeFactor = 3;

// Automatic coarse cones (--cone-scale auto) that fail at quantize::kCoarseConeQuadEdges (e.g. a
// cone of index 3 at a thin tip) are tried once more at this many times the smoothing length.
constexpr double kCoarseRetryFactor = 1.4;

// Thin-part sizing (after a dead end at every scale, or an early stop below): vertices whose relative size falls below
// this count as thin; the fallback runs only if there is one.
constexpr double kThinSize = 0.95;
// Whole-curve feature labels (--feature-curve-labels) split a smooth curve where it turns by 60°
// or more within this many target quad edges (param::ParamOptions::feature_corner_length).
constexpr double kFeatureCornerQuadEdges = 2;
// --surface-cone-pairs auto: on for inputs of at most this many triangles. Each set of pairs costs
// a whole-mesh solve (2-3 s at 100K triangles) and the map's fewer cones may make its rounding
// longer: feline (100K), with them on its coarse-cone map at the time, took 85 s in all instead of
// 70 s (issue 5 asks 80 s), for 114 → 96 irregular vertices.
constexpr int kSurfacePairMaxFaces = 60'000;
// --count-adjustments auto: this many moves for inputs of at most kCountAdjustMaxFaces triangles
// (with a count asked for), else none. Each move tried is a whole-mesh solve (about 1.4 s at 100K
// triangles): feline's three moves cost 16 s of its 80 s budget (issue 5). 16 since 2026-12-07
// (8 before): of the 20-mesh regression at 5,000 quads only wingnut used all 8, and with 16 it
// takes 14: 5,080 → 5,035 quads, Hausdorff 0.0040 → 0.0031, capture 0.960 → 0.965.
constexpr int kAutoCountAdjustments = 16;
constexpr int kCountAdjustMaxFaces = 60'000;
// The count adjustment's quads are kept unless their Hausdorff distance to the input exceeds that
// of the quads before it by this factor, or exceeds kFarFromInput where theirs does not (see the
// design note "Count adjustment"). At 1.25, knot1's adjusted 4,984 quads (0.00214, below every
// peer's) gave way to 5,216 (0.00163).
constexpr double kAdjustedDistanceGrowth = 1.5;
// Hausdorff distance (fraction of the input's bbox diagonal) above which the result is called coarse.
constexpr double kFarFromInput = 0.01;
// A cone that dead-ends at two scales where the surface's radius is below this many quad edges
// (thin-part size) stops the quantization there: more scales of the same map rarely help there,
// and the thin-part retry does (octopus: 8 scales, 204 s, all dead-ending at tentacle tips).
constexpr double kThinDeadEndSize = 0.5;
constexpr int kThinDeadEndAttempts = 2;
// A feature-free map below the coarse-cone density (quantize::kQuadsPerCone) whose rounding still
// dead-ends at two scales (on a cone, or on a translation once the cones are placed) stops there
// and is tried with coarse cones when its cones beyond the topology's are more than one per this
// many target quads; if the coarse map fails too, the first map is quantized again at all its
// scales (the quantization has no resume). dragon at its default density (385 cones for 18,097
// quads): the map dead-ended at ×1.00, 1.02, 0.98, 1.04 and 0.96 of the scale and gave 28,727
// quads at ×1.25 after 475 s of quantization; with coarse cones (231) 18,574 quads in 50 s.
// elk (one cone per 62 quads at 5,000) dead-ends once and succeeds at the next scale, untouched
// (dilo, one per 73, did so before the backtracking at blocked cones).
constexpr double kDeadEndQuadsPerCone = 2 * quantize::kQuadsPerCone;

// The same density request kRefineFactor times finer (more quads).
void refine_density(const core::TriMesh& mesh, quantize::QuantizeOptions* options) {
  if (options->target_faces > 0) {
    options->target_faces = static_cast<int>(std::lround(options->target_faces * kRefineFactor));
  } else if (options->edge_length > 0) {
    options->edge_length /= std::sqrt(kRefineFactor);
  } else {
    options->edge_length = quantize::target_edge_length(mesh, *options) / std::sqrt(kRefineFactor);
  }
}

// The cone of index 3 or more (a quad vertex of valence 1 or 0) for which the quantization
// refused `map` (kInvalidInput): one outside the components it lets keep such a cone
// (QuantizeStats::faces_with_unresolved_cones); null when it did not refuse the map for a cone.
const param::ConeInfo* refused_cone(const core::TriMesh& mesh, const param::ParamResult& map,
                                    const quantize::QuantizeResult& quantized) {
  if (quantized.status.code() != core::StatusCode::kInvalidInput) return nullptr;
  std::vector<char> unresolved(mesh.n_vertices(), 0);
  for (const int f : quantized.stats.faces_with_unresolved_cones)
    for (int k = 0; k < 3; ++k) unresolved[mesh.F(f, k)] = 1;
  for (const param::ConeInfo& c : map.cones)
    if (c.index >= 3 && !unresolved[c.vertex]) return &c;
  return nullptr;
}


int remesh_stages(const RemeshArgs& args, const CommonOptions& common, LoadedMesh& loaded, Progress& progress,
                  nlohmann::json* report_out);

int run_remesh(const RemeshArgs& args, const CommonOptions& common) {
  core::check_can_write(args.output);
  if (!args.map_output.empty()) core::check_can_write(args.map_output);
  Progress progress(common.quiet);
  LoadedMesh loaded = load_and_repair(args.input, progress);
  const core::TriMesh& mesh = loaded.repaired.mesh;
  nlohmann::json report;
  report["command"] = "remesh";
  report["status"] = "ok";
  report["input"] = input_json(args.input, loaded.raw);
  report["repair"] = to_json(loaded.repaired.report);
  report["mesh"] = to_json(core::topology_stats(mesh));
  report["output"] = args.output;
  if (!args.map_output.empty()) report["map_output"] = args.map_output;
  // A failure after this point still writes the report (status "error", the message, and the
  // figures of the stages that ran), but no mesh.
  try {
    return remesh_stages(args, common, loaded, progress, &report);
  } catch (const CliError& e) {
    report["status"] = "error";
    report["error"] = e.message;
    report.erase("output");
    report["timings"] = progress.timings();
    write_report(common, report);
    throw;
  }
}

int remesh_stages(const RemeshArgs& args, const CommonOptions& common, LoadedMesh& loaded, Progress& progress,
                  nlohmann::json* report_out) {
  nlohmann::json& report = *report_out;
  const core::TriMesh& mesh = loaded.repaired.mesh;
  auto on_progress = [&progress](const std::string& stage, int step, int n_steps) {
    progress.step(stage + " " + std::to_string(step) + "/" + std::to_string(n_steps));
  };

  quantize::QuantizeOptions quantize_options;
  quantize_options.target_faces = args.target_faces;
  quantize_options.edge_length = args.edge_length;
  // A dead end with the features stops the quantization: the map is parametrized again without
  // them (below) rather than quantized as it is.
  quantize_options.quantize_without_features = false;
  quantize_options.threads = common.threads;
  quantize_options.progress = on_progress;
  quantize_options.time_budget_seconds = args.time_budget;
  quantize_options.count_tolerance = args.count_tolerance;
  quantize_options.max_count_adjustments =
      args.count_adjustments >= 0
          ? args.count_adjustments
          : (args.edge_length > 0 || mesh.n_faces() > kCountAdjustMaxFaces ? 0 : kAutoCountAdjustments);

  param::ParamOptions param_options = args.param;
  param_options.cone_pair_distance =
      quantize::recommended_cone_pair_distance(mesh, quantize_options, args.cone_pair_distance);
  param_options.cone_pair_max_hops = quantize::kRecommendedConePairHops;
  param_options.cone_pair_surface =
      args.surface_cone_pairs == "on" || (args.surface_cone_pairs == "auto" && mesh.n_faces() <= kSurfacePairMaxFaces);
  const double quad_edge = quantize::target_edge_length(mesh, quantize_options);
  param_options.feature_corner_length = kFeatureCornerQuadEdges * quad_edge;
  param_options.cone_split_distance = std::max(0.0, args.cone_split_distance) * quad_edge;
  param_options.cone_scale = std::max(0.0, args.cone_scale) * quad_edge;
  param_options.threads = common.threads;
  param_options.progress = on_progress;
  FeatureInput feature_input = apply_feature_args(args.features, args.input, &loaded, &param_options);
  // Stray creases: on a smooth model, the few sharp fragments the crease filter keeps (an ear's
  // rim, a claw, a kink of the tessellation) are each a couple of quads long; they cannot shape
  // the layout, yet aligning them adds cones and distortion, and on 100K-triangle models made
  // the quantization dead-end after minutes (feline, armadillo), after which they were dropped
  // anyway. They come first in feature_edges (the given edges follow).
  {
    const int n_creases = feature_input.n_detected - feature_input.n_not_creases;
    if (args.min_crease_quads > 0 && n_creases > 0) {
      const std::vector<std::array<int, 2>> creases(param_options.feature_edges.begin(),
                                                    param_options.feature_edges.begin() + n_creases);
      const quantize::CurveSummary curves = quantize::summarize_curves(mesh, creases, quantize_options);
      if (curves.longest_quad_edges < args.min_crease_quads && !curves.has_knife_edge) {
        param_options.feature_edges.erase(param_options.feature_edges.begin(),
                                          param_options.feature_edges.begin() + n_creases);
        feature_input.n_stray_creases = n_creases;
        if (!common.quiet)
          std::fprintf(stderr,
                       "quadify: %s: the %d crease edges form only short curves (the longest %.1f quad "
                       "edges, below --min-crease-quads %g): not aligned\n",
                       args.input.c_str(), n_creases, curves.longest_quad_edges, args.min_crease_quads);
      }
    }
  }
  SizingInput sizing = apply_sizing_args(args.sizing, loaded, progress);
  sizing.apply_to(&param_options);
  quantize_options.face_size = sizing.face_size;
  quantize_options.face_metric = sizing.face_metric;
  quantize_options.face_direction = sizing.face_direction;
  quantize_options.direction_weight = sizing.direction_weight;
  // Boundaries as explicit feature edges, so that curves too small for the density (tiny holes,
  // short creases) can be left unaligned.
  if (param_options.align_boundaries) {
    const core::EdgeTopology topo = core::build_edge_topology(mesh);
    for (int e = 0; e < topo.n_edges(); ++e)
      if (topo.is_boundary_edge(e)) param_options.feature_edges.push_back({topo.edge_vertex(e, 0), topo.edge_vertex(e, 1)});
    param_options.align_boundaries = false;
  }
  {
    const size_t before = param_options.feature_edges.size();
    param_options.feature_edges = quantize::features_for_density(mesh, param_options.feature_edges, quantize_options);
    feature_input.n_too_small = static_cast<int>(before - param_options.feature_edges.size());
  }
  // Feature sizing: without sizes of the user's, quads shrink around closed feature curves too
  // short for 12 quad edges, small holes' rims (param::feature_loop_vertex_size), and along bands
  // narrower than half a quad between two feature curves (param::feature_strip_vertex_size); the
  // count stays.
  std::vector<double> feature_size;  // per vertex, the smaller of the loops' and the strips'
  std::string feature_sizing_mode;
  if (args.feature_sizing && sizing.face_size.empty() && sizing.face_metric.empty() &&
      !param_options.feature_edges.empty()) {
    feature_size = param::feature_loop_vertex_size(mesh, param_options.feature_edges, quad_edge);
    const std::vector<double> strip_size =
        param::feature_strip_vertex_size(mesh, param_options.feature_edges, quad_edge);
    auto sized = [](const std::vector<double>& s) {
      return std::count_if(s.begin(), s.end(), [](double x) { return x < 1; });
    };
    const auto loop_vertices = sized(feature_size), strip_vertices = sized(strip_size);
    feature_sizing_mode = loop_vertices > 0 && strip_vertices > 0 ? "feature-loops+strips"
                          : strip_vertices > 0                    ? "feature-strips"
                                                                  : "feature-loops";
    for (size_t v = 0; v < feature_size.size(); ++v)
      feature_size[v] = std::min(feature_size[v], strip_size[v]);
    const double smallest = *std::min_element(feature_size.begin(), feature_size.end());
    if (smallest < 1) {
      sizing.face_size = param::face_size_from_vertices(mesh, feature_size);
      const auto [lo, hi] = std::minmax_element(sizing.face_size.begin(), sizing.face_size.end());
      sizing.report = {{"mode", feature_sizing_mode},
                       {"smallest_relative_edge", number(smallest)},
                       {"sized_vertices", sized(feature_size)},
                       {"strip_vertices", strip_vertices},
                       {"min", number(*lo)},
                       {"max", number(*hi)}};
      sizing.apply_to(&param_options);
      quantize_options.face_size = sizing.face_size;
    } else {
      feature_size.clear();
    }
  }
  // The report's param and quantize sections, written as soon as a stage has run.
  int fine_cones = -1;  // the feature-free map's cones, when coarse cones replaced it
  std::string coarse_reason;
  bool features_dropped = false;
  std::string features_dropped_reason;
  int refinements = 0;
  auto param_json = [&](const param::ParamResult& map) {
    const param::ParamStats& ps = map.stats;
    return nlohmann::json{
        {"cones", ps.n_cones},
        {"seam_edges", ps.n_seam_edges},
        {"patches", ps.n_patches},
        {"improved", ps.n_improved},
        {"cancelled_pairs", ps.n_cancelled_pairs},
        {"surface_pairs", ps.n_surface_pairs},
        {"far_pairs", ps.n_far_pairs},
        {"split_cones", ps.n_split_cones},
        {"deferred_matchings", ps.n_deferred_matchings},
        {"coarse_cones", ps.coarse_cones},
        {"coarse_cones_fallback_reason", coarse_reason.empty() ? ps.coarse_cones_fallback_reason : coarse_reason},
        {"fine_cones", fine_cones >= 0 ? nlohmann::json(fine_cones) : nlohmann::json()},
        {"tau", number(ps.tau)},
        {"flipped", ps.n_flipped},
        {"features", feature_json(feature_input, ps)},
        {"sizing", sizing.report},
        {"curvature_alignment", direction_json(sizing, ps)},
        {"seconds", ps.seconds_total},
        {"profile", param_profile_json(ps)}};
  };
  auto quantize_json = [&](const quantize::QuantizeResult& map) {
    const quantize::QuantizeStats& qs = map.stats;
    return nlohmann::json{
        {"scale", qs.scale},
        {"target_faces", args.target_faces},  // 0: the default density (see --target-faces)
        {"target_edge_length", quad_edge},    // the quad edge length asked for, in model units
        {"uv_area", qs.uv_area},
        {"integer_dofs", qs.n_integer_dofs},
        {"reverted", qs.n_reverted},
        {"scale_retries", qs.n_scale_retries},
        {"count_corrections", qs.n_count_corrections},
        {"count_corrections_kept", qs.n_count_corrections_kept},
        {"count_adjustments", qs.n_count_adjustments},
        {"seconds_count_adjustment", qs.seconds_count_adjustment},
        {"flipped", qs.n_flipped},
        {"cones", qs.n_cones},
        {"aligned_features", qs.n_aligned_features},
        {"released_feature_lines", qs.n_released_feature_lines},
        {"released_feature_edges", qs.n_released_feature_edges},
        {"refinements", refinements},
        {"features_dropped", features_dropped || qs.features_dropped},
        {"features_dropped_reason", features_dropped ? features_dropped_reason : qs.features_dropped_reason},
        {"clustered_cones", qs.n_clustered_cones},
        {"cone_collisions", qs.n_cone_collisions},
        {"unstuck_cones", qs.n_unstuck_cones},
        {"newton_iterations", qs.n_iterations},
        {"seconds_setup", qs.seconds_setup},
        {"seconds_rounding", qs.seconds_rounding},
        {"seconds_final", qs.seconds_final},
        {"seconds", qs.seconds}};
  };
  auto parametrize = [&](const param::ParamOptions& options) {
    progress.begin("param");
    param::ParamResult result = param::compute_seamless_param(mesh, options);
    progress.end();
    warn_feature_fallbacks(args.input, result.stats, common.quiet);
    report["param"] = param_json(result);
    if (result.status.code() == core::StatusCode::kInvalidInput)
      throw CliError{kExitBadInput, args.input + ": " + result.status.message()};
    if (!result.status.is_ok())
      throw CliError{kExitInternal, args.input + ": seamless parametrization failed: " + result.status.to_string()};
    return result;
  };
  auto quantize_map = [&](const param::ParamResult& map) {
    progress.begin("quantize");
    quantize::QuantizeResult result = quantize::quantize_seamless(mesh, map, quantize_options);
    progress.end();
    report["quantize"] = quantize_json(result);
    return result;
  };
  // Coarse cones by default: a feature-free map with more cones than the grid has room for (they
  // follow the tessellation's curvature, not the target density) is parametrized again with its
  // matchings rounded on a smoothed copy; if that fails, the map stays as it is. The scale for a
  // map of n cones, 0 for none.
  auto coarse_cone_scale = [&](int n_cones) {
    if (args.cone_scale >= 0 || !param_options.feature_edges.empty() || !param_options.face_direction.empty())
      return 0.0;
    return quantize::recommended_cone_scale(mesh, quantize_options, n_cones);
  };
  // A map that coarse cones will replace stops before τ's continuation (its cones are all that is
  // used); it is parametrized in full only if the coarse maps fail.
  param_options.continue_before_tau = [&](int n_cones) { return !(coarse_cone_scale(n_cones) > 0); };
  param::ParamResult seamless = parametrize(param_options);
  // With dead_end (see kDeadEndQuadsPerCone), the map's cones dead-ended: coarse cones are tried
  // whatever their density.
  auto coarsen = [&](bool dead_end = false) {
    const double scale = dead_end ? quantize::kCoarseConeQuadEdges * quad_edge : coarse_cone_scale(seamless.stats.n_cones);
    if (!(scale > 0)) return;
    if (!common.quiet && !dead_end)
      std::fprintf(stderr,
                   "quadify: %s: %d cones, more than one per %.0f target quads beyond what the topology "
                   "needs: rounding the matchings on a copy smoothed at %.2g quad edges (--cone-scale 0 "
                   "keeps them)\n",
                   args.input.c_str(), seamless.stats.n_cones, quantize::kQuadsPerCone,
                   quantize::kCoarseConeQuadEdges);
    // If that copy's map cannot be used, once more on a copy smoothed kCoarseRetryFactor more.
    for (int attempt = 0; attempt < 2; ++attempt) {
      param::ParamOptions coarse_options = param_options;
      coarse_options.continue_before_tau = nullptr;
      coarse_options.cone_scale = attempt == 0 ? scale : kCoarseRetryFactor * scale;
      coarse_options.cone_scale_fallback = false;
      progress.begin("param");
      param::ParamResult coarse = param::compute_seamless_param(mesh, coarse_options);
      progress.end();
      if (coarse.status.is_ok()) {
        fine_cones = seamless.stats.n_cones;
        seamless = std::move(coarse);
        report["param"] = param_json(seamless);
        return;
      }
      coarse_reason = coarse.stats.coarse_cones_fallback_reason;
      if (!common.quiet)
        std::fprintf(stderr, "quadify: %s: coarse cones at %.2g quad edges not used (%s)%s\n", args.input.c_str(),
                     coarse_options.cone_scale / quad_edge,
                     coarse_reason.c_str(),
                     attempt == 0 ? "; trying a smoother copy" : "; keeping the map's cones");
    }
    if (seamless.stats.stopped_before_tau) {
      param::ParamOptions full_options = param_options;
      full_options.continue_before_tau = nullptr;
      seamless = parametrize(full_options);
    }
  };
  coarsen();
  quantize_options.feature_time_budget_seconds =
      std::max(kMinFeatureSeconds, kFeatureTimeFactor * seamless.stats.seconds_total);
  // Thin parts (see the retry below): the field, computed at the first dead end that needs it.
  const bool thin_retry_allowed =
      args.thin_parts && (sizing.face_size.empty() || !feature_size.empty()) && sizing.face_metric.empty();
  std::vector<double> thin;
  auto thin_field = [&]() -> const std::vector<double>& {
    if (thin.empty()) thin = param::thin_part_vertex_size(mesh, quad_edge);
    return thin;
  };
  // A feature-free map with cones of its own (not coarse ones, --cone-scale auto) that dead-end
  // (see kDeadEndQuadsPerCone).
  auto coarse_retry_possible = [&]() {
    return args.cone_scale < 0 && fine_cones < 0 && param_options.feature_edges.empty() &&
           param_options.face_direction.empty() && seamless.stats.n_aligned_features == 0 &&
           quantize::recommended_cone_scale(mesh, quantize_options, seamless.stats.n_cones, kDeadEndQuadsPerCone) > 0;
  };
  bool stopped_for_coarse_cones = false;
  quantize_options.continue_after_dead_end = [&](const quantize::DeadEnd& de) {
    if (de.attempts_without_features < kThinDeadEndAttempts) return true;
    // On a cone or a translation: with the backtracking at blocked cones, a map with too many
    // cones for the grid places them and then dead-ends on the translations between them
    // (dragon at its default density, at every scale).
    if (coarse_retry_possible()) {
      stopped_for_coarse_cones = true;
      return false;
    }
    if (de.cone_vertex < 0) return true;
    return !(thin_retry_allowed && thin_field()[de.cone_vertex] < kThinDeadEndSize);
  };
  quantize::QuantizeResult integer_map = quantize_map(seamless);
  // A cone of index 3 or more (a quad vertex of valence 1, which the quantization refuses) in a
  // map the features shaped: without them the map gets coarse cones and cone splitting
  // (mannequin-devil at 5,000 quads: index 3 at a horn tip with its creases, also after the
  // thin-part retry; without them 38 cones).
  std::string bad_cone_reason;
  if (seamless.stats.n_aligned_features > 0)
    if (const param::ConeInfo* c = refused_cone(mesh, seamless, integer_map))
      bad_cone_reason = "the map with them has a cone of index " + std::to_string(c->index) + " at vertex " +
                        std::to_string(c->vertex) + ", a quad vertex of valence " + std::to_string(4 - c->index);
  // The features could not be kept on integer iso-lines: the map they shaped (more cones, more
  // distortion) is no longer worth its price, so parametrize and quantize again without them.
  // A map whose quantization cannot be set up (kNumericalFailure: the elimination too large for
  // its cones, dragon's feature map with 858) is no better.
  const bool unusable_feature_map = seamless.stats.n_aligned_features > 0 &&
                                    integer_map.status.code() == core::StatusCode::kNumericalFailure;
  if ((integer_map.stats.features_dropped &&
       (integer_map.status.is_ok() || integer_map.status.code() == core::StatusCode::kNotConverged)) ||
      !bad_cone_reason.empty() || unusable_feature_map) {
    features_dropped = true;
    features_dropped_reason = !bad_cone_reason.empty()    ? bad_cone_reason
                              : unusable_feature_map ? integer_map.status.message()
                                                     : integer_map.stats.features_dropped_reason;
    if (!common.quiet)
      std::fprintf(stderr,
                   "quadify: %s: the aligned features do not fit the quad grid at this density (%s; "
                   "%.0f s spent on them); remeshing without them (a larger --target-faces may keep "
                   "them, --feature-angle 0%s skips them from the start)\n",
                   args.input.c_str(), features_dropped_reason.c_str(),
                   seamless.stats.seconds_total + integer_map.stats.seconds,
                   core::topology_stats(mesh).n_boundary_loops > 0 ? " --no-boundary-alignment" : "");
    param_options.feature_edges.clear();
    param_options.align_boundaries = false;
    // The feature sizing goes with the features (mannequin-devil at 5,000 quads: quads shrunk
    // along bands of creases no longer aligned, Hausdorff 0.0082 → 0.0137).
    if (!feature_size.empty()) {
      feature_size.clear();
      sizing.face_size.clear();
      sizing.report = {{"mode", "uniform"}, {"feature_sizing_dropped", feature_sizing_mode}};
      sizing.apply_to(&param_options);
      quantize_options.face_size.clear();
    }
    seamless = parametrize(param_options);
    coarsen();
    integer_map = quantize_map(seamless);
  }
  quantize_options.continue_after_dead_end = nullptr;
  // Cones that dead-end (see kDeadEndQuadsPerCone): coarse cones, else the first map at all its
  // scales.
  if (stopped_for_coarse_cones && integer_map.stats.stopped_at_dead_end) {
    if (!common.quiet)
      std::fprintf(stderr,
                   "quadify: %s: no integer map at the first scales (%s): rounding the matchings on a "
                   "copy smoothed at %.2g quad edges, to place fewer cones (--cone-scale 0 keeps them)\n",
                   args.input.c_str(), integer_map.status.message().c_str(), quantize::kCoarseConeQuadEdges);
    param::ParamResult first_map = seamless;
    coarsen(true);
    if (fine_cones >= 0) integer_map = quantize_map(seamless);
    if (fine_cones < 0 || !integer_map.status.is_ok()) {
      if (!common.quiet)
        std::fprintf(stderr, "quadify: %s: %s; back to the first map, at all its scales\n", args.input.c_str(),
                     fine_cones < 0 ? "no coarse cones"
                                    : ("no integer map with coarse cones either (" + integer_map.status.message() + ")").c_str());
      seamless = std::move(first_map);
      fine_cones = -1;
      report["param"] = param_json(seamless);
      integer_map = quantize_map(seamless);
    }
  }
  // Thin parts: where the surface wraps a radius smaller than the quad edge (tentacles, fingers,
  // horns), the cones at their tips find no grid points, and every scale dead-ends (octopus at
  // 5,000 quads), or a tip keeps a cone of index 3 that cone splitting could not move. Without a
  // size field of the user's, parametrize and quantize once more with quads as small as the local
  // radius there (param::thin_part_vertex_size; the count stays).
  const bool dead_end = (integer_map.status.code() == core::StatusCode::kNotConverged &&
                         !integer_map.stats.out_of_time) ||
                        refused_cone(mesh, seamless, integer_map) != nullptr;
  if (dead_end && thin_retry_allowed) {
    thin_field();
    double thin_area = 0, area = 0;
    for (int f = 0; f < mesh.n_faces(); ++f) {
      const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)),
                            p2 = mesh.V.row(mesh.F(f, 2));
      const double a = 0.5 * (p1 - p0).cross(p2 - p0).norm();
      area += a;
      for (int k = 0; k < 3; ++k)
        if (thin[mesh.F(f, k)] < kThinSize) thin_area += a / 3;
    }
    const double smallest = thin.empty() ? 1.0 : *std::min_element(thin.begin(), thin.end());
    if (smallest < kThinSize) {
      if (!common.quiet)
        std::fprintf(stderr,
                     "quadify: %s: no integer map (%s); %.0f%% of the surface is thinner than "
                     "the quads (radius of curvature below a quad edge): parametrizing again with quads "
                     "down to %.2f times as long there\n",
                     args.input.c_str(), integer_map.status.message().c_str(), 100 * thin_area / area, smallest);
      std::vector<double> sizes = thin;  // with the feature sizes, where smaller
      for (size_t v = 0; v < feature_size.size(); ++v) sizes[v] = std::min(sizes[v], feature_size[v]);
      sizing.face_size = param::face_size_from_vertices(mesh, sizes);
      sizing.report = {{"mode", feature_size.empty() ? "thin-parts" : "thin-parts+" + feature_sizing_mode},
                       {"reason", integer_map.status.message()},
                       {"min", number(smallest)},
                       {"thin_area_share", number(thin_area / area)}};
      // A quantization stopped early at a thin dead end resumes its other scales if the retry
      // fails too.
      std::optional<param::ParamResult> stopped_map;
      if (integer_map.stats.stopped_at_dead_end) stopped_map = seamless;
      const SizingInput sizing_before = sizing;
      const param::ParamOptions param_options_before = param_options;
      const int fine_cones_before = fine_cones;
      sizing.apply_to(&param_options);
      quantize_options.face_size = sizing.face_size;
      seamless = parametrize(param_options);
      coarsen();
      integer_map = quantize_map(seamless);
      if (!integer_map.status.is_ok() && stopped_map) {
        if (!common.quiet)
          std::fprintf(stderr,
                       "quadify: %s: no integer map with thin-part sizing either (%s); back to the "
                       "first map, at its other scales\n",
                       args.input.c_str(), integer_map.status.message().c_str());
        sizing = sizing_before;
        param_options = param_options_before;
        quantize_options.face_size = sizing.face_size;
        seamless = std::move(*stopped_map);
        fine_cones = fine_cones_before;
        report["param"] = param_json(seamless);
        integer_map = quantize_map(seamless);
      }
    }
  }
  if (integer_map.status.is_ok() && integer_map.stats.n_released_feature_edges > 0 && !common.quiet)
    std::fprintf(stderr,
                 "quadify: %s: %d aligned feature edges near dead ends of the rounding were released "
                 "(not on quad edges; a larger --target-faces may keep them)\n",
                 args.input.c_str(), integer_map.stats.n_released_feature_edges);
  if (!integer_map.status.is_ok())
    throw CliError{kExitInternal,
                   args.input + ": quantization failed: " + integer_map.status.to_string() +
                       (integer_map.status.code() == core::StatusCode::kNotConverged &&
                                !integer_map.stats.out_of_time
                            ? " (a larger --target-faces often helps)"
                            : "")};

  quadex::ExtractOptions extract_options;
  extract_options.output_uv = args.keep_uv;
  // A component that keeps a cone of index 3 or more (the quantization lets it through below a few
  // quads: spot_nonmanifold's tetrahedron) is left out of the extraction and replaced by its split
  // triangles below (split_small_components).
  auto extract = [&](const quantize::QuantizeResult& map) {
    progress.begin("extract");
    const std::vector<int>& left_out = map.stats.faces_with_unresolved_cones;
    quadex::ExtractResult result;
    if (left_out.empty()) {
      result = quadex::extract_quads(map.uv, extract_options);
    } else {
      // The kept faces, in order (none: no quads, every component is split below).
      std::vector<int> kept_face;
      for (int f = 0, i = 0; f < mesh.n_faces(); ++f)
        if (i < static_cast<int>(left_out.size()) && left_out[i] == f)
          ++i;
        else
          kept_face.push_back(f);
      core::UVMesh kept;
      kept.mesh.V = map.uv.mesh.V;
      kept.mesh.F.resize(static_cast<Eigen::Index>(kept_face.size()), 3);
      kept.corner_uv.resize(3 * kept.mesh.F.rows(), 2);
      for (size_t i = 0; i < kept_face.size(); ++i) {
        kept.mesh.F.row(i) = map.uv.mesh.F.row(kept_face[i]);
        kept.corner_uv.middleRows(3 * i, 3) = map.uv.corner_uv.middleRows(3 * kept_face[i], 3);
      }
      if (!kept_face.empty()) {
        result = quadex::extract_quads(kept, extract_options);
        for (int& f : result.vertex_face)
          if (f >= 0) f = kept_face[f];
      }
    }
    progress.end();
    return result;
  };
  quadex::ExtractResult extracted = extract(integer_map);
  if (!extracted.status.is_ok())
    throw CliError{kExitInternal, args.input + ": quad extraction failed: " + extracted.status.to_string()};
  // Only an input that was manifold before the repair must give manifold quads (the places
  // where the repair split a non-manifold edge or vertex are kept as they are).
  const bool manifold_input = loaded.repaired.report.nonmanifold_edges_split == 0 &&
                              loaded.repaired.report.nonmanifold_vertices_split == 0;
  // Components too small for the grid (degenerate or non-quad faces): their triangles split.
  auto split_small = [&](const quantize::QuantizeResult& map, const quadex::ExtractResult& ex) {
    quadex::SmallComponentOptions small_options;
    small_options.replace_faces = map.stats.faces_with_unresolved_cones;
    quadex::SmallComponentResult small =
        quadex::split_small_components(map.uv, ex.quads, ex.vertex_face, small_options);
    if (!small.status.is_ok())
      throw CliError{kExitInternal, args.input + ": small components: " + small.status.to_string()};
    return small;
  };
  quadex::SmallComponentResult small = split_small(integer_map, extracted);
  // The quads must be manifold once the small components are split (their degenerate faces are no
  // reason to refine the whole grid).
  auto kept_quads = [&]() -> const core::PolyMesh& {
    return small.stats.n_replaced > 0 ? small.quads : extracted.quads;
  };
  for (; refinements < kMaxRefinements && manifold_input &&
         !quadex::compute_quad_metrics(kept_quads()).manifold;
       ++refinements) {
    const int faces_before = extracted.stats.n_faces;
    refine_density(mesh, &quantize_options);
    quantize::QuantizeResult finer = quantize_map(seamless);
    if (!finer.status.is_ok()) break;
    quadex::ExtractResult finer_quads = extract(finer);
    if (!finer_quads.status.is_ok()) break;
    if (!common.quiet)
      std::fprintf(stderr,
                   "quadify: %s: the %d quads are not manifold (a handle thinner than about a quad "
                   "has a loop of one quad around it); quantized again on a finer grid: %d quads\n",
                   args.input.c_str(), faces_before, finer_quads.stats.n_faces);
    integer_map = std::move(finer);
    extracted = std::move(finer_quads);
    small = split_small(integer_map, extracted);
  }
  if (small.stats.n_replaced > 0) {
    extracted.quads = std::move(small.quads);
    if (!common.quiet) {
      const size_t left_out = integer_map.stats.faces_with_unresolved_cones.size();
      const std::string left_out_note =
          left_out == 0 ? std::string()
                        : "; " + std::to_string(left_out) +
                              " triangles left out of the extraction for a cone of index 3 or more";
      std::fprintf(stderr,
                   "quadify: %s: %d component(s) too small for the quad grid became %d quads, three per "
                   "input triangle (%d extracted faces that were not all quads removed%s)\n",
                   args.input.c_str(), small.stats.n_replaced, small.stats.n_quads_added,
                   small.stats.n_faces_removed, left_out_note.c_str());
    }
  }
  // The extracted quads finished: faces that are not quads (where the grid meets a boundary the
  // map does not follow) become quads, then the relaxation smooths them and the rest.
  auto finish_quads = [&](quadex::ExtractResult* quads, quadex::PureQuadStats* pure_stats) {
    if (args.pure_quads) {
      quadex::PureQuadResult pure = quadex::make_pure_quads(quads->quads);
      if (!pure.status.is_ok())
        throw CliError{kExitInternal, args.input + ": pure quads: " + pure.status.to_string()};
      quads->quads = std::move(pure.quads);
      *pure_stats = pure.stats;
    }
    quadex::RelaxStats stats;
    if (!args.relax) return stats;
    progress.begin("relax");
    quadex::RelaxOptions relax_options;
    relax_options.feature_edges = param_options.feature_edges;
    if (!args.feature_snap) relax_options.snap_reach = 0;
    relax_options.tentative_snaps = args.tentative_snaps;
    if (!args.fit) relax_options.fit_fraction = 0;
    quadex::RelaxResult relaxed = quadex::relax_bad_quads(quads->quads, mesh, relax_options);
    progress.end();
    if (!relaxed.status.is_ok())
      throw CliError{kExitInternal, args.input + ": quad relaxation failed: " + relaxed.status.to_string()};
    quads->quads = std::move(relaxed.quads);
    return relaxed.stats;
  };
  quadex::PureQuadStats pure_stats;
  quadex::RelaxStats relax_stats = finish_quads(&extracted, &pure_stats);
  // The count adjustment moves the map like another rounding would, and the quads' distance to
  // the input with it: its quads are kept unless they are farther from the input than those of
  // the map before it by more than kAdjustedDistanceGrowth, or beyond kFarFromInput where those are
  // not (then the count stays as the rounding left it). Not after a refinement (its map was not
  // adjusted for the count asked).
  // The metrics of the quads kept, where the comparison measured them (the report's measure
  // step then reuses them: they do not depend on the UVs stripped below).
  quadex::QuadMetricsOptions metric_options;
  metric_options.hausdorff_samples = args.samples;
  std::optional<quadex::QuadMetrics> kept_metrics;
  bool adjustment_undone = false;
  if (integer_map.uv_unadjusted.corner_uv.rows() > 0 && refinements == 0) {
    progress.begin("measure");
    kept_metrics = quadex::compute_quad_metrics(extracted.quads, &mesh, metric_options);
    const double adjusted_distance = kept_metrics->hausdorff_sym;
    progress.end();
    quantize::QuantizeResult plain_map = integer_map;
    plain_map.uv = std::move(plain_map.uv_unadjusted);
    plain_map.uv_unadjusted = core::UVMesh{};
    plain_map.stats.uv_area = plain_map.stats.uv_area_unadjusted;
    quadex::ExtractResult plain = extract(plain_map);
    if (plain.status.is_ok()) {
      quadex::SmallComponentResult plain_small = split_small(plain_map, plain);
      if (plain_small.stats.n_replaced == small.stats.n_replaced) {
        if (plain_small.stats.n_replaced > 0) plain.quads = std::move(plain_small.quads);
        quadex::PureQuadStats plain_pure;
        const quadex::RelaxStats plain_relax = finish_quads(&plain, &plain_pure);
        progress.begin("measure");
        const quadex::QuadMetrics pm = quadex::compute_quad_metrics(plain.quads, &mesh, metric_options);
        progress.end();
        const bool farther = adjusted_distance > kAdjustedDistanceGrowth * pm.hausdorff_sym ||
                             (adjusted_distance > kFarFromInput && pm.hausdorff_sym < adjusted_distance);
        if ((pm.manifold || !manifold_input) && farther) {
          if (!common.quiet)
            std::fprintf(stderr,
                         "quadify: %s: the count adjustment's %d quads are %.2fx as far from the input "
                         "(Hausdorff %.3g) as the %d quads before it: keeping those\n",
                         args.input.c_str(), extracted.quads.n_faces(), adjusted_distance / pm.hausdorff_sym,
                         adjusted_distance, plain.quads.n_faces());
          integer_map = std::move(plain_map);
          extracted = std::move(plain);
          relax_stats = plain_relax;
          pure_stats = plain_pure;
          kept_metrics = pm;
          adjustment_undone = true;
        }
      }
    }
  }
  if (!args.keep_uv) {
    extracted.quads.uv.resize(0, 2);
    extracted.quads.face_uv.clear();
  }

  progress.begin("write");
  // The map first; should the mesh then fail to write, the map goes too (no partial output).
  if (!args.map_output.empty()) core::write_uv_obj(args.map_output, integer_map.uv);
  try {
    core::write_mesh(args.output, extracted.quads);
  } catch (...) {
    std::error_code ec;
    if (!args.map_output.empty()) std::filesystem::remove(args.map_output, ec);
    throw;
  }
  progress.end();

  report["param"] = param_json(seamless);
  report["quantize"] = quantize_json(integer_map);
  report["quantize"]["count_adjustment_undone"] = adjustment_undone;
  const quadex::ExtractStats& es = extracted.stats;
  report["extract"] = {{"vertices", es.n_vertices}, {"faces", es.n_faces}, {"non_quads", es.n_non_quads},
                       {"boundary_crossings", es.n_boundary_crossings}, {"seconds", es.seconds}};
  report["small_components"] = {{"replaced", small.stats.n_replaced},
                                 {"faces_removed", small.stats.n_faces_removed},
                                 {"quads_added", small.stats.n_quads_added}};
  if (args.pure_quads)
    report["pure_quads"] = {{"non_quads_before", pure_stats.n_non_quads_before},
                            {"non_quads_after", pure_stats.n_non_quads_after},
                            {"edges_collapsed", pure_stats.n_edges_collapsed},
                            {"vertices_removed", pure_stats.n_vertices_removed},
                            {"boundary_splits", pure_stats.n_boundary_splits},
                            {"paths", pure_stats.n_paths},
                            {"edges_split", pure_stats.n_edges_split},
                            {"centers", pure_stats.n_centers},
                            {"midpoints_shifted", pure_stats.n_midpoints_shifted},
                            {"doublets_removed", pure_stats.n_doublets_removed},
                            {"merged", pure_stats.n_merged},
                            {"faces_split", pure_stats.n_faces_split},
                            {"quads_added", pure_stats.n_quads_added},
                            {"worst_quality", pure_stats.worst_quality}};
  if (args.relax)
    report["relax"] = {{"bad_before", relax_stats.n_bad_before},
                       {"bad_after", relax_stats.n_bad_after},
                       {"flipped_before", relax_stats.n_flipped_before},
                       {"flipped_after", relax_stats.n_flipped_after},
                       {"moves", relax_stats.n_moves},
                       {"jumps", relax_stats.n_jumps},
                       {"feature_vertices_moved", relax_stats.n_feature_vertices_moved},
                       {"unfolded", relax_stats.n_unfolded},
                       {"snapped", relax_stats.n_snapped},
                       {"tentative_snaps", relax_stats.n_tentative_snaps},
                       {"fitted", relax_stats.n_fitted},
                       {"fit_distance_before", relax_stats.fit_distance_before},
                       {"fit_distance_after", relax_stats.fit_distance_after},
                       {"diagonals_turned", relax_stats.n_diagonals_turned},
                       {"seconds", relax_stats.seconds}};
  if (args.measure) {
    progress.begin("measure");
    const quadex::QuadMetrics m =
        kept_metrics ? *kept_metrics : quadex::compute_quad_metrics(extracted.quads, &mesh, metric_options);
    progress.end();
    report["quads"] = {{"faces", m.n_faces},
                       {"non_quads", m.n_non_quads},
                       {"irregular_vertices", m.n_irregular},
                       {"flipped_quads", m.n_flipped},
                       {"degenerate_faces", m.n_degenerate},
                       {"manifold", m.manifold},
                       {"components", m.n_components},
                       {"genus", m.genus},
                       {"sj_min", number(m.sj_min)},
                       {"sj_mean", number(m.sj_mean)},
                       {"angle_dev_mean", number(m.angle_dev_mean)},
                       {"hausdorff_sym", number(m.hausdorff_sym)},
                       {"mean_dist_sym", number(m.mean_dist_sym)},
                       {"feature_capture", m.feature_capture >= 0 ? number(m.feature_capture) : nlohmann::json()},
                       {"feature_hausdorff", m.feature_capture >= 0 ? number(m.feature_hausdorff) : nlohmann::json()},
                       {"principal_angle_mean",
                        m.principal_angle_mean >= 0 ? number(m.principal_angle_mean) : nlohmann::json()},
                       {"anisotropic_quads", m.n_anisotropic_quads}};
    // A component smaller than about one quad gets no grid point inside and so no quad: say so
    // rather than let a part of the model vanish silently.
    const int input_components = core::topology_stats(mesh).n_components;
    const int lost = std::max(0, input_components - m.n_components);
    report["quads"]["components_lost"] = lost;
    if (lost > 0 && !common.quiet)
      std::fprintf(stderr,
                   "quadify: warning: %s: %d of %d components got no quads (smaller than about one "
                   "quad at this density; a larger --target-faces or a smaller --edge-length keeps "
                   "them)\n",
                   args.input.c_str(), lost, input_components);
    // A result farther from the input than kFarFromInput of the diagonal (at 1,000 quads seven of
    // twelve bench meshes; at 5,000 none) is said to be coarse, with what helps.
    if (m.hausdorff_sym > kFarFromInput && !common.quiet)
      std::fprintf(stderr,
                   "quadify: warning: %s: the quads leave the input by up to %.2g%% of its diagonal (Hausdorff "
                   "distance); a larger --target-faces or a smaller --edge-length follows it more closely\n",
                   args.input.c_str(), 100 * m.hausdorff_sym);
    if (!common.quiet) {
      std::printf("%s -> %s: %d faces (%d not quads), %d irregular vertices, %d flipped, Hausdorff %.3g of the "
                  "diagonal",
                  args.input.c_str(), args.output.c_str(), m.n_faces, m.n_non_quads, m.n_irregular, m.n_flipped,
                  m.hausdorff_sym);
      // Where features were to be aligned: the share of the sharp-edge length on quad edges
      // (quadify check's feature capture; not for the stray creases of a smooth model).
      if (m.feature_capture >= 0 && (features_dropped || !param_options.feature_edges.empty()))
        std::printf(", feature capture %.3f", m.feature_capture);
      std::printf("\n");
    }
  } else if (!common.quiet) {
    std::printf("%s -> %s: %d faces (%d not quads)\n", args.input.c_str(), args.output.c_str(), es.n_faces,
                es.n_non_quads);
  }
  report["timings"] = progress.timings();
  write_report(common, report);
  return kExitOk;
}

// An option that takes a number or "auto" (its default, shown as such in --help): `set` gets the
// text; `check` validates it unless it is "auto" (an error names `expected`, e.g. "a
// non-negative number").
CLI::Option* add_auto_option(CLI::App& app, const std::string& name,
                             std::function<void(const std::string&)> set, const std::string& help,
                             const CLI::Validator& check, const std::string& expected,
                             const std::string& type_name) {
  return app.add_option_function<std::string>(name, std::move(set), help)
      // The validator's own message would print its range (a non-negative number's ends at DBL_MAX).
      ->check([check, expected](const std::string& text) {
        if (text == "auto" || check(text).empty()) return std::string();
        return "'" + text + "' is neither " + expected + " nor auto";
      })
      ->default_str("auto")
      ->type_name(type_name);
}

}  // namespace

CommandRunner register_remesh(CLI::App& app) {
  auto args = std::make_shared<RemeshArgs>();
  app.add_option("input", args->input, "Triangle mesh (OBJ, OFF, PLY, STL, glTF, GLB)")->required()->type_name("IN");
  app.add_option("-o,--output", args->output,
                 "Quad mesh to write: .obj (quads as 4-vertex faces), .gltf (+.bin) or .glb (triangulated "
                 "surface + quad wireframe as lines)")
      ->required()
      ->type_name("OUT");
  auto* target = app.add_option("--target-faces", args->target_faces,
                                "Number of quads wanted (default: max(5000, #triangles/6)); usually met "
                                "within 0.5% up to 60,000 input triangles and a few percent above (see --count-adjustments), exceeded "
                                "where a handle is thinner than about a quad (the grid is refined by 1.3x until "
                                "every handle keeps its quads)")
                     ->check(CLI::Range(1, 100'000'000))
                     ->type_name("N");
  auto* edge_length = app.add_option("--edge-length", args->edge_length,
                                     "Quad edge length in model units (instead of --target-faces)")
      ->check(CLI::PositiveNumber)
      ->excludes(target)
      ->type_name("H");
  app.add_option("--energy", args->param.energy,
                 "Distortion minimised by the parametrization: tau (default), sd, arap, linf-arap, conformal")
      ->transform(CLI::CheckedTransformer(kEnergies, CLI::ignore_case))
      ->default_str("tau");
  app.add_option("--cone-pair-distance", args->cone_pair_distance,
                 "Remove pairs of opposite cones (valence 3 next to valence 5) joined by a seam path "
                 "shorter than this many quad edge lengths (and at least 8 mean edge lengths of the input), "
                 "by changing the matchings along the path: such pairs cannot sit on distinct grid points "
                 "and add two irregular vertices (0 = keep every cone)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--surface-cone-pairs", args->surface_cone_pairs,
                 "Also cancel the cone pairs within --cone-pair-distance over the surface whose seam path is "
                 "long (the cut joins near vertices by long seam paths), where the map's tau grows by at most 25% "
                 "and no face's size by more than 1.75 times, then those within 4 times that distance under the "
                 "same bounds: on, off (only pairs joined by a short seam path), "
                 "auto (the default: on up to 60,000 input triangles; each set costs a whole-mesh solve). "
                 "knot1 at 5,000 quads: 26 -> 10 irregular vertices, genus3 28 -> 24")
      ->check(CLI::IsMember({"on", "off", "auto"}))
      ->capture_default_str();
  app.add_option("--cone-split-distance", args->cone_split_distance,
                 "Split every cone of index above --cone-split-max-index (index 3 is a quad vertex of valence "
                 "1, which no quad mesh has: the rounding makes them at the tips of thin parts, such as "
                 "tentacles), one unit of index at a time moved to a vertex about this many quad edge lengths "
                 "away along the seams (0 = keep them; extraction then rejects such a map)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--cone-split-max-index", args->param.cone_split_max_index,
                 "With --cone-split-distance: cones of a larger index are split (2: index 3 and more, which no "
                 "quad mesh can have; 1: also index 2, a flat quad corner, and +1 cones crowded within half "
                 "the distance of another)")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  add_auto_option(
      app, "--cone-scale",
      [args](const std::string& text) { args->cone_scale = text == "auto" ? -1 : std::stod(text); },
      "Round the matchings on a copy of the mesh smoothed at this many quad edge lengths, so that "
      "curvature details smaller than that make no cones of their own; ignored while features are "
      "aligned. 0 = off; auto (the default): 1.4, then 1.96 if that copy cannot be used, when the "
      "feature-free map has more than one cone per 40 target quads beyond the 4|Euler "
      "characteristic| a closed surface needs, or more than one per 80 and its rounding dead-ends at two "
      "scales of the rounding (its cone count is then param.fine_cones in the report), else off",
      CLI::NonNegativeNumber, "a non-negative number", "Q|auto");
  app.add_option("--min-crease-quads", args->min_crease_quads,
                 "Leave the detected creases unaligned when every crease curve is shorter than this "
                 "many quad edges and none is a knife edge (median dihedral angle of at least 120 "
                 "degrees): the stray sharp fragments of an organic model (an ear's rim, a claw), too "
                 "short to shape the quads, which would add cones and distortion (0 = always align)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  auto* count_adjustments = add_auto_option(
      app, "--count-adjustments",
      [args](const std::string& text) { args->count_adjustments = text == "auto" ? -1 : std::stoi(text); },
      "With --target-faces or the default density (not with --edge-length): after the integer "
      "rounding, move up to this many integer unknowns (seam translations, cone positions) by one "
      "unit each while the quad count is more than 0.5% off the target, where a move brings it "
      "closer, keeping a move only if the map stays flip-free and its distortion energy grows by at "
      "most the share of the target it gains (and 1%; twice that share in a round where no move "
      "is within it); the count is known exactly before a move, "
      "and each move tried costs a whole-mesh solve. 0 = off; auto (the default): 16 up to 60,000 "
      "input triangles, else 0. At 5,000 quads: 19 of 20 bench meshes within 0.5% of the target "
      "(without: 4), the result differing like another rounding would (Hausdorff up or down)",
      CLI::Range(0, 1000), "an integer from 0 to 1000", "N|auto");
  count_adjustments->excludes(edge_length);
  app.add_option("--count-tolerance", args->count_tolerance,
                 "With --target-faces or the default density (not with --edge-length): aim the count at the target (the rounding grows the map by 2-3% on "
                 "average) and, while it is further than this fraction from the target, run the integer "
                 "rounding again at a scale corrected by the growth measured (at most twice, each about as "
                 "long as the first), keeping the count closest to the target; 0.015 suits (mean error "
                 "2.9% -> 1.0% at 5,000 quads). 0 = off: a few percent more quads than asked, one rounding")
      ->check(CLI::NonNegativeNumber)
      ->excludes(edge_length)
      ->capture_default_str();
  app.add_option("--time-budget", args->time_budget,
                 "Stop the quantization after this many seconds with a message naming the scale and the "
                 "stage reached (0 = no limit)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->type_name("SECONDS");
  app.add_flag("!--no-thin-parts", args->thin_parts,
               "Do not retry a quantization that dead-ends with smaller quads where the surface is thinner "
               "than a quad (by default, without --adaptive or --size-field: quads down to a quarter of "
               "the target edge where the radius of curvature is below it, the count kept; sizing.mode "
               "\"thin-parts\" in the report)");
  app.add_flag("!--no-feature-sizing", args->feature_sizing,
               "Keep the quad size uniform around short closed feature curves and narrow feature bands "
               "(by default, without --adaptive or --size-field: a closed crease or boundary loop less "
               "than 12 target quad edges long, such as a small hole's rim, gets 12 quads around, and a "
               "band narrower than half a quad edge between two creases, such as a narrow chamfer, gets "
               "quads as long as it is wide, down to 0.3 of the target edge, growing back by a quarter "
               "per quad edge; the count kept; sizing.mode \"feature-loops\", \"feature-strips\" or "
               "\"feature-loops+strips\" in the report)");
  app.add_flag("--uv", args->keep_uv, "Keep the integer UVs as per-corner texture coordinates in the output");
  app.add_option("--map", args->map_output,
                 "Also write the integer-seamless map the quads were extracted from: the repaired input "
                 "triangles with per-corner integer-grid UVs, as an OBJ (quad edges are its integer "
                 "iso-lines; `quadify check` measures it)")
      ->type_name("MAP.obj");
  app.add_flag("!--no-relax", args->relax,
               "Keep the extracted vertex positions (by default, vertices of quads with a corner of "
               "scaled Jacobian below 0.2 are relaxed on the input surface)");
  app.add_flag("!--no-pure-quads", args->pure_quads,
               "Keep the faces that are not quads where the quad grid meets a boundary it does not "
               "follow (by default a face of odd degree loses a sliver's short edge or a flat boundary "
               "corner, merges with an odd neighbour, or gets a midpoint on a boundary edge or on the "
               "edges along a path of faces to the nearest other odd face or boundary, and every face "
               "is then split into quads; see pure_quads in the report)");
  app.add_flag("!--no-feature-snap", args->feature_snap,
               "Do not move quad vertices onto a nearby feature curve that their quads cut off (by "
               "default, part of the relaxation; see relax.snapped in the report)");
  app.add_flag("!--no-tentative-snaps", args->tentative_snaps,
               "Do not retry the snaps refused because a quad around the vertex would fold, where the "
               "quads are farthest from the input (by default the relaxation is run again with the "
               "farthest two alone, then up to four together, and kept when it is closer to the input "
               "without worse quads; see relax.tentative_snaps in the report)");
  app.add_flag("!--no-fit", args->fit,
               "Do not move quad vertices where the quads are farthest from the input (by default, part "
               "of the relaxation: a vertex whose quads deviate by more than 0.8 of the largest "
               "deviation moves to the input surface point under them that lowers it most, keeping "
               "its quads' corners; see relax.fitted and relax.fit_distance_* in the report)");
  app.add_flag("!--no-measure", args->measure,
               "Skip the quality measures (Hausdorff distance, scaled Jacobian) of the report");
  app.add_option("--samples", args->samples, "Area samples per surface for the Hausdorff distance")
      ->check(CLI::Range(1000, 10'000'000))
      ->capture_default_str();
  // Whole-curve labels at acute corners lower τ, but the quads of the map on fandisk were
  // farther from the input (README, "Acute corners"): opt-in here.
  args->features.acute_curve_labels = false;
  add_feature_options(app, &args->features);
  add_sizing_options(app, &args->sizing);
  return [args](const CommonOptions& common) { return run_remesh(*args, common); };
}

}  // namespace quadify::cli
