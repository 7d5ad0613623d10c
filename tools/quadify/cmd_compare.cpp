// quadify compare --inputs DIR --outputs NAME=DIR ... -o OUTDIR: the feature benchmark. For every
// input mesh and every tool folder, the tool's output of the same name is measured against the
// input (compute_quad_metrics: faces, valences, scaled Jacobian, angles, Hausdorff, feature
// capture, flips) and pictured with the input's sharp edges; writes compare.{md,csv,json} and
// index.html (+ img/*.svg) in OUTDIR, all at once (atomically), or nothing on bad input.
#include "commands.h"
#include "render_svg.h"

#include <libcore/atomic_file.h>
#include <libcore/read_mesh.h>
#include <libcore/repair.h>
#include <libcore/status.h>
#include <libquadex/quad_metrics.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#ifdef QUADIFY_WITH_TBB
#include <tbb/parallel_for.h>
#endif

namespace quadify::cli {
namespace {

namespace fs = std::filesystem;

constexpr int kPictureWidth = 480, kPictureHeight = 360;  // SVG size, pixels
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Output names tried for input `<stem>`, in order: the tool's own name, then quadify's bench
// layout (bench/run_bench.py writes `<stem>_quad.obj`).
constexpr const char* kOutputSuffixes[] = {"", "_quad", "_quads"};
// Readable formats in order of preference when one stem has several files.
constexpr core::MeshFormat kFormatOrder[] = {core::MeshFormat::kObj, core::MeshFormat::kOff, core::MeshFormat::kPly,
                                             core::MeshFormat::kStl, core::MeshFormat::kGlb, core::MeshFormat::kGltf};

struct CompareArgs {
  std::string inputs;
  std::vector<std::string> outputs;  // NAME=DIR
  std::string out_dir;
  std::vector<std::string> only;
  int samples = 100'000;
  double feature_angle = 40.0;
};

struct Model {
  std::string name;  // file stem
  fs::path path;
};

// Seconds of a peer's run from a results.tsv (see ../shared/peers/README.md).
struct PeerRun {
  double seconds = kNaN;
  std::string status;
};

struct Tool {
  std::string name;
  fs::path dir;
  std::map<std::string, std::vector<fs::path>> files;  // stem → readable mesh files, preferred first
  std::map<std::string, PeerRun> peer_runs;             // mesh → row of results.tsv
  fs::path peer_table;                                  // the results.tsv read, if any
};

struct Row {
  std::string status = "missing";  // ok | missing | error: <message>
  fs::path file;
  std::string note;  // e.g. the peer's status for a missing output
  quadex::QuadMetrics metrics;
  double seconds = kNaN;
  std::string seconds_source;
  std::string svg;
  bool ok() const { return status == "ok"; }
};

struct ModelResult {
  std::string input_error;
  int input_faces = 0;
  double diagonal = 0;
  int n_sharp = 0;
  double sharp_length = 0;  // × bbox diagonal
  std::string svg;
  std::vector<Row> rows;  // one per tool
};

int format_rank(core::MeshFormat format) {
  for (int i = 0; i < static_cast<int>(std::size(kFormatOrder)); ++i)
    if (kFormatOrder[i] == format) return i;
  return -1;
}

// Readable mesh files of a folder by stem, sorted by stem, each stem's files by kFormatOrder.
std::map<std::string, std::vector<fs::path>> mesh_files(const fs::path& dir) {
  std::map<std::string, std::vector<fs::path>> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    if (format_rank(core::format_from_extension(entry.path())) < 0) continue;
    files[entry.path().stem().string()].push_back(entry.path());
  }
  for (auto& [stem, paths] : files)
    std::sort(paths.begin(), paths.end(), [](const fs::path& a, const fs::path& b) {
      const int ra = format_rank(core::format_from_extension(a)), rb = format_rank(core::format_from_extension(b));
      return ra != rb ? ra < rb : a < b;
    });
  return files;
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, sep)) fields.push_back(field);
  if (!line.empty() && line.back() == sep) fields.emplace_back();
  return fields;
}

// Rows of a peers' results.tsv for this tool: `peer` equal to the tool's name or folder name (or
// every row when the table has no `peer` column). Unreadable or foreign tables give nothing.
std::map<std::string, PeerRun> read_peer_table(const fs::path& tsv, const std::set<std::string>& peer_names) {
  std::map<std::string, PeerRun> runs;
  std::ifstream in(tsv);
  std::string line;
  if (!in || !std::getline(in, line)) return runs;
  const std::vector<std::string> header = split(line, '\t');
  auto column = [&](const char* name) {
    const auto it = std::find(header.begin(), header.end(), name);
    return it == header.end() ? -1 : static_cast<int>(it - header.begin());
  };
  const int mesh_col = column("mesh"), peer_col = column("peer"), seconds_col = column("wall_s"),
            status_col = column("status");
  if (mesh_col < 0 || (seconds_col < 0 && status_col < 0)) return runs;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> f = split(line, '\t');
    auto field = [&](int c) { return c >= 0 && c < static_cast<int>(f.size()) ? f[c] : std::string(); };
    if (field(mesh_col).empty() || (peer_col >= 0 && !peer_names.count(field(peer_col)))) continue;
    PeerRun run;
    run.status = field(status_col);
    try {
      if (!field(seconds_col).empty()) run.seconds = std::stod(field(seconds_col));
    } catch (const std::exception&) {
      run.seconds = kNaN;
    }
    runs[field(mesh_col)] = run;
  }
  return runs;
}

// The run's seconds from a quadify JSON report: a top-level "seconds", else the sum of the
// "timings" stages without "measure" (the quality measures are not part of remeshing). Reports of
// `check` and `info` time measuring, not remeshing, and give nothing.
std::optional<double> report_seconds(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return std::nullopt;
  if (j.contains("seconds") && j["seconds"].is_number()) return j["seconds"].get<double>();
  const std::string command = j.value("command", std::string());
  if (command == "check" || command == "info" || !j.contains("timings") || !j["timings"].is_object())
    return std::nullopt;
  double seconds = 0;
  for (const auto& [stage, value] : j["timings"].items())
    if (stage != "measure" && value.is_number()) seconds += value.get<double>();
  return seconds;
}

// Seconds of the run that wrote `output` (input `stem`): `<stem>.json` or `<output stem>.json`
// beside it, or `reports/<stem>.json` beside its folder (the bench layout), else the peers' table.
void find_seconds(const Tool& tool, const std::string& stem, const fs::path& output, Row* row) {
  const fs::path dir = output.parent_path();
  for (const fs::path& candidate : {dir / (stem + ".json"), dir / (output.stem().string() + ".json"),
                                    dir.parent_path() / "reports" / (stem + ".json")}) {
    std::error_code ec;
    if (!fs::is_regular_file(candidate, ec)) continue;
    if (const auto seconds = report_seconds(candidate)) {
      row->seconds = *seconds;
      row->seconds_source = candidate.string();
      return;
    }
  }
  if (const auto it = tool.peer_runs.find(stem); it != tool.peer_runs.end() && std::isfinite(it->second.seconds)) {
    row->seconds = it->second.seconds;
    row->seconds_source = tool.peer_table.string();
  }
}

fs::path find_output(const Tool& tool, const std::string& stem) {
  for (const char* suffix : kOutputSuffixes)
    if (const auto it = tool.files.find(stem + suffix); it != tool.files.end()) return it->second.front();
  return {};
}

ModelResult compare_model(const Model& model, const std::vector<Tool>& tools, const CompareArgs& args) {
  ModelResult result;
  result.rows.resize(tools.size());
  core::TriMesh reference;
  try {
    const core::RepairResult repaired = core::repair_mesh(core::read_mesh(model.path));
    if (!repaired.status.is_ok()) throw core::InputError(model.path.string() + ": " + repaired.status.message());
    reference = repaired.mesh;
  } catch (const core::InputError& e) {
    result.input_error = e.what();
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    result.input_error = model.path.string() + ": " + e.what();
  }
  const Camera camera = camera_for_bbox(reference.V, kPictureWidth, kPictureHeight);
  SvgStyle style;
  if (result.input_error.empty()) {
    result.input_faces = reference.n_faces();
    result.diagonal = core::bbox_diagonal(reference.V);
    style.highlight = sharp_edges(reference, args.feature_angle);
    result.n_sharp = static_cast<int>(style.highlight.size());
    for (const auto& [a, b] : style.highlight) result.sharp_length += (b - a).norm();
    if (result.diagonal > 0) result.sharp_length /= result.diagonal;
    SvgStyle input_style = style;
    input_style.wireframe = false;
    input_style.tint_non_quads = false;
    result.svg = render_svg(core::to_poly(reference), camera, input_style);
  }

  quadex::QuadMetricsOptions options;
  options.hausdorff_samples = args.samples;
  options.feature_angle_deg = args.feature_angle;
  auto measure = [&](size_t t) {
    Row& row = result.rows[t];
    const Tool& tool = tools[t];
    row.file = find_output(tool, model.name);
    if (row.file.empty()) {
      if (const auto it = tool.peer_runs.find(model.name); it != tool.peer_runs.end() && it->second.status != "ok")
        row.note = it->second.status;
      return;
    }
    find_seconds(tool, model.name, row.file, &row);
    if (!result.input_error.empty()) {
      row.status = "error: input: " + result.input_error;
      return;
    }
    try {
      const core::PolyMesh quads = core::read_mesh(row.file);
      row.metrics = quadex::compute_quad_metrics(quads, &reference, options);
      row.svg = render_svg(quads, camera, style);
      row.status = "ok";
    } catch (const core::InputError& e) {
      row.status = std::string("error: ") + e.what();
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::exception& e) {  // one bad output must not end the whole benchmark
      row.status = "error: " + row.file.string() + ": " + e.what();
    }
  };
#ifdef QUADIFY_WITH_TBB
  tbb::parallel_for(size_t{0}, tools.size(), measure);
#else
  for (size_t t = 0; t < tools.size(); ++t) measure(t);
#endif
  return result;
}

// ---- formatting ------------------------------------------------------------------------------

std::string format(const char* spec, double x) {
  if (!std::isfinite(x)) return "";
  char text[64];
  std::snprintf(text, sizeof text, spec, x);
  return text;
}

// Per-model figures in the text outputs; each formatted once, so bold marks what a reader sees.
struct Cells {
  std::string seconds, faces, quads, non_quads, irregular, valences, sj_min, sj_mean, angle_mean, angle_max,
      hausdorff, mean_dist, capture, feature_hausdorff, flipped;
};

// "3:8 5:8": valence:count, by valence (without valence 4 when skip_regular).
std::string valence_text(const std::map<int, int>& histogram, bool skip_regular) {
  std::string text;
  for (auto [valence, count] : histogram) {
    if (skip_regular && valence == 4) continue;
    if (!text.empty()) text += ' ';
    text.append(std::to_string(valence)).append(":").append(std::to_string(count));
  }
  return text;
}

Cells cells(const Row& row) {
  Cells c;
  c.seconds = format("%.3g", row.seconds);
  if (!row.ok()) return c;
  const quadex::QuadMetrics& m = row.metrics;
  c.faces = std::to_string(m.n_faces);
  c.quads = std::to_string(m.n_faces - m.n_non_quads);
  c.non_quads = std::to_string(m.n_non_quads);
  c.irregular = std::to_string(m.n_irregular);
  c.valences = valence_text(m.valence_histogram, /*skip_regular=*/true);
  c.sj_min = format("%.3f", m.sj_min);
  c.sj_mean = format("%.3f", m.sj_mean);
  c.angle_mean = format("%.1f", m.angle_dev_mean);
  c.angle_max = format("%.1f", m.angle_dev_max);
  c.hausdorff = m.has_reference ? format("%.3g", m.hausdorff_sym) : "";
  c.mean_dist = m.has_reference ? format("%.3g", m.mean_dist_sym) : "";
  c.capture = m.feature_capture >= 0 ? format("%.3f", m.feature_capture) : "";
  c.feature_hausdorff = m.feature_hausdorff >= 0 ? format("%.3g", m.feature_hausdorff) : "";
  c.flipped = std::to_string(m.n_flipped);
  return c;
}

// Which rows of one model hold the best printed value of a column (ties all best); none when
// fewer than two tools have a value.
std::vector<bool> best(const std::vector<std::string>& values, bool lower_is_better) {
  std::vector<bool> is_best(values.size(), false);
  std::vector<double> parsed(values.size(), kNaN);
  int n = 0;
  for (size_t i = 0; i < values.size(); ++i)
    if (!values[i].empty()) {
      parsed[i] = std::stod(values[i]);
      ++n;
    }
  if (n < 2) return is_best;
  double target = lower_is_better ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  for (double x : parsed)
    if (std::isfinite(x)) target = lower_is_better ? std::min(target, x) : std::max(target, x);
  for (size_t i = 0; i < values.size(); ++i) is_best[i] = parsed[i] == target;
  return is_best;
}

struct Best {
  std::vector<bool> hausdorff, capture, flipped;
};

Best best_of(const std::vector<Cells>& c) {
  std::vector<std::string> h, fc, fl;
  for (const Cells& x : c) {
    h.push_back(x.hausdorff);
    fc.push_back(x.capture);
    fl.push_back(x.flipped);
  }
  return {best(h, true), best(fc, false), best(fl, true)};
}

std::string status_text(const Row& row) {
  return row.note.empty() ? row.status : row.status + " (" + row.note + ")";
}

std::string markdown_cell(std::string s) {
  for (size_t i = 0; (i = s.find('|', i)) != std::string::npos; i += 2) s.replace(i, 1, "\\|");
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s.empty() ? "–" : s;
}

std::string csv_cell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string html(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// A file name made of the characters that need no quoting anywhere.
std::string file_token(const std::string& s) {
  std::string out;
  for (unsigned char c : s) out += std::isalnum(c) || c == '-' || c == '.' ? static_cast<char>(c) : '_';
  return out;
}

std::string picture_path(const std::string& model, const std::string& tool) {
  return "img/" + file_token(model) + "__" + file_token(tool) + ".svg";
}

std::string bold_if(const std::string& s, bool bold, const char* open, const char* close) {
  return bold && !s.empty() ? open + s + close : s;
}

std::string markdown_table(const std::vector<Model>& models, const std::vector<Tool>& tools,
                           const std::vector<ModelResult>& results) {
  std::string md =
      "| model | tool | status | s | faces | quads | non-quads | irregular | valences ≠ 4 | SJ min | SJ mean | "
      "angle dev mean | angle dev max | Hausdorff | feature capture | feature Hausdorff | flipped |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < models.size(); ++i) {
    std::vector<Cells> c;
    for (const Row& row : results[i].rows) c.push_back(cells(row));
    const Best b = best_of(c);
    for (size_t t = 0; t < tools.size(); ++t) {
      const Cells& x = c[t];
      const std::vector<std::string> fields = {
          models[i].name, tools[t].name, status_text(results[i].rows[t]), x.seconds, x.faces, x.quads, x.non_quads,
          x.irregular, x.valences, x.sj_min, x.sj_mean, x.angle_mean, x.angle_max,
          bold_if(x.hausdorff, b.hausdorff[t], "**", "**"), bold_if(x.capture, b.capture[t], "**", "**"),
          x.feature_hausdorff, bold_if(x.flipped, b.flipped[t], "**", "**")};
      md += "|";
      for (const std::string& f : fields) md.append(" ").append(markdown_cell(f)).append(" |");
      md += "\n";
    }
  }
  return md;
}

std::string csv_table(const std::vector<Model>& models, const std::vector<Tool>& tools,
                      const std::vector<ModelResult>& results) {
  std::string csv =
      "model,tool,status,file,seconds,seconds_source,faces,quads,non_quads,irregular_vertices,valence_histogram,"
      "sj_min,sj_mean,angle_dev_mean,angle_dev_max,hausdorff_sym,mean_dist_sym,feature_capture,feature_hausdorff,"
      "flipped_quads,manifold,components\n";
  for (size_t i = 0; i < models.size(); ++i)
    for (size_t t = 0; t < tools.size(); ++t) {
      const Row& row = results[i].rows[t];
      const quadex::QuadMetrics& m = row.metrics;
      std::vector<std::string> f = {models[i].name, tools[t].name, status_text(row), row.file.string(),
                                    format("%.6g", row.seconds), row.seconds_source};
      if (row.ok()) {
        const std::string valences = valence_text(m.valence_histogram, /*skip_regular=*/false);
        f.insert(f.end(), {std::to_string(m.n_faces), std::to_string(m.n_faces - m.n_non_quads),
                           std::to_string(m.n_non_quads), std::to_string(m.n_irregular), valences,
                           format("%.6g", m.sj_min), format("%.6g", m.sj_mean), format("%.6g", m.angle_dev_mean),
                           format("%.6g", m.angle_dev_max), format("%.6g", m.hausdorff_sym),
                           format("%.6g", m.mean_dist_sym),
                           m.feature_capture >= 0 ? format("%.6g", m.feature_capture) : "",
                           m.feature_hausdorff >= 0 ? format("%.6g", m.feature_hausdorff) : "",
                           std::to_string(m.n_flipped), m.manifold ? "true" : "false", std::to_string(m.n_components)});
      } else {
        f.resize(f.size() + 16);
      }
      for (size_t k = 0; k < f.size(); ++k) csv.append(k ? "," : "").append(csv_cell(f[k]));
      csv += "\n";
    }
  return csv;
}

nlohmann::json row_json(const std::string& model, const std::string& tool, const Row& row) {
  nlohmann::json j;
  j["model"] = model;
  j["tool"] = tool;
  j["status"] = row.status;
  if (!row.note.empty()) j["note"] = row.note;
  j["file"] = row.file.empty() ? nlohmann::json(nullptr) : nlohmann::json(row.file.string());
  j["seconds"] = number(row.seconds);
  if (!row.seconds_source.empty()) j["seconds_source"] = row.seconds_source;
  if (!row.ok()) return j;
  const quadex::QuadMetrics& m = row.metrics;
  nlohmann::json degrees = nlohmann::json::object(), valences = nlohmann::json::object();
  for (auto [d, n] : m.faces_by_degree) degrees[std::to_string(d)] = n;
  for (auto [v, n] : m.valence_histogram) valences[std::to_string(v)] = n;
  j["picture"] = picture_path(model, tool);
  j["vertices"] = m.n_vertices;
  j["faces"] = m.n_faces;
  j["quads"] = m.n_faces - m.n_non_quads;
  j["non_quads"] = m.n_non_quads;
  j["faces_by_degree"] = degrees;
  j["irregular_vertices"] = m.n_irregular;
  j["valence_histogram"] = valences;
  j["degenerate_faces"] = m.n_degenerate;
  j["manifold"] = m.manifold;
  j["components"] = m.n_components;
  j["genus"] = m.genus;
  j["flipped_quads"] = m.n_flipped;
  j["sj_min"] = number(m.sj_min);
  j["sj_mean"] = number(m.sj_mean);
  j["angle_dev_mean"] = number(m.angle_dev_mean);
  j["angle_dev_max"] = number(m.angle_dev_max);
  j["edge_len_cv"] = number(m.edge_len_cv);
  j["hausdorff_sym"] = m.has_reference ? number(m.hausdorff_sym) : nlohmann::json(nullptr);
  j["mean_dist_sym"] = m.has_reference ? number(m.mean_dist_sym) : nlohmann::json(nullptr);
  j["feature_capture"] = m.feature_capture >= 0 ? number(m.feature_capture) : nlohmann::json(nullptr);
  j["feature_hausdorff"] = m.feature_hausdorff >= 0 ? number(m.feature_hausdorff) : nlohmann::json(nullptr);
  return j;
}

nlohmann::json json_report(const CompareArgs& args, const std::vector<Model>& models, const std::vector<Tool>& tools,
                           const std::vector<ModelResult>& results) {
  nlohmann::json report;
  report["command"] = "compare";
  report["quadify_version"] = QUADIFY_VERSION;
  report["inputs"] = args.inputs;
  report["feature_angle_deg"] = args.feature_angle;
  report["samples"] = args.samples;
  nlohmann::json tool_list = nlohmann::json::array();
  for (const Tool& tool : tools) tool_list.push_back({{"name", tool.name}, {"dir", tool.dir.string()}});
  report["tools"] = tool_list;
  nlohmann::json model_list = nlohmann::json::array(), rows = nlohmann::json::array();
  for (size_t i = 0; i < models.size(); ++i) {
    const ModelResult& r = results[i];
    nlohmann::json m = {{"model", models[i].name}, {"input", models[i].path.string()}};
    if (r.input_error.empty()) {
      m["faces"] = r.input_faces;
      m["bbox_diagonal"] = number(r.diagonal);
      m["sharp_edges"] = r.n_sharp;
      m["sharp_length"] = number(r.sharp_length);
      m["picture"] = picture_path(models[i].name, "input");
    } else {
      m["error"] = r.input_error;
    }
    model_list.push_back(m);
    for (size_t t = 0; t < tools.size(); ++t) rows.push_back(row_json(models[i].name, tools[t].name, r.rows[t]));
  }
  report["models"] = model_list;
  report["rows"] = rows;
  return report;
}

constexpr const char* kHtmlHead = R"(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>quadify compare</title>
<style>
body { font: 13px/1.35 sans-serif; margin: 16px; color: #1c2430; background: #fff; }
h1 { font-size: 20px; margin: 0 0 4px; } h2 { font-size: 16px; margin: 22px 0 6px; }
.legend span { display: inline-block; width: 12px; height: 12px; vertical-align: -2px; margin: 0 3px 0 10px; }
.row { display: flex; flex-wrap: wrap; gap: 10px; }
.card { display: flex; gap: 6px; border: 1px solid #d6dae0; border-radius: 4px; padding: 5px; background: #fafbfc; }
.card img, .card .none { width: 360px; height: 270px; }
.card .none { display: flex; align-items: center; justify-content: center; background: #eceef1; color: #8a93a0; }
.card.absent { background: #f1f2f4; align-self: flex-start; }
.figs { width: 190px; } .figs h3 { font-size: 14px; margin: 2px 0 4px; }
.figs table { border-collapse: collapse; } .figs td { padding: 0 4px 0 0; vertical-align: top; }
.figs td:first-child { color: #5b6573; white-space: nowrap; } .err { color: #b3261e; word-break: break-all; }
</style></head><body>
)";

std::string figure_rows(const std::vector<std::pair<std::string, std::string>>& figures) {
  std::string out = "<table>";
  for (const auto& [name, value] : figures)
    if (!value.empty()) out += "<tr><td>" + name + "</td><td>" + value + "</td></tr>";
  return out + "</table>";
}

std::string html_index(const CompareArgs& args, const std::vector<Model>& models, const std::vector<Tool>& tools,
                       const std::vector<ModelResult>& results) {
  std::string page = kHtmlHead;
  page += "<h1>quadify compare</h1>\n<p>Inputs <code>" + html(args.inputs) + "</code>; tools:";
  for (const Tool& tool : tools) page += " <b>" + html(tool.name) + "</b> <code>" + html(tool.dir.string()) + "</code>";
  page += ". Tables: <a href=\"compare.md\">compare.md</a>, <a href=\"compare.csv\">compare.csv</a>, "
          "<a href=\"compare.json\">compare.json</a>.</p>\n<p class=\"legend\">Distances are fractions of the input's "
          "bounding-box diagonal; best per model in bold.<span style=\"background:#ff1f1f\"></span>input sharp edges "
          "(dihedral &gt; " + format("%g", args.feature_angle) + "°)<span style=\"background:#f5d66b\"></span>non-quad "
          "faces<span style=\"background:#9e8070\"></span>faces seen from behind (open or flipped surfaces)</p>\n";
  for (size_t i = 0; i < models.size(); ++i) {
    const ModelResult& r = results[i];
    page += "<h2 id=\"" + html(file_token(models[i].name)) + "\">" + html(models[i].name) + "</h2>\n<div class=\"row\">\n";
    page += "<div class=\"card\">";
    if (r.input_error.empty())
      page += "<a href=\"" + picture_path(models[i].name, "input") + "\"><img src=\"" +
              picture_path(models[i].name, "input") + "\" alt=\"input " + html(models[i].name) + "\"></a>";
    else
      page += "<div class=\"none\">unreadable</div>";
    page += "<div class=\"figs\"><h3>input</h3>";
    if (r.input_error.empty())
      page += figure_rows({{"triangles", std::to_string(r.input_faces)},
                           {"sharp edges", std::to_string(r.n_sharp)},
                           {"sharp length", format("%.3g", r.sharp_length) + " diag"}});
    else
      page += "<p class=\"err\">" + html(r.input_error) + "</p>";
    page += "</div></div>\n";

    std::vector<Cells> c;
    for (const Row& row : r.rows) c.push_back(cells(row));
    const Best b = best_of(c);
    for (size_t t = 0; t < tools.size(); ++t) {
      const Row& row = r.rows[t];
      const Cells& x = c[t];
      const std::string picture = picture_path(models[i].name, tools[t].name);
      page += row.ok() ? "<div class=\"card\">" : "<div class=\"card absent\">";
      if (row.ok())
        page += "<a href=\"" + picture + "\"><img src=\"" + picture + "\" alt=\"" + html(tools[t].name) + " " +
                html(models[i].name) + "\"></a>";
      page += "<div class=\"figs\"><h3>" + html(tools[t].name) + "</h3>";
      if (row.ok()) {
        page += figure_rows({{"seconds", x.seconds},
                             {"faces", x.faces},
                             {"non-quads", x.non_quads},
                             {"irregular", x.irregular},
                             {"valences", x.valences},
                             {"SJ min", x.sj_min},
                             {"SJ mean", x.sj_mean},
                             {"angle dev", x.angle_mean + "° / " + x.angle_max + "°"},
                             {"Hausdorff", bold_if(x.hausdorff, b.hausdorff[t], "<b>", "</b>")},
                             {"feature capt.", bold_if(x.capture, b.capture[t], "<b>", "</b>")},
                             {"feature Hd.", x.feature_hausdorff},
                             {"flipped", bold_if(x.flipped, b.flipped[t], "<b>", "</b>")}});
      } else {
        page += "<p class=\"err\">" + html(status_text(row)) + "</p>";
      }
      page += "</div></div>\n";
    }
    page += "</div>\n";
  }
  page += "</body></html>\n";
  return page;
}

// ---- the command -----------------------------------------------------------------------------

std::vector<Tool> parse_tools(const std::vector<std::string>& specs) {
  std::vector<Tool> tools;
  std::set<std::string> names;
  for (const std::string& spec : specs) {
    const size_t eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
      throw CliError{kExitBadInput, "--outputs '" + spec + "': expected NAME=DIR (e.g. quadriflow=peers/quadriflow)"};
    Tool tool;
    tool.name = spec.substr(0, eq);
    tool.dir = spec.substr(eq + 1);
    if (file_token(tool.name) != tool.name)
      throw CliError{kExitBadInput, "--outputs " + spec + ": NAME may hold only letters, digits, '-', '_' and '.'"};
    if (!names.insert(tool.name).second)
      throw CliError{kExitBadInput, "--outputs " + spec + ": the name '" + tool.name + "' is given twice"};
    std::error_code ec;
    if (!fs::is_directory(tool.dir, ec))
      throw CliError{kExitBadInput, "--outputs " + spec + ": " + tool.dir.string() +
                                        (fs::exists(tool.dir, ec) ? " is not a directory" : " does not exist")};
    tool.files = mesh_files(tool.dir);
    const fs::path canonical = fs::weakly_canonical(tool.dir, ec);
    const fs::path folder = ec ? tool.dir.lexically_normal() : canonical;
    for (const fs::path& tsv : {folder / "results.tsv", folder.parent_path() / "results.tsv"}) {
      if (!fs::is_regular_file(tsv, ec)) continue;
      tool.peer_runs = read_peer_table(tsv, {tool.name, folder.filename().string()});
      if (!tool.peer_runs.empty()) {
        tool.peer_table = tsv;
        break;
      }
    }
    tools.push_back(std::move(tool));
  }
  return tools;
}

std::vector<Model> find_models(const CompareArgs& args, bool quiet) {
  const fs::path dir = args.inputs;
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw CliError{kExitBadInput,
                   "--inputs " + dir.string() + (fs::exists(dir, ec) ? ": not a directory" : ": no such directory")};
  std::vector<Model> models;
  for (const auto& [stem, paths] : mesh_files(dir)) {
    if (paths.size() > 1 && !quiet)
      std::fprintf(stderr, "quadify: compare: %s: several inputs named %s, using %s\n", dir.string().c_str(),
                   stem.c_str(), paths.front().filename().string().c_str());
    models.push_back({stem, paths.front()});
  }
  if (models.empty())
    throw CliError{kExitBadInput, "--inputs " + dir.string() + ": no meshes (.obj .off .ply .stl .gltf .glb)"};
  if (!args.only.empty()) {
    std::vector<Model> chosen;
    for (const std::string& name : args.only) {
      const auto it = std::find_if(models.begin(), models.end(), [&](const Model& m) { return m.name == name; });
      if (it == models.end())
        throw CliError{kExitBadInput, "--only " + name + ": no mesh of that name in " + dir.string()};
      if (std::none_of(chosen.begin(), chosen.end(), [&](const Model& m) { return m.name == name; }))
        chosen.push_back(*it);
    }
    std::sort(chosen.begin(), chosen.end(), [](const Model& a, const Model& b) { return a.name < b.name; });
    models = std::move(chosen);
  }
  return models;
}

int run_compare(const CompareArgs& args, const CommonOptions& common) {
  std::vector<Model> models = find_models(args, common.quiet);
  const std::vector<Tool> tools = parse_tools(args.outputs);
  const fs::path out_dir = args.out_dir;
  std::error_code ec;
  if (fs::exists(out_dir, ec) && !fs::is_directory(out_dir, ec))
    throw CliError{kExitBadInput, "-o " + out_dir.string() + ": exists and is not a directory"};

  std::vector<ModelResult> results(models.size());
  std::mutex progress_mutex;
  int n_done = 0;
  auto run_model = [&](size_t i) {
    const auto start = std::chrono::steady_clock::now();
    results[i] = compare_model(models[i], tools, args);
    if (common.quiet) return;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    int n_ok = 0, n_missing = 0;
    for (const Row& row : results[i].rows) {
      n_ok += row.ok();
      n_missing += row.status == "missing";
    }
    std::lock_guard lock(progress_mutex);
    ++n_done;
    std::fprintf(stderr, "quadify: compare %s: %d measured, %d missing, %d errors in %.1f s (%d/%zu)\n",
                 models[i].name.c_str(), n_ok, n_missing, static_cast<int>(tools.size()) - n_ok - n_missing, seconds,
                 n_done, models.size());
  };
#ifdef QUADIFY_WITH_TBB
  tbb::parallel_for(size_t{0}, models.size(), run_model);
#else
  for (size_t i = 0; i < models.size(); ++i) run_model(i);
#endif

  std::vector<core::AtomicFilePart> parts;
  auto add_part = [&](const fs::path& path, std::string text) {
    auto shared = std::make_shared<std::string>(std::move(text));
    parts.push_back({path, [shared](std::ostream& out) { out << *shared; }});
  };
  add_part(out_dir / "compare.md", markdown_table(models, tools, results));
  add_part(out_dir / "compare.csv", csv_table(models, tools, results));
  add_part(out_dir / "compare.json", json_report(args, models, tools, results).dump(1) + "\n");
  add_part(out_dir / "index.html", html_index(args, models, tools, results));
  for (size_t i = 0; i < models.size(); ++i) {
    if (!results[i].svg.empty()) add_part(out_dir / picture_path(models[i].name, "input"), std::move(results[i].svg));
    for (size_t t = 0; t < tools.size(); ++t)
      if (results[i].rows[t].ok())
        add_part(out_dir / picture_path(models[i].name, tools[t].name), std::move(results[i].rows[t].svg));
  }
  fs::create_directories(out_dir / "img", ec);
  if (ec) throw core::OutputError(out_dir.string() + ": cannot create the folder (" + ec.message() + ")");
  core::write_files_atomically(parts);
  if (!common.quiet) std::fprintf(stderr, "quadify: compare: wrote %s\n", (out_dir / "index.html").string().c_str());
  return kExitOk;
}

}  // namespace

CommandRunner register_compare(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  app.add_option("--inputs", args->inputs,
                 "Folder of input triangle meshes (OBJ, OFF, PLY, STL, glTF, GLB); the file stem names the model")
      ->required()
      ->type_name("DIR");
  app.add_option("--outputs", args->outputs,
                 "A tool's output folder, as NAME=DIR; repeat for each tool. The output of model <stem> is "
                 "<stem>.<ext> (or <stem>_quad.<ext>) in DIR, any readable format; seconds come from a quadify "
                 "report <stem>.json beside it (or in ../reports/), else from a results.tsv in DIR or its parent "
                 "(row with peer = NAME or the folder name)")
      ->required()
      ->type_name("NAME=DIR");
  app.add_option("-o,--output", args->out_dir,
                 "Folder to write compare.md, compare.csv, compare.json, index.html and img/*.svg into (created "
                 "if missing; files are replaced atomically)")
      ->required()
      ->type_name("OUTDIR");
  app.add_option("--only", args->only, "Compare only these models (stems), comma-separated")
      ->delimiter(',')
      ->type_name("a,b");
  app.add_option("--samples", args->samples, "Area samples per surface for the Hausdorff distances")
      ->check(CLI::Range(1000, 10'000'000))
      ->capture_default_str();
  app.add_option("--feature-angle", args->feature_angle,
                 "Dihedral angle (degrees) above which an input edge is sharp: feature capture and the red "
                 "edges of the pictures")
      ->check(CLI::Range(0.0, 180.0))
      ->capture_default_str();
  app.footer(
      "Measures every tool's output against its input (faces, valences, scaled Jacobian, angle deviation, "
      "symmetric Hausdorff and feature capture as fractions of the input's bbox diagonal, flipped quads) and "
      "pictures each with the input's sharp edges in red from one camera per model. A missing output is "
      "listed as missing, an unreadable one as \"error: <message>\"; both leave the exit code 0.");
  return [args](const CommonOptions& common) { return run_compare(*args, common); };
}

}  // namespace quadify::cli
