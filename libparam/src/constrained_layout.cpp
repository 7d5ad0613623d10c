#include <libcore/topology.h>
#include <libparam/constrained_layout.h>

#include <libcore/predicates.h>
#include <libcore/sparse_solver.h>

#include <Eigen/Geometry>
#include <Eigen/LU>

#ifdef QUADIFY_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#endif

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <cstdint>
#include <array>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>

#include "constraint_elimination.h"
#include "direction_alignment.h"
#include "distortion_energy.h"
#include "cut_layout.h"
#include "layout_optimizer.h"

namespace quadify::param {
namespace {

// Dimensionless penalty weights (× area / Σ edge²) of the optional long homotopy.
constexpr double kHomotopyWeights[] = {1e0, 1e2, 1e4, 1e6};
// Newton stop of the homotopy stages (fraction of the energy): run the iterations out.
constexpr double kHomotopyTolerance = 1e-12;

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Entry (d, j) of R_90^r.
double rotation_entry(int r, int d, int j) {
  const Eigen::Vector2d col =
      rotate_quarter(j == 0 ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1), r);
  return col[d];
}

// Sums duplicate variables and drops zero coefficients.
SparseRow compress(const std::map<int, double>& acc) {
  SparseRow row;
  for (const auto& [v, a] : acc)
    if (a != 0) row.entries.push_back({v, a});
  return row;
}

// The copy fixed per component (translation gauge): gauge[comp] when given and valid, else the
// component's first copy.
std::vector<int> gauge_fixed_copies(const CopyLayout& copies, const std::vector<int>& gauge) {
  const int n = copies.n_copies();
  std::vector<char> gauge_set(copies.n_components, 0);
  std::vector<int> fixed;
  auto fix_copy = [&](int k) {
    fixed.push_back(k);
    gauge_set[copies.copy_component[k]] = 1;
  };
  for (int comp = 0; comp < copies.n_components; ++comp) {
    const int g = gauge.empty() ? -1 : gauge[comp];
    if (g >= 0 && g < n && copies.copy_component[g] == comp) fix_copy(g);
  }
  for (int k = 0; k < n; ++k)
    if (copies.copy_component[k] >= 0 && !gauge_set[copies.copy_component[k]]) fix_copy(k);
  return fixed;
}

}  // namespace

core::Status build_copy_layout(const core::TriMesh& mesh, const Eigen::MatrixX2d& corner_uv,
                               const std::vector<SeamMatching>& seams, double seam_tol,
                               CopyLayout* out) {
  const int nf = mesh.n_faces();
  if (corner_uv.rows() != 3 * nf)
    return core::Status::invalid_input("corner_uv has " + std::to_string(corner_uv.rows()) +
                                       " rows, expected 3·#F = " + std::to_string(3 * nf));
  if (!corner_uv.allFinite()) return core::Status::invalid_input("corner_uv is not finite");
  core::EdgeTopology topo;
  try {
    topo = core::build_edge_topology(mesh);
  } catch (const std::invalid_argument& e) {
    return core::Status::invalid_input(e.what());
  }
  // Seam list → matching per edge.
  std::vector<int> edge_matching(topo.n_edges(), -1);
  for (const SeamMatching& s : seams) {
    int he = -1;
    if (s.face_a >= 0 && s.face_a < nf)
      for (int k = 0; k < 3; ++k)
        if (mesh.F(s.face_a, k) == s.edge_vertex0 &&
            mesh.F(s.face_a, (k + 1) % 3) == s.edge_vertex1)
          he = 3 * s.face_a + k;
    if (he < 0 || topo.twin[he] < 0 || topo.twin[he] / 3 != s.face_b)
      return core::Status::invalid_input("seam (" + std::to_string(s.edge_vertex0) + ", " +
                                         std::to_string(s.edge_vertex1) + ") of faces " +
                                         std::to_string(s.face_a) + "/" + std::to_string(s.face_b) +
                                         " is not an interior edge of the mesh");
    // Store the matching in the orientation of edge_halfedge.
    const int e = topo.face_edge(he / 3, he % 3);
    edge_matching[e] = topo.edge_halfedge[e] == he ? ((s.matching % 4) + 4) % 4
                                                   : ((4 - s.matching % 4) % 4 + 4) % 4;
  }
  // Merge corners across edges without a seam.
  std::vector<int> parent(3 * nf);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> is_seam(topo.n_edges(), 0);
  for (int e = 0; e < topo.n_edges(); ++e) {
    const int he = topo.edge_halfedge[e], tw = topo.twin[he];
    if (tw < 0) continue;
    const int fa = he / 3, ka = he % 3, fb = tw / 3, kb = tw % 3;
    const int ca0 = 3 * fa + ka, ca1 = 3 * fa + (ka + 1) % 3;
    const int cb1 = 3 * fb + kb, cb0 = 3 * fb + (kb + 1) % 3;
    const bool agree =
        corner_uv.row(ca0) == corner_uv.row(cb0) && corner_uv.row(ca1) == corner_uv.row(cb1);
    if (edge_matching[e] > 0 || (edge_matching[e] == 0 && !agree)) {
      is_seam[e] = 1;
      continue;
    }
    if (!agree)
      return core::Status::invalid_input(
          "edge (" + std::to_string(mesh.F(fa, ka)) + ", " +
          std::to_string(mesh.F(fa, (ka + 1) % 3)) + ") between faces " + std::to_string(fa) +
          " and " + std::to_string(fb) +
          " has different UVs on its sides but is not a listed seam");
    parent[find_root(parent, ca0)] = find_root(parent, cb0);
    parent[find_root(parent, ca1)] = find_root(parent, cb1);
  }
  CopyLayout cl;
  cl.corner_copy.assign(3 * nf, -1);
  std::vector<int> root_copy(3 * nf, -1);
  for (int c = 0; c < 3 * nf; ++c) {
    const int r = find_root(parent, c);
    if (root_copy[r] < 0) {
      root_copy[r] = cl.n_copies();
      cl.copy_vertex.push_back(mesh.F(c / 3, c % 3));
    }
    cl.corner_copy[c] = root_copy[r];
  }
  std::vector<int> face_comp;
  cl.n_components = core::face_components(mesh, topo, &face_comp);
  cl.copy_component.assign(cl.n_copies(), -1);
  cl.x.resize(2 * cl.n_copies());
  for (int c = 0; c < 3 * nf; ++c) {
    const int k = cl.corner_copy[c];
    cl.copy_component[k] = face_comp[c / 3];
    cl.x.segment<2>(2 * k) = corner_uv.row(c).transpose();
  }
  // Seams with their residuals.
  Eigen::Vector2d lo = corner_uv.colwise().minCoeff(), hi = corner_uv.colwise().maxCoeff();
  const double tol = seam_tol * std::max((hi - lo).norm(), 1e-300);
  for (int e = 0; e < topo.n_edges(); ++e) {
    if (!is_seam[e]) continue;
    const int he = topo.edge_halfedge[e], tw = topo.twin[he];
    const int fa = he / 3, ka = he % 3, fb = tw / 3, kb = tw % 3;
    CopySeam s;
    s.face_a = fa;
    s.face_b = fb;
    s.a0 = cl.corner_copy[3 * fa + ka];
    s.a1 = cl.corner_copy[3 * fa + (ka + 1) % 3];
    s.b1 = cl.corner_copy[3 * fb + kb];
    s.b0 = cl.corner_copy[3 * fb + (kb + 1) % 3];
    s.matching = std::max(0, edge_matching[e]);
    const Eigen::Vector2d ea = cl.x.segment<2>(2 * s.a1) - cl.x.segment<2>(2 * s.a0);
    const Eigen::Vector2d eb = cl.x.segment<2>(2 * s.b1) - cl.x.segment<2>(2 * s.b0);
    const double residual = (eb - rotate_quarter(ea, s.matching)).norm();
    if (!(residual <= tol))
      return core::Status::invalid_input(
          "seam edge (" + std::to_string(mesh.F(fa, ka)) + ", " +
          std::to_string(mesh.F(fa, (ka + 1) % 3)) + ") between faces " + std::to_string(fa) +
          " and " + std::to_string(fb) + " violates its matching " + std::to_string(s.matching) +
          ": residual " + std::to_string(residual) + " > " + std::to_string(tol));
    cl.seams.push_back(s);
  }
  *out = std::move(cl);
  return core::Status::ok();
}

ConstrainedLayoutResult solve_constrained_layout(const core::TriMesh& mesh,
                                                 const CopyLayout& copies,
                                                 const Eigen::VectorXd& x0,
                                                 const std::vector<AffineRow>& old_rows,
                                                 const std::vector<AffineRow>& new_rows,
                                                 const ConstrainedLayoutOptions& options) {
  ConstrainedLayoutResult res;
  const int nf = mesh.n_faces();
  const int n = copies.n_copies();
  const int n_seams = static_cast<int>(copies.seams.size());
  const int n_ext = 2 * n + 2 * n_seams;
  if (static_cast<int>(copies.corner_copy.size()) != 3 * nf ||
      (x0.size() != 2 * n && x0.size() != n_ext) || !(options.rest_scale > 0) ||
      (!options.face_size.empty() && static_cast<int>(options.face_size.size()) != nf) ||
      (!options.face_metric.empty() && static_cast<int>(options.face_metric.size()) != nf) ||
      (!options.gauge_copies.empty() &&
       static_cast<int>(options.gauge_copies.size()) != copies.n_components)) {
    res.status = core::Status::invalid_input("solve_constrained_layout: sizes do not match");
    return res;
  }
  // Internal variables: [one, 0 | translations (2 per seam) | copies (2 each)]. The eliminator
  // pivots on the highest-index unit coefficient, so copies become dependent on the
  // translations: x_b0 = R^r x_a0 + t, and integer rows on translations stay unimodular.
  const int kOne = 0, t_base = 2, x_base = 2 + 2 * n_seams;
  const int n_vars = x_base + 2 * n;
  auto internal = [&](int e) { return e < 2 * n ? x_base + e : t_base + (e - 2 * n); };
  auto homogenize = [&](const AffineRow& row) {
    std::map<int, double> acc;
    for (const auto& [v, a] : row.entries) acc[internal(v)] += a;
    if (row.rhs != 0) acc[kOne] -= row.rhs;
    return compress(acc);
  };
  for (const auto* rows : {&old_rows, &new_rows})
    for (const AffineRow& row : *rows)
      for (const auto& [v, a] : row.entries)
        if (v < 0 || v >= n_ext) {
          res.status = core::Status::invalid_input("solve_constrained_layout: variable " +
                                                   std::to_string(v) + " out of range");
          return res;
        }
  // The domain: faces over the internal copies, rest frames of the 3D triangles × rest_scale.
  LayoutDomain domain;
  domain.n_copies = n_vars / 2;
  domain.face_copies.resize(nf);
  domain.rest_inverse.resize(nf);
  domain.area.resize(nf);
  double total_area = 0, edge_len = 0;
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k)
      domain.face_copies[f][k] = x_base / 2 + copies.corner_copy[3 * f + k];
    const Eigen::Matrix2d dm = sized_rest_frame(mesh, f, options.rest_scale, options.face_size,
                                                options.face_metric, &domain.area[f]);
    domain.rest_inverse[f] = dm.inverse();
    total_area += domain.area[f];
    edge_len += dm(0, 0);
  }
  edge_len /= std::max(nf, 1);

  std::vector<char> never_pivot(n_vars, 0);
  never_pivot[kOne] = never_pivot[kOne + 1] = 1;
  for (int k : gauge_fixed_copies(copies, options.gauge_copies))
    never_pivot[x_base + 2 * k] = never_pivot[x_base + 2 * k + 1] = 1;

  // Seam rows: x_b0 − R^r x_a0 − t = 0 and x_b1 − R^r x_a1 − t = 0.
  ConstraintEliminator elim(n_vars, never_pivot);
  for (int si = 0; si < n_seams; ++si) {
    const CopySeam& s = copies.seams[si];
    for (const auto& [a, b] : {std::pair{s.a0, s.b0}, std::pair{s.a1, s.b1}})
      for (int d = 0; d < 2; ++d) {
        std::map<int, double> acc;
        acc[x_base + 2 * b + d] += 1;
        for (int j = 0; j < 2; ++j)
          if (const double r = rotation_entry(s.matching, d, j); r != 0)
            acc[x_base + 2 * a + j] -= r;
        acc[t_base + 2 * si + d] -= 1;
        elim.add_row(compress(acc));
      }
  }
  for (const AffineRow& row : old_rows) elim.add_row(homogenize(row));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n_vars);
  x[kOne] = 1;
  x.segment(x_base, 2 * n) = x0.head(2 * n);
  for (int si = 0; si < n_seams; ++si) {
    const CopySeam& s = copies.seams[si];
    x.segment<2>(t_base + 2 * si) = x.segment<2>(x_base + 2 * s.b0) -
                                    rotate_quarter(x.segment<2>(x_base + 2 * s.a0), s.matching);
  }
  const Reduction old_red = elim.reduction(x);
  x = old_red.expand(old_red.restrict(x));

  std::vector<SparseRow> added;
  res.independent.assign(new_rows.size(), 0);
  for (size_t i = 0; i < new_rows.size(); ++i) {
    SparseRow row = homogenize(new_rows[i]);
    if (elim.add_row(row)) {
      res.independent[i] = 1;
      added.push_back(std::move(row));
    }
  }
  int n_never_pivot = 0;
  for (char c : never_pivot) n_never_pivot += c;
  Reduction red;
  if (options.reduce_only) {
    red = elim.reduction(x);
  } else if (n_vars - n_never_pivot - elim.rank() == 0) {
    // No freedom left (e.g. every vertex pinned): the layout is the constant part. Handled here
    // because the projection would factor an empty matrix.
    red = elim.reduction(x);
    x = red.c;
  } else if (!added.empty()) {
    // Penalty unit: area / Σ (length scale)², one UV edge per pair of new rows.
    const double weight_unit =
        total_area /
        std::max(1e-300, 0.5 * static_cast<double>(added.size()) * edge_len * edge_len);
    // Optional long homotopy inside the old space before the transition: large moves (cones
    // pulled apart onto distinct grid points) need more Newton steps than its stages take.
    if (options.homotopy_iterations > 0) {
      Eigen::VectorXd y = old_red.restrict(x);
      for (const double w : kHomotopyWeights) {
        OptimizeSettings st;
        st.max_iterations = options.homotopy_iterations;
        st.relative_tolerance = kHomotopyTolerance;
        st.penalty_rows = &added;
        st.penalty_weight = w * weight_unit;
        const OptimizeReport r = optimize_layout(domain, old_red, st, &y);
        res.iterations += r.iterations;
        if (!r.status.is_ok()) break;
        x = old_red.expand(y);
      }
    }
    TransitionReport tr = move_into_constraints(domain, old_red, elim, added, weight_unit, &x);
    res.iterations += tr.iterations;
    red = std::move(tr.reduction);
    res.status = tr.status;
  } else {
    red = old_red;
  }
  res.n_flipped = options.reduce_only ? 0 : count_flipped(domain, x);
  if (!options.reduce_only && res.n_flipped == 0 && res.status.is_ok()) {
    OptimizeSettings st;
    const EnergyDensity ed = energy_density(options.energy);
    st.density = ed.density;
    st.power = ed.power;
    st.max_iterations = options.max_newton_iters;
    st.relative_tolerance = options.relative_tolerance;
    Eigen::VectorXd y = red.restrict(x);
    const OptimizeReport rep = optimize_layout(domain, red, st, &y);
    res.iterations += rep.iterations;
    if (rep.status.is_ok()) {
      const Eigen::VectorXd xn = red.expand(y);
      if (count_flipped(domain, xn) == 0) x = xn;
    }
    if (!options.tau_powers.empty()) {
      LayoutProblem problem(domain, red);
      for (const double p : options.tau_powers) {
        OptimizeSettings ts;
        ts.density = Density::kPowerSD;
        ts.power = p;
        ts.max_iterations = kTauStageIterations;
        ts.relative_tolerance = kTauStageTolerance;
        Eigen::VectorXd yt = red.restrict(x);
        const OptimizeReport tr = optimize_layout(problem, ts, &yt);
        res.iterations += tr.iterations;
        if (!tr.status.is_ok() || !std::isfinite(tr.energy)) break;
        const Eigen::VectorXd xn = red.expand(yt);
        if (count_flipped(domain, xn) != 0) break;
        x = xn;
      }
    }
    res.n_flipped = count_flipped(domain, x);
  }
  if (res.status.is_ok() && res.n_flipped > 0)
    res.status = core::Status::not_converged(std::to_string(res.n_flipped) +
                                             " flipped faces in the constrained layout");
  // Back to the external order [copies | translations].
  std::vector<int> ext_of(n_vars, -1);
  for (int e = 0; e < n_ext; ++e) ext_of[internal(e)] = e;
  res.x.resize(n_ext);
  for (int e = 0; e < n_ext; ++e) res.x[e] = x[internal(e)];
  Eigen::SparseMatrix<double, Eigen::RowMajor> P(n_ext, red.n_free());
  std::vector<Eigen::Triplet<double>> trip;
  res.reduction.c.resize(n_ext);
  for (int e = 0; e < n_ext; ++e) {
    res.reduction.c[e] = red.c[internal(e)];
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, internal(e)); it;
         ++it)
      trip.emplace_back(e, static_cast<int>(it.col()), it.value());
  }
  P.setFromTriplets(trip.begin(), trip.end());
  res.reduction.P = std::move(P);
  for (int v : red.free_vars) res.reduction.free_vars.push_back(ext_of[v]);
  return res;
}

}  // namespace quadify::param

namespace quadify::param {
namespace {

// P holds sums of products of small integers; anything this small is cancellation round-off.
constexpr double kPinCancelled = 1e-12;
// Fraction of the largest flip-free step taken, so triangles keep a positive area.
constexpr double kPinStepFraction = 0.8;
// Armijo constant and halvings of the energy line search.
constexpr double kPinArmijo = 1e-4;
constexpr int kPinBacktracks = 40;
// Halvings of a prescribed step that the exact predicate found flipped (round-off at the bound).
constexpr int kPinExactHalvings = 10;
// Diagonal shift relative to the mean Hessian diagonal (the global rotation is a null mode).
constexpr double kPinRegularization = 1e-9;
// Below this many faces the per-face evaluation runs serially.
constexpr int kPinParallelMinFaces = 2048;
// Consecutive stalled steps of PinnedLayout::pin before the blocking targets are dropped.
constexpr int kStalledSteps = 2;
// Newton stop of a penalty stage (fraction of the energy). A stage only has to bring the targets
// closer for the next, heavier one; 1e-8 until 2026-12-06 ran most stages to their iteration cap:
// 1e-5 gives the same figures on the 20-mesh regression at 5,000 quads with 17% fewer Newton
// steps of quantization (dilo 264 → 156, beetle 375 → 246).
constexpr double kPinStageTolerance = 1e-5;
// A penalty stage counts as progress for a target when its residual shrinks below this fraction.
constexpr double kPinShrink = 0.5;
// A target whose residual after the homotopy is above this fraction of its initial distance
// is held back by the barrier (it blocks).
constexpr double kPinHeldBack = 0.05;


}  // namespace

struct PinnedLayout::Impl {
  struct Face {
    std::vector<int> ys;                             // reduced variables of the face
    Eigen::Matrix<double, 4, Eigen::Dynamic> M;      // edge-vector coordinates = M·y[ys] (narrow)
    int wide = -1;                                   // index among the wide faces, or -1
  };
  // Wide faces (more free variables than PinnedLayoutOptions::wide_face_variables: with hundreds
  // of cones, the loops around them are solved for translations, which then depend on every cone
  // on one side of a seam, and a face along that seam on all of them) store no k×k Hessian: they
  // are assembled in the internal coordinates, 6 per face, into Hx and mapped once per evaluation,
  // H += Pwᵀ·Hx·Pw, whose entries the faces along one seam share (dragon at its default density
  // had faces of 460 variables, 9.2e7 element entries, 3 GB). Per wide face: the local indices
  // (2·corner + d) of its coordinates and the offsets of its 6×6 block in Hx's values; Pw: P's
  // rows of those coordinates; s_entry: per entry of the product (a fixed pattern) its offset in
  // H's values.
  struct Wide {
    std::vector<int> faces;
    std::vector<int> var;                            // local index → internal variable
    std::vector<std::array<int, 6>> local;
    std::vector<std::array<int, 36>> hx_entry;
    Eigen::SparseMatrix<double> Hx, Pw, PwT;
    std::vector<int> s_entry;
    std::vector<double> g6, h6;                      // per wide face: 6 and 36 values
    Eigen::VectorXd gx;
    bool empty() const { return faces.empty(); }
  };
  Wide wide;
  LayoutDomain domain;
  Reduction red;                  // internal variables
  ConstrainedReduction ext;       // external order
  std::vector<int> ext_to_int;
  std::vector<Face> faces;
  Eigen::SparseMatrix<double> H;  // fixed pattern, both triangles
  std::vector<int> diag_offset;
  core::SparseSolver solver;
  Density density = Density::kSymmetricDirichlet;
  double power = 1;
  Eigen::VectorXd y, x;           // reduced and internal full variables
  std::vector<char> state;        // per reduced variable: 0 free, 1 pinned, 2 prescribed
  // Quadratic penalty w·Σ (y_j − target)² of PinnedLayout::pin's homotopy (free variables).
  std::vector<std::pair<int, double>> penalty;
  double penalty_weight = 0;
  // Direction alignment: per face the image coefficients (α, β) of its direction (zero: none),
  // the penalized UV coordinate and the weight (see PinnedLayoutOptions::face_direction).
  std::vector<Eigen::Vector2d> dir_coef;
  std::vector<int> dir_axis;
  double dir_weight = 0;
  std::vector<double> face_value;
  // Per-face gradients and Hessians in the reduced variables, one flat array each: face f's
  // gradient at g_base[f] (k entries), its Hessian at h_base[f] (k×k, column-major).
  std::vector<double> face_g, face_h;
  std::vector<size_t> g_base, h_base;
  // The assembly as a gather: H's value e sums face_h[h_source[h_start[e] ..]] and free variable
  // i's gradient face_g[g_source[g_start[i] ..]], both in face order, the order in which a
  // scatter over the faces adds them (the same sums to the bit), so that entries and variables
  // can be summed in parallel. h_row/h_col: the entry's row and column.
  std::vector<size_t> h_start, g_start;
  std::vector<std::uint32_t> h_source, g_source;
  std::vector<int> h_row, h_col;

  int n() const { return red.n_free(); }

  // work(i) for i in [0, n), in parallel chunks of `grain` from kPinParallelMinFaces items on.
  template <class F>
  void for_range(int n, int grain, F&& work) {
#ifdef QUADIFY_WITH_TBB
    if (n >= kPinParallelMinFaces) {
      tbb::parallel_for(tbb::blocked_range<int>(0, n, grain),
                        [&](const tbb::blocked_range<int>& r) {
                          for (int i = r.begin(); i < r.end(); ++i) work(i);
                        });
      return;
    }
#endif
    for (int i = 0; i < n; ++i) work(i);
  }
  template <class F>
  void for_faces(F&& work) {
    for_range(domain.n_faces(), 256, work);
  }

  Eigen::Matrix2d edge_matrix(const Eigen::VectorXd& xx, int f) const {
    const auto& fc = domain.face_copies[f];
    Eigen::Matrix2d X;
    for (int d = 0; d < 2; ++d) {
      X(d, 0) = xx[2 * fc[1] + d] - xx[2 * fc[0] + d];
      X(d, 1) = xx[2 * fc[2] + d] - xx[2 * fc[0] + d];
    }
    return X;
  }

  // Energy at xx; with derivatives: gradient g (0 at non-free variables) and H (identity rows
  // and columns at non-free variables). With v: Hv = H_full·v on the free rows.
  double evaluate(const Eigen::VectorXd& xx, bool derivatives, Eigen::VectorXd* g,
                  const Eigen::VectorXd* v = nullptr, Eigen::VectorXd* Hv = nullptr) {
    const int nf = domain.n_faces();
    face_value.resize(nf);
    if (derivatives) {
      face_g.resize(g_base[nf]);  // no-ops after the first evaluation
      face_h.resize(h_base[nf]);
    }
    for_faces([&](int f) {
      const Eigen::Matrix2d J = edge_matrix(xx, f) * domain.rest_inverse[f];
      const DensityEval ev = evaluate_density(density, power, J, derivatives, true);
      const double a = domain.area[f];
      face_value[f] = ev.finite ? a * ev.value : std::numeric_limits<double>::infinity();
      // Alignment term w·a·q², q = Σ_j c_j·X(k, j) (local edge-vector variable 2j + k).
      const bool aligned = !dir_coef.empty() && dir_coef[f].squaredNorm() > 0;
      double q = 0;
      if (aligned) {
        const Eigen::Matrix2d X = edge_matrix(xx, f);
        q = dir_coef[f].x() * X(dir_axis[f], 0) + dir_coef[f].y() * X(dir_axis[f], 1);
        face_value[f] += dir_weight * a * q * q;
      }
      if (!derivatives || !ev.finite) return;
      Eigen::Vector4d g4;
      Eigen::Matrix4d h4;
      edge_vector_derivatives(domain.rest_inverse[f], a, ev, &g4, &h4);
      if (aligned)
        for (int j = 0; j < 2; ++j) {
          g4[2 * j + dir_axis[f]] += 2 * dir_weight * a * q * dir_coef[f][j];
          for (int i = 0; i < 2; ++i)
            h4(2 * j + dir_axis[f], 2 * i + dir_axis[f]) +=
                2 * dir_weight * a * dir_coef[f][j] * dir_coef[f][i];
        }
      const Face& el = faces[f];
      if (el.wide >= 0) {  // in the internal coordinates: x-edge (2j + d) = x_{j+1,d} − x_{0,d}
        double* g6 = wide.g6.data() + 6 * el.wide;
        double* h6 = wide.h6.data() + 36 * el.wide;
        Eigen::Matrix<double, 4, 6> D = Eigen::Matrix<double, 4, 6>::Zero();
        for (int j = 0; j < 2; ++j)
          for (int d = 0; d < 2; ++d) {
            D(2 * j + d, 2 * (j + 1) + d) = 1;
            D(2 * j + d, d) = -1;
          }
        Eigen::Map<Eigen::Matrix<double, 6, 1>> g6_map(g6);
        Eigen::Map<Eigen::Matrix<double, 6, 6>> h6_map(h6);
        g6_map = D.transpose() * g4;
        h6_map = D.transpose() * h4 * D;
        return;
      }
      // M'·g4 and M'·h4·M column by column: no temporaries, no GEMM set-up for a k×k result.
      const Eigen::Index k = el.M.cols();
      double* fg = face_g.data() + g_base[f];
      double* fh = face_h.data() + h_base[f];
      for (Eigen::Index i = 0; i < k; ++i) {
        const Eigen::Vector4d hm = h4 * el.M.col(i);
        fg[i] = el.M.col(i).dot(g4);
        for (Eigen::Index j = 0; j <= i; ++j) fh[j + i * k] = fh[i + j * k] = el.M.col(j).dot(hm);
      }
    });
    double energy = 0;
    for (int f = 0; f < nf; ++f) {
      if (!std::isfinite(face_value[f])) return std::numeric_limits<double>::infinity();
      energy += face_value[f];
    }
    if (!derivatives) return energy;
    g->resize(n());
    double* vals = H.valuePtr();
    for_range(n(), 4096, [&](int i) {
      double sum = 0;
      if (state[i] == 0)
        for (size_t s = g_start[i]; s < g_start[i + 1]; ++s) sum += face_g[g_source[s]];
      (*g)[i] = sum;
    });
    for_range(static_cast<int>(H.nonZeros()), 4096, [&](int e) {
      double sum = 0;
      if (state[h_row[e]] == 0 && state[h_col[e]] == 0)
        for (size_t s = h_start[e]; s < h_start[e + 1]; ++s) sum += face_h[h_source[s]];
      else if (h_row[e] == h_col[e])
        sum = 1;
      vals[e] = sum;
    });
    if (!wide.empty()) add_wide(g);
    if (Hv) {  // the free rows' response to the non-free columns' displacement v
      Hv->setZero(n());
      if (!wide.empty()) {
        Eigen::VectorXd vn = Eigen::VectorXd::Zero(n());
        for (int i = 0; i < n(); ++i)
          if (state[i] != 0) vn[i] = (*v)[i];
        const Eigen::VectorXd hv = wide.PwT * (wide.Hx * (wide.Pw * vn));
        for (int i = 0; i < n(); ++i)
          if (state[i] == 0) (*Hv)[i] += hv[i];
      }
      for (int f = 0; f < nf; ++f) {
        const Face& el = faces[f];
        if (el.wide >= 0) continue;
        const size_t k = el.ys.size();
        const double* fh = face_h.data() + h_base[f];
        for (size_t j = 0; j < k; ++j) {
          if (state[el.ys[j]] == 0) continue;
          for (size_t i = 0; i < k; ++i)
            if (state[el.ys[i]] == 0) (*Hv)[el.ys[i]] += fh[i + j * k] * (*v)[el.ys[j]];
        }
      }
    }
    return energy;
  }

  // Adds the wide faces' Hessian (into H's free rows and columns) and gradient (after the gather).
  void add_wide(Eigen::VectorXd* g) {
    double* hx = wide.Hx.valuePtr();
    std::fill(hx, hx + wide.Hx.nonZeros(), 0.0);
    wide.gx.setZero(static_cast<Eigen::Index>(wide.var.size()));
    for (size_t w = 0; w < wide.faces.size(); ++w) {
      for (int a = 0; a < 36; ++a) hx[wide.hx_entry[w][a]] += wide.h6[36 * w + a];
      for (int a = 0; a < 6; ++a) wide.gx[wide.local[w][a]] += wide.g6[6 * w + a];
    }
    const Eigen::SparseMatrix<double> S = wide.PwT * (wide.Hx * wide.Pw);
    if (static_cast<size_t>(S.nonZeros()) != wide.s_entry.size())
      throw std::logic_error("PinnedLayout: the wide faces' product changed its pattern");
    double* vals = H.valuePtr();
    for (int c = 0; c < S.outerSize(); ++c)
      for (int e = S.outerIndexPtr()[c]; e < S.outerIndexPtr()[c + 1]; ++e)
        if (state[S.innerIndexPtr()[e]] == 0 && state[c] == 0) vals[wide.s_entry[e]] += S.valuePtr()[e];
    const Eigen::VectorXd gy = wide.PwT * wide.gx;
    for (int i = 0; i < n(); ++i)
      if (state[i] == 0) (*g)[i] += gy[i];
  }

  double penalty_value(const Eigen::VectorXd& yy) const {
    double e = 0;
    for (const auto& [j, t] : penalty) e += penalty_weight * (yy[j] - t) * (yy[j] - t);
    return e;
  }
  // Adds the penalty's gradient and Hessian (after evaluate() with derivatives).
  void add_penalty(const Eigen::VectorXd& yy, Eigen::VectorXd* g) {
    for (const auto& [j, t] : penalty) {
      if (state[j] != 0) continue;
      (*g)[j] += 2 * penalty_weight * (yy[j] - t);
      H.valuePtr()[diag_offset[j]] += 2 * penalty_weight;
    }
  }

  // Solves H·dy = rhs with a small diagonal shift on the free rows (retried larger on failure).
  bool solve_many(const Eigen::MatrixXd& rhs, Eigen::MatrixXd* out) {
    double mean_diag = 0;
    int n_free_rows = 0;
    for (int i = 0; i < n(); ++i)
      if (state[i] == 0) {
        mean_diag += H.valuePtr()[diag_offset[i]];
        ++n_free_rows;
      }
    mean_diag = n_free_rows > 0 ? mean_diag / n_free_rows : 1;
    if (!(mean_diag > 0)) mean_diag = 1;
    double shift = kPinRegularization * mean_diag;
    // The shift goes onto H's free diagonal in place (no copy of H per solve) and the saved
    // values are put back after.
    std::vector<double> diagonal;
    diagonal.reserve(static_cast<size_t>(n_free_rows));
    for (int i = 0; i < n(); ++i)
      if (state[i] == 0) diagonal.push_back(H.valuePtr()[diag_offset[i]]);
    auto set_diagonal = [&](double add) {
      size_t d = 0;
      for (int i = 0; i < n(); ++i)
        if (state[i] == 0) H.valuePtr()[diag_offset[i]] = diagonal[d++] + add;
    };
    bool solved = false;
    for (int attempt = 0; attempt < 6 && !solved; ++attempt, shift *= 100) {
      set_diagonal(shift);
      if (!solver.factorize(H).is_ok()) continue;
      *out = solver.solve(rhs);
      solved = out->allFinite();
    }
    set_diagonal(0);
    return solved;
  }
  bool solve(const Eigen::VectorXd& rhs, Eigen::VectorXd* dy) {
    Eigen::MatrixXd out;
    if (!solve_many(rhs, &out)) return false;
    *dy = out.col(0);
    return true;
  }

  // Linear response to the displacement v of the non-free variables (zero elsewhere): one Newton
  // solve at x with v prescribed, the free variables following by the Hessian. *dx = P·dy in the
  // internal full order; false when the factorization fails.
  bool prescribed_response(const Eigen::VectorXd& v, Eigen::VectorXd* dx) {
    Eigen::VectorXd g, Hv, dy;
    evaluate(x, true, &g, &v, &Hv);
    Eigen::VectorXd rhs = -Hv;
    for (int i = 0; i < n(); ++i)
      if (state[i] != 0) rhs[i] = v[i];
    if (!solve(rhs, &dy)) return false;
    for (int i = 0; i < n(); ++i)
      if (state[i] != 0) dy[i] = v[i];
    *dx = red.P * dy;
    return true;
  }

  double max_step(const Eigen::VectorXd& xx, const Eigen::VectorXd& dx) const {
    double t = std::numeric_limits<double>::infinity();
    for (int f = 0; f < domain.n_faces(); ++f) {
      const Eigen::Matrix2d X = edge_matrix(xx, f);
      if (!(X.determinant() > 0)) continue;
      t = std::min(t, flip_root(X, edge_matrix(dx, f)));
    }
    return t;
  }
};

PinnedLayout::PinnedLayout() : impl_(std::make_unique<Impl>()) {}
PinnedLayout::~PinnedLayout() = default;
PinnedLayout::PinnedLayout(PinnedLayout&&) noexcept = default;
PinnedLayout& PinnedLayout::operator=(PinnedLayout&&) noexcept = default;

const ConstrainedReduction& PinnedLayout::reduction() const { return impl_->ext; }
int PinnedLayout::n_free() const { return impl_->n(); }
const Eigen::VectorXd& PinnedLayout::y() const { return impl_->y; }
bool PinnedLayout::is_pinned(int j) const { return impl_->state[j] == 1; }
void PinnedLayout::unpin(int j) {
  if (j >= 0 && j < impl_->n() && impl_->state[j] == 1) impl_->state[j] = 0;
}
PinnedLayout::Saved PinnedLayout::saved() const { return {impl_->y, impl_->x, impl_->state}; }
void PinnedLayout::restore(const Saved& s) {
  impl_->y = s.y;
  impl_->x = s.x;
  impl_->state = s.state;
}
int PinnedLayout::n_flipped() const { return count_flipped(impl_->domain, impl_->x); }

Eigen::VectorXd PinnedLayout::x() const {
  Eigen::VectorXd out(impl_->ext_to_int.size());
  for (size_t e = 0; e < impl_->ext_to_int.size(); ++e) out[e] = impl_->x[impl_->ext_to_int[e]];
  return out;
}

core::Status PinnedLayout::init(const core::TriMesh& mesh, const CopyLayout& copies,
                                const Eigen::VectorXd& x0, const PinnedLayoutOptions& options) {
  Impl& m = *impl_;
  const int nf = mesh.n_faces();
  const int n = copies.n_copies();
  const int n_seams = static_cast<int>(copies.seams.size());
  if (static_cast<int>(copies.corner_copy.size()) != 3 * nf || x0.size() < 2 * n ||
      !(options.rest_scale > 0) ||
      (!options.face_size.empty() && static_cast<int>(options.face_size.size()) != nf) ||
      (!options.face_metric.empty() && static_cast<int>(options.face_metric.size()) != nf) ||
      (!options.prefer_free.empty() && static_cast<int>(options.prefer_free.size()) != n) ||
      (!options.gauge_copies.empty() &&
       static_cast<int>(options.gauge_copies.size()) != copies.n_components))
    return core::Status::invalid_input("PinnedLayout: sizes do not match");
  // Slots of two scalar variables: [one | preferred copies | translations | other copies]. The
  // eliminator pivots on the highest-index unit coefficient: other copies first, then
  // translations, and preferred copies only when nothing else is left in a row.
  std::vector<int> copy_slot(n), seam_slot(n_seams);
  int slot = 1;
  for (int k = 0; k < n; ++k)
    if (!options.prefer_free.empty() && options.prefer_free[k]) copy_slot[k] = slot++;
  for (int s = 0; s < n_seams; ++s) seam_slot[s] = slot++;
  for (int k = 0; k < n; ++k)
    if (options.prefer_free.empty() || !options.prefer_free[k]) copy_slot[k] = slot++;
  const int n_vars = 2 * slot;
  m.ext_to_int.resize(2 * n + 2 * n_seams);
  for (int k = 0; k < n; ++k)
    for (int d = 0; d < 2; ++d) m.ext_to_int[2 * k + d] = 2 * copy_slot[k] + d;
  for (int s = 0; s < n_seams; ++s)
    for (int d = 0; d < 2; ++d) m.ext_to_int[2 * n + 2 * s + d] = 2 * seam_slot[s] + d;

  m.domain = LayoutDomain();
  m.domain.n_copies = slot;
  m.domain.face_copies.resize(nf);
  m.domain.rest_inverse.resize(nf);
  m.domain.area.resize(nf);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) m.domain.face_copies[f][k] = copy_slot[copies.corner_copy[3 * f + k]];
    const Eigen::Matrix2d dm = sized_rest_frame(mesh, f, options.rest_scale, options.face_size,
                                                options.face_metric, &m.domain.area[f]);
    m.domain.rest_inverse[f] = dm.inverse();
  }
  const EnergyDensity ed = energy_density(options.energy);
  m.density = ed.density;
  m.power = ed.power;

  std::vector<char> never_pivot(n_vars, 0);
  never_pivot[0] = never_pivot[1] = 1;
  for (int k : gauge_fixed_copies(copies, options.gauge_copies))
    never_pivot[2 * copy_slot[k]] = never_pivot[2 * copy_slot[k] + 1] = 1;
  std::vector<char> pivot_last(n_vars, 0);
  if (!options.prefer_free_coords.empty()) {
    if (static_cast<int>(options.prefer_free_coords.size()) != 2 * n)
      return core::Status::invalid_input("PinnedLayout: prefer_free_coords has the wrong size");
    for (int k = 0; k < n; ++k)
      for (int d = 0; d < 2; ++d) pivot_last[2 * copy_slot[k] + d] = options.prefer_free_coords[2 * k + d];
  }
  ConstraintEliminator elim(n_vars, never_pivot, {}, pivot_last);
  for (int si = 0; si < n_seams; ++si) {
    const CopySeam& s = copies.seams[si];
    for (const auto& [a, b] : {std::pair{s.a0, s.b0}, std::pair{s.a1, s.b1}})
      for (int d = 0; d < 2; ++d) {
        std::map<int, double> acc;
        acc[2 * copy_slot[b] + d] += 1;
        for (int j = 0; j < 2; ++j)
          if (const double r = rotation_entry(s.matching, d, j); r != 0)
            acc[2 * copy_slot[a] + j] -= r;
        acc[2 * seam_slot[si] + d] -= 1;
        elim.add_row(compress(acc));
      }
  }
  for (const AffineRow& row : options.extra_rows) {
    std::map<int, double> acc;
    for (const auto& [var, coef] : row.entries) {
      if (var < 0 || var >= 2 * n)
        return core::Status::invalid_input("PinnedLayout: extra row variable out of range");
      acc[2 * copy_slot[var / 2] + var % 2] += coef;
    }
    elim.add_row(compress(acc));
  }
  Eigen::VectorXd xi = Eigen::VectorXd::Zero(n_vars);
  xi[0] = 1;
  for (int k = 0; k < n; ++k) xi.segment<2>(2 * copy_slot[k]) = x0.segment<2>(2 * k);
  for (int si = 0; si < n_seams; ++si) {
    const CopySeam& s = copies.seams[si];
    xi.segment<2>(2 * seam_slot[si]) =
        xi.segment<2>(2 * copy_slot[s.b0]) -
        rotate_quarter(xi.segment<2>(2 * copy_slot[s.a0]), s.matching);
  }
  m.red = elim.reduction(xi);
  m.y = m.red.restrict(xi);
  m.x = m.red.expand(m.y);
  if (!options.face_direction.empty() && options.direction_weight > 0) {
    if (static_cast<int>(options.face_direction.size()) != nf)
      return core::Status::invalid_input("PinnedLayout: face_direction needs one vector per face");
    const DirectionField field = make_direction_field(mesh, m.domain, options.face_direction);
    m.dir_coef.assign(nf, Eigen::Vector2d::Zero());
    m.dir_axis.assign(nf, 0);
    m.dir_weight = options.direction_weight;
    for (int i = 0; i < field.size(); ++i) {
      const int f = field.face[i];
      m.dir_coef[f] = field.coef[i];
      const Eigen::Vector2d img = m.edge_matrix(m.x, f) * field.coef[i];
      m.dir_axis[f] = std::abs(img.x()) >= std::abs(img.y()) ? 1 : 0;
    }
  }
  m.state.assign(m.n(), 0);
  if (const int flips = count_flipped(m.domain, m.x); flips > 0)
    return core::Status::invalid_input("PinnedLayout: " + std::to_string(flips) +
                                       " flipped faces at the start");
  // External reduction.
  {
    const int n_ext = 2 * n + 2 * n_seams;
    std::vector<int> ext_of(n_vars, -1);
    for (int e = 0; e < n_ext; ++e) ext_of[m.ext_to_int[e]] = e;
    std::vector<Eigen::Triplet<double>> trip;
    m.ext.c.resize(n_ext);
    for (int e = 0; e < n_ext; ++e) {
      m.ext.c[e] = m.red.c[m.ext_to_int[e]];
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m.red.P, m.ext_to_int[e]);
           it; ++it)
        trip.emplace_back(e, static_cast<int>(it.col()), it.value());
    }
    m.ext.P.resize(n_ext, m.n());
    m.ext.P.setFromTriplets(trip.begin(), trip.end());
    m.ext.free_vars.clear();
    for (int v : m.red.free_vars) m.ext.free_vars.push_back(ext_of[v]);
  }
  // Face elements over the edge-vector coordinates (shared translation parts cancel).
  m.faces.assign(nf, {});
  m.for_faces([&](int f) {
    const auto& fc = m.domain.face_copies[f];
    std::array<std::vector<std::pair<int, double>>, 4> rows;
    for (int j = 0; j < 2; ++j)
      for (int d = 0; d < 2; ++d) {
        auto& e = rows[2 * j + d];
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m.red.P, 2 * fc[j + 1] + d);
             it; ++it)
          e.push_back({static_cast<int>(it.col()), it.value()});
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m.red.P, 2 * fc[0] + d); it;
             ++it)
          e.push_back({static_cast<int>(it.col()), -it.value()});
        std::sort(e.begin(), e.end());
        std::vector<std::pair<int, double>> merged;
        for (const auto& [v, a] : e) {
          if (!merged.empty() && merged.back().first == v)
            merged.back().second += a;
          else
            merged.push_back({v, a});
        }
        std::erase_if(merged, [](const auto& p) { return std::abs(p.second) <= kPinCancelled; });
        e = std::move(merged);
      }
    Impl::Face& el = m.faces[f];
    for (const auto& row : rows)
      for (const auto& [v, a] : row) el.ys.push_back(v);
    std::sort(el.ys.begin(), el.ys.end());
    el.ys.erase(std::unique(el.ys.begin(), el.ys.end()), el.ys.end());
    if (el.ys.size() > options.wide_face_variables) return;  // assembled through Pw (see Impl::Wide)
    el.M = Eigen::Matrix<double, 4, Eigen::Dynamic>::Zero(4, el.ys.size());
    for (int i = 0; i < 4; ++i)
      for (const auto& [v, a] : rows[i])
        el.M(i, std::lower_bound(el.ys.begin(), el.ys.end(), v) - el.ys.begin()) += a;
  });
  // Wide faces: local numbering of their copies' coordinates, Hx's pattern (6×6 per face), Pw,
  // and the pattern of Pwᵀ·Hx·Pw (fixed: Eigen's sparse product keeps structural zeros).
  m.wide = Impl::Wide();
  for (int f = 0; f < nf; ++f)
    if (m.faces[f].ys.size() > options.wide_face_variables) {
      m.faces[f].wide = static_cast<int>(m.wide.faces.size());
      m.wide.faces.push_back(f);
    }
  Eigen::SparseMatrix<double> wide_pattern;
  if (!m.wide.empty()) {
    Impl::Wide& w = m.wide;
    std::vector<int> local_of(n_vars, -1);
    for (const int f : w.faces) {
      std::array<int, 6> loc;
      for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 2; ++d) {
          const int var = 2 * m.domain.face_copies[f][c] + d;
          if (local_of[var] < 0) {
            local_of[var] = static_cast<int>(w.var.size());
            w.var.push_back(var);
          }
          loc[2 * c + d] = local_of[var];
        }
      w.local.push_back(loc);
    }
    const int nw = static_cast<int>(w.var.size());
    std::vector<Eigen::Triplet<double>> trip;
    for (const auto& loc : w.local)
      for (int a : loc)
        for (int b : loc) trip.emplace_back(a, b, 1.0);
    w.Hx.resize(nw, nw);
    w.Hx.setFromTriplets(trip.begin(), trip.end());
    w.Hx.makeCompressed();
    for (const auto& loc : w.local) {
      std::array<int, 36> entry;
      for (int b = 0; b < 6; ++b)
        for (int a = 0; a < 6; ++a) {
          const int* begin = w.Hx.innerIndexPtr() + w.Hx.outerIndexPtr()[loc[b]];
          const int* end = w.Hx.innerIndexPtr() + w.Hx.outerIndexPtr()[loc[b] + 1];
          entry[a + 6 * b] = static_cast<int>(std::lower_bound(begin, end, loc[a]) - w.Hx.innerIndexPtr());
        }
      w.hx_entry.push_back(entry);
    }
    trip.clear();
    for (int r = 0; r < nw; ++r)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m.red.P, w.var[r]); it; ++it)
        trip.emplace_back(r, static_cast<int>(it.col()), it.value());
    w.Pw.resize(nw, m.n());
    w.Pw.setFromTriplets(trip.begin(), trip.end());
    w.Pw.makeCompressed();
    w.PwT = w.Pw.transpose();
    w.PwT.makeCompressed();
    wide_pattern = w.PwT * (w.Hx * w.Pw);
    w.g6.assign(6 * w.faces.size(), 0.0);
    w.h6.assign(36 * w.faces.size(), 0.0);
  }
  // The elimination can couple many unknowns in one triangle (a map with very many cones: the
  // loops around them are solved for translations, which then chain); the narrow faces' element
  // Hessians and the wide faces' product are stored (options.max_element_entries). Refused with
  // a clear error above the limit.
  {
    double entries = static_cast<double>(wide_pattern.nonZeros()) + 36.0 * m.wide.faces.size();
    size_t widest = 0;
    for (const Impl::Face& el : m.faces) {
      if (el.wide < 0) entries += static_cast<double>(el.ys.size()) * static_cast<double>(el.ys.size());
      widest = std::max(widest, el.ys.size());
    }
    if (entries > options.max_element_entries) {
      char msg[400];
      std::snprintf(msg, sizeof msg,
                    "the seam constraints, eliminated, couple up to %zu unknowns in one triangle "
                    "(%.3g Hessian entries, %.0f per triangle, above the limit of %.3g, about %.1f GB): "
                    "the map has too many cones for this elimination",
                    widest, entries, entries / std::max(nf, 1), options.max_element_entries,
                    options.max_element_entries * 32 / 1e9);
      return core::Status::numerical_failure(msg);
    }
  }
  // Hessian pattern, analysed once.
  std::vector<Eigen::Triplet<double>> trip;
  for (int i = 0; i < m.n(); ++i) trip.emplace_back(i, i, 0.0);
  for (const Impl::Face& el : m.faces)
    if (el.wide < 0)
      for (int a : el.ys)
        for (int b : el.ys) trip.emplace_back(a, b, 0.0);
  for (int c = 0; c < wide_pattern.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(wide_pattern, c); it; ++it)
      trip.emplace_back(static_cast<int>(it.row()), c, 0.0);
  m.H.resize(m.n(), m.n());
  m.H.setFromTriplets(trip.begin(), trip.end());
  m.H.makeCompressed();
  auto locate = [&](int row, int col) {
    const int* begin = m.H.innerIndexPtr() + m.H.outerIndexPtr()[col];
    const int* end = m.H.innerIndexPtr() + m.H.outerIndexPtr()[col + 1];
    return static_cast<int>(std::lower_bound(begin, end, row) - m.H.innerIndexPtr());
  };
  m.diag_offset.resize(m.n());
  for (int i = 0; i < m.n(); ++i) m.diag_offset[i] = locate(i, i);
  m.wide.s_entry.clear();
  for (int c = 0; c < wide_pattern.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(wide_pattern, c); it; ++it)
      m.wide.s_entry.push_back(locate(static_cast<int>(it.row()), c));
  // The flat per-face arrays and the gather lists (see Impl::h_source), in a scatter's order:
  // faces ascending, then column j, then row i.
  const int nfaces = static_cast<int>(m.faces.size());
  m.g_base.assign(nfaces + 1, 0);
  m.h_base.assign(nfaces + 1, 0);
  // Wide faces have no entries here.
  auto element_size = [&](int f) { return m.faces[f].wide >= 0 ? size_t{0} : m.faces[f].ys.size(); };
  for (int f = 0; f < nfaces; ++f) {
    const size_t k = element_size(f);
    m.g_base[f + 1] = m.g_base[f] + k;
    m.h_base[f + 1] = m.h_base[f] + k * k;
  }
  if (m.h_base[nfaces] > std::numeric_limits<std::uint32_t>::max())
    return core::Status::numerical_failure("PinnedLayout: more per-face Hessian entries than 32-bit indices hold");
  const size_t nnz = static_cast<size_t>(m.H.nonZeros());
  std::vector<int> entry_of(m.h_base[nfaces]);
  m.h_start.assign(nnz + 1, 0);
  m.g_start.assign(static_cast<size_t>(m.n()) + 1, 0);
  for (int f = 0; f < nfaces; ++f) {
    const std::vector<int>& ys = m.faces[f].ys;
    const size_t k = element_size(f);
    for (size_t j = 0; j < k; ++j)
      for (size_t i = 0; i < k; ++i) {
        const int e = locate(ys[i], ys[j]);
        entry_of[m.h_base[f] + i + j * k] = e;
        ++m.h_start[e + 1];
      }
    for (size_t i = 0; i < k; ++i) ++m.g_start[ys[i] + 1];
  }
  for (size_t e = 0; e < nnz; ++e) m.h_start[e + 1] += m.h_start[e];
  for (int i = 0; i < m.n(); ++i) m.g_start[i + 1] += m.g_start[i];
  m.h_source.resize(m.h_base[nfaces]);
  m.g_source.resize(m.g_base[nfaces]);
  {
    std::vector<size_t> h_fill(m.h_start.begin(), m.h_start.end() - 1);
    std::vector<size_t> g_fill(m.g_start.begin(), m.g_start.end() - 1);
    for (int f = 0; f < nfaces; ++f) {
      const std::vector<int>& ys = m.faces[f].ys;
      const size_t k = element_size(f);
      for (size_t j = 0; j < k; ++j)
        for (size_t i = 0; i < k; ++i) {
          const size_t local = m.h_base[f] + i + j * k;
          m.h_source[h_fill[entry_of[local]]++] = static_cast<std::uint32_t>(local);
        }
      for (size_t i = 0; i < k; ++i) m.g_source[g_fill[ys[i]]++] = static_cast<std::uint32_t>(m.g_base[f] + i);
    }
  }
  m.h_row.resize(nnz);
  m.h_col.resize(nnz);
  for (int c = 0; c < m.n(); ++c)
    for (int e = m.H.outerIndexPtr()[c]; e < m.H.outerIndexPtr()[c + 1]; ++e) {
      m.h_row[e] = m.H.innerIndexPtr()[e];
      m.h_col[e] = c;
    }
  if (m.n() > 0) {
    std::fill(m.H.valuePtr(), m.H.valuePtr() + m.H.nonZeros(), 0.0);
    for (int i = 0; i < m.n(); ++i) m.H.valuePtr()[m.diag_offset[i]] = 1;
    if (const core::Status st = m.solver.analyze(m.H); !st.is_ok())
      return core::Status::numerical_failure("PinnedLayout: analysis failed: " + st.message());
  }
  return core::Status::ok();
}

bool PinnedLayout::determined_faces_valid(
    const std::vector<std::pair<int, double>>& targets) const {
  const Impl& m = *impl_;
  std::vector<char> target(m.n(), 0);
  Eigen::VectorXd y_target = m.y;
  for (const auto& [j, value] : targets) {
    if (j < 0 || j >= m.n()) return false;
    target[j] = 1;
    y_target[j] = value;
  }
  const Eigen::VectorXd x_target = m.red.expand(y_target);
  for (int f = 0; f < m.domain.n_faces(); ++f) {
    bool determined = true, moved = false;
    for (const int j : m.faces[f].ys) {
      determined = determined && (m.state[j] == 1 || target[j]);
      moved = moved || target[j];
    }
    if (!determined || !moved) continue;
    const auto& fc = m.domain.face_copies[f];
    if (core::orient2d(x_target.segment<2>(2 * fc[0]), x_target.segment<2>(2 * fc[1]),
                       x_target.segment<2>(2 * fc[2])) <= 0)
      return false;
  }
  return true;
}

int PinnedLayout::minimize(int max_iterations, double relative_tolerance, core::Status* status) {
  Impl& m = *impl_;
  *status = core::Status::ok();
  if (m.n() == 0) return 0;
  Eigen::VectorXd g, dy;
  double energy = m.evaluate(m.x, true, &g) + m.penalty_value(m.y);
  m.add_penalty(m.y, &g);
  int iterations = 0;
  for (int it = 0; it < max_iterations; ++it) {
    if (!m.solve(-g, &dy)) {
      *status = core::Status::numerical_failure("PinnedLayout: Newton system failed");
      break;
    }
    for (int i = 0; i < m.n(); ++i)
      if (m.state[i] != 0) dy[i] = 0;
    const double decrement = -g.dot(dy);
    if (decrement <= relative_tolerance * std::abs(energy)) break;
    const Eigen::VectorXd dx = m.red.P * dy;
    double alpha = std::min(1.0, kPinStepFraction * m.max_step(m.x, dx));
    Eigen::VectorXd x_trial;
    int bt = 0;
    for (; bt < kPinBacktracks; ++bt, alpha *= 0.5) {
      x_trial = m.x + alpha * dx;
      const double e = m.evaluate(x_trial, false, nullptr) + m.penalty_value(m.y + alpha * dy);
      if (e <= energy - kPinArmijo * alpha * decrement) break;
    }
    if (bt == kPinBacktracks) break;
    const Eigen::VectorXd y_trial = m.y + alpha * dy;
    const Eigen::VectorXd x_new = m.red.expand(y_trial);
    if (count_flipped(m.domain, x_new) > 0) break;  // round-off at the barrier: stop here
    m.y = y_trial;
    m.x = x_new;
    ++iterations;
    const double previous = energy;
    energy = m.evaluate(m.x, true, &g) + m.penalty_value(m.y);
    m.add_penalty(m.y, &g);
    if (previous - energy <= 1e-3 * relative_tolerance * std::abs(previous)) break;
  }
  return iterations;
}

std::vector<int> PinnedLayout::limiting_faces(const std::vector<std::pair<int, double>>& targets) {
  Impl& m = *impl_;
  std::vector<int> prescribed;
  Eigen::VectorXd v = Eigen::VectorXd::Zero(m.n());
  for (const auto& [j, value] : targets) {
    if (j < 0 || j >= m.n() || m.state[j] != 0) continue;
    m.state[j] = 2;
    prescribed.push_back(j);
    v[j] = value - m.y[j];
  }
  std::vector<int> out;
  if (prescribed.empty()) return out;
  Eigen::VectorXd dx;
  const bool solved = m.prescribed_response(v, &dx);
  for (const int j : prescribed) m.state[j] = 0;
  if (!solved) return out;
  for (int f = 0; f < m.domain.n_faces(); ++f)
    if (flip_root(m.edge_matrix(m.x, f), m.edge_matrix(dx, f)) <= 1) out.push_back(f);
  return out;
}

PinReport PinnedLayout::pin(const std::vector<std::pair<int, double>>& targets,
                            const PinSettings& settings, int relax_iterations,
                            double relax_tolerance) {
  Impl& m = *impl_;
  PinReport rep;
  const size_t nt = targets.size();
  rep.pinned.assign(nt, 0);
  rep.blocking.assign(nt, 0);
  // A call without penalty stages that pins nothing leaves the layout as it found it (see the end).
  const Eigen::VectorXd y_start = m.y, x_start = m.x;
  std::vector<char> active(nt, 0);
  for (size_t i = 0; i < nt; ++i) {
    const int j = targets[i].first;
    if (j < 0 || j >= m.n() || m.state[j] != 0) continue;  // out of range or already taken
    active[i] = 1;
    m.state[j] = 2;
  }
  // Faces that the pinned and prescribed variables alone determine cannot be helped by the free
  // ones: a target that leaves one of them flipped or degenerate (e.g. a cone on the line of two
  // pinned cones of its triangle) is dropped before any step.
  {
    Eigen::VectorXd y_target = m.y;
    for (size_t i = 0; i < nt; ++i)
      if (active[i]) y_target[targets[i].first] = targets[i].second;
    const Eigen::VectorXd x_target = m.red.expand(y_target);
    for (int f = 0; f < m.domain.n_faces(); ++f) {
      const Impl::Face& el = m.faces[f];
      bool determined = true, moved = false;
      for (const int j : el.ys) {
        determined = determined && m.state[j] != 0;
        moved = moved || m.state[j] == 2;
      }
      if (!determined || !moved) continue;
      const auto& fc = m.domain.face_copies[f];
      if (core::orient2d(x_target.segment<2>(2 * fc[0]), x_target.segment<2>(2 * fc[1]),
                         x_target.segment<2>(2 * fc[2])) > 0)
        continue;
      for (size_t i = 0; i < nt; ++i)
        if (active[i] && std::binary_search(el.ys.begin(), el.ys.end(), targets[i].first)) {
          active[i] = 0;
          rep.blocking[i] = 1;
          m.state[targets[i].first] = 0;
        }
    }
  }
  // Targets farther than a full flip-free step (cones pulled apart, a translation that shears a
  // handle) first move by a penalty homotopy: Newton on energy + w·Σ (y_j − target)² with w
  // growing, where the barrier bends the layout out of the way instead of the linear response
  // crushing it. A target that the barrier holds back (its residual stops shrinking) blocks.
  if (settings.penalty_stages > 0) {
    Eigen::VectorXd v0 = Eigen::VectorXd::Zero(m.n());
    double v_max = 0;
    for (size_t i = 0; i < nt; ++i)
      if (active[i]) {
        v0[targets[i].first] = targets[i].second - m.y[targets[i].first];
        v_max = std::max(v_max, std::abs(v0[targets[i].first]));
      }
    bool reaches = v_max == 0;
    Eigen::VectorXd dx0;
    if (!reaches && m.prescribed_response(v0, &dx0))
      reaches = kPinStepFraction * m.max_step(m.x, dx0) >= 1;
    if (!reaches) {
      double mean_area = 0, mean_edge_sq = 0;
      for (int f = 0; f < m.domain.n_faces(); ++f) {
        mean_area += m.domain.area[f];
        const Eigen::Matrix2d dm = m.domain.rest_inverse[f].inverse();
        mean_edge_sq += dm.col(0).squaredNorm();
      }
      // One triangle's stiffness: energy per squared displacement of a vertex.
      const double unit = mean_area / std::max(1e-300, mean_edge_sq);
      std::vector<double> initial(nt, 0), last(nt, 0);
      m.penalty.clear();
      for (size_t i = 0; i < nt; ++i)
        if (active[i]) {
          m.state[targets[i].first] = 0;
          m.penalty.push_back(targets[i]);
          initial[i] = last[i] = std::abs(targets[i].second - m.y[targets[i].first]);
        }
      double w = settings.first_penalty;
      for (int stage = 0; stage < settings.penalty_stages; ++stage, w *= settings.penalty_growth) {
        m.penalty_weight = w * unit;
        core::Status st;
        rep.iterations += minimize(settings.stage_iterations, kPinStageTolerance, &st);
        if (!st.is_ok()) {
          rep.status = st;
          break;
        }
        double r_max = 0;
        bool shrinking = false;
        for (size_t i = 0; i < nt; ++i)
          if (active[i]) {
            const double r = std::abs(targets[i].second - m.y[targets[i].first]);
            r_max = std::max(r_max, r);
            shrinking = shrinking || r < kPinShrink * last[i];
            last[i] = r;
          }
        if (r_max < settings.snap_residual || (stage >= 2 && !shrinking)) break;
      }
      m.penalty.clear();
      m.penalty_weight = 0;
      for (size_t i = 0; i < nt; ++i) {
        if (!active[i]) continue;
        if (last[i] > settings.snap_residual && last[i] > kPinHeldBack * initial[i]) {
          active[i] = 0;  // held back by the barrier
          rep.blocking[i] = 1;
        } else {
          m.state[targets[i].first] = 2;
        }
      }
    }
  }
  Eigen::VectorXd g, Hv, dy, v = Eigen::VectorXd::Zero(m.n());
  int stalled = 0, approach = 0;
  for (int step = 0; step < settings.max_steps; ++step) {
    v.setZero();
    bool any = false;
    for (size_t i = 0; i < nt; ++i)
      if (active[i]) {
        v[targets[i].first] = targets[i].second - m.y[targets[i].first];
        any = any || v[targets[i].first] != 0;
      }
    if (!any) break;
    // One factorization, two directions: the response of the free variables to the prescribed
    // displacement (H_ff·dp_f = −H_fp·v, dp = v on the targets), and the energy Newton step
    // (H_ff·de_f = −g_f). The first is taken as far as it stays flip-free (to the targets when
    // the whole of it is), the second then relaxes the layout away from the barrier; mixed in one
    // direction, the energy part would keep the step short of the targets near a barrier.
    const double energy = m.evaluate(m.x, true, &g, &v, &Hv);
    Eigen::MatrixXd rhs(m.n(), 2);
    rhs.col(0) = -Hv;
    rhs.col(1) = -g;
    for (int i = 0; i < m.n(); ++i)
      if (m.state[i] != 0) {
        rhs(i, 0) = v[i];
        rhs(i, 1) = 0;
      }
    Eigen::MatrixXd dirs;
    if (!m.solve_many(rhs, &dirs)) {
      rep.status = core::Status::numerical_failure("PinnedLayout: Newton system failed");
      break;
    }
    for (int i = 0; i < m.n(); ++i)
      if (m.state[i] != 0) {
        dirs(i, 0) = v[i];
        dirs(i, 1) = 0;
      }
    dy = dirs.col(0);
    const Eigen::VectorXd dx = m.red.P * dy;
    const double t_max = m.max_step(m.x, dx);
    double alpha = t_max * kPinStepFraction >= 1 ? 1.0 : kPinStepFraction * t_max;
    bool accepted = false;
    for (int h = 0; h < kPinExactHalvings; ++h, alpha *= 0.5) {
      Eigen::VectorXd y_new = m.y + alpha * dy;
      if (alpha == 1.0)
        for (size_t i = 0; i < nt; ++i)
          if (active[i]) y_new[targets[i].first] = targets[i].second;
      const Eigen::VectorXd x_new = m.red.expand(y_new);
      if (count_flipped(m.domain, x_new) > 0) continue;
      m.y = std::move(y_new);
      m.x = x_new;
      accepted = true;
      ++rep.iterations;
      break;
    }
    if (accepted && alpha < 1.0) {
      // Energy step from the new point (the old Newton direction, if still a descent one).
      const Eigen::VectorXd de = dirs.col(1);
      const Eigen::VectorXd dxe = m.red.P * de;
      const double e0 = m.evaluate(m.x, false, nullptr);
      double beta = std::min(1.0, kPinStepFraction * m.max_step(m.x, dxe));
      const double decrease = std::max(0.0, energy - e0);
      (void)decrease;
      for (int bt = 0; bt < kPinBacktracks / 4; ++bt, beta *= 0.5) {
        const Eigen::VectorXd y_new = m.y + beta * de;
        const Eigen::VectorXd x_new = m.red.expand(y_new);
        if (!(m.evaluate(x_new, false, nullptr) < e0)) continue;
        if (count_flipped(m.domain, x_new) > 0) continue;
        m.y = y_new;
        m.x = x_new;
        break;
      }
    }
    if (!accepted) alpha = 0;
    if (alpha == 1.0) continue;  // targets reached (the next step sees v = 0)
    // Stalled (tiny steps), or approaching without ever reaching: when the target squeezes a
    // region to zero area (two cones that meet through a seam), the limiting triangles shrink
    // as fast as the remaining displacement and every step stops at the same fraction.
    stalled = alpha < settings.stall_fraction ? stalled + 1 : 0;
    ++approach;
    if (stalled < kStalledSteps && approach < settings.approach_steps) continue;
    approach = 0;
    // Drop the targets whose faces limit the step: they collide with something.
    stalled = 0;
    // Limiting faces (they would flip within the full step) and the faces around them: the
    // region being squeezed. The targets that enter its faces are the culprits.
    std::vector<char> limiting(m.n(), 0), squeezed_slot(m.domain.n_copies, 0);
    for (int f = 0; f < m.domain.n_faces(); ++f) {
      const Eigen::Matrix2d X = m.edge_matrix(m.x, f);
      if (flip_root(X, m.edge_matrix(dx, f)) > 1 / kPinStepFraction) continue;
      for (const int c : m.domain.face_copies[f]) squeezed_slot[c] = 1;
    }
    for (int f = 0; f < m.domain.n_faces(); ++f) {
      const auto& fc = m.domain.face_copies[f];
      if (squeezed_slot[fc[0]] || squeezed_slot[fc[1]] || squeezed_slot[fc[2]])
        for (int j : m.faces[f].ys) limiting[j] = 1;
    }
    bool dropped = false;
    for (size_t i = 0; i < nt; ++i)
      if (active[i] && limiting[targets[i].first]) {
        active[i] = 0;
        rep.blocking[i] = 1;
        m.state[targets[i].first] = 0;
        dropped = true;
      }
    if (!dropped) {
      for (size_t i = 0; i < nt; ++i)
        if (active[i]) {
          active[i] = 0;
          rep.blocking[i] = 1;
          m.state[targets[i].first] = 0;
        }
    }
    if (std::none_of(active.begin(), active.end(), [](char a) { return a != 0; })) break;
  }
  for (size_t i = 0; i < nt; ++i) {
    if (!active[i]) continue;
    const int j = targets[i].first;
    if (m.y[j] == targets[i].second) {
      m.state[j] = 1;
      rep.pinned[i] = 1;
    } else {
      m.state[j] = 0;
    }
  }
  // Nothing pinned by plain steps: they are undone instead of relaxed from. The layout was
  // relaxed before the call, and relaxing a layout pushed against a barrier takes up to
  // relax_iterations Newton steps, so a failed attempt cost ~5× a successful one (beetle at 5,000
  // quads: pin iterations 580 → 367). After the penalty homotopy the layout is near a minimum
  // already, its relaxation is short, and the next attempt starts better from it than from the
  // layout before (mask: 198 pin iterations kept; undone, 217).
  if (settings.penalty_stages == 0 && rep.status.is_ok() &&
      std::none_of(rep.pinned.begin(), rep.pinned.end(), [](char p) { return p != 0; })) {
    m.y = y_start;
    m.x = x_start;
    return rep;
  }
  if (rep.status.is_ok() && relax_iterations > 0) {
    core::Status st;
    rep.iterations += minimize(relax_iterations, relax_tolerance, &st);
    rep.status = st;
  }
  return rep;
}

}  // namespace quadify::param
