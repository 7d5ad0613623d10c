// quadify param IN -o OUT.obj: seamless parametrization (libparam), written as a UV OBJ with
// per-corner texture coordinates (seams visible), plus its metrics in the report.
#include "commands.h"

#include <libcore/uv_metrics.h>
#include <libcore/atomic_file.h>
#include <libcore/write_mesh.h>
#include <libparam/seamless_param.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>

namespace quadify::cli {
namespace {

struct ParamArgs {
  std::string input;
  std::string output;
  param::ParamOptions options;
  FeatureArgs features;
  SizingArgs sizing;
};

const std::map<std::string, param::RoundingOrder> kOrders = {
    {"bottom-up", param::RoundingOrder::kBottomUp},
    {"top-down", param::RoundingOrder::kTopDown},
};


int run_param(const ParamArgs& args, const CommonOptions& common) {
  core::check_can_write(args.output);
  Progress progress(common.quiet);
  LoadedMesh loaded = load_and_repair(args.input, progress);

  param::ParamOptions options = args.options;
  options.threads = common.threads;
  const FeatureInput feature_input = apply_feature_args(args.features, args.input, &loaded, &options);
  SizingInput sizing = apply_sizing_args(args.sizing, loaded, progress);
  sizing.apply_to(&options);
  options.progress = [&progress](const std::string& stage, int step, int n_steps) {
    progress.step(stage + " " + std::to_string(step) + "/" + std::to_string(n_steps));
  };
  progress.begin("param");
  const param::ParamResult result = param::compute_seamless_param(loaded.repaired.mesh, options);
  progress.end();
  warn_feature_fallbacks(args.input, result.stats, common.quiet);
  if (result.status.code() == core::StatusCode::kInvalidInput)
    throw CliError{kExitBadInput, args.input + ": " + result.status.message()};
  if (!result.status.is_ok() && result.status.code() != core::StatusCode::kNotConverged)
    throw CliError{kExitInternal, args.input + ": parametrization failed: " + result.status.to_string()};

  progress.begin("metrics");
  const core::UVMetrics m = core::compute_uv_metrics(result.uv);
  progress.end();
  progress.begin("write");
  core::write_uv_obj(args.output, result.uv);
  progress.end();

  const param::ParamStats& s = result.stats;
  if (!common.quiet) {
    std::printf("%s: %d triangles, %d components -> %s\n", args.input.c_str(), loaded.repaired.mesh.n_faces(),
                s.n_components, args.output.c_str());
    std::printf("tau %.4g, flipped %d, cones %d, seam edges %d, seam residual %.3g, patches %d (improved %d), "
                "%.2f s\n",
                m.tau, m.n_flipped, m.n_cones, m.n_seam_edges, m.seam_residual_abs, s.n_patches, s.n_improved,
                s.seconds_total);
    if (s.n_direction_faces > 0)
      std::printf("curvature alignment: %d faces, mean angle to the axes %.1f deg (unaligned %.1f deg)\n",
                  s.n_direction_faces, s.direction_angle, s.direction_angle_initial);
    if (s.n_feature_edges > 0)
      std::printf("features: %d edges, %d aligned, %d disabled (τ bound %d, wedge conflicts %d, flips %d)\n",
                  s.n_feature_edges, s.n_aligned_features, s.n_disabled_features, s.n_disabled_by_tau,
                  s.n_disabled_by_wedge, s.n_disabled_by_flips);
  }
  if (!result.status.is_ok())
    std::fprintf(stderr, "quadify: warning: %s: %s\n", args.input.c_str(), result.status.message().c_str());

  nlohmann::json report;
  report["command"] = "param";
  report["status"] = result.status.is_ok() ? "ok" : result.status.to_string();
  report["input"] = input_json(args.input, loaded.raw);
  report["repair"] = to_json(loaded.repaired.report);
  report["mesh"] = to_json(core::topology_stats(loaded.repaired.mesh));
  report["output"] = args.output;
  report["param"] = {{"energy", [&] {
                        for (auto& [name, e] : kEnergies)
                          if (e == args.options.energy) return name;
                        return std::string("?");
                      }()},
                     {"components", s.n_components},
                     {"seam_edges", s.n_seam_edges},
                     {"cones", s.n_cones},
                     {"patches", s.n_patches},
                     {"improved", s.n_improved},
                     {"cancelled_pairs", s.n_cancelled_pairs},
                     {"surface_pairs", s.n_surface_pairs},
                     {"far_pairs", s.n_far_pairs},
                     {"split_cones", s.n_split_cones},
                     {"deferred_matchings", s.n_deferred_matchings},
                     {"coarse_cones", s.coarse_cones},
                     {"coarse_cones_fallback_reason", s.coarse_cones_fallback_reason},
                     {"batches", s.n_batches},
                     {"iterations", s.total_iterations},
                     {"flipped", s.n_flipped},
                     {"free_variables", s.n_free_variables},
                     {"tau", number(s.tau)},
                     {"sd_max", number(s.sd_max)},
                     {"seam_residual", number(s.seam_residual)},
                     {"features", feature_json(feature_input, s)},
                     {"sizing", sizing.report},
                     {"curvature_alignment", direction_json(sizing, s)},
                     {"seconds_total", s.seconds_total},
                     {"profile", param_profile_json(s)}};  // the seconds per stage and solver step
  report["metrics"] = {{"tau", number(m.tau)},
                       {"flipped", m.n_flipped},
                       {"degenerate", m.n_degenerate},
                       {"sd_mean", number(m.sd_mean)},
                       {"sd_max", number(m.sd_max)},
                       {"cones", m.n_cones},
                       {"seam_edges", m.n_seam_edges},
                       {"seam_residual_abs", number(m.seam_residual_abs)},
                       {"seam_residual_max", number(m.seam_residual_max)},
                       {"matchings_integer", m.matchings_integer},
                       {"gauss_bonnet_error", number(m.gauss_bonnet_error)}};
  report["timings"] = progress.timings();
  write_report(common, report);
  return kExitOk;
}

}  // namespace

CommandRunner register_param(CLI::App& app) {
  auto args = std::make_shared<ParamArgs>();
  param::ParamOptions& o = args->options;
  app.add_option("input", args->input, "Triangle mesh (OBJ, OFF, PLY, STL, glTF, GLB)")->required()->type_name("IN");
  app.add_option("-o,--output", args->output, "UV OBJ to write (per-corner vt; seams visible)")
      ->required()
      ->type_name("OUT.obj");
  app.add_option("--energy", o.energy,
                 "Distortion minimised at every step: tau (max isometric distortion, flip-free), sd "
                 "(symmetric Dirichlet, flip-free), arap, linf-arap, conformal (these may flip)")
      ->transform(CLI::CheckedTransformer(kEnergies, CLI::ignore_case))
      ->default_str("tau");
  app.add_option("--order", o.order,
                 "Rounding order of the matchings: bottom-up (smallest rounding error first) or top-down")
      ->transform(CLI::CheckedTransformer(kOrders, CLI::ignore_case))
      ->default_str("bottom-up");
  app.add_option("--step", o.threshold_step, "Increment of the rounding-error threshold between batches")
      ->check(CLI::Range(0.01, 0.5))
      ->capture_default_str();
  app.add_flag("!--no-local-estimation", o.local_estimation,
               "Round every matching to the nearest integer instead of testing floor and ceiling on a patch");
  app.add_option("--estimation-min-error", o.local_estimation_min_error,
                 "Matchings with at least this rounding error go through local estimation")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  app.add_option("--patch-levels", o.patch_bfs_levels, "BFS ring levels of a local-estimation patch")
      ->check(CLI::Range(1, 20))
      ->capture_default_str();
  app.add_option("--max-newton-iters", o.max_newton_iters, "Newton iterations per layout optimization")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  app.add_option("--cone-pair-distance", o.cone_pair_distance,
                 "Remove pairs of opposite cones joined by a path of at most --cone-pair-hops seam edges "
                 "shorter than this (model units) by changing the matchings along it (0 = off, the paper)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--cone-pair-hops", o.cone_pair_max_hops, "Seam edges of a cone-pair cancellation path")
      ->check(CLI::Range(1, 10))
      ->capture_default_str();
  app.add_flag("--surface-cone-pairs", o.cone_pair_surface,
               "With --cone-pair-distance: then also remove the pairs within that distance over the surface "
               "whose seam path is longer, along that seam path, where the map's tau grows by at most 25% and no "
               "face's size by more than 1.75 times");
  app.add_option("--cone-split-distance", o.cone_split_distance,
                 "Split every cone of index above --cone-split-max-index (a quad vertex of valence 1 or 2, made "
                 "at the tips of thin parts), moving one unit of index at a time to a vertex about this far "
                 "(model units) along the seams (0 = off, the paper)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--cone-split-max-index", o.cone_split_max_index,
                 "With --cone-split-distance: cones of a larger index are split (2: index 3 and more, which no "
                 "quad mesh can have; 1: also index 2, a flat quad corner, and +1 cones crowded within half "
                 "the distance of another)")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  app.add_option("--cone-scale", o.cone_scale,
                 "Round the matchings on a copy of the mesh smoothed at this length (model units), so that "
                 "curvature details smaller than it make no cones, then lay out the mesh itself under "
                 "them; ignored with features or boundary alignment (0 = off, the paper)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  add_feature_options(app, &args->features);
  add_sizing_options(app, &args->sizing);
  return [args](const CommonOptions& common) { return run_param(*args, common); };
}

}  // namespace quadify::cli
