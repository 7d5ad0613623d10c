#include "report.h"

#include <libcore/atomic_file.h>
#include <libcore/read_mesh.h>
#include <libcore/status.h>
#include <libparam/sizing.h>

#include <Eigen/SVD>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <unordered_set>
#include <iomanip>
#include <map>

namespace quadify::cli {
using core::edge_key;
namespace {
constexpr auto kAnnounceAfter = std::chrono::seconds(1);  // stages shorter than this stay silent
}

Progress::Progress(bool quiet) : quiet_(quiet) {
  if (!quiet_) watcher_ = std::thread([this] { watch(); });
}

Progress::~Progress() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (watcher_.joinable()) watcher_.join();
}

void Progress::begin(const std::string& stage) {
  std::lock_guard lock(mutex_);
  stage_ = stage;
  stage_start_ = std::chrono::steady_clock::now();
  announced_ = false;
  cv_.notify_all();
}

void Progress::end() {
  std::lock_guard lock(mutex_);
  if (stage_.empty()) return;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_start_).count();
  timings_[stage_] = timings_.value(stage_, 0.0) + seconds;
  if (announced_ && !quiet_) std::fprintf(stderr, "quadify: %s done in %.1f s\n", stage_.c_str(), seconds);
  stage_.clear();
}

void Progress::step(const std::string& text) {
  std::lock_guard lock(mutex_);
  if (quiet_) return;
  if (!announced_) {
    std::fprintf(stderr, "quadify: %s ...\n", stage_.c_str());
    announced_ = true;
  }
  std::fprintf(stderr, "quadify:   %s\n", text.c_str());
}

void Progress::watch() {
  std::unique_lock lock(mutex_);
  while (!stop_) {
    cv_.wait_for(lock, std::chrono::milliseconds(100));
    if (!stage_.empty() && !announced_ && std::chrono::steady_clock::now() - stage_start_ >= kAnnounceAfter) {
      std::fprintf(stderr, "quadify: %s ...\n", stage_.c_str());
      announced_ = true;
    }
  }
}

LoadedMesh load_and_repair(const std::filesystem::path& path, Progress& progress) {
  LoadedMesh loaded;
  progress.begin("read");
  loaded.raw = core::read_mesh(path);  // throws InputError naming the file
  progress.end();
  progress.begin("repair");
  loaded.repaired = core::repair_mesh(loaded.raw);
  progress.end();
  if (!loaded.repaired.status.is_ok())
    throw CliError{kExitBadInput, path.string() + ": " + loaded.repaired.status.message()};
  return loaded;
}

void add_feature_options(CLI::App& app, FeatureArgs* a) {
  app.add_option("--feature-angle", a->angle_deg,
                 "Sharp edges (dihedral angle above this, degrees) become chains of quad edges; 0 = no "
                 "detected features")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 180.0));
  app.add_option("--feature-side-angle", a->side_angle_deg,
                 "Keep only sharp edges that are creases between two smooth sides: a chain of sharp "
                 "edges is dropped when the median, over its edges, of the largest dihedral angle of "
                 "the other edges of their faces is at least this (degrees), and so are groups of "
                 "fewer than 6 sharp edges unless their median dihedral angle is at least 120 degrees "
                 "(a short knife edge, such as a blade's tip, stays), and chains of 4 edges or more whose dihedral angles "
                 "are all at least 60 degrees and within 5 degrees of each other stay too (a machined edge, such as "
                 "a drilled hole's rim beside faceted walls); this leaves out the sharp edges of scans and sculpts "
                 "(coarsely tessellated tips, folds and crevices); 0 = every sharp edge")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 180.0));
  app.add_option("--feature-edges", a->edge_file,
                 "Extra feature edges: a text file with one pair 'a b' of 0-based input vertex ids per "
                 "line ('#' starts a comment)")
      ->type_name("FILE");
  app.add_flag("!--no-obj-features", a->from_obj_lines,
               "Ignore the input OBJ's 'l' lines (by default they are feature edges)");
  app.add_flag("!--no-boundary-alignment", a->boundaries,
               "Do not align boundaries with quad edges (by default they are features, so open meshes "
               "get quads along their boundaries)");
  app.add_option("--feature-mode", a->soft,
                 "When features are aligned: 'during' the rounding of the matchings, as hard "
                 "constraints (paper Alg. 2), or 'after' it, as soft constraints pulled in until "
                 "the alignment error is at most 1e-5 (Alg. 3: the map keeps its distortion bound, "
                 "fewer features are disabled)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, bool>{{"during", false}, {"after", true}}))
      ->default_str("during");
  app.add_option("--feature-max-tau", a->max_tau,
                 "Disable a feature whose locally estimated distortion tau stays above this")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--feature-max-wedge-stretch", a->max_wedge_stretch,
                 "Where two features meet, the angle between them may be stretched or shrunk by at "
                 "most this factor to become a multiple of 90 degrees (else one is disabled); lower "
                 "values avoid flat quad corners where creases meet almost straight")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 100.0));
  app.add_flag("--feature-curve-labels", a->curve_labels,
               "Label the edges of a smooth feature curve (consecutive edges within 30 degrees of "
               "straight) together, as one straight iso-line, instead of edge by edge (the paper's "
               "Alg. 2), where a curve that bends in the layout switches axes, and loses edges, where "
               "it is straight on the surface; a curve that turns by 60 degrees or more within two "
               "target quad edges (a rounded corner) is split there, at its sharpest joint; "
               "experimental: at 5,000 quads it helps on some CAD parts (fandisk's curved rims, "
               "casting, wingnut) and hurts on others; at 2,000 it hurts on most");
  app.add_option("--acute-curve-labels", a->acute_curve_labels,
                 "on: a smooth feature curve that ends where another feature leaves at 15 to 45 "
                 "degrees (an acute wedge) is labeled as a whole curve, its straight run from there "
                 "(edges within 45 degrees of its first), so that the wedge opens to a quarter turn "
                 "at its tip instead of being squeezed between two parallel iso-lines (fandisk: tau "
                 "2.91 -> 2.06); off: edge by edge, as the paper's Alg. 2. On by default in `param`; "
                 "off by default in the remesher, where it made fandisk's quads farther from the "
                 "input (Hausdorff 0.0020 -> 0.0036 at 5,000 quads)")
      ->capture_default_str();
}


namespace {

FeatureInput collect_feature_edges(const FeatureArgs& args, const std::string& input,
                                   const LoadedMesh& loaded, param::ParamOptions* options) {
  FeatureInput fi;
  const core::TriMesh& mesh = loaded.repaired.mesh;
  const core::EdgeTopology topo = core::build_edge_topology(mesh);
  options->align_boundaries = args.boundaries;
  options->feature_max_tau = args.max_tau;
  options->feature_mode = args.soft ? param::FeatureMode::kAfterRounding : param::FeatureMode::kDuringRounding;
  fi.soft = args.soft;
  fi.curve_labels = args.curve_labels;
  fi.acute_curve_labels = args.acute_curve_labels;
  options->feature_max_wedge_stretch = args.max_wedge_stretch;
  options->feature_curve_labels = args.curve_labels;
  options->feature_acute_curve_labels = args.acute_curve_labels;
  options->feature_edges.clear();
  if (args.angle_deg > 0) {
    core::CreaseOptions crease;
    crease.angle_deg = args.angle_deg;
    crease.max_side_angle_deg = args.side_angle_deg;
    fi.n_detected = static_cast<int>(core::sharp_edges(mesh, topo, args.angle_deg).size());
    for (const int e : core::crease_edges(mesh, topo, crease))
      options->feature_edges.push_back({topo.edge_vertex(e, 0), topo.edge_vertex(e, 1)});
    fi.n_not_creases = fi.n_detected - static_cast<int>(options->feature_edges.size());
  }
  // Given edges in input vertex ids, with where they came from.
  struct Given {
    int a, b;
    std::string where;
  };
  std::vector<Given> given;
  if (args.from_obj_lines)
    for (size_t i = 0; i < loaded.raw.lines.size(); ++i)
      given.push_back({loaded.raw.lines[i][0], loaded.raw.lines[i][1],
                       input + ": line segment " + std::to_string(i + 1)});
  if (!args.edge_file.empty()) {
    std::ifstream in(args.edge_file);
    if (!in) throw CliError{kExitBadInput, args.edge_file + ": cannot read the feature edge file"};
    std::string line;
    for (int ln = 1; std::getline(in, line); ++ln) {
      if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
      std::istringstream ls(line);
      long long a = 0, b = 0;
      if (!(ls >> a)) continue;  // empty or comment line
      std::string rest;
      if (!(ls >> b) || (ls >> rest))
        throw CliError{kExitBadInput, args.edge_file + ": line " + std::to_string(ln) +
                                          ": expected two vertex ids 'a b'"};
      const std::string where = args.edge_file + ": line " + std::to_string(ln);
      if (a < 0 || b < 0 || a >= loaded.raw.n_vertices() || b >= loaded.raw.n_vertices())
        throw CliError{kExitBadInput, where + ": vertex id out of range (the input has " +
                                          std::to_string(loaded.raw.n_vertices()) + " vertices)"};
      given.push_back({static_cast<int>(a), static_cast<int>(b), where});
    }
  }
  fi.n_given = static_cast<int>(given.size());
  if (given.empty()) return fi;
  std::unordered_set<long long> raw_edges;
  for (int f = 0; f < loaded.raw.n_faces(); ++f)
    for (int k = 0; k < loaded.raw.degree(f); ++k)
      raw_edges.insert(edge_key(loaded.raw.vertex(f, k), loaded.raw.vertex(f, (k + 1) % loaded.raw.degree(f))));
  std::unordered_set<long long> out_edges;
  for (int e = 0; e < topo.n_edges(); ++e) out_edges.insert(edge_key(topo.edge_vertex(e, 0), topo.edge_vertex(e, 1)));
  // Input vertex → repaired vertices (several after a split; a welded one maps to its survivor,
  // the nearest repaired vertex).
  std::vector<std::vector<int>> outputs(loaded.raw.n_vertices());
  for (size_t v = 0; v < loaded.repaired.vertex_origin.size(); ++v)
    outputs[loaded.repaired.vertex_origin[v]].push_back(static_cast<int>(v));
  auto outputs_of = [&](int a) -> const std::vector<int>& {
    if (outputs[a].empty() && mesh.n_vertices() > 0) {
      Eigen::Index best = 0;
      (mesh.V.rowwise() - loaded.raw.V.row(a)).rowwise().squaredNorm().minCoeff(&best);
      outputs[a].push_back(static_cast<int>(best));
    }
    return outputs[a];
  };
  for (const Given& g : given) {
    if (g.a == g.b || !raw_edges.count(edge_key(g.a, g.b)))
      throw CliError{kExitBadInput, g.where + ": (" + std::to_string(g.a) + ", " + std::to_string(g.b) +
                                        ") is not an edge of " + input};
    bool found = false;
    for (const int oa : outputs_of(g.a))
      for (const int ob : outputs_of(g.b))
        if (oa != ob && out_edges.count(edge_key(oa, ob))) {
          options->feature_edges.push_back({oa, ob});
          found = true;
        }
    if (!found) ++fi.n_lost;
  }
  if (fi.n_lost > 0)
    std::fprintf(stderr, "quadify: warning: %s: %d feature edges were removed by the repair\n",
                 input.c_str(), fi.n_lost);
  return fi;
}

}  // namespace

void warn_feature_fallbacks(const std::string& input, const param::ParamStats& stats, bool quiet) {
  if (quiet) return;
  if (stats.n_feature_partial_fallbacks > 0)
    std::fprintf(stderr,
                 "quadify: %s: %d of %d components could not be parametrized flip-free with all their "
                 "features and were parametrized without those near where they failed (%s)\n",
                 input.c_str(), stats.n_feature_partial_fallbacks, stats.n_components,
                 stats.feature_fallback_reason.c_str());
  if (stats.n_feature_fallbacks == 0) return;
  std::fprintf(stderr,
               "quadify: %s: %d of %d components could not be parametrized flip-free with their "
               "features and were parametrized without them (%s)\n",
               input.c_str(), stats.n_feature_fallbacks, stats.n_components,
               stats.feature_fallback_reason.c_str());
}

FeatureInput apply_feature_args(const FeatureArgs& args, const std::string& input,
                                LoadedMesh* loaded, param::ParamOptions* options) {
  FeatureInput fi = collect_feature_edges(args, input, *loaded, options);
  fi.n_wedges_flipped = core::flip_feature_wedges(&loaded->repaired.mesh, options->feature_edges);
  return fi;
}

nlohmann::json param_profile_json(const param::ParamStats& s) {
  return {{"seconds_cut", s.seconds_cut},
          {"seconds_optimize", s.seconds_optimize},
          {"seconds_local_estimation", s.seconds_local_estimation},
          {"seconds_elimination", s.seconds_elimination},
          {"seconds_setup", s.seconds_setup},
          {"seconds_assembly", s.seconds_assembly},
          {"seconds_analyze", s.seconds_analyze},
          {"seconds_factorize", s.seconds_factorize},
          {"seconds_line_search", s.seconds_line_search},
          {"seconds_projection", s.seconds_projection},
          {"seconds_tau", s.seconds_tau},
          {"transition_iterations", s.n_transition_iterations},
          {"batch_iterations", s.n_batch_iterations},
          {"tau_iterations", s.n_tau_iterations},
          {"max_hessian_nonzeros", s.max_hessian_nonzeros},
          {"max_element_variables", s.max_element_variables},
          {"max_sum_sq_element_variables", s.max_sum_sq_element_variables}};
}

nlohmann::json feature_json(const FeatureInput& fi, const param::ParamStats& s) {
  return {{"mode", fi.soft ? "after" : "during"},
          {"curve_labels", fi.curve_labels},
          {"acute_curve_labels", fi.acute_curve_labels},
          {"acute_curves", s.n_acute_curves},
          {"detected_sharp_edges", fi.n_detected},
          {"sharp_edges_not_creases", fi.n_not_creases},
          {"given_edges", fi.n_given},
          {"given_edges_lost_in_repair", fi.n_lost},
          {"too_small_for_density", fi.n_too_small},
          {"stray_creases", fi.n_stray_creases},
          {"wedges_flipped", fi.n_wedges_flipped},
          {"feature_edges", s.n_feature_edges},
          {"aligned", s.n_aligned_features},
          {"disabled", s.n_disabled_features},
          {"disabled_by_tau", s.n_disabled_by_tau},
          {"disabled_by_wedge", s.n_disabled_by_wedge},
          {"disabled_by_flips", s.n_disabled_by_flips},
          {"patches", s.n_feature_patches},
          {"components_without_features", s.n_feature_fallbacks},
          {"components_without_features_near_failure", s.n_feature_partial_fallbacks},
          {"fallback_reason", s.feature_fallback_reason},
          {"alignment_error", number(s.feature_alignment_error)}};
}

nlohmann::json to_json(const core::RepairReport& r) {
  return {{"input_vertices", r.input_vertices},
          {"input_faces", r.input_faces},
          {"polygons_triangulated", r.polygons_triangulated},
          {"invalid_faces_removed", r.invalid_faces_removed},
          {"welded_vertices", r.welded_vertices},
          {"degenerate_faces_removed", r.degenerate_faces_removed},
          {"caps_removed", r.caps_removed},
          {"folds_flipped", r.folds_flipped},
          {"fin_faces_removed", r.fin_faces_removed},
          {"duplicate_faces_removed", r.duplicate_faces_removed},
          {"unreferenced_vertices_removed", r.unreferenced_vertices_removed},
          {"faces_reoriented", r.faces_reoriented},
          {"nonmanifold_edges_split", r.nonmanifold_edges_split},
          {"nonmanifold_vertices_split", r.nonmanifold_vertices_split},
          {"output_vertices", r.output_vertices},
          {"output_faces", r.output_faces},
          {"components", r.n_components},
          {"boundary_loops", r.n_boundary_loops},
          {"changed", r.changed()}};
}

nlohmann::json to_json(const core::TopologyStats& s) {
  return {{"vertices", s.n_vertices},
          {"edges", s.n_edges},
          {"faces", s.n_faces},
          {"components", s.n_components},
          {"boundary_loops", s.n_boundary_loops},
          {"euler_characteristic", s.euler_characteristic},
          {"nonmanifold_edges", s.n_nonmanifold_edges},
          {"nonmanifold_vertices", s.n_nonmanifold_vertices},
          {"manifold", s.is_manifold()},
          {"genus", s.genus}};
}

nlohmann::json input_json(const std::filesystem::path& path, const core::PolyMesh& raw) {
  std::map<int, int> by_degree;
  for (int f = 0; f < raw.n_faces(); ++f) ++by_degree[raw.degree(f)];
  nlohmann::json degrees = nlohmann::json::object();
  for (auto [d, n] : by_degree) degrees[std::to_string(d)] = n;
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  return {{"path", path.string()},
          {"format", core::format_name(core::format_from_extension(path))},
          {"bytes", ec ? 0 : bytes},
          {"vertices", raw.n_vertices()},
          {"faces", raw.n_faces()},
          {"faces_by_degree", degrees},
          {"has_uv", raw.has_uv()},
          {"lines", raw.lines.size()},
          {"bbox_diagonal", core::bbox_diagonal(raw.V)}};
}

void write_report(const CommonOptions& options, nlohmann::json report) {
  if (options.json_path.empty()) return;
  report["quadify_version"] = QUADIFY_VERSION;
  const std::string text = report.dump(2) + "\n";
  core::write_file_atomically(options.json_path, [&](std::ostream& out) { out << text; });
}

void add_sizing_options(CLI::App& app, SizingArgs* a) {
  auto* adaptive = app.add_flag(
      "--adaptive", a->adaptive,
      "Curvature-adaptive quad sizes: edge length ∝ 1/sqrt(curvature) (even chordal error), "
      "smaller quads where the surface bends more; the total stays near the target count");
  app.add_option("--adaptive-ratio", a->max_ratio,
                 "With --adaptive: largest over smallest quad edge length")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 100.0));
  app.add_flag("--anisotropic", a->anisotropic,
               "With --adaptive: a length per principal direction (∝ 1/sqrt of that curvature), so "
               "quads stretch along the direction in which the surface bends less (cylinders, "
               "fillets), within --adaptive-ratio")
      ->needs(adaptive);
  app.add_option("--size-field", a->size_file,
                 "Relative quad edge length per input vertex: a text file of one positive number per "
                 "line, in the input's vertex order ('#' starts a comment); only ratios matter")
      ->type_name("FILE")
      ->excludes(adaptive);
  app.add_flag("--align-curvature", a->align_curvature,
               "Align quad edges with the principal curvature directions where the surface is "
               "clearly anisotropic (larger curvature at least twice the smaller and at least 4 / "
               "bbox diagonal), as a soft term of the layout energy (paper 6.1)");
  app.add_option("--curvature-weight", a->curvature_weight,
                 "With --align-curvature: weight of the alignment against distortion (higher: "
                 "closer alignment, more distortion)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
}

void SizingInput::apply_to(param::ParamOptions* options) const {
  options->face_size = face_size;
  options->face_metric = face_metric;
  options->face_direction = face_direction;
  options->direction_weight = direction_weight;
}

nlohmann::json direction_json(const SizingInput& input, const param::ParamStats& stats) {
  if (input.face_direction.empty()) return nullptr;
  return {{"faces", stats.n_direction_faces},
          {"weight", input.direction_weight},
          {"angle_initial_deg", number(stats.direction_angle_initial)},
          {"angle_deg", number(stats.direction_angle)}};
}

SizingInput apply_sizing_args(const SizingArgs& args, const LoadedMesh& loaded, Progress& progress) {
  SizingInput out;
  const core::TriMesh& mesh = loaded.repaired.mesh;
  if (args.align_curvature) {
    progress.begin("curvature");
    out.face_direction = param::principal_face_directions(mesh);
    out.direction_weight = args.curvature_weight;
    progress.end();
  }
  if (args.adaptive) {
    progress.begin("sizing");
    param::AdaptiveSizingOptions o;
    o.max_ratio = args.max_ratio;
    if (args.anisotropic) {
      out.face_metric = param::adaptive_face_metric(mesh, o);
      progress.end();
      // Edge lengths asked for: the reciprocals of the metric's two larger singular values
      // (the third acts along the normal).
      double lo = INFINITY, hi = 0;
      for (const Eigen::Matrix3d& m : out.face_metric) {
        const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3d>(m).singularValues();
        lo = std::min(lo, 1 / sv(0));
        hi = std::max(hi, 1 / sv(0));
        lo = std::min(lo, 1 / sv(1));
        hi = std::max(hi, 1 / sv(1));
      }
      out.report["mode"] = "adaptive-anisotropic";
      out.report["max_ratio"] = args.max_ratio;
      out.report["min"] = number(lo);
      out.report["max"] = number(hi);
      return out;
    }
    out.face_size = param::adaptive_face_size(mesh, o);
    progress.end();
    out.report["mode"] = "adaptive";
    out.report["max_ratio"] = args.max_ratio;
  } else if (!args.size_file.empty()) {
    std::ifstream in(args.size_file);
    if (!in) throw CliError{kExitBadInput, args.size_file + ": cannot read the size field"};
    std::vector<double> input_size;
    std::string line;
    for (int ln = 1; std::getline(in, line); ++ln) {
      if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
      std::istringstream ls(line);
      double value = 0;
      if (!(ls >> value)) {
        std::string word;
        std::istringstream again(line);
        if (again >> word)
          throw CliError{kExitBadInput, args.size_file + ": line " + std::to_string(ln) +
                                            ": expected a number, found '" + word + "'"};
        continue;  // empty or comment line
      }
      std::string rest;
      if (ls >> rest)
        throw CliError{kExitBadInput, args.size_file + ": line " + std::to_string(ln) +
                                          ": expected one number per line"};
      if (!(value > 0) || !std::isfinite(value))
        throw CliError{kExitBadInput, args.size_file + ": line " + std::to_string(ln) +
                                          ": sizes must be positive"};
      input_size.push_back(value);
    }
    if (static_cast<int>(input_size.size()) != loaded.raw.n_vertices())
      throw CliError{kExitBadInput, args.size_file + ": " + std::to_string(input_size.size()) +
                                        " sizes for an input of " +
                                        std::to_string(loaded.raw.n_vertices()) + " vertices"};
    std::vector<double> vertex_size(mesh.n_vertices());
    for (int v = 0; v < mesh.n_vertices(); ++v)
      vertex_size[v] = input_size[loaded.repaired.vertex_origin[v]];
    out.face_size = param::face_size_from_vertices(mesh, vertex_size);
    out.report["mode"] = "file";
    out.report["file"] = args.size_file;
  } else {
    out.report["mode"] = "uniform";
    return out;
  }
  const auto [lo, hi] = std::minmax_element(out.face_size.begin(), out.face_size.end());
  out.report["min"] = number(*lo);
  out.report["max"] = number(*hi);
  return out;
}

}  // namespace quadify::cli
