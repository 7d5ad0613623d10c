// quadify check FILE [--reference IN]: metrics of a parametrization or a quad mesh made by any
// tool. A triangle mesh with texture coordinates is checked as a map (distortion, flips, seams,
// cones, Gauss–Bonnet); anything else as a polygon mesh (quad quality, topology, distances).
#include "commands.h"

#include <libcore/read_mesh.h>
#include <libcore/status.h>
#include <libcore/topology.h>
#include <libcore/uv_metrics.h>
#include <libquadex/quad_metrics.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>

namespace quadify::cli {
namespace {

struct CheckArgs {
  std::string file;
  std::string reference;
  std::string mode = "auto";  // auto | uv | quad
  double feature_angle = 40.0;
  int samples = 100'000;
};

bool all_triangles(const core::PolyMesh& mesh) {
  for (int f = 0; f < mesh.n_faces(); ++f)
    if (mesh.degree(f) != 3) return false;
  return true;
}

nlohmann::json check_uv(const std::string& file, const core::PolyMesh& raw, Progress& progress) {
  progress.begin("uv metrics");
  const core::UVMesh map = core::to_uvmesh(raw);
  try {
    (void)core::build_edge_topology(map.mesh);
  } catch (const std::invalid_argument& e) {
    throw CliError{kExitBadInput, file + ": not a manifold oriented triangle mesh (" + e.what() + ")"};
  }
  const core::UVMetrics m = core::compute_uv_metrics(map);
  progress.end();

  int max_index = 0, sum_index = 0;
  nlohmann::json cones = nlohmann::json::array();
  for (const auto& c : m.cones) {
    const int index = static_cast<int>(std::lround(c.index));
    sum_index += index;
    max_index = std::max(max_index, std::abs(index));
    cones.push_back({{"vertex", c.vertex}, {"index", c.index}});
  }
  std::printf("%s: parametrization of %d triangles\n", file.c_str(), m.n_faces);
  std::printf("distortion: tau %.4g (sigma1 max %.4g, sigma2 min %.4g), symmetric Dirichlet mean %.4g max %.4g\n",
              m.tau, m.sigma1_max, m.sigma2_min, m.sd_mean, m.sd_max);
  std::printf("flipped %d, degenerate %d\n", m.n_flipped, m.n_degenerate);
  std::printf("seams: %d edges, max residual %.3g (relative), matchings %s\n", m.n_seam_edges,
              m.seam_residual_max, m.matchings_integer ? "integer" : "NOT integer");
  std::printf("cones: %d (indices sum %d, integer: %s), Gauss-Bonnet error %.3g rad (chi %d)\n", m.n_cones,
              sum_index, m.cone_indices_integer ? "yes" : "no", m.gauss_bonnet_error, m.euler_characteristic);

  nlohmann::json j;
  j["kind"] = "uv";
  j["faces"] = m.n_faces;
  j["flipped"] = m.n_flipped;
  j["degenerate"] = m.n_degenerate;
  j["tau"] = number(m.tau);
  j["sigma1_max"] = number(m.sigma1_max);
  j["sigma2_min"] = number(m.sigma2_min);
  j["sd_mean"] = number(m.sd_mean);
  j["sd_max"] = number(m.sd_max);
  j["conformal_mean"] = number(m.conformal_mean);
  j["conformal_max"] = number(m.conformal_max);
  j["area_mean"] = number(m.area_mean);
  j["area_max"] = number(m.area_max);
  j["seam_edges"] = m.n_seam_edges;
  j["seam_residual_max"] = number(m.seam_residual_max);
  j["seam_residual_abs"] = number(m.seam_residual_abs);
  j["matchings_integer"] = m.matchings_integer;
  j["cones"] = m.n_cones;
  j["cone_index_sum"] = sum_index;
  j["cone_indices_integer"] = m.cone_indices_integer;
  j["cone_list"] = cones;
  j["euler_characteristic"] = m.euler_characteristic;
  j["gauss_bonnet_error"] = number(m.gauss_bonnet_error);
  j["uv_bbox_diagonal"] = number(m.uv_bbox_diagonal);
  return j;
}

nlohmann::json check_quads(const CheckArgs& args, const core::PolyMesh& raw, Progress& progress) {
  core::TriMesh reference;
  bool has_reference = false;
  if (!args.reference.empty()) {
    const LoadedMesh ref = load_and_repair(args.reference, progress);
    reference = ref.repaired.mesh;
    has_reference = true;
  }
  progress.begin("quad metrics");
  quadex::QuadMetricsOptions options;
  options.feature_angle_deg = args.feature_angle;
  options.hausdorff_samples = args.samples;
  const quadex::QuadMetrics m = quadex::compute_quad_metrics(raw, has_reference ? &reference : nullptr, options);
  progress.end();

  nlohmann::json degrees = nlohmann::json::object(), valences = nlohmann::json::object();
  for (auto [d, n] : m.faces_by_degree) degrees[std::to_string(d)] = n;
  for (auto [v, n] : m.valence_histogram) valences[std::to_string(v)] = n;
  const std::string degenerate =
      m.n_degenerate > 0 ? " (" + std::to_string(m.n_degenerate) + " faces visit a vertex twice)" : "";
  std::printf("%s: %d vertices, %d faces (%d not quads), %s%s, %d components, %d boundary loops, chi %d\n",
              args.file.c_str(), m.n_vertices, m.n_faces, m.n_non_quads, m.manifold ? "manifold" : "NOT manifold",
              degenerate.c_str(), m.n_components, m.n_boundary_loops, m.euler_characteristic);
  std::printf("irregular vertices %d, flipped quads %d, scaled Jacobian min %.3f mean %.3f, angle deviation mean %.2f deg, "
              "edge length CV %.3f\n",
              m.n_irregular, m.n_flipped, m.sj_min, m.sj_mean, m.angle_dev_mean, m.edge_len_cv);
  if (m.has_reference) {
    std::printf("distance to %s (x bbox diagonal): Hausdorff %.4g (to %.4g, from %.4g), mean %.4g\n",
                args.reference.c_str(), m.hausdorff_sym, m.hausdorff_to_ref, m.hausdorff_from_ref, m.mean_dist_sym);
    if (m.feature_capture >= 0)
      std::printf("feature capture %.4f (feature Hausdorff %.4g)\n", m.feature_capture, m.feature_hausdorff);
    if (m.principal_angle_mean >= 0)
      std::printf("principal curvature alignment: mean angle %.2f deg over %d quads in anisotropic regions "
                  "(22.5 = random)\n",
                  m.principal_angle_mean, m.n_anisotropic_quads);
  }

  nlohmann::json j;
  j["kind"] = "quad";
  j["vertices"] = m.n_vertices;
  j["faces"] = m.n_faces;
  j["faces_by_degree"] = degrees;
  j["non_quads"] = m.n_non_quads;
  j["valence_histogram"] = valences;
  j["irregular_vertices"] = m.n_irregular;
  j["degenerate_faces"] = m.n_degenerate;
  j["manifold"] = m.manifold;
  j["components"] = m.n_components;
  j["boundary_loops"] = m.n_boundary_loops;
  j["euler_characteristic"] = m.euler_characteristic;
  j["genus"] = m.genus;
  j["flipped_quads"] = m.n_flipped;
  j["sj_min"] = number(m.sj_min);
  j["sj_mean"] = number(m.sj_mean);
  j["angle_dev_mean"] = number(m.angle_dev_mean);
  j["angle_dev_max"] = number(m.angle_dev_max);
  j["edge_len_cv"] = number(m.edge_len_cv);
  j["edge_len_mean"] = number(m.edge_len_mean);
  if (m.has_reference) {
    j["reference"] = args.reference;
    j["hausdorff_sym"] = number(m.hausdorff_sym);
    j["hausdorff_to_ref"] = number(m.hausdorff_to_ref);
    j["hausdorff_from_ref"] = number(m.hausdorff_from_ref);
    j["mean_dist_sym"] = number(m.mean_dist_sym);
    j["feature_capture"] = m.feature_capture >= 0 ? number(m.feature_capture) : nlohmann::json(nullptr);
    j["feature_hausdorff"] = m.feature_hausdorff >= 0 ? number(m.feature_hausdorff) : nlohmann::json(nullptr);
    j["principal_angle_mean"] =
        m.principal_angle_mean >= 0 ? number(m.principal_angle_mean) : nlohmann::json(nullptr);
    j["anisotropic_quads"] = m.n_anisotropic_quads;
  }
  return j;
}

int run_check(const CheckArgs& args, const CommonOptions& common) {
  Progress progress(common.quiet);
  progress.begin("read");
  const core::PolyMesh raw = core::read_mesh(args.file);
  progress.end();
  std::string mode = args.mode;
  if (mode == "auto") mode = raw.has_uv() && all_triangles(raw) ? "uv" : "quad";
  if (mode == "uv" && !raw.has_uv())
    throw CliError{kExitBadInput, args.file + ": --mode uv needs texture coordinates (OBJ vt), the file has none"};

  nlohmann::json report;
  report["command"] = "check";
  report["status"] = "ok";
  report["input"] = input_json(args.file, raw);
  report["check"] = mode == "uv" ? check_uv(args.file, raw, progress) : check_quads(args, raw, progress);
  report["timings"] = progress.timings();
  write_report(common, report);
  return kExitOk;
}

}  // namespace

CommandRunner register_check(CLI::App& app) {
  auto args = std::make_shared<CheckArgs>();
  app.add_option("file", args->file, "Mesh to measure: a UV-mapped triangle OBJ or a quad/polygon mesh")
      ->required()
      ->type_name("FILE");
  app.add_option("--reference", args->reference,
                 "Input triangle mesh to measure distances (Hausdorff, mean) and feature capture against")
      ->type_name("IN");
  app.add_option("--mode", args->mode,
                 "auto: a triangle mesh with UVs is checked as a map, anything else as a quad mesh")
      ->check(CLI::IsMember({"auto", "uv", "quad"}))
      ->capture_default_str();
  app.add_option("--feature-angle", args->feature_angle,
                 "Dihedral angle (degrees) above which a reference edge is sharp, for feature capture")
      ->check(CLI::Range(0.0, 180.0))
      ->capture_default_str();
  app.add_option("--samples", args->samples, "Area samples per surface for the distance measures")
      ->check(CLI::Range(1000, 10'000'000))
      ->capture_default_str();
  return [args](const CommonOptions& common) { return run_check(*args, common); };
}

}  // namespace quadify::cli
