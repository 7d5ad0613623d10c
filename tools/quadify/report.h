// The CLI's shared pieces: the JSON report, stage progress on stderr, exit codes, option structs.
#pragma once

#include <libcore/mesh.h>
#include <libcore/repair.h>
#include <libcore/topology.h>
#include <libparam/seamless_param.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <cmath>
#include <map>
#include <mutex>
#include <string>
#include <thread>

namespace quadify::cli {

// A JSON number, or null for NaN and ±inf (JSON has neither).
inline nlohmann::json number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

// Names of the distortion energies for --energy.
inline const std::map<std::string, param::Energy> kEnergies = {
    {"tau", param::Energy::kTau},
    {"sd", param::Energy::kSymmetricDirichlet},
    {"arap", param::Energy::kArap},
    {"linf-arap", param::Energy::kLinfArap},
    {"conformal", param::Energy::kConformal},
};

// Documented exit codes (README, --help).
constexpr int kExitOk = 0;
constexpr int kExitInternal = 1;   // a bug or resource failure (bad_alloc, failed write)
constexpr int kExitBadInput = 2;   // unusable input file or options

struct CommonOptions {
  std::string json_path;  // --json FILE
  int threads = 0;        // --threads N (0 = all cores)
  bool quiet = false;     // --quiet
};

// A user-facing failure: message already names the file and the problem.
struct CliError {
  int exit_code;
  std::string message;
};

// Prints "quadify: <stage> ..." on stderr when a stage runs longer than a second, and its duration
// when it ends; records every stage's seconds for the report.
class Progress {
 public:
  explicit Progress(bool quiet);
  ~Progress();
  void begin(const std::string& stage);
  void end();  // ends the current stage
  // Optional sub-step text of the current stage (e.g. "batch 3/5"), printed when verbose.
  void step(const std::string& text);
  const nlohmann::json& timings() const { return timings_; }

 private:
  void watch();
  bool quiet_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::thread watcher_;
  bool stop_ = false;
  std::string stage_;
  std::chrono::steady_clock::time_point stage_start_;
  bool announced_ = false;
  nlohmann::json timings_ = nlohmann::json::object();
};

// Reading + repair, shared by every command that takes a triangle mesh.
struct LoadedMesh {
  core::PolyMesh raw;
  core::RepairResult repaired;
};
LoadedMesh load_and_repair(const std::filesystem::path& path, Progress& progress);

// Feature alignment options shared by `param` and the remesher.
struct FeatureArgs {
  double angle_deg = 40;     // --feature-angle: sharp edges above this dihedral angle; 0 = none
  double side_angle_deg = 15;  // --feature-side-angle: crease filter (core::CreaseOptions); 0 = off
  std::string edge_file;     // --feature-edges FILE: lines "a b" of input vertex ids (0-based)
  bool from_obj_lines = true;  // OBJ `l` lines of the input are feature edges too
  bool boundaries = true;    // boundaries are features (--no-boundary-alignment turns it off)
  double max_tau = 2.5;      // --feature-max-tau
  double max_wedge_stretch = 1.95;  // --feature-max-wedge-stretch
  bool curve_labels = false;  // --feature-curve-labels: smooth feature curves labeled as one
  bool acute_curve_labels = true;  // --acute-curve-labels on|off (the remesher: off by default)
  bool soft = false;         // --feature-mode after: Alg. 3 (param::FeatureMode::kAfterRounding)
};
void add_feature_options(CLI::App& app, FeatureArgs* args);
// One line on stderr (unless quiet) when components of `input` fell back to a parametrization
// without their features (param::ParamStats::n_feature_fallbacks).
void warn_feature_fallbacks(const std::string& input, const param::ParamStats& stats, bool quiet);
// Sets options->feature_edges (detected sharp edges, the file's and the OBJ's feature lines,
// mapped onto the repaired mesh), align_boundaries and feature_max_tau. Throws CliError naming
// the file for an unreadable edge file or an edge that is not an edge of the input.
struct FeatureInput {
  int n_detected = 0;  // sharp edges found by the dihedral angle
  int n_not_creases = 0;  // of those, left out by the crease filter (no smooth sides, fragments)
  int n_given = 0;     // edges from the file and the OBJ lines
  int n_lost = 0;      // given edges that the repair removed (e.g. with a degenerate face)
  int n_too_small = 0;  // edges of curves too short for the quad density (remesh only)
  int n_stray_creases = 0;  // creases left out as an organic model's stray fragments (remesh only)
  int n_wedges_flipped = 0;  // core::flip_feature_wedges on the repaired mesh
  bool soft = false;    // Alg. 3 (--feature-mode after)
  bool curve_labels = false;  // --feature-curve-labels
  bool acute_curve_labels = true;  // --acute-curve-labels
};
// Also flips the feature wedges of loaded->repaired.mesh (core::flip_feature_wedges: faces
// change, vertex ids stay).
FeatureInput apply_feature_args(const FeatureArgs& args, const std::string& input,
                                LoadedMesh* loaded, param::ParamOptions* options);
nlohmann::json feature_json(const FeatureInput& input, const param::ParamStats& stats);

// Where a parametrization's time went: seconds per stage and per solver step, iteration counts
// and the largest system (`quadify param` and the remesher's report, under param.profile).
nlohmann::json param_profile_json(const param::ParamStats& stats);

// Sizing options shared by `param` and the remesher (paper section 7, isotropic scaling).
struct SizingArgs {
  bool adaptive = false;     // --adaptive: curvature-adaptive sizes (param::adaptive_face_size)
  double max_ratio = 4;      // --adaptive-ratio
  bool anisotropic = false;  // --anisotropic: per-direction lengths (param::adaptive_face_metric)
  std::string size_file;     // --size-field FILE: one relative edge length per input vertex
  bool align_curvature = false;  // --align-curvature: param::principal_face_directions
  double curvature_weight = 3;   // --curvature-weight: ParamOptions::direction_weight
};
void add_sizing_options(CLI::App& app, SizingArgs* args);
// Per-face sizes of the repaired mesh (empty: uniform) and their report. Throws CliError naming
// the file for an unreadable size field, a wrong count or a value that is not positive.
struct SizingInput {
  std::vector<double> face_size;
  std::vector<Eigen::Matrix3d> face_metric;
  std::vector<Eigen::Vector3d> face_direction;  // --align-curvature (empty: off)
  double direction_weight = 3;
  nlohmann::json report;
  // Sets the sizing and alignment fields of the parametrization options.
  void apply_to(param::ParamOptions* options) const;
};
// The "curvature_alignment" part of a report (null when off).
nlohmann::json direction_json(const SizingInput& input, const param::ParamStats& stats);
SizingInput apply_sizing_args(const SizingArgs& args, const LoadedMesh& loaded, Progress& progress);

nlohmann::json to_json(const core::RepairReport& report);
nlohmann::json to_json(const core::TopologyStats& stats);
nlohmann::json input_json(const std::filesystem::path& path, const core::PolyMesh& raw);

// Writes the report atomically to options.json_path if set.
void write_report(const CommonOptions& options, nlohmann::json report);

}  // namespace quadify::cli
