// Method (Levi 2021, Def. 3.2; greedy rounding in the spirit of mixed-integer quadrangulation):
// 1. Scale. Each unit square of the scaled map is one quad, so s = sqrt(target / UV area). With
//    an edge length h instead, s = sqrt(3D area / UV area) / h (the map is isometric up to a global
//    factor). The rest shapes of the energy are scaled along, so the optimizer keeps this scale.
// 2. Unknowns. Vertex copies are the corners merged across edges where both sides agree
//    (param::build_copy_layout). The integer candidates are both coordinates of every cone copy
//    and both components of every seam translation t = x_b0 − R^r x_a0. The translation gauge
//    fixes one copy per component (a cone copy when there is one) at the origin. Candidates are
//    turned into affine rows "candidate = integer" and fed to libparam's exact incremental
//    eliminator together with the homogeneous seam rows: a row dependent on earlier ones is an
//    integer combination of integer rows (unit pivots, 0/±1 coefficients) and is dropped.
// 3. Rounding. Cone copies first (a cone fixed only through the translations around it may sit
//    on a half-integer, see Rounder::run), then translations, each in batches by rounding error
//    (below 1/8, 2/8, …; the last batch takes the rest; smallest error first). A cone goes to the
//    nearest corner of its grid cell not yet taken by another cone vertex of its chart. After
//    each batch the layout is moved flip-free into the new constraint space and re-optimized
//    (param::solve_constrained_layout: penalty homotopy + projection + barrier Newton). A batch
//    that leaves flips (a triangle degenerated, e.g. two cones on one grid point) or makes a
//    fully determined unknown fractional (wrong parity) is reverted and split in halves; a single
//    failing unknown is rounded to the other neighbouring integer. Parity is checked before any
//    solve by the elimination alone (see Rounder::repair_parity); a run that dead-ends because
//    both neighbours of an unknown imply a fractional cone restarts with those cones first.
//    If that fails too, or after 16 failed re-optimizations, the rounding restarts at nearby
//    scales (×1 ± 2%, ±4%), then at scales grown by ×1.25 (max_scale_retries times).
// 4. Exactness. The free variables y are rounded to multiples of 2^-30 and x = P·y + c is
//    evaluated with P, c dyadic (integers, or halves where a pivot of 2 was unavoidable): every
//    term and partial sum is a multiple of 2^-38 far below 2^53 ulps, so the evaluation is exact
//    and the transitions and cones are exact integers. This is verified (kInternal otherwise), and
//    flips are counted with the exact orientation predicate.
#include <libcore/predicates.h>
#include <libparam/constrained_layout.h>
#include <libquantize/quantize.h>

#include <Eigen/Geometry>

#ifdef QUADIFY_WITH_TBB
#include <tbb/task_arena.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <limits>
#include <tuple>

namespace quadify::quantize {
namespace {

using Clock = std::chrono::steady_clock;

// Default density: one quad per this many triangles, and at least kMinDefaultQuads quads.
constexpr int kDefaultTrianglesPerQuad = 6;
constexpr int kMinDefaultQuads = 100;
// Free variables are rounded to multiples of 2^-kDyadicBits UV units (a quad is 1 unit), far
// below any triangle's size, so the rounding cannot flip a triangle in practice (checked).
constexpr int kDyadicBits = 30;
// The elimination pivots on unit coefficients where it can; a translation row through two seams
// with matching 2 can leave a pivot of 2, so P and c are dyadic with small denominators. Up to
// 2^-kMaxDenominatorBits, the products with y (multiples of 2^-kDyadicBits) stay exact.
constexpr int kMaxDenominatorBits = 8;
// An implied (fully determined) candidate farther than this from an integer is fractional; exact
// implied values are multiples of 1/4 (the determinant of I − R^r is 2 or 4), so 1/8 separates
// them from round-off.
constexpr double kParityTolerance = 0.125;
// Failed re-optimizations (each a full penalty homotopy) tolerated at one scale before the scale
// is refined: bounds the time spent on cones too close to be separated at this density.
constexpr int kMaxFailedSolvesPerScale = 16;
// Floor of recommended_cone_pair_distance, in mean edge lengths of the input.
constexpr double kConePairMeshEdges = 8;
// Restarts at one scale with the cones that a run found doomed by parity rounded first.
constexpr int kMaxPriorityRestarts = 4;
// Sweeps over a batch of the parity repair (each tries every item's other neighbour once).
constexpr int kParityRepairPasses = 3;
// Newton iterations per stage of the long penalty homotopy used for a single failing unknown.
constexpr int kSingleHomotopyIterations = 40;
// Relative Newton tolerance of the intermediate and final re-optimizations.
constexpr double kBatchTolerance = 1e-4;
constexpr double kFinalTolerance = 1e-7;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// An integer candidate: one scalar variable (a cone-copy coordinate or a seam translation).
struct Candidate {
  std::vector<std::pair<int, double>> form;
  bool is_cone = false;  // a cone-copy coordinate (else a seam translation)
  int copy = -1;         // the cone copy
  int coord = 0;         // its coordinate (0: u, 1: v)
  double value(const Eigen::VectorXd& x) const {
    double v = 0;
    for (const auto& [var, a] : form) v += a * x[var];
    return v;
  }
};

// Entry (d, j) of R_90^r.
int rotation_entry(int r, int d, int j) {
  static constexpr int kR[4][2][2] = {
      {{1, 0}, {0, 1}}, {{0, -1}, {1, 0}}, {{-1, 0}, {0, -1}}, {{0, 1}, {-1, 0}}};
  return kR[((r % 4) + 4) % 4][d][j];
}

// 3D surface area of the mesh.
double surface_area(const core::TriMesh& mesh) {
  double area = 0;
  for (int f = 0; f < mesh.n_faces(); ++f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0));
    area += 0.5 * (Eigen::Vector3d(mesh.V.row(mesh.F(f, 1))) - p0)
                      .cross(Eigen::Vector3d(mesh.V.row(mesh.F(f, 2))) - p0)
                      .norm();
  }
  return area;
}

// The quad count used when neither target_faces nor edge_length is given.
int default_target_faces(const core::TriMesh& mesh) {
  return std::max(kMinDefaultQuads, mesh.n_faces() / kDefaultTrianglesPerQuad);
}

double uv_area(const param::CopyLayout& cl, const Eigen::VectorXd& x, int nf) {
  double a = 0;
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector2d p0 = x.segment<2>(2 * cl.corner_copy[3 * f]),
                          p1 = x.segment<2>(2 * cl.corner_copy[3 * f + 1]),
                          p2 = x.segment<2>(2 * cl.corner_copy[3 * f + 2]);
    const Eigen::Vector2d e1 = p1 - p0, e2 = p2 - p0;
    a += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
  }
  return a;
}

int count_flipped(const param::CopyLayout& cl, const Eigen::VectorXd& x, int nf) {
  int n = 0;
  for (int f = 0; f < nf; ++f)
    if (core::orient2d(x.segment<2>(2 * cl.corner_copy[3 * f]),
                       x.segment<2>(2 * cl.corner_copy[3 * f + 1]),
                       x.segment<2>(2 * cl.corner_copy[3 * f + 2])) <= 0)
      ++n;
  return n;
}

// The state of one rounding run at a fixed scale.
class Rounder {
 public:
  // One integer candidate set to rhs.
  struct Item {
    int candidate;
    double rhs;
    double value;  // before rounding
  };

  Rounder(const core::TriMesh& mesh, const param::CopyLayout& cl,
          const std::vector<Candidate>& candidates, const std::vector<char>& is_cone_copy,
          const param::ConstrainedLayoutOptions& layout_options, QuantizeStats* stats)
      : mesh_(mesh),
        cl_(cl),
        cand_(candidates),
        is_cone_copy_(is_cone_copy),
        lopt_(layout_options),
        stats_(stats),
        priority_(candidates.size(), 0) {}

  // Rounds every candidate starting from x (satisfying the seam rows); false when stuck.
  bool run(Eigen::VectorXd x, double threshold_step,
           const std::function<void(const std::string&, int, int)>& progress) {
    x_ = std::move(x);
    decided_.assign(cand_.size(), 0);
    rows_.clear();
    const int n_steps = std::max(1, static_cast<int>(std::ceil(0.5 / threshold_step - 1e-9)));
    // Cones first: a cone's position is fixed by the translations around it through (I − R^r),
    // whose determinant is 2 or 4, so integer translations alone may put it on a half-integer.
    // Fixing the cones first makes the translations integer combinations of the cone integers.
    for (const bool cone_phase : {true, false})
      for (int step = 0; step < n_steps; ++step) {
        if (progress) progress("quantize", step + (cone_phase ? 0 : n_steps), 2 * n_steps);
        const bool last = step + 1 == n_steps;
        const double eps = threshold_step * (step + 1);
        std::vector<Item> items = cone_phase ? cone_batch(eps, last) : translation_batch(eps, last);
        if (items.empty()) continue;
        if (!process(items, last && !cone_phase)) return false;
      }
    // A final solve without new rows converges the layout further.
    lopt_.relative_tolerance = kFinalTolerance;
    param::ConstrainedLayoutResult res =
        param::solve_constrained_layout(mesh_, cl_, x_, rows_, {}, lopt_);
    stats_->n_iterations += res.iterations;
    if (!res.status.is_ok() || res.n_flipped > 0) return false;
    x_ = res.x;
    reduction_ = std::move(res.reduction);
    return true;
  }

  const Eigen::VectorXd& x() const { return x_; }
  const std::vector<int>& doomed() const { return doomed_; }
  void set_priority(const std::vector<char>& priority) { priority_ = priority; }

  // Translations with rounding error below eps (all when last), smallest error first.
  std::vector<Item> translation_batch(double eps, bool last) const {
    std::vector<std::pair<double, int>> batch;  // (error, candidate)
    for (size_t i = 0; i < cand_.size(); ++i) {
      if (decided_[i] || cand_[i].is_cone) continue;
      const double v = cand_[i].value(x_);
      const double err = std::abs(v - std::round(v));
      if (last || err < eps) batch.push_back({err, static_cast<int>(i)});
    }
    std::sort(batch.begin(), batch.end());
    std::vector<Item> items;
    for (const auto& [err, i] : batch) {
      const double v = cand_[i].value(x_);
      items.push_back({i, std::round(v), v});
    }
    return items;
  }

  // Cone copies whose distance (max norm) to the nearest integer point is below eps (all when
  // last), nearest first. Each goes to the nearest corner of its grid cell that no other cone
  // vertex of its component occupies yet (in the cut layout), so that nearby cones do not
  // collapse onto one grid point.
  std::vector<Item> cone_batch(double eps, bool last) const {
    std::map<std::tuple<int, long long, long long>, int> occupied;  // (component, u, v) → vertex
    std::vector<std::pair<double, int>> batch;  // (error, u candidate of the copy)
    for (size_t i = 0; i < cand_.size(); ++i) {
      if (!cand_[i].is_cone || cand_[i].coord != 0) continue;
      const int k = cand_[i].copy;
      const double pu = x_[2 * k], pv = x_[2 * k + 1];
      if (decided_[i] && decided_[i + 1]) {
        occupied[{cl_.copy_component[k], std::llround(pu), std::llround(pv)}] = cl_.copy_vertex[k];
        continue;
      }
      // Priority cones (those a previous run at this scale found doomed) go first, in the first
      // batch, so that the later roundings can still be moved to fix their parity.
      const double err = priority_[i]
                             ? -1.0
                             : std::max(std::abs(pu - std::round(pu)), std::abs(pv - std::round(pv)));
      if (last || err < eps) batch.push_back({err, static_cast<int>(i)});
    }
    std::sort(batch.begin(), batch.end());
    std::vector<Item> items;
    for (const auto& [err, i] : batch) {
      const int k = cand_[i].copy, comp = cl_.copy_component[k], vertex = cl_.copy_vertex[k];
      const double pu = x_[2 * k], pv = x_[2 * k + 1];
      std::vector<std::pair<double, std::pair<double, double>>> corners;
      for (const double gu : {std::floor(pu), std::ceil(pu)})
        for (const double gv : {std::floor(pv), std::ceil(pv)})
          corners.push_back({std::hypot(gu - pu, gv - pv), {gu, gv}});
      std::sort(corners.begin(), corners.end());
      std::pair<double, double> pick = corners[0].second;
      for (const auto& [dist, g] : corners) {
        const auto it = occupied.find({comp, std::llround(g.first), std::llround(g.second)});
        if (it == occupied.end() || it->second == vertex) {
          pick = g;
          break;
        }
      }
      occupied[{comp, std::llround(pick.first), std::llround(pick.second)}] = vertex;
      if (!decided_[i]) items.push_back({i, pick.first, pu});
      if (!decided_[i + 1]) items.push_back({i + 1, pick.second, pv});
    }
    return items;
  }
  const param::ConstrainedReduction& reduction() const { return reduction_; }
  int n_rows() const { return static_cast<int>(rows_.size()); }

 private:
  param::AffineRow row_of(const Item& it) const {
    param::AffineRow row;
    row.entries = cand_[it.candidate].form;
    row.rhs = it.rhs;
    return row;
  }

  // Candidates that `items` (on top of the committed rows) would imply fractional: an
  // elimination only, no solve.
  std::vector<int> offenders_of(const std::vector<Item>& items) const {
    std::vector<param::AffineRow> new_rows;
    for (const Item& it : items) new_rows.push_back(row_of(it));
    param::ConstrainedLayoutOptions reduce = lopt_;
    reduce.reduce_only = true;
    const param::ConstrainedLayoutResult res =
        param::solve_constrained_layout(mesh_, cl_, x_, rows_, new_rows, reduce);
    std::vector<int> offenders = implied_fractional(res.reduction, items);
    return offenders;
  }

  // Parity repair before any solve: while the batch implies fractional candidates, move single
  // roundings to their other neighbouring integer when that lowers the number of offenders
  // (changing one coordinate of a ±1 cone by one flips the parity of (I − R)·x). Returns the
  // offenders left (empty when the batch is parity-clean).
  std::vector<int> repair_parity(std::vector<Item>* items) const {
    std::vector<int> offenders = offenders_of(*items);
    for (int pass = 0; pass < kParityRepairPasses && !offenders.empty(); ++pass) {
      bool improved = false;
      for (size_t i = 0; i < items->size() && !offenders.empty(); ++i) {
        Item& it = (*items)[i];
        const double kept = it.rhs;
        it.rhs = it.value < kept ? kept - 1 : kept + 1;
        std::vector<int> trial = offenders_of(*items);
        if (trial.size() < offenders.size()) {
          offenders = std::move(trial);
          improved = true;
        } else {
          it.rhs = kept;
        }
      }
      if (!improved) break;
    }
    return offenders;
  }

  bool try_items(std::vector<Item> items) {
    last_offenders_ = repair_parity(&items);
    if (!last_offenders_.empty()) {
      ++n_failed_;
      return false;
    }
    std::vector<param::AffineRow> new_rows;
    for (const Item& it : items) new_rows.push_back(row_of(it));
    param::ConstrainedLayoutResult res =
        param::solve_constrained_layout(mesh_, cl_, x_, rows_, new_rows, lopt_);
    stats_->n_iterations += res.iterations;
    if (res.status.is_ok() && res.n_flipped == 0) {
      for (size_t i = 0; i < items.size(); ++i) {
        decided_[items[i].candidate] = 1;
        if (res.independent[i]) rows_.push_back(new_rows[i]);
      }
      x_ = res.x;
      ++stats_->n_batches;
      return true;
    }
    ++n_failed_;
    if (res.status.code() == core::StatusCode::kNumericalFailure ||
        res.status.code() == core::StatusCode::kInvalidInput)
      hard_failure_ = res.status;
    // Two cones of one face at the same point: a cone collision.
    for (int f = 0; f < mesh_.n_faces() && res.x.size() == x_.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = cl_.corner_copy[3 * f + k], b = cl_.corner_copy[3 * f + (k + 1) % 3];
        if (is_cone_copy_[a] && is_cone_copy_[b] &&
            res.x.segment<2>(2 * a) == res.x.segment<2>(2 * b)) {
          ++stats_->n_cone_collisions;
          f = mesh_.n_faces();
          break;
        }
      }
    return false;
  }

  // Candidates that the constraints now determine completely (an empty row of P) must come out
  // as integers. A cone fixed through (I − R^r) by other integers can land on a half-integer:
  // returns those (undecided) candidates; process() then rounds them first, from the current
  // layout, so that the other roundings cannot force them onto the wrong parity.
  std::vector<int> implied_fractional(const param::ConstrainedReduction& red,
                                      const std::vector<Item>& items) const {
    // Items are checked too: an item whose row depends on earlier rows is dropped by the
    // elimination, and its implied value need not be its rounding.
    // Pairs are checked as well: two undecided candidates with the same free part (P rows equal
    // up to sign) and offsets that differ by a non-integer (a ± b = ½, typical of a ±1 cone and a
    // translation through I − R) can never both be integers, which a greedy order would only see
    // once one of them is fixed, too late to repair.
    std::vector<int> offenders;
    std::vector<double> rhs(cand_.size(), std::numeric_limits<double>::quiet_NaN());
    for (const Item& it : items) rhs[it.candidate] = it.rhs;
    std::map<std::vector<std::pair<int, double>>, std::pair<int, double>> free_part;
    for (size_t i = 0; i < cand_.size(); ++i) {
      if (decided_[i]) continue;
      const int v = cand_[i].form[0].first;
      if (red.P.row(v).nonZeros() != 0) {
        std::vector<std::pair<int, double>> key;
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, v); it; ++it)
          key.push_back({static_cast<int>(it.col()), it.value()});
        const double sign = key.front().second < 0 ? -1 : 1;
        for (auto& [col, a] : key) a *= sign;
        const double offset = sign * red.c[v];
        const auto [pos, inserted] = free_part.try_emplace(key, static_cast<int>(i), offset);
        const double diff = offset - pos->second.second;
        if (!inserted && std::abs(diff - std::round(diff)) > kParityTolerance)
          offenders.push_back(static_cast<int>(i));
        continue;
      }
      if (std::abs(red.c[v] - std::round(red.c[v])) > kParityTolerance ||
          (!std::isnan(rhs[i]) && std::abs(red.c[v] - rhs[i]) > kParityTolerance))
        offenders.push_back(static_cast<int>(i));
    }
    return offenders;
  }

  // Commits the items, splitting the batch on failure.
  bool process(const std::vector<Item>& items, bool final_batch) {
    lopt_.relative_tolerance = final_batch ? kFinalTolerance : kBatchTolerance;
    if (items.empty() || try_items(items)) return true;
    if (!hard_failure_.is_ok() || n_failed_ >= kMaxFailedSolvesPerScale) return false;
    ++stats_->n_reverted;
    if (items.size() > 1) {
      const size_t half = items.size() / 2;
      return process({items.begin(), items.begin() + half}, final_batch) &&
             process(refresh({items.begin() + half, items.end()}), final_batch);
    }
    // A single unknown: the same integer with a longer homotopy, then the other neighbour.
    lopt_.homotopy_iterations = kSingleHomotopyIterations;
    Item other = items[0];
    other.rhs = other.value < other.rhs ? other.rhs - 1 : other.rhs + 1;
    bool ok = try_items(items);
    std::vector<int> offenders = last_offenders_;
    if (!ok) {
      ok = try_items({other});
      // Both neighbours imply fractional candidates: the committed roundings already doom them.
      if (!ok && !offenders.empty() && !last_offenders_.empty()) {
        offenders.insert(offenders.end(), last_offenders_.begin(), last_offenders_.end());
        for (const int o : offenders)
          if (cand_[o].is_cone) doomed_.push_back(o - cand_[o].coord);
      }
    }
    lopt_.homotopy_iterations = 0;
    return ok;
  }

  // Re-rounds items from the current layout (after part of their batch was committed).
  std::vector<Item> refresh(std::vector<Item> items) const {
    for (Item& it : items) {
      it.value = cand_[it.candidate].value(x_);
      it.rhs = std::round(it.value);
    }
    return items;
  }

 public:
  core::Status hard_failure_;

 private:
  const core::TriMesh& mesh_;
  const param::CopyLayout& cl_;
  const std::vector<Candidate>& cand_;
  const std::vector<char>& is_cone_copy_;
  param::ConstrainedLayoutOptions lopt_;
  QuantizeStats* stats_;
  Eigen::VectorXd x_;
  std::vector<char> decided_;
  int n_failed_ = 0;  // failed re-optimizations at this scale
  std::vector<int> last_offenders_;  // of the last try_items that failed its parity repair
  std::vector<int> doomed_;          // u candidates of cone copies found doomed by parity
  std::vector<char> priority_;       // per candidate (u candidate of a cone copy): round first
  std::vector<param::AffineRow> rows_;
  param::ConstrainedReduction reduction_;
};

// Whether a is a multiple of 2^-kMaxDenominatorBits (exactly).
bool dyadic(double a) {
  const double scaled = std::ldexp(a, kMaxDenominatorBits);
  return scaled == std::round(scaled);
}

// x = P·y + c with y rounded to the dyadic grid; false if P or c is not dyadic.
bool exact_expand(const param::ConstrainedReduction& red, const Eigen::VectorXd& x,
                  Eigen::VectorXd* out, std::string* why) {
  const double unit = std::ldexp(1.0, -kDyadicBits);
  const int nf = static_cast<int>(red.free_vars.size());
  Eigen::VectorXd y(nf);
  for (int j = 0; j < nf; ++j) y[j] = std::round(x[red.free_vars[j]] / unit) * unit;
  out->resize(red.P.rows());
  for (int v = 0; v < red.P.rows(); ++v) {
    if (!dyadic(red.c[v])) {
      *why = "offset of variable " + std::to_string(v) + " is " + std::to_string(red.c[v]);
      return false;
    }
    double s = red.c[v];
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, v); it; ++it) {
      if (!dyadic(it.value())) {
        *why = "coefficient (" + std::to_string(v) + ", " + std::to_string(it.col()) + ") is " +
               std::to_string(it.value());
        return false;
      }
      s += it.value() * y[it.col()];
    }
    (*out)[v] = s;
  }
  return true;
}

QuantizeResult run(const core::TriMesh& mesh, const param::ParamResult& seamless,
                   const QuantizeOptions& options) {
  const auto t0 = Clock::now();
  QuantizeResult out;
  out.uv = seamless.uv;
  QuantizeStats& st = out.stats;
  const int nf = mesh.n_faces();
  if (options.target_faces < 0 || !(options.edge_length >= 0) || !(options.threshold_step > 0) ||
      options.threshold_step > 0.5 || !(options.scale_growth > 1) ||
      options.max_scale_retries < 0 || options.near_scale_tries < 0 ||
      !(options.near_scale_step >= 0 && options.near_scale_step < 0.2)) {
    out.status = core::Status::invalid_input(
        "quantize options: need target_faces ≥ 0, edge_length ≥ 0, 0 < threshold_step ≤ 0.5, "
        "scale_growth > 1, max_scale_retries ≥ 0, near_scale_tries ≥ 0, 0 ≤ near_scale_step < 0.2");
    return out;
  }
  if (nf == 0 || seamless.uv.corner_uv.rows() != 3 * nf) {
    out.status = core::Status::invalid_input("seamless map has " +
                                             std::to_string(seamless.uv.corner_uv.rows()) +
                                             " corner UVs for " + std::to_string(nf) + " faces");
    return out;
  }
  param::CopyLayout cl;
  out.status = param::build_copy_layout(mesh, seamless.uv.corner_uv, seamless.seams,
                                        options.input_seam_tol, &cl);
  if (!out.status.is_ok()) {
    out.status = core::Status::invalid_input("input map is not seamless: " + out.status.message());
    return out;
  }
  if (const int flips = count_flipped(cl, cl.x, nf); flips > 0) {
    out.status = core::Status::invalid_input("input map has " + std::to_string(flips) +
                                             " flipped or degenerate faces");
    return out;
  }
  // Cones and the gauge copy of each component.
  std::vector<char> is_cone_vertex(mesh.n_vertices(), 0);
  for (const param::ConeInfo& c : seamless.cones) {
    if (c.vertex < 0 || c.vertex >= mesh.n_vertices()) {
      out.status =
          core::Status::invalid_input("cone vertex " + std::to_string(c.vertex) + " out of range");
      return out;
    }
    is_cone_vertex[c.vertex] = 1;
  }
  st.n_cones = static_cast<int>(seamless.cones.size());
  std::vector<char> is_cone_copy(cl.n_copies(), 0);
  std::vector<int> gauge(cl.n_components, -1);
  for (int k = 0; k < cl.n_copies(); ++k) {
    is_cone_copy[k] = is_cone_vertex[cl.copy_vertex[k]];
    const int comp = cl.copy_component[k];
    if (gauge[comp] < 0 || (is_cone_copy[k] && !is_cone_copy[gauge[comp]])) gauge[comp] = k;
  }
  // Candidates: cone-copy coordinates, then seam translations.
  std::vector<Candidate> candidates;
  for (int k = 0; k < cl.n_copies(); ++k)
    if (is_cone_copy[k])
      for (int d = 0; d < 2; ++d) candidates.push_back({{{2 * k + d, 1.0}}, true, k, d});
  const int n_copy_vars = 2 * cl.n_copies();
  for (size_t si = 0; si < cl.seams.size(); ++si)
    for (int d = 0; d < 2; ++d)
      candidates.push_back({{{n_copy_vars + 2 * static_cast<int>(si) + d, 1.0}}, false});
  st.n_candidates = static_cast<int>(candidates.size());

  // Scale.
  const double area3d = surface_area(mesh);
  const double area_uv = uv_area(cl, cl.x, nf);
  double scale = 0;
  if (options.target_faces > 0) {
    scale = std::sqrt(options.target_faces / area_uv);
  } else if (options.edge_length > 0) {
    scale = std::sqrt(area3d / area_uv) / options.edge_length;
  } else {
    scale = std::sqrt(default_target_faces(mesh) / area_uv);
  }
  if (!(scale > 0) || !std::isfinite(scale)) {
    out.status =
        core::Status::invalid_input("cannot scale a map of UV area " + std::to_string(area_uv));
    return out;
  }

  param::ConstrainedLayoutOptions lopt;
  lopt.energy = options.energy;
  lopt.max_newton_iters = options.max_newton_iters;
  lopt.gauge_copies = gauge;
  std::optional<Eigen::VectorXd> best;
  core::Status failure;
  // Scales tried: the target, small jitters that keep the quad count within about ±8% (a
  // greedy rounding that dead-ends often succeeds from a slightly different start), then
  // refinements by scale_growth.
  std::vector<double> scales = {scale};
  for (int j = 1; j <= options.near_scale_tries; ++j) {
    const double jitter = options.near_scale_step * ((j + 1) / 2);
    scales.push_back(scale * (j % 2 == 1 ? 1 + jitter : 1 - jitter));
  }
  for (int r = 1; r <= options.max_scale_retries; ++r)
    scales.push_back(scale * std::pow(options.scale_growth, r));
  for (int attempt = 0; attempt < static_cast<int>(scales.size()); ++attempt) {
    st.n_scale_retries = attempt;
    scale = scales[attempt];
    // Scaled copies, each component translated so that its gauge copy is at the origin, then
    // the seam translations.
    Eigen::VectorXd x(n_copy_vars + 2 * cl.seams.size());
    for (int k = 0; k < cl.n_copies(); ++k)
      x.segment<2>(2 * k) =
          scale * (cl.x.segment<2>(2 * k) - cl.x.segment<2>(2 * gauge[cl.copy_component[k]]));
    for (size_t si = 0; si < cl.seams.size(); ++si) {
      const param::CopySeam& s = cl.seams[si];
      for (int d = 0; d < 2; ++d)
        x[n_copy_vars + 2 * si + d] = x[2 * s.b0 + d] -
                                      rotation_entry(s.matching, d, 0) * x[2 * s.a0] -
                                      rotation_entry(s.matching, d, 1) * x[2 * s.a0 + 1];
    }
    lopt.rest_scale = scale * std::sqrt(area_uv / area3d);
    // At one scale, a run that dead-ends on cones doomed by parity restarts with those cones
    // rounded first (a few times), before the scale changes.
    std::vector<char> priority(candidates.size(), 0);
    std::optional<Rounder> found;
    bool ok = false;
    for (int restart = 0; restart <= kMaxPriorityRestarts; ++restart) {
      found.emplace(mesh, cl, candidates, is_cone_copy, lopt, &st);
      found->set_priority(priority);
      ok = found->run(x, options.threshold_step, options.progress);
      if (ok || !found->hard_failure_.is_ok()) break;
      bool added = false;
      for (const int u : found->doomed())
        if (!priority[u]) priority[u] = added = true;
      if (!added) break;
    }
    Rounder& rounder = *found;
    if (!rounder.hard_failure_.is_ok()) {
      failure = rounder.hard_failure_;
      break;
    }
    if (ok) {
      Eigen::VectorXd xe;
      std::string why;
      if (!exact_expand(rounder.reduction(), rounder.x(), &xe, &why)) {
        out.status = core::Status::internal("the constraint elimination is not dyadic (" + why +
                                            "): no exact integer map");
        st.seconds = seconds_since(t0);
        return out;
      }
      st.scale = scale;
      st.n_integer_dofs = rounder.n_rows();
      st.n_rounded = st.n_candidates;
      best = xe;
      break;
    }
  }
  if (!best) {
    out.status =
        failure.is_ok()
            ? core::Status::not_converged("no flip-free integer-seamless map within " +
                                          std::to_string(scales.size()) + " scales")
            : failure;
    st.seconds = seconds_since(t0);
    return out;
  }
  // Exact verification of Def. 3.2.
  const Eigen::VectorXd& x = *best;
  for (size_t i = 0; i < candidates.size(); ++i) {
    const double v = candidates[i].value(x);
    if (v != std::round(v)) {
      out.status =
          core::Status::internal("integer quantity " + std::to_string(i) + " is " +
                                 std::to_string(v) + ", not an exact integer after snapping");
      st.seconds = seconds_since(t0);
      return out;
    }
  }
  for (const param::CopySeam& s : cl.seams) {
    const Eigen::Vector2d ea = x.segment<2>(2 * s.a1) - x.segment<2>(2 * s.a0);
    const Eigen::Vector2d eb = x.segment<2>(2 * s.b1) - x.segment<2>(2 * s.b0);
    Eigen::Vector2d rea;
    for (int d = 0; d < 2; ++d)
      rea[d] = rotation_entry(s.matching, d, 0) * ea[0] + rotation_entry(s.matching, d, 1) * ea[1];
    if (eb != rea) {
      out.status = core::Status::internal("seam between faces " + std::to_string(s.face_a) +
                                          " and " + std::to_string(s.face_b) +
                                          " is not exactly seamless after snapping");
      st.seconds = seconds_since(t0);
      return out;
    }
  }
  for (int c = 0; c < 3 * nf; ++c)
    out.uv.corner_uv.row(c) = x.segment<2>(2 * cl.corner_copy[c]).transpose();
  st.n_flipped = count_flipped(cl, x, nf);
  st.uv_area = uv_area(cl, x, nf);
  st.seconds = seconds_since(t0);
  if (st.n_flipped > 0)
    out.status = core::Status::not_converged(std::to_string(st.n_flipped) +
                                             " faces flipped by the exact snapping");
  return out;
}

}  // namespace

double target_edge_length(const core::TriMesh& mesh, const QuantizeOptions& options) {
  if (options.target_faces <= 0 && options.edge_length > 0) return options.edge_length;
  const int target = options.target_faces > 0 ? options.target_faces : default_target_faces(mesh);
  return std::sqrt(surface_area(mesh) / target);
}

double recommended_cone_pair_distance(const core::TriMesh& mesh, const QuantizeOptions& options,
                                      double quad_edges) {
  if (!(quad_edges > 0) || mesh.n_faces() == 0) return 0;
  double sum = 0;
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      sum += (mesh.V.row(mesh.F(f, k)) - mesh.V.row(mesh.F(f, (k + 1) % 3))).norm();
  const double mean_edge = sum / (3.0 * mesh.n_faces());
  return std::max(quad_edges * target_edge_length(mesh, options), kConePairMeshEdges * mean_edge);
}

QuantizeResult quantize_seamless(const core::TriMesh& mesh, const param::ParamResult& seamless,
                                 const QuantizeOptions& options) {
#ifdef QUADIFY_WITH_TBB
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    return arena.execute([&] { return run(mesh, seamless, options); });
  }
#endif
  return run(mesh, seamless, options);
}

}  // namespace quadify::quantize
