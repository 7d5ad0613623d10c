#include "report.h"

#include <libcore/atomic_file.h>
#include <libcore/read_mesh.h>
#include <libcore/status.h>

#include <cstdio>
#include <iomanip>
#include <map>

namespace quadify::cli {
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

nlohmann::json to_json(const core::RepairReport& r) {
  return {{"input_vertices", r.input_vertices},
          {"input_faces", r.input_faces},
          {"polygons_triangulated", r.polygons_triangulated},
          {"invalid_faces_removed", r.invalid_faces_removed},
          {"welded_vertices", r.welded_vertices},
          {"degenerate_faces_removed", r.degenerate_faces_removed},
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

}  // namespace quadify::cli
