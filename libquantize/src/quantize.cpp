// Method (Levi 2021, Def. 3.2; greedy rounding in the spirit of mixed-integer quadrangulation):
// 1. Scale. Each unit square of the scaled map is one quad, so s = sqrt(target / UV area). With
//    an edge length h instead, s = sqrt(3D area / UV area) / h (the map is isometric up to a global
//    factor). The rest shapes of the energy are scaled along, so the optimizer keeps this scale.
// 2. Unknowns. Vertex copies are the corners merged across edges where both sides agree
//    (param::build_copy_layout). The integer candidates are both coordinates of every cone copy
//    and both components of every seam translation t = x_b0 − R^r x_a0. The translation gauge
//    fixes one copy per component (a cone copy when there is one) at the origin. The seam rows are
//    eliminated once (param::PinnedLayout) with the cone copies kept free and translations
//    pivoted before them: the loop around a cone, (I − R)·x_cone = Σ R·t, is solved for a
//    translation (unit coefficient), so every candidate is an integer combination of free
//    integer columns (checked; no parity conditions remain) and rounding pins free variables.
//    The Hessian pattern over the free variables never changes: element maps and the symbolic
//    factorization are built once per scale, every batch costs numeric factorizations only.
// 3. Rounding. Cones first, then the remaining free integer columns (translations around
//    handles). Cones within 1.5 units of another cone of their chart (same-sign clusters left by
//    the parametrization) go first, jointly: pairs (cone, free grid point) by distance, so that
//    they take distinct grid points, moved by a penalty homotopy while the rest of the map is
//    free. The other cones follow in batches by rounding error (below 1/8, 2/8, …). A batch is
//    pinned by Newton steps that prescribe the remaining displacement of its targets (the free
//    variables follow by the Hessian's response, as far as the step stays flip-free, plus an
//    energy step); targets whose faces limit every step (a collision, a squeezed region) are
//    dropped and try other free grid points (or the other neighbouring integer) one at a time.
//    A run that still dead-ends restarts at nearby scales (×1 ± 2%, ±4%), then at scales grown
//    by ×1.25 (max_scale_retries times). options.time_budget_seconds bounds the whole,
//    options.feature_time_budget_seconds the attempts with aligned features.
//    Aligned feature lines are optional candidates. They are rounded after the cones and before
//    the translations (they get the first choice of the room), and a line that reaches no integer
//    is released. A cone or a translation that dead-ends has the alignment rows in its way
//    released: the faces that would fold along the linear response of its move
//    (PinnedLayout::limiting_faces) and, if no aligned edge lies on them, 1, 2, 4 or 8 vertex
//    rings around them; the layout is rebuilt from the current one without those rows, the
//    integers already reached are pinned again, and the stage goes on. If that does not get
//    through either, the run is repeated with the lines rounded last, where they cannot block a
//    required unknown, releasing again where a cone or translation dead-ends. (Until 2026-12,
//    a translation that dead-ended with the lines rounded first went straight to the lines-last
//    run: casting at 5,000 quads released 71 aligned edges there in 60 s; releasing in the
//    first run, 17 in 29 s, feature capture 0.852 → 0.863.) Only if that fails too are the
//    features dropped.
// 4. Exactness. The free variables y are rounded to multiples of 2^-30 and x = P·y + c is
//    evaluated with P, c dyadic (integers, or halves where a pivot of 2 was unavoidable): every
//    term and partial sum is a multiple of 2^-38 far below 2^53 ulps, so the evaluation is exact
//    and the transitions and cones are exact integers. This is verified (kInternal otherwise), and
//    flips are counted with the exact orientation predicate.
// 5. Count adjustment (off here by default, on in the remesher; before step 4): unknowns moved
//    by a unit where the quad count, known exactly from the integers, gets closer to the target
//    (see kCountAdjustTries).
#include <libcore/predicates.h>
#include <libcore/topology.h>
#include <libparam/constrained_layout.h>
#include <libquantize/quantize.h>

#include <libparam/sizing.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#ifdef QUADIFY_WITH_TBB
#include <tbb/task_arena.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <limits>
#include <cstdio>
#include <tuple>

namespace quadify::quantize {
namespace {

using Clock = std::chrono::steady_clock;

// Default density: one quad per this many triangles, and at least kMinDefaultQuads quads. The
// triangle count measures a scan's or a sculpt's detail, not a CAD part's: a triangulated CAD part
// is economical (long thin triangles on flat faces), and one quad per six triangles left its
// creases thinner than a quad and its fillets on a few quads. At the former floor of 100, the
// defaults were block 746 quads (feature capture 0.547, Hausdorff 0.0208 of the diagonal), wingnut
// 1,128 (0.772, 0.0057), casting 1,813 (0.750, 0.0170, 100 s: 286 aligned feature edges released
// at dead ends of the rounding), spot 976 and knot1 1,066; at 5,000 every bench mesh keeps its
// Hausdorff below 1% (block 0.949 / 0.0086, wingnut 0.964 / 0.0025, casting 0.923 / 0.0073, 18 s),
// and 5,000 is the density of the peers' figures. Inputs above 30,000 triangles keep one quad per
// six triangles.
constexpr int kDefaultTrianglesPerQuad = 6;
constexpr int kMinDefaultQuads = 5000;
// Components below this many quads (at the scale of an attempt's target) may keep cones of
// index 3 or more: the grid cannot resolve them (see quantize_seamless).
constexpr double kMinQuadsForCones = 16;
// Free variables are rounded to multiples of 2^-kDyadicBits UV units (a quad is 1 unit), far
// below any triangle's size, so the rounding cannot flip a triangle in practice (checked).
constexpr int kDyadicBits = 30;
// The elimination pivots on unit coefficients where it can; a translation row through two seams
// with matching 2 can leave a pivot of 2, so P and c are dyadic with small denominators. Up to
// 2^-kMaxDenominatorBits, the products with y (multiples of 2^-kDyadicBits) stay exact.
constexpr int kMaxDenominatorBits = 8;
// Cones closer than this (max norm, quad units) to another cone of their chart compete for grid
// points: they are rounded first, jointly.
constexpr double kClusterRadius = 1.5;
// Rings of grid cells around a cone's own cell searched for a free grid point.
constexpr int kGridRing = 1;
// Penalty stages (param::PinSettings) for clustered cones, which move up to a unit or two.
constexpr int kFarPenaltyStages = 8;
// Other grid points tried, one at a time, for a cone whose batch could not move it.
constexpr size_t kConeAlternatives = 4;
// Backtracking at a cone that reaches none of them (Rounder::unstick_cone): the pinned cones of
// its chart within a radius (grid units, max norm) are freed, nearest first up to a number, and
// rounded again together with it; first 2 units and 4 cones, then 3 and 8. On the 20-mesh
// regression at 5,000 quads the first stage freed nothing that mattered and the second took dilo
// through its first scale (its dead end at ×1.00 had sent it to ×1.02: Hausdorff 0.0037 → 0.0027,
// 4,997 → 5,000 quads); alone, the second fails where the first gets through (the sphere's map at
// two quads: more cones to place at once).
constexpr std::pair<double, size_t> kUnstickStages[] = {{2, 4}, {3, 8}};
// Floor of recommended_cone_pair_distance, in mean edge lengths of the input.
constexpr double kConePairMeshEdges = 8;
// Scales tried with the aligned features before they are dropped: the target and the first two
// jitters (×1.02, ×0.98), each in both orders (feature lines before the translations, then after
// them). casting at 4,000–6,000 quads (7 targets) dropped its features at 3 targets with the
// target scale alone (a cone or a translation dead-ends), at 1 with the jitters, which cost time
// only where the target scale dead-ends (4,000: 52 → 86 s).
constexpr size_t kFeatureScaleTries = 3;
// A rounding with features that dead-ends on a cone or a translation releases the alignment rows
// on the faces that resist the blocked move (PinnedLayout::limiting_faces), or within the first
// of kReleaseRings vertex rings of them that holds some, and goes on from where it stopped (at
// most QuantizeOptions::feature_release_rounds times per run).
constexpr int kReleaseRings[] = {0, 1, 2, 4, 8};
// Average growth of the UV area (the quad count) in the rounding's re-optimizations: the
// flip-free energy resists compression more than stretching, so the integer constraints push the
// map outwards. Measured without allowing for it: +2.7% at 5,000 quads (20 bench meshes, −1.6%
// to +6.8%), +1.4% at 20,000 (7 meshes), +1.5% at 1,000 (11 meshes, ±5%). The scale allows for
// it with a count correction (QuantizeOptions::count_tolerance > 0: the quad count is centred on
// the target), which starts from it.
constexpr double kExpectedGrowth = 0.02;
// Count adjustment (QuantizeOptions::max_count_adjustments): once every integer
// unknown is pinned, the UV area of a closed map, which is its quad count, depends on them alone
// (the free variables deform the charts inside: the signed area of a cut-open closed surface is a
// sum over its twin seam curves, and for twins c and R·c + t the shape of c cancels, leaving
// −½ t × R(q − p) of its ends; checked: the final re-optimization leaves the area at its integer
// to 1e-9). So the count that moving one free integer column by ±1 gives (a translation, and with
// it the cones the elimination expresses by it) is known before trying it (on an open map whose
// boundary is not aligned, approximately). Per round, the kCountAdjustTries moves that bring the
// count closest are tried (pinned, relaxed at the batch tolerance), and further ones, up to
// kCountAdjustMaxTries, while none of them qualifies (block at 5,000 quads: the four closest
// landings flip or cost 2.3% of the energy, the ninth costs 0.9%; with its folded slivers
// repaired, the second round's first twelve landings flip or cost 1.06–1.17%, and 24 tries
// bring it from 5,189 to 5,000 quads); of those that stay flip-free
// and whose energy (symmetric Dirichlet, scale divided out) grows by at most
// kAdjustEnergyPerCount × the share of the target they gain, and by at most
// kMaxAdjustEnergyGrowth, the one of least growth per quad gained is kept and relaxed fully; until
// the count is within kCountAdjustTolerance of the target or no move qualifies. A bound per face
// instead (no face's singular values changed by more than 30%) refused every move on spot and
// fertility at 5,000 quads: a column moves cones too, and the faces beside a cone moved by a unit
// change by up to 2×, as with any choice of a cone's grid point by the rounding. Measured over the
// 20-mesh regression at 5,000 quads (README, design note "Count adjustment"): the counts land
// within 0.05% of the target on 18 meshes, but the Hausdorff distance moves both ways as at
// another rounding (fandisk 0.0019 → 0.0033, teapot 0.0060 → 0.0047). With the tolerance at
// 0.5% instead of 0.05% (fewer moves: fandisk's 5,023 quads stay as they are) and the further
// tries, 18 of 20 land within 0.5%, and the Hausdorff distance stays below the best peer's on
// every mesh that has one: the remesher's default up to 60,000 triangles (README, benchmark
// "Count adjustment by default"). A move that could not be pinned flip-free is not tried again
// in a later round, and up to 64 are tried while none qualifies (24 until 2026-12-07): casting at
// 5,000 quads found its first valid move at the 35th try, and its later rounds at tries 29-41,
// among moves that failed in every round; now 6 moves take it from 5,189 to 5,025 quads
// (Hausdorff 0.0080 → 0.0073) in 8 s instead of 0 moves in 3.7 s.
constexpr int kCountAdjustTries = 4;
constexpr int kCountAdjustMaxTries = 64;
constexpr double kCountAdjustTolerance = 0.005;
constexpr double kAdjustEnergyPerCount = 1;
// A round in which no tried move is within that budget keeps the cheapest one within twice it
// (2026-12-07): wingnut at 5,000 quads stopped at 5,035 (0.7% off; QuadWild 5,013), its next
// moves costing 0.89% of the energy for 0.5% of the count, 1.5% for 0.64%; now 5,001 quads,
// Hausdorff 0.0031 → 0.0026, capture 0.965 → 0.968 (its worst quad 0.134 → 0.044, a snapped
// vertex's); the 19 other meshes of the 20-mesh regression byte-identical (every round of theirs
// had a move within the budget). Twice the budget in every round instead changed which moves come
// first: wingnut took 8 moves, its quads went 1.5 times as far from the input, and the count
// adjustment was undone (5,264 quads).
constexpr double kLooseAdjustEnergyPerCount = 2;
constexpr double kMaxAdjustEnergyGrowth = 1.01;
// Relative Newton tolerance of the intermediate and final re-optimizations.
constexpr double kBatchTolerance = 1e-4;
constexpr double kFinalTolerance = 1e-7;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// An integer candidate: one scalar variable (a cone-copy coordinate or a seam translation).
struct Candidate {
  std::vector<std::pair<int, double>> form;
  bool is_cone = false;  // a cone-copy coordinate (else a seam translation or a feature end)
  int copy = -1;         // the cone copy, or the copy of a feature end
  int coord = 0;         // its coordinate (0: u, 1: v)
  bool is_feature = false;  // the constant coordinate of an aligned feature's end: optional
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

// The quad count asked for: target_faces, or the default density's; 0 for an edge length, which
// asks for none.
int asked_count(const core::TriMesh& mesh, const QuantizeOptions& options) {
  if (options.target_faces > 0) return options.target_faces;
  return options.edge_length > 0 ? 0 : default_target_faces(mesh);
}

// Singular values (σ1 ≥ σ2) of face f's map from the surface to the UV plane.
Eigen::Vector2d face_singular_values(const core::TriMesh& mesh, const param::CopyLayout& cl,
                                     const Eigen::VectorXd& x, int f) {
  const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)), p2 = mesh.V.row(mesh.F(f, 2));
  const Eigen::Vector3d a = p1 - p0, b = p2 - p0;
  const double la = a.norm();
  if (!(la > 0)) return {0, 0};
  const Eigen::Vector3d ex = a / la;
  const Eigen::Vector3d n = a.cross(b);
  if (!(n.norm() > 0)) return {0, 0};
  const Eigen::Vector3d ey = n.normalized().cross(ex);
  Eigen::Matrix2d E;  // surface edges in the face's frame
  E << la, b.dot(ex), 0, b.dot(ey);
  const Eigen::Vector2d u0 = x.segment<2>(2 * cl.corner_copy[3 * f]), u1 = x.segment<2>(2 * cl.corner_copy[3 * f + 1]),
                        u2 = x.segment<2>(2 * cl.corner_copy[3 * f + 2]);
  Eigen::Matrix2d U;
  U.col(0) = u1 - u0;
  U.col(1) = u2 - u0;
  const Eigen::Matrix2d J = U * E.inverse();
  return Eigen::JacobiSVD<Eigen::Matrix2d>(J).singularValues();
}

// Signed UV area of face f.
double face_uv_area(const param::CopyLayout& cl, const Eigen::VectorXd& x, int f) {
  const Eigen::Vector2d p0 = x.segment<2>(2 * cl.corner_copy[3 * f]),
                        p1 = x.segment<2>(2 * cl.corner_copy[3 * f + 1]),
                        p2 = x.segment<2>(2 * cl.corner_copy[3 * f + 2]);
  const Eigen::Vector2d e1 = p1 - p0, e2 = p2 - p0;
  return 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
}

double uv_area(const param::CopyLayout& cl, const Eigen::VectorXd& x, int nf) {
  double a = 0;
  for (int f = 0; f < nf; ++f) a += face_uv_area(cl, x, f);
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

// Releases aligned feature rows near a dead end (see Rounder::release_near_dead_end): given the
// faces that resist the blocked move, drops the alignment rows around them from *rows and their
// ends from *candidates and *prefer_free_coords; returns the number of rows dropped (0: none).
using ReleaseFeatures =
    std::function<int(const std::vector<int>& faces, std::vector<param::AffineRow>* rows,
                      std::vector<char>* prefer_free_coords, std::vector<Candidate>* candidates)>;

// One rounding run at a fixed scale over a param::PinnedLayout (see the method note above).
class Rounder {
 public:
  enum class Outcome { kDone, kStuck, kOutOfTime, kFailed };

  Rounder(const core::TriMesh& mesh, const param::CopyLayout& cl,
          std::vector<Candidate> candidates, const std::vector<char>& is_cone_copy, const QuantizeOptions& options,
          QuantizeStats* stats, Clock::time_point deadline, std::string scale_label,
          bool features_last = false, ReleaseFeatures release = {})
      : mesh_(mesh),
        cl_(cl),
        cand_(std::move(candidates)),
        is_cone_copy_(is_cone_copy),
        opt_(options),
        stats_(stats),
        deadline_(deadline),
        label_(std::move(scale_label)),
        features_last_(features_last),
        release_(std::move(release)) {}

  Outcome run(const Eigen::VectorXd& x, const param::PinnedLayoutOptions& layout_options) {
    lopt_ = layout_options;
    auto tc = Clock::now();
    status_ = layout_.init(mesh_, cl_, x, lopt_);
    stats_->seconds_setup += seconds_since(tc);
    if (!status_.is_ok()) return Outcome::kFailed;
    if (!find_integer_columns()) return Outcome::kFailed;
    tc = Clock::now();
    stats_->n_iterations += layout_.minimize(opt_.max_newton_iters, kBatchTolerance, &status_);
    if (!status_.is_ok()) return Outcome::kFailed;
    // A dead end on a cone or a translation comes from the alignment rows in the way: those
    // near it are released and the stage goes on.
    // The feature lines go before the translations, or after them with features_last_.
    Outcome outcome = with_release([this] { return round_cones(); });
    if (outcome == Outcome::kDone && !features_last_) outcome = round_features();
    if (outcome == Outcome::kDone) outcome = with_release([this] { return round_others(); });
    if (outcome == Outcome::kDone && features_last_) outcome = round_features();
    stats_->seconds_rounding += seconds_since(tc);
    if (outcome != Outcome::kDone) return outcome;
    tc = Clock::now();
    stats_->n_iterations += layout_.minimize(opt_.max_newton_iters, kFinalTolerance, &status_);
    stats_->seconds_final += seconds_since(tc);
    if (!status_.is_ok()) return Outcome::kFailed;
    for (const int j : int_cols_)
      if (!layout_.is_pinned(j) && !released_[j]) return Outcome::kStuck;
    if (layout_.n_flipped() != 0) return Outcome::kStuck;
    // The adjustment keeps only flip-free layouts (its trials are checked, and minimize() stays
    // flip-free), so the count above still holds after it.
    tc = Clock::now();
    const int adjustments_before = stats_->n_count_adjustments;
    Eigen::VectorXd unadjusted;
    if (opt_.max_count_adjustments > 0) unadjusted = layout_.x();
    adjust_count();
    if (stats_->n_count_adjustments > adjustments_before) unadjusted_x_ = std::move(unadjusted);
    stats_->seconds_count_adjustment += seconds_since(tc);
    return status_.is_ok() ? Outcome::kDone : Outcome::kFailed;
  }

  // Symmetric Dirichlet energy of the map with the scale `unit` divided out, per unit of surface
  // area (4 for an isometry); face_area: the mesh's triangle areas.
  double map_energy(const Eigen::VectorXd& x, double unit, const std::vector<double>& face_area) const {
    double e = 0, area = 0;
    for (int f = 0; f < mesh_.n_faces(); ++f) {
      const Eigen::Vector2d sv = face_singular_values(mesh_, cl_, x, f) / unit;
      const double a = face_area[f];
      if (!(sv[1] > 0)) return std::numeric_limits<double>::infinity();
      e += a * (sv[0] * sv[0] + sv[1] * sv[1] + 1 / (sv[0] * sv[0]) + 1 / (sv[1] * sv[1]));
      area += a;
    }
    return area > 0 ? e / area : 0;
  }

  // Count adjustment (see kCountAdjustTries): at most opt_.max_count_adjustments rounds, each
  // trying the moves of one pinned integer column by ±1 that bring the count closest (and closer)
  // and keeping the cheapest within its energy budget; a trial is undone exactly (restore).
  void adjust_count() {
    const long long target = asked_count(mesh_, opt_);
    if (target <= 0 || opt_.max_count_adjustments <= 0) return;
    const int nf = mesh_.n_faces();
    const Eigen::SparseMatrix<double> P = layout_.reduction().P;  // column-major copy
    const int n_copy_vars = 2 * cl_.n_copies();
    std::vector<std::vector<int>> copy_faces(cl_.n_copies());
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        std::vector<int>& fs = copy_faces[cl_.corner_copy[3 * f + k]];
        if (fs.empty() || fs.back() != f) fs.push_back(f);
      }
    std::vector<int> stamp(nf, -1);
    // The map's scale (UV units per model unit), which the energy below divides out.
    const double unit = std::sqrt(uv_area(cl_, layout_.x(), nf) / surface_area(mesh_));
    std::vector<double> face_area(nf);
    for (int f = 0; f < nf; ++f) {
      const Eigen::Vector3d p0 = mesh_.V.row(mesh_.F(f, 0)), p1 = mesh_.V.row(mesh_.F(f, 1)),
                            p2 = mesh_.V.row(mesh_.F(f, 2));
      face_area[f] = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    }
    // Moves (column, ±1) that could not be pinned flip-free: not tried again in later rounds.
    std::vector<std::pair<int, int>> failed;
    for (int round = 0; round < opt_.max_count_adjustments; ++round) {
      const Eigen::VectorXd x = layout_.x();
      const long long count = std::llround(uv_area(cl_, x, nf));
      const long long gap = target - count;
      if (std::abs(gap) <= std::llround(kCountAdjustTolerance * target)) return;
      struct Move {
        long long miss, change;
        int col, delta;
      };
      std::vector<Move> moves;
      Eigen::VectorXd moved = x;  // x with one column's move applied, undone after each move
      std::vector<double> base;   // the touched faces' areas in x
      for (const int j : int_cols_) {
        if (!layout_.is_pinned(j) || released_[j]) continue;
        std::vector<int> faces;
        for (Eigen::SparseMatrix<double>::InnerIterator it(P, j); it; ++it)
          if (it.row() < n_copy_vars)
            for (const int f : copy_faces[it.row() / 2])
              if (stamp[f] != j) {
                stamp[f] = j;
                faces.push_back(f);
              }
        base.clear();
        for (const int f : faces) base.push_back(face_uv_area(cl_, x, f));
        for (const int delta : {-1, 1}) {
          for (Eigen::SparseMatrix<double>::InnerIterator it(P, j); it; ++it) moved[it.row()] += delta * it.value();
          double change = 0;
          for (size_t i = 0; i < faces.size(); ++i) change += face_uv_area(cl_, moved, faces[i]) - base[i];
          for (Eigen::SparseMatrix<double>::InnerIterator it(P, j); it; ++it) moved[it.row()] = x[it.row()];
          const long long dc = std::llround(change);
          if (std::abs(gap - dc) < std::abs(gap) &&
              std::find(failed.begin(), failed.end(), std::pair(j, delta)) == failed.end())
            moves.push_back({std::abs(gap - dc), std::abs(dc), j, delta});
        }
      }
      std::sort(moves.begin(), moves.end(), [](const Move& a, const Move& b) {
        return std::tie(a.miss, a.change, a.col, a.delta) < std::tie(b.miss, b.change, b.col, b.delta);
      });
      const double energy = map_energy(x, unit, face_area);
      // The kCountAdjustTries moves that bring the count closest are tried; of those whose
      // energy growth is within their budget (kAdjustEnergyPerCount times the share of the target
      // they gain, at most kMaxAdjustEnergyGrowth), the one of least growth per quad gained is kept;
      // if none is, the one of least growth per quad within kLooseAdjustEnergyPerCount's budget.
      const param::PinnedLayout::Saved start = layout_.saved();
      std::optional<param::PinnedLayout::Saved> best, best_loose;
      double best_cost = std::numeric_limits<double>::infinity(), best_loose_cost = best_cost;
      for (size_t t = 0; t < moves.size(); ++t) {
        if (t >= static_cast<size_t>(best ? kCountAdjustTries : kCountAdjustMaxTries)) break;
        if (out_of_time()) break;
        const Move& m = moves[t];
        const double value = layout_.y()[m.col] + m.delta;
        layout_.unpin(m.col);
        const std::vector<char> pinned = pin({{m.col, value}});
        if (!status_.is_ok()) return;
        const bool valid = pinned[0] && layout_.is_pinned(m.col) && layout_.n_flipped() == 0;
        if (!valid) failed.emplace_back(m.col, m.delta);
        const double growth = valid ? map_energy(layout_.x(), unit, face_area) / energy - 1 : std::numeric_limits<double>::infinity();
        const double gained = static_cast<double>(std::abs(gap) - m.miss);
        const double budget = std::min(kMaxAdjustEnergyGrowth - 1, kAdjustEnergyPerCount * gained / target);
        const double loose_budget = std::min(kMaxAdjustEnergyGrowth - 1, kLooseAdjustEnergyPerCount * gained / target);
        const double cost = std::max(0.0, growth) / gained;
        if (growth <= budget && cost < best_cost) {
          best_cost = cost;
          best = layout_.saved();
        } else if (!best && growth <= loose_budget && cost < best_loose_cost) {
          best_loose_cost = cost;
          best_loose = layout_.saved();
        }
        layout_.restore(start);
        ++stats_->n_reverted;
      }
      if (!best) best = std::move(best_loose);
      if (!best) return;
      layout_.restore(*best);
      stats_->n_iterations += layout_.minimize(opt_.max_newton_iters, kFinalTolerance, &status_);
      if (!status_.is_ok()) return;
      ++stats_->n_count_adjustments;
    }
  }

  // The integer candidates of the run: those given, less the ends of released feature rows.
  const std::vector<Candidate>& candidates() const { return cand_; }
  // Free columns left unpinned: feature lines that reached no integer (their features are not
  // on iso-lines; no required candidate depends on them).
  const std::vector<char>& released() const { return released_; }
  int n_released() const { return static_cast<int>(std::count(released_.begin(), released_.end(), 1)); }

  const param::PinnedLayout& layout() const { return layout_; }
  // The layout (external order) before the count adjustment, when it kept a move; else empty.
  const Eigen::VectorXd& unadjusted_x() const { return unadjusted_x_; }
  const core::Status& status() const { return status_; }
  int n_integer_columns() const { return static_cast<int>(int_cols_.size()); }
  int n_pinned() const { return n_pinned_; }
  const std::string& stuck_reason() const { return stuck_; }
  // Whether the dead end came while rounding the cones (which go first in either order).
  bool stuck_on_cones() const { return stuck_on_cones_; }
  // The mesh vertex of the cone the run dead-ended on (-1: not on a cone).
  int stuck_cone_vertex() const { return stuck_cone_vertex_; }
  // Mesh faces that resist the move of the unknown the run dead-ended on
  // (param::PinnedLayout::limiting_faces, for both neighbouring integers or grid points).
  const std::vector<int>& stuck_faces() const { return stuck_faces_; }

 private:
  // A cone copy whose two coordinates are free variables.
  struct Cone {
    int copy, col_u, col_v;
  };

  // Free columns that are integer candidates, and the lattice check: every candidate must be an
  // integer combination of them plus an integer offset, so that pinning them to integers makes
  // every candidate an integer (no parity conditions).
  bool find_integer_columns() {
    const param::ConstrainedReduction& red = layout_.reduction();
    std::vector<int> col_of_var(red.P.rows(), -1);
    for (size_t j = 0; j < red.free_vars.size(); ++j) col_of_var[red.free_vars[j]] = static_cast<int>(j);
    std::vector<char> is_candidate_var(red.P.rows(), 0);
    for (const Candidate& c : cand_) is_candidate_var[c.form[0].first] = 1;
    std::vector<char> is_int_col(red.free_vars.size(), 0);
    for (size_t j = 0; j < red.free_vars.size(); ++j)
      is_int_col[j] = is_candidate_var[red.free_vars[j]];
    for (size_t i = 0; i < cand_.size(); ++i) {
      const int v = cand_[i].form[0].first;
      bool integral = red.c[v] == std::round(red.c[v]);
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, v); it; ++it)
        integral = integral && is_int_col[it.col()] && it.value() == std::round(it.value());
      if (!integral) {
        status_ = core::Status::internal(
            "integer unknown " + std::to_string(i) +
            " is not an integer combination of the free integer unknowns (non-unit pivot)");
        return false;
      }
    }
    int_cols_.clear();
    cones_.clear();
    for (size_t j = 0; j < red.free_vars.size(); ++j)
      if (is_int_col[j]) int_cols_.push_back(static_cast<int>(j));
    // Feature columns, and the columns that required (cone and translation) candidates use: a
    // feature column outside the latter may stay unpinned.
    released_.assign(red.free_vars.size(), 0);
    feature_col_.assign(red.free_vars.size(), 0);
    required_col_.assign(red.free_vars.size(), 0);
    for (const Candidate& c : cand_) {
      const int v = c.form[0].first;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, v); it; ++it) {
        if (c.is_feature && col_of_var[v] == static_cast<int>(it.col())) feature_col_[it.col()] = 1;
        if (!c.is_feature) required_col_[it.col()] = 1;
      }
    }
    for (int k = 0; k < cl_.n_copies(); ++k) {
      if (!is_cone_copy_[k]) continue;
      const int cu = col_of_var[2 * k], cv = col_of_var[2 * k + 1];
      if (cu >= 0 && cv >= 0) cones_.push_back({k, cu, cv});
    }
    return true;
  }

  void report_progress(const char* what) const {
    if (opt_.progress) opt_.progress("quantize " + label_ + " " + what, n_pinned_, n_integer_columns());
  }

  bool out_of_time() const { return Clock::now() > deadline_; }

  // A feature line no cone or translation depends on: it may stay unpinned (released).
  bool optional_col(int j) const { return feature_col_[j] && !required_col_[j]; }

  // Pins (column, value) targets; returns the per-target pinned flags.
  std::vector<char> pin(const std::vector<std::pair<int, double>>& targets, bool far = false) {
    param::PinSettings settings;
    if (far) settings.penalty_stages = kFarPenaltyStages;
    const param::PinReport rep =
        layout_.pin(targets, settings, opt_.max_newton_iters, kBatchTolerance);
    stats_->n_iterations += rep.iterations;
    if (!rep.status.is_ok()) status_ = rep.status;
    for (const char p : rep.pinned) n_pinned_ += p;
    ++stats_->n_batches;
    return rep.pinned;
  }

  Eigen::Vector2d position(const Cone& c) const {
    return {layout_.y()[c.col_u], layout_.y()[c.col_v]};
  }
  using GridKey = std::tuple<int, long long, long long>;  // (component, u, v)
  GridKey key(const Cone& c, double u, double v) const {
    return {cl_.copy_component[c.copy], std::llround(u), std::llround(v)};
  }
  bool free_point(const Cone& c, double u, double v) const {
    const auto it = occupied_.find(key(c, u, v));
    return it == occupied_.end() || it->second == cl_.copy_vertex[c.copy];
  }

  // Grid points around a cone (its cell's corners and the ring around them) that no other cone
  // vertex of its chart holds, nearest first; a coordinate already pinned stays.
  std::vector<Eigen::Vector2d> grid_choices(const Cone& c) const {
    const Eigen::Vector2d p = position(c);
    const bool u_pinned = layout_.is_pinned(c.col_u), v_pinned = layout_.is_pinned(c.col_v);
    std::vector<std::pair<double, Eigen::Vector2d>> pts;
    for (int du = -kGridRing; du <= 1 + kGridRing; ++du)
      for (int dv = -kGridRing; dv <= 1 + kGridRing; ++dv) {
        const Eigen::Vector2d g(u_pinned ? p.x() : std::floor(p.x()) + du,
                                v_pinned ? p.y() : std::floor(p.y()) + dv);
        if ((u_pinned && du != 0) || (v_pinned && dv != 0)) continue;
        if (!free_point(c, g.x(), g.y())) continue;
        pts.push_back({(g - p).norm(), g});
      }
    std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<Eigen::Vector2d> out;
    for (const auto& [d, g] : pts) out.push_back(g);
    return out;
  }

  // Cones whose positions are within kClusterRadius of another unpinned cone of their chart:
  // these compete for grid points and are rounded first, jointly, while everything else can
  // still move (a cone pulled a whole unit away from its neighbour needs the most room).
  std::vector<char> clustered(const std::vector<int>& open) const {
    std::vector<char> in(cones_.size(), 0);
    std::map<std::tuple<int, long long, long long>, std::vector<int>> buckets;
    for (const int i : open) {
      const Eigen::Vector2d p = position(cones_[i]);
      buckets[{cl_.copy_component[cones_[i].copy], std::llround(std::floor(p.x() / kClusterRadius)),
               std::llround(std::floor(p.y() / kClusterRadius))}]
          .push_back(i);
    }
    for (const int i : open) {
      const Eigen::Vector2d p = position(cones_[i]);
      const int comp = cl_.copy_component[cones_[i].copy];
      const long long bu = std::llround(std::floor(p.x() / kClusterRadius)),
                      bv = std::llround(std::floor(p.y() / kClusterRadius));
      for (long long du = -1; du <= 1 && !in[i]; ++du)
        for (long long dv = -1; dv <= 1 && !in[i]; ++dv) {
          const auto it = buckets.find({comp, bu + du, bv + dv});
          if (it == buckets.end()) continue;
          for (const int o : it->second)
            if (o != i && cl_.copy_vertex[cones_[o].copy] != cl_.copy_vertex[cones_[i].copy] &&
                (position(cones_[o]) - p).lpNorm<Eigen::Infinity>() < kClusterRadius)
              in[i] = in[o] = 1;
        }
    }
    return in;
  }

  // Rounds a batch of cones jointly: pairs (cone, free grid point) by increasing distance, each
  // cone taking the nearest point no earlier cone of the batch took. Cones that the pin could
  // not move (a collision or a fold in the way) then try their other grid points one by one.
  Outcome round_cone_batch(const std::vector<int>& batch, bool cluster) {
    std::vector<std::tuple<double, int, Eigen::Vector2d>> pairs;
    for (const int i : batch)
      for (const Eigen::Vector2d& g : grid_choices(cones_[i]))
        pairs.push_back({(g - position(cones_[i])).norm(), i, g});
    std::stable_sort(pairs.begin(), pairs.end(),
                     [](const auto& a, const auto& b) { return std::get<0>(a) < std::get<0>(b); });
    std::map<int, Eigen::Vector2d> pick;
    std::map<GridKey, int> taken;
    std::vector<std::pair<int, double>> picked_targets;
    for (const auto& [d, i, g] : pairs) {
      if (pick.count(i)) continue;
      const GridKey k = key(cones_[i], g.x(), g.y());
      if (const auto it = taken.find(k);
          it != taken.end() && cl_.copy_vertex[cones_[it->second].copy] != cl_.copy_vertex[cones_[i].copy])
        continue;
      if (cluster) {
        // Cones of one triangle must take a positively oriented lattice triangle.
        std::vector<std::pair<int, double>> trial = picked_targets;
        if (!layout_.is_pinned(cones_[i].col_u)) trial.push_back({cones_[i].col_u, g.x()});
        if (!layout_.is_pinned(cones_[i].col_v)) trial.push_back({cones_[i].col_v, g.y()});
        if (!layout_.determined_faces_valid(trial)) continue;
        picked_targets = std::move(trial);
      }
      pick[i] = g;
      taken[k] = i;
    }
    std::vector<std::pair<int, double>> targets;
    std::vector<int> owner;
    for (const auto& [i, g] : pick) {
      if (!layout_.is_pinned(cones_[i].col_u)) {
        targets.push_back({cones_[i].col_u, g.x()});
        owner.push_back(i);
      }
      if (!layout_.is_pinned(cones_[i].col_v)) {
        targets.push_back({cones_[i].col_v, g.y()});
        owner.push_back(i);
      }
    }
    if (out_of_time()) return Outcome::kOutOfTime;
    pin(targets, cluster);
    if (!status_.is_ok()) return Outcome::kFailed;
    report_progress("cones");
    for (const int i : batch) {
      const Cone& c = cones_[i];
      if (layout_.is_pinned(c.col_u) && layout_.is_pinned(c.col_v)) {
        occupied_[key(c, layout_.y()[c.col_u], layout_.y()[c.col_v])] = cl_.copy_vertex[c.copy];
        continue;
      }
      ++stats_->n_cone_collisions;
      bool placed = false;
      const std::vector<Eigen::Vector2d> choices = grid_choices(c);
      size_t tried = 0;
      for (size_t a = 0; a < choices.size() && tried < kConeAlternatives && !placed; ++a) {
        if (out_of_time()) return Outcome::kOutOfTime;
        std::vector<std::pair<int, double>> t;
        if (!layout_.is_pinned(c.col_u)) t.push_back({c.col_u, choices[a].x()});
        if (!layout_.is_pinned(c.col_v)) t.push_back({c.col_v, choices[a].y()});
        // A grid point that leaves a triangle of pinned cones flat or reversed is skipped
        // without a solve (e.g. a third cone of a triangle of cones on the line of the other two).
        if (!layout_.determined_faces_valid(t)) continue;
        ++tried;
        ++stats_->n_reverted;
        pin(t, cluster);
        if (!status_.is_ok()) return Outcome::kFailed;
        placed = layout_.is_pinned(c.col_u) && layout_.is_pinned(c.col_v);
      }
      if (!placed) {
        if (const Outcome o = unstick_cone(i, &placed); o != Outcome::kDone) return o;
        if (placed) continue;
      }
      if (!placed) {
        const Eigen::Vector2d p = position(c);
        stuck_on_cones_ = true;
        stuck_cone_vertex_ = cl_.copy_vertex[c.copy];
        for (size_t a = 0; a < std::min(choices.size(), size_t{2}); ++a) {
          std::vector<std::pair<int, double>> t;
          if (!layout_.is_pinned(c.col_u)) t.push_back({c.col_u, choices[a].x()});
          if (!layout_.is_pinned(c.col_v)) t.push_back({c.col_v, choices[a].y()});
          add_stuck_faces(t);
        }
        stuck_ = "cone vertex " + std::to_string(cl_.copy_vertex[c.copy]) + " at (" +
                 std::to_string(p.x()) + ", " + std::to_string(p.y()) +
                 ") reaches no free grid point flip-free";
        return Outcome::kStuck;
      }
      occupied_[key(c, layout_.y()[c.col_u], layout_.y()[c.col_v])] = cl_.copy_vertex[c.copy];
      report_progress("cones");
    }
    return Outcome::kDone;
  }

  // Backtracking (ours): cone i reached no free grid point. The pinned cones of its chart near it
  // (kUnstickStages: within a radius, nearest first, up to a number) are freed and rounded again
  // together with it as a cluster (distinct grid points by distance, the penalty homotopy); their
  // grid points and the room between them are what blocks it, when another cone took the point it
  // needed first. If that fails, the layout, the grid and the dead end's record are restored
  // exactly (PinnedLayout::restore) and the next stage frees more; after the last, *placed stays
  // false. Not nested.
  Outcome unstick_cone(int i, bool* placed) {
    *placed = false;
    if (unsticking_) return Outcome::kDone;
    size_t freed = 0;
    for (const auto& [radius, max_cones] : kUnstickStages)
      if (const Outcome o = unstick_cone(i, radius, max_cones, &freed, placed); o != Outcome::kDone || *placed)
        return o;
    return Outcome::kDone;
  }

  // One stage of unstick_cone; *freed: the cones the previous stage freed (a stage that would free
  // no more, the same ones, is skipped), updated.
  Outcome unstick_cone(int i, double radius, size_t max_cones, size_t* freed, bool* placed) {
    const Cone& c = cones_[i];
    const Eigen::Vector2d p = position(c);
    std::vector<std::pair<double, int>> near;
    for (int o = 0; o < static_cast<int>(cones_.size()); ++o) {
      const Cone& n = cones_[o];
      if (o == i || cl_.copy_component[n.copy] != cl_.copy_component[c.copy] ||
          cl_.copy_vertex[n.copy] == cl_.copy_vertex[c.copy] || !layout_.is_pinned(n.col_u) ||
          !layout_.is_pinned(n.col_v))
        continue;
      const double d = (position(n) - p).lpNorm<Eigen::Infinity>();
      if (d <= radius) near.push_back({d, o});
    }
    std::sort(near.begin(), near.end());
    if (near.size() > max_cones) near.resize(max_cones);
    if (near.size() <= *freed) return Outcome::kDone;
    *freed = near.size();
    const param::PinnedLayout::Saved saved = layout_.saved();
    const std::map<GridKey, int> occupied = occupied_;
    const std::vector<int> stuck_faces = stuck_faces_;
    const std::string stuck = stuck_;
    const bool stuck_on_cones = stuck_on_cones_;
    const int stuck_cone_vertex = stuck_cone_vertex_, n_pinned = n_pinned_;
    std::vector<int> batch = {i};
    for (const auto& [d, o] : near) {
      const Cone& n = cones_[o];
      occupied_.erase(key(n, layout_.y()[n.col_u], layout_.y()[n.col_v]));
      layout_.unpin(n.col_u);
      layout_.unpin(n.col_v);
      n_pinned_ -= 2;
      batch.push_back(o);
    }
    unsticking_ = true;
    const Outcome o = round_cone_batch(batch, true);
    unsticking_ = false;
    if (o == Outcome::kDone) {
      ++stats_->n_unstuck_cones;
      *placed = true;
      return o;
    }
    if (o != Outcome::kStuck) return o;
    layout_.restore(saved);
    occupied_ = occupied;
    stuck_faces_ = stuck_faces;
    n_pinned_ = n_pinned;
    stuck_ = stuck;
    stuck_on_cones_ = stuck_on_cones;
    stuck_cone_vertex_ = stuck_cone_vertex;
    return Outcome::kDone;
  }

  Outcome round_cones() {
    std::vector<int> open(cones_.size());
    std::iota(open.begin(), open.end(), 0);
    // Clusters first, then the rest by distance to the nearest grid point in batches.
    const std::vector<char> in_cluster = clustered(open);
    std::vector<int> cluster_batch;
    for (const int i : open)
      if (in_cluster[i]) cluster_batch.push_back(i);
    stats_->n_clustered_cones += static_cast<int>(cluster_batch.size());
    if (!cluster_batch.empty())
      if (const Outcome o = round_cone_batch(cluster_batch, true); o != Outcome::kDone) return o;
    const int n_steps = std::max(1, static_cast<int>(std::ceil(0.5 / opt_.threshold_step - 1e-9)));
    for (int step = 0; step < n_steps; ++step) {
      const double eps = opt_.threshold_step * (step + 1);
      std::vector<int> batch;
      for (size_t i = 0; i < cones_.size(); ++i) {
        const Cone& c = cones_[i];
        if (layout_.is_pinned(c.col_u) && layout_.is_pinned(c.col_v)) continue;
        const Eigen::Vector2d p = position(c);
        const double err =
            std::max(std::abs(p.x() - std::round(p.x())), std::abs(p.y() - std::round(p.y())));
        if (step + 1 == n_steps || err < eps) batch.push_back(static_cast<int>(i));
      }
      if (batch.empty()) continue;
      if (const Outcome o = round_cone_batch(batch, false); o != Outcome::kDone) return o;
    }
    return Outcome::kDone;
  }

  // Pins free column j alone at its nearest integer, else at the other neighbouring one (far:
  // with the penalty homotopy); *placed tells whether one of them held.
  Outcome pin_neighbouring_integer(int j, bool far, bool* placed) {
    const double v = layout_.y()[j];
    *placed = false;
    for (const double alt : {std::round(v), v < std::round(v) ? std::round(v) - 1 : std::round(v) + 1}) {
      if (out_of_time()) return Outcome::kOutOfTime;
      ++stats_->n_reverted;
      pin({{j, alt}}, far);
      if (!status_.is_ok()) return Outcome::kFailed;
      if ((*placed = layout_.is_pinned(j))) break;
    }
    return Outcome::kDone;
  }

  // Feature lines (free feature columns no required candidate depends on), in batches by
  // rounding error like the cones, so that the map can make room between close lines; a line
  // that reaches neither neighbouring integer (by a penalty homotopy) is released: it stays where
  // it is, and its features are not on an iso-line.
  Outcome round_features() {
    const int n_steps = std::max(1, static_cast<int>(std::ceil(0.5 / opt_.threshold_step - 1e-9)));
    for (int step = 0; step < n_steps; ++step) {
      const double eps = opt_.threshold_step * (step + 1);
      std::vector<std::pair<int, double>> targets;
      for (const int j : int_cols_) {
        if (!optional_col(j) || layout_.is_pinned(j) || released_[j]) continue;
        const double v = layout_.y()[j];
        if (step + 1 == n_steps || std::abs(v - std::round(v)) < eps) targets.push_back({j, std::round(v)});
      }
      if (targets.empty()) continue;
      if (out_of_time()) return Outcome::kOutOfTime;
      pin(targets);
      if (!status_.is_ok()) return Outcome::kFailed;
      report_progress("features");
      for (const auto& [j, value] : targets) {
        if (layout_.is_pinned(j)) continue;
        bool placed = false;
        if (const Outcome o = pin_neighbouring_integer(j, true, &placed); o != Outcome::kDone) return o;
        if (!placed) released_[j] = 1;
      }
    }
    return Outcome::kDone;
  }

  // The remaining integer columns (translations and lone cone coordinates) to their nearest
  // integers in one batch; a blocked one then tries both neighbouring integers alone. With
  // features_last_, feature lines no required candidate depends on are left to round_features.
  Outcome round_others() {
    std::vector<std::pair<int, double>> targets;
    for (const int j : int_cols_)
      if (!layout_.is_pinned(j) && !released_[j] && !(features_last_ && optional_col(j)))
        targets.push_back({j, std::round(layout_.y()[j])});
    if (targets.empty()) return Outcome::kDone;
    if (out_of_time()) return Outcome::kOutOfTime;
    pin(targets);
    if (!status_.is_ok()) return Outcome::kFailed;
    report_progress("translations");
    for (const auto& [j, value] : targets) {
      if (layout_.is_pinned(j)) continue;
      const double v = layout_.y()[j];
      bool placed = false;
      // Both neighbouring integers by Newton steps, then by the penalty homotopy (which can
      // carry the map farther, e.g. past an aligned feature line in the way).
      for (const bool far : {false, true}) {
        if (placed) break;
        if (const Outcome o = pin_neighbouring_integer(j, far, &placed); o != Outcome::kDone) return o;
      }
      if (!placed) {
        add_stuck_faces({{j, std::floor(v)}});
        add_stuck_faces({{j, std::floor(v) + 1}});
        stuck_ = "a seam translation at " + std::to_string(v) + " reaches no integer flip-free";
        return Outcome::kStuck;
      }
    }
    return Outcome::kDone;
  }

  // Runs a rounding stage; while it dead-ends and feature rows near the dead end can be
  // released (at most options.feature_release_rounds times), releases them and runs the stage
  // again.
  template <class Stage>
  Outcome with_release(Stage stage) {
    Outcome o = stage();
    for (int round = 0; o == Outcome::kStuck && release_ && round < opt_.feature_release_rounds;
         ++round) {
      if (out_of_time()) return Outcome::kOutOfTime;
      if (!release_near_dead_end()) return status_.is_ok() ? o : Outcome::kFailed;
      o = stage();
    }
    return o;
  }

  // Drops the feature rows near the faces that resist the blocked move and rebuilds the layout
  // from the current one: the elimination changes, so every integer column whose value the
  // pinned columns determined (an integer) is pinned again at that value. False when no row is
  // near the dead end or the rebuild fails (status_).
  bool release_near_dead_end() {
    if (stuck_faces_.empty()) return false;
    const param::ConstrainedReduction& red = layout_.reduction();
    std::vector<char> determined(red.P.rows(), 1);
    for (int v = 0; v < red.P.rows(); ++v)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, v); it; ++it)
        if (!layout_.is_pinned(static_cast<int>(it.col()))) determined[v] = 0;
    const Eigen::VectorXd x_ext = layout_.x();
    const int n = release_(stuck_faces_, &lopt_.extra_rows, &lopt_.prefer_free_coords, &cand_);
    if (n == 0) return false;
    const auto tc = Clock::now();
    status_ = layout_.init(mesh_, cl_, x_ext.head(2 * cl_.n_copies()), lopt_);
    stats_->seconds_setup += seconds_since(tc);
    if (!status_.is_ok() || !find_integer_columns()) return false;
    const param::ConstrainedReduction& red2 = layout_.reduction();
    std::vector<std::pair<int, double>> targets;
    for (const int j : int_cols_) {
      const int v = red2.free_vars[j];
      if (determined[v] && x_ext[v] == std::round(x_ext[v])) targets.push_back({j, x_ext[v]});
    }
    n_pinned_ = 0;
    pin(targets);
    stuck_faces_.clear();
    stuck_.clear();
    stuck_on_cones_ = false;
    stuck_cone_vertex_ = -1;
    return status_.is_ok();
  }

  void add_stuck_faces(const std::vector<std::pair<int, double>>& targets) {
    for (const int f : layout_.limiting_faces(targets)) stuck_faces_.push_back(f);
    std::sort(stuck_faces_.begin(), stuck_faces_.end());
    stuck_faces_.erase(std::unique(stuck_faces_.begin(), stuck_faces_.end()), stuck_faces_.end());
  }

  const core::TriMesh& mesh_;
  const param::CopyLayout& cl_;
  std::vector<Candidate> cand_;
  const std::vector<char>& is_cone_copy_;
  const QuantizeOptions& opt_;
  QuantizeStats* stats_;
  Clock::time_point deadline_;
  std::string label_;
  bool features_last_;  // translations before feature lines (they cannot block a translation)
  ReleaseFeatures release_;
  param::PinnedLayoutOptions lopt_;
  param::PinnedLayout layout_;
  Eigen::VectorXd unadjusted_x_;
  core::Status status_;
  std::vector<int> int_cols_;
  std::vector<char> released_, feature_col_, required_col_;  // per free column
  std::vector<Cone> cones_;
  std::map<GridKey, int> occupied_;  // grid points of pinned cones → their mesh vertex
  int n_pinned_ = 0;
  std::string stuck_;
  bool stuck_on_cones_ = false;
  int stuck_cone_vertex_ = -1;
  std::vector<int> stuck_faces_;
  bool unsticking_ = false;  // inside unstick_cone
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
      options.feature_release_rounds < 0 || !(options.time_budget_seconds >= 0) ||
      !(options.feature_time_budget_seconds >= 0) ||
      !(options.near_scale_step >= 0 && options.near_scale_step < 0.2) ||
      !(options.count_tolerance >= 0) || options.max_count_corrections < 0) {
    out.status = core::Status::invalid_input(
        "quantize options: need target_faces ≥ 0, edge_length ≥ 0, 0 < threshold_step ≤ 0.5, "
        "scale_growth > 1, max_scale_retries ≥ 0, near_scale_tries ≥ 0, feature_release_rounds ≥ 0, "
        "0 ≤ near_scale_step < 0.2, count_tolerance ≥ 0, max_count_corrections ≥ 0");
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
  // Aligned features (param::FeatureAlignment): the constant coordinate of both ends is an
  // integer candidate, and the alignment rows are eliminated with the seams.
  struct FeatureRow {
    param::AffineRow row;
    int face, a, b, coord;  // its face, the copies of its ends and the constant coordinate
  };
  std::vector<FeatureRow> feature_rows;
  const size_t n_base_candidates = candidates.size();
  for (const param::FeatureAlignment& fa : seamless.features) {
    if (fa.face < 0 || fa.face >= nf || fa.corner < 0 || fa.corner > 2 || fa.constant_coord < 0 ||
        fa.constant_coord > 1) {
      out.status = core::Status::invalid_input("feature alignment on face " + std::to_string(fa.face) +
                                               " is out of range");
      return out;
    }
    const int a = cl.corner_copy[3 * fa.face + fa.corner];
    const int b = cl.corner_copy[3 * fa.face + (fa.corner + 1) % 3];
    const int c = fa.constant_coord;
    const double scale_ref = std::max({1.0, std::abs(cl.x[2 * a + c]), std::abs(cl.x[2 * b + c])});
    if (std::abs(cl.x[2 * b + c] - cl.x[2 * a + c]) > options.input_seam_tol * scale_ref * 1e3) {
      out.status = core::Status::invalid_input("feature edge on face " + std::to_string(fa.face) +
                                               " is not aligned with its axis in the input map");
      return out;
    }
    FeatureRow fr{{}, fa.face, a, b, c};
    fr.row.entries = {{2 * a + c, -1.0}, {2 * b + c, 1.0}};
    feature_rows.push_back(fr);
  }
  // The feature rows kept so far (rows near a dead end are released, see below), and for them
  // the alignment rows, the candidates (base ones, then the ends' constant coordinates) and the
  // coordinates the elimination should keep free.
  std::vector<char> feature_kept(feature_rows.size(), 1);
  std::vector<param::AffineRow> kept_rows;
  std::vector<char> feature_coords;
  auto select_features = [&]() {
    candidates.resize(n_base_candidates);
    kept_rows.clear();
    std::vector<char> is_candidate(n_copy_vars, 0);
    for (const Candidate& c : candidates)
      if (c.is_cone) is_candidate[c.form[0].first] = 1;
    feature_coords.assign(n_copy_vars, 0);
    for (size_t r = 0; r < feature_rows.size(); ++r) {
      if (!feature_kept[r]) continue;
      const FeatureRow& fr = feature_rows[r];
      kept_rows.push_back(fr.row);
      for (const int k : {fr.a, fr.b}) {
        // Cone coordinates are candidates already (and keep their own pivot preference).
        if (!is_candidate[2 * k + fr.coord]) {
          feature_coords[2 * k + fr.coord] = 1;
          is_candidate[2 * k + fr.coord] = 1;
          candidates.push_back({{{2 * k + fr.coord, 1.0}}, false, k, fr.coord, true});
        }
      }
    }
  };
  select_features();
  st.n_candidates = static_cast<int>(candidates.size());

  // Scale.
  double area3d = surface_area(mesh);
  if (!options.face_size.empty() || !options.face_metric.empty()) {
    if ((!options.face_size.empty() && static_cast<int>(options.face_size.size()) != nf) ||
        (!options.face_metric.empty() && static_cast<int>(options.face_metric.size()) != nf)) {
      out.status = core::Status::invalid_input("face_size or face_metric does not have one entry per face");
      return out;
    }
    area3d = param::sized_area(mesh, options.face_size, options.face_metric);
  }
  const double area_uv = uv_area(cl, cl.x, nf);
  const int count_target = asked_count(mesh, options);
  double scale = count_target > 0 ? std::sqrt(count_target / area_uv)
                                  : std::sqrt(area3d / area_uv) / options.edge_length;
  if (count_target > 0 && options.count_tolerance > 0) scale /= std::sqrt(1 + kExpectedGrowth);
  if (!(scale > 0) || !std::isfinite(scale)) {
    out.status =
        core::Status::invalid_input("cannot scale a map of UV area " + std::to_string(area_uv));
    return out;
  }

  // A cone of index 3 or more (UV angle 90° or less) would be a quad vertex of valence 1 or 0:
  // extraction refuses it, so no rounding is tried (octopus spent 150 s on such a map). Except in
  // a component of less than kMinQuadsForCones quads at this scale, which the grid cannot resolve
  // anyway (the remesher extracts without it and splits its triangles): the tetrahedron that the
  // repair splits off spot_nonmanifold (6.6 quads) has four cones and no room to move one.
  {
    std::vector<double> component_quads(cl.n_components, 0.0);
    for (int f = 0; f < nf; ++f)
      component_quads[cl.copy_component[cl.corner_copy[3 * f]]] += scale * scale * face_uv_area(cl, cl.x, f);
    std::vector<int> vertex_component(mesh.n_vertices(), -1);
    for (int k = 0; k < cl.n_copies(); ++k) vertex_component[cl.copy_vertex[k]] = cl.copy_component[k];
    std::vector<char> component_unresolved(cl.n_components, 0);
    for (const param::ConeInfo& c : seamless.cones) {
      if (c.index < 3) continue;
      const int comp = vertex_component[c.vertex];
      if (component_quads[comp] < kMinQuadsForCones) {
        component_unresolved[comp] = 1;
        continue;
      }
      if (out.status.is_ok())  // the first such cone is named
        out.status = core::Status::invalid_input(
            "cone vertex " + std::to_string(c.vertex) + " has index " + std::to_string(c.index) + " (UV angle " +
            std::to_string(90 * (4 - c.index)) + "°): no quad mesh has a vertex of valence " +
            std::to_string(4 - c.index) + " (split such cones: param::ParamOptions::cone_split_distance)");
    }
    // Named also when the map is refused (the caller tells the refused cone from these).
    for (int f = 0; f < nf; ++f)
      if (component_unresolved[cl.copy_component[cl.corner_copy[3 * f]]])
        out.stats.faces_with_unresolved_cones.push_back(f);
    if (!out.status.is_ok()) return out;
  }
  param::PinnedLayoutOptions lopt;
  lopt.energy = options.energy;
  lopt.face_size = options.face_size;
  lopt.face_metric = options.face_metric;
  lopt.face_direction = options.face_direction;
  lopt.direction_weight = options.direction_weight;
  lopt.gauge_copies = gauge;
  lopt.prefer_free = is_cone_copy;
  lopt.max_element_entries = options.max_element_entries;
  const std::vector<Candidate> base_candidates(candidates.begin(),
                                               candidates.begin() + n_base_candidates);
  const Clock::time_point deadline =
      options.time_budget_seconds > 0
          ? t0 + std::chrono::duration_cast<Clock::duration>(
                     std::chrono::duration<double>(options.time_budget_seconds))
          : Clock::time_point::max();
  const Clock::time_point feature_deadline =
      options.feature_time_budget_seconds > 0
          ? std::min(deadline, t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                                        options.feature_time_budget_seconds)))
          : deadline;
  std::optional<Eigen::VectorXd> best;
  // The best map before its count adjustment (exact, as best), when the adjustment moved it.
  std::optional<Eigen::VectorXd> best_unadjusted;
  auto unadjusted_of = [](const Rounder& rounder) -> std::optional<Eigen::VectorXd> {
    Eigen::VectorXd xu;
    std::string why;
    if (rounder.unadjusted_x().size() == 0 ||
        !exact_expand(rounder.layout().reduction(), rounder.unadjusted_x(), &xu, &why))
      return std::nullopt;
    return xu;
  };
  int best_attempt = -1;
  core::Status failure;
  std::string last_stuck;
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
  // With aligned features, the target scale and its first two jitters keep them; if all dead-end
  // (feature curves closer than the grid allows), the features are dropped and every scale is
  // tried without them.
  struct Attempt {
    double scale;
    bool with_features, features_last;
  };
  std::vector<Attempt> attempts;
  // Releases the kept feature rows on the faces of the first of kReleaseRings vertex-ring
  // neighbourhoods of `faces` that holds some (see ReleaseFeatures).
  std::vector<std::vector<int>> vertex_faces;
  const ReleaseFeatures release = [&](const std::vector<int>& faces,
                                      std::vector<param::AffineRow>* rows,
                                      std::vector<char>* prefer_free_coords,
                                      std::vector<Candidate>* attempt_candidates) {
    if (vertex_faces.empty()) {
      vertex_faces.resize(mesh.n_vertices());
      for (int f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) vertex_faces[mesh.F(f, k)].push_back(f);
    }
    std::vector<char> in_region(nf, 0);
    std::vector<int> front;
    for (const int f : faces)
      if (f >= 0 && f < nf && !in_region[f]) {
        in_region[f] = 1;
        front.push_back(f);
      }
    int n = 0, grown = 0;
    for (const int rings : kReleaseRings) {
      for (; grown < rings; ++grown) {
        std::vector<int> next;
        for (const int f : front)
          for (int k = 0; k < 3; ++k)
            for (const int g : vertex_faces[mesh.F(f, k)])
              if (!in_region[g]) {
                in_region[g] = 1;
                next.push_back(g);
              }
        front = std::move(next);
      }
      for (size_t r = 0; r < feature_rows.size(); ++r)
        if (feature_kept[r] && in_region[feature_rows[r].face]) {
          feature_kept[r] = 0;
          ++n;
        }
      if (n > 0) break;
    }
    if (n == 0) return 0;
    select_features();
    *rows = kept_rows;
    *prefer_free_coords = feature_coords;
    *attempt_candidates = candidates;
    return n;
  };
  if (!feature_rows.empty())
    for (size_t i = 0; i < std::min<size_t>(kFeatureScaleTries, scales.size()); ++i) {
      attempts.push_back({scales[i], true, false});
      attempts.push_back({scales[i], true, true});
    }
  if (feature_rows.empty() || options.quantize_without_features)
    for (const double sc : scales) attempts.push_back({sc, false, false});
  // The layout options of a run at `scale` (with or without the kept feature rows) and its start:
  // the scaled copies, each component translated so that its gauge copy is at the origin.
  auto start_at = [&](double at_scale, bool with_features) {
    lopt.extra_rows = with_features ? kept_rows : std::vector<param::AffineRow>{};
    lopt.prefer_free_coords = with_features ? feature_coords : std::vector<char>{};
    lopt.rest_scale = at_scale * std::sqrt(area_uv / area3d);
    Eigen::VectorXd x(n_copy_vars);
    for (int k = 0; k < cl.n_copies(); ++k)
      x.segment<2>(2 * k) =
          at_scale * (cl.x.segment<2>(2 * k) - cl.x.segment<2>(2 * gauge[cl.copy_component[k]]));
    return x;
  };
  for (int attempt = 0; attempt < static_cast<int>(attempts.size()); ++attempt) {
    st.n_scale_retries = attempt;
    scale = attempts[attempt].scale;
    const bool with_features = attempts[attempt].with_features;
    const std::vector<Candidate>& attempt_candidates = with_features ? candidates : base_candidates;
    const Eigen::VectorXd x = start_at(scale, with_features);
    char label[48];
    std::snprintf(label, sizeof label, "x%.3f%s", scale / scales[0],
                  with_features ? (attempts[attempt].features_last ? " features-last" : "")
                                : (feature_rows.empty() ? "" : " no-features"));
    Rounder rounder(mesh, cl, attempt_candidates, is_cone_copy, options, &st,
                    with_features ? feature_deadline : deadline, label,
                    attempts[attempt].features_last, with_features ? release : ReleaseFeatures{});
    const Rounder::Outcome outcome = rounder.run(x, lopt);
    st.n_integer_dofs = rounder.n_integer_columns();
    if (outcome == Rounder::Outcome::kFailed && with_features && options.quantize_without_features &&
        rounder.status().code() == core::StatusCode::kNumericalFailure) {
      // With the features' rows eliminated, the layout can be too large to set up (dragon's
      // feature map: long aligned lines couple up to 939 unknowns in one triangle): the
      // features count as not fitting, and the attempts without them follow.
      last_stuck = rounder.status().message();
      st.features_dropped_reason = last_stuck;
      while (attempt + 1 < static_cast<int>(attempts.size()) && attempts[attempt + 1].with_features) ++attempt;
      continue;
    }
    if (outcome == Rounder::Outcome::kFailed) {
      failure = rounder.status();
      break;
    }
    if (outcome == Rounder::Outcome::kOutOfTime && with_features && feature_deadline < deadline) {
      // The features' own budget: they count as not fitting; the attempts without them follow.
      char msg[256];
      std::snprintf(msg, sizeof msg,
                    "the rounding with the aligned features exceeded its time budget of %.3g s "
                    "(%d of %d integer unknowns rounded)",
                    options.feature_time_budget_seconds, rounder.n_pinned(), rounder.n_integer_columns());
      last_stuck = msg;
      st.features_dropped_reason = msg;
      while (attempt + 1 < static_cast<int>(attempts.size()) && attempts[attempt + 1].with_features) ++attempt;
      continue;
    }
    if (outcome == Rounder::Outcome::kOutOfTime) {
      char msg[512];
      std::snprintf(msg, sizeof msg,
                    "quantization exceeded its time budget of %.3g s while rounding at scale "
                    "x%.3f of the target (attempt %d of %zu, %d of %d integer unknowns rounded); "
                    "a larger --time-budget, a larger --target-faces (fewer cone collisions) or "
                    "a larger --cone-pair-distance may help",
                    options.time_budget_seconds, scale / scales[0], attempt + 1, attempts.size(),
                    rounder.n_pinned(), rounder.n_integer_columns());
      failure = core::Status::not_converged(msg);
      st.out_of_time = true;
      break;
    }
    if (outcome == Rounder::Outcome::kStuck) {
      last_stuck = rounder.stuck_reason();
      if (with_features) st.features_dropped_reason = last_stuck;
      // The cones are rounded first in both orders: the other order would dead-end alike.
      if (with_features && rounder.stuck_on_cones() && attempt + 1 < static_cast<int>(attempts.size()) &&
          attempts[attempt + 1].with_features && attempts[attempt + 1].scale == scale)
        ++attempt;
      if (!with_features && options.continue_after_dead_end && attempt + 1 < static_cast<int>(attempts.size())) {
        DeadEnd de;
        de.attempt = attempt + 1;
        for (int a = 0; a <= attempt; ++a) de.attempts_without_features += !attempts[a].with_features;
        de.scale = scale / scales[0];
        de.cone_vertex = rounder.stuck_cone_vertex();
        de.faces = rounder.stuck_faces();
        de.reason = last_stuck;
        if (!options.continue_after_dead_end(de)) {
          st.stopped_at_dead_end = true;
          failure = core::Status::not_converged(
              "no flip-free integer-seamless map: stopped after " + std::to_string(attempt + 1) + " of " +
              std::to_string(attempts.size()) + " attempts at a dead end (" + last_stuck + ")");
          break;
        }
      }
      continue;
    }
    Eigen::VectorXd xe;
    std::string why;
    if (!exact_expand(rounder.layout().reduction(), rounder.layout().x(), &xe, &why)) {
      out.status = core::Status::internal("the constraint elimination is not dyadic (" + why +
                                          "): no exact integer map");
      st.seconds = seconds_since(t0);
      return out;
    }
    st.scale = scale;
    st.features_dropped = !feature_rows.empty() && !with_features;
    if (!st.features_dropped) st.features_dropped_reason.clear();
    st.n_released_feature_lines = rounder.n_released();
    st.n_released_feature_edges =
        with_features ? static_cast<int>(std::count(feature_kept.begin(), feature_kept.end(), 0))
                      : 0;
    candidates = rounder.candidates();
    st.n_candidates = static_cast<int>(candidates.size());
    best = xe;
    best_unadjusted = unadjusted_of(rounder);
    best_attempt = attempt;
    break;
  }
  // Count correction: the re-optimizations grow the map (rounded translations add area) by a
  // few percent beyond what the scale asks for (kExpectedGrowth on average, which the scale above
  // allows for with count_tolerance > 0), by an amount that differs from mesh to mesh and from
  // scale to scale (±2% at 5,000 quads). While the count is off by more than count_tolerance, the
  // rounding is run again at the scale that expects the growth halfway between the one measured
  // and the average one, without releasing features, and the map closest to the target is kept;
  // a run that dead-ends, flips or keeps fewer feature lines leaves the map as it is (the next
  // one tries a grid finer by half a near_scale_step).
  if (best && count_target > 0 && options.count_tolerance > 0) {
    const double target = count_target;
    double best_area = uv_area(cl, *best, nf);
    double last_growth = best_area / (st.scale * st.scale * area_uv) - 1;
    double stuck_scale = 0;  // of the last run, when it was not usable
    const Attempt& first = attempts[best_attempt];
    const std::vector<Candidate> attempt_candidates = first.with_features ? candidates : base_candidates;
    for (int r = 0; r < options.max_count_corrections &&
                    std::abs(best_area - target) > options.count_tolerance * target;
         ++r) {
      scale = stuck_scale > 0 ? stuck_scale * (1 + 0.5 * options.near_scale_step)
                              : std::sqrt(target / ((1 + 0.5 * (last_growth + kExpectedGrowth)) * area_uv));
      stuck_scale = 0;
      ++st.n_count_corrections;
      const Eigen::VectorXd x = start_at(scale, first.with_features);
      char label[48];
      std::snprintf(label, sizeof label, "x%.3f count", scale / scales[0]);
      Rounder rounder(mesh, cl, attempt_candidates, is_cone_copy, options, &st,
                      first.with_features ? feature_deadline : deadline, label, first.features_last);
      const Rounder::Outcome outcome = rounder.run(x, lopt);
      if (outcome == Rounder::Outcome::kOutOfTime || outcome == Rounder::Outcome::kFailed) break;
      Eigen::VectorXd xe;
      std::string why;
      if (outcome != Rounder::Outcome::kDone || rounder.n_released() > st.n_released_feature_lines ||
          !exact_expand(rounder.layout().reduction(), rounder.layout().x(), &xe, &why) ||
          count_flipped(cl, xe, nf) > 0) {
        // Not usable: the next run tries a slightly finer grid (dead ends come where the grid
        // is too coarse for the cones, as in the restarts above).
        stuck_scale = scale;
        continue;
      }
      const double last_area = uv_area(cl, xe, nf);
      last_growth = last_area / (scale * scale * area_uv) - 1;
      if (std::abs(last_area - target) < std::abs(best_area - target)) {
        best = xe;
        best_unadjusted = unadjusted_of(rounder);
        best_area = last_area;
        st.scale = scale;
        st.n_released_feature_lines = rounder.n_released();
        candidates = rounder.candidates();
        st.n_candidates = static_cast<int>(candidates.size());
        ++st.n_count_corrections_kept;
      }
    }
  }
  if (!best) {
    st.features_dropped =
        !feature_rows.empty() && (failure.is_ok() || st.stopped_at_dead_end) && !last_stuck.empty();
    out.status = failure.is_ok()
                     ? core::Status::not_converged(
                           "no flip-free integer-seamless map within " +
                           std::to_string(attempts.size()) + " attempts" +
                           (last_stuck.empty() ? "" : " (last: " + last_stuck + ")"))
                     : failure;
    st.seconds = seconds_since(t0);
    return out;
  }
  // Exact verification of Def. 3.2 (of the map before its count adjustment too, which the
  // result keeps when it is exact and flip-free).
  auto verify_exact = [&](const Eigen::VectorXd& x, int* n_rounded) {
    int rounded = 0;
    for (size_t i = 0; i < candidates.size(); ++i) {
      const double v = candidates[i].value(x);
      rounded += v == std::round(v);
      if (v != std::round(v) && !candidates[i].is_feature)
        return core::Status::internal("integer quantity " + std::to_string(i) + " is " +
                                      std::to_string(v) + ", not an exact integer after snapping");
    }
    for (const param::CopySeam& s : cl.seams) {
      const Eigen::Vector2d ea = x.segment<2>(2 * s.a1) - x.segment<2>(2 * s.a0);
      const Eigen::Vector2d eb = x.segment<2>(2 * s.b1) - x.segment<2>(2 * s.b0);
      Eigen::Vector2d rea;
      for (int d = 0; d < 2; ++d)
        rea[d] = rotation_entry(s.matching, d, 0) * ea[0] + rotation_entry(s.matching, d, 1) * ea[1];
      if (eb != rea)
        return core::Status::internal("seam between faces " + std::to_string(s.face_a) + " and " +
                                      std::to_string(s.face_b) + " is not exactly seamless after snapping");
    }
    if (n_rounded) *n_rounded = rounded;
    return core::Status::ok();
  };
  const Eigen::VectorXd& x = *best;
  if (const core::Status exact = verify_exact(x, &st.n_rounded); !exact.is_ok()) {
    out.status = exact;
    st.seconds = seconds_since(t0);
    return out;
  }
  for (int c = 0; c < 3 * nf; ++c)
    out.uv.corner_uv.row(c) = x.segment<2>(2 * cl.corner_copy[c]).transpose();
  if (best_unadjusted && verify_exact(*best_unadjusted, nullptr).is_ok() &&
      count_flipped(cl, *best_unadjusted, nf) == 0) {
    out.uv_unadjusted = out.uv;
    for (int c = 0; c < 3 * nf; ++c)
      out.uv_unadjusted.corner_uv.row(c) = best_unadjusted->segment<2>(2 * cl.corner_copy[c]).transpose();
    st.uv_area_unadjusted = uv_area(cl, *best_unadjusted, nf);
  }
  if (!st.features_dropped)
    for (const FeatureRow& fr : feature_rows) {
      const param::AffineRow& row = fr.row;
      const double v = x[row.entries[0].first];
      st.n_aligned_features += v == std::round(v) && x[row.entries[1].first] == v;
    }
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

double recommended_cone_scale(const core::TriMesh& mesh, const QuantizeOptions& options, int n_cones,
                              double quads_per_cone) {
  if (mesh.n_faces() == 0) return 0;
  const double h = target_edge_length(mesh, options);
  const double target_quads = surface_area(mesh) / (h * h);
  // Cones beyond what the topology asks for: a closed surface of Euler characteristic χ needs
  // at least 4|χ| of them (eight on a sphere), which no smoothing removes.
  const core::TopologyStats topo = core::topology_stats(mesh);
  const int needed = topo.n_boundary_loops == 0 ? 4 * std::abs(topo.euler_characteristic) : 0;
  return (n_cones - needed) * quads_per_cone > target_quads ? kCoarseConeQuadEdges * h : 0;
}

namespace {

// The curves (connected components) of `edges`, vertex-id pairs of `mesh`: each edge's curve (a
// root vertex; -1 for an edge with a vertex out of range) and each curve's length in model units
// (indexed by its root vertex; every listed edge counts).
struct Curves {
  std::vector<int> edge_curve;
  std::vector<double> length;
};

Curves find_curves(const core::TriMesh& mesh, const std::vector<std::array<int, 2>>& edges) {
  const int nv = mesh.n_vertices();
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  auto valid = [&](const std::array<int, 2>& e) { return e[0] >= 0 && e[1] >= 0 && e[0] < nv && e[1] < nv; };
  for (const auto& e : edges)
    if (valid(e)) parent[find(e[0])] = find(e[1]);
  Curves c;
  c.edge_curve.assign(edges.size(), -1);
  c.length.assign(nv, 0);
  for (size_t i = 0; i < edges.size(); ++i)
    if (valid(edges[i])) {
      const int r = c.edge_curve[i] = find(edges[i][0]);
      c.length[r] += (mesh.V.row(edges[i][0]) - mesh.V.row(edges[i][1])).norm();
    }
  return c;
}

}  // namespace

std::vector<std::array<int, 2>> features_for_density(
    const core::TriMesh& mesh, const std::vector<std::array<int, 2>>& feature_edges,
    const QuantizeOptions& options, double min_quad_edges) {
  const Curves curves = find_curves(mesh, feature_edges);
  std::vector<int> degree(mesh.n_vertices(), 0);
  for (size_t i = 0; i < feature_edges.size(); ++i)
    if (curves.edge_curve[i] >= 0) {
      ++degree[feature_edges[i][0]];
      ++degree[feature_edges[i][1]];
    }
  std::vector<char> open(mesh.n_vertices(), 0);
  for (size_t i = 0; i < feature_edges.size(); ++i)
    if (curves.edge_curve[i] >= 0 && (degree[feature_edges[i][0]] != 2 || degree[feature_edges[i][1]] != 2))
      open[curves.edge_curve[i]] = 1;
  const double h = target_edge_length(mesh, options);
  std::vector<std::array<int, 2>> kept;
  for (size_t i = 0; i < feature_edges.size(); ++i) {
    const int r = curves.edge_curve[i];
    if (r >= 0 && curves.length[r] >= min_quad_edges * h * (open[r] ? 1 : 4)) kept.push_back(feature_edges[i]);
  }
  return kept;
}

CurveSummary summarize_curves(const core::TriMesh& mesh, const std::vector<std::array<int, 2>>& edges,
                              const QuantizeOptions& options, double knife_deg) {
  CurveSummary out;
  const Curves curves = find_curves(mesh, edges);
  // The faces on each edge (by its sorted vertex pair), for the dihedral angles.
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  std::map<std::pair<int, int>, int> edge_curve;
  for (size_t i = 0; i < edges.size(); ++i)
    if (curves.edge_curve[i] >= 0) {
      const std::pair<int, int> key{std::min(edges[i][0], edges[i][1]), std::max(edges[i][0], edges[i][1])};
      edge_faces[key];
      edge_curve[key] = curves.edge_curve[i];
    }
  if (edge_faces.empty()) return out;
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      const auto it = edge_faces.find({std::min(a, b), std::max(a, b)});
      if (it != edge_faces.end()) it->second.push_back(f);
    }
  auto normal = [&](int f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)), p2 = mesh.V.row(mesh.F(f, 2));
    return (p1 - p0).cross(p2 - p0).normalized();
  };
  std::map<int, std::vector<double>> angles;
  for (const auto& [e, faces] : edge_faces)
    if (faces.size() == 2)
      angles[edge_curve[e]].push_back(
          std::acos(std::clamp(normal(faces[0]).dot(normal(faces[1])), -1.0, 1.0)) * 180 / std::numbers::pi);
  const double h = target_edge_length(mesh, options);
  for (const double l : curves.length) out.longest_quad_edges = std::max(out.longest_quad_edges, l / h);
  for (auto& [r, a] : angles) {
    std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
    if (a[a.size() / 2] >= knife_deg) out.has_knife_edge = true;
  }
  return out;
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
