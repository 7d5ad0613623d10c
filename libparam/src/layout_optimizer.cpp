#include "layout_optimizer.h"

#include <libcore/predicates.h>
#include <libcore/sparse_solver.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SparseCore>

#ifdef QUADIFY_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#endif

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <limits>

namespace quadify::param {
namespace {

// Problems with at most this many reduced variables use a dense Cholesky (local patches).
constexpr int kDenseMaxVariables = 250;
// Fraction of the largest flip-free step actually taken, so triangles keep a positive area.
constexpr double kFlipFreeStepFraction = 0.8;
// Armijo sufficient-decrease constant and the number of halvings before giving up.
constexpr double kArmijo = 1e-4;
constexpr int kMaxBacktracks = 40;
// Diagonal shift relative to the mean Hessian diagonal: removes the global-rotation null space.
constexpr double kRegularization = 1e-9;
// Below this many faces the per-face evaluation runs serially (patches; thread overhead).
constexpr int kParallelMinFaces = 2048;

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// P holds sums of products of small integers; a difference of two rows below this is
// cancellation round-off, i.e. zero.
constexpr double kCancelledCoefficient = 1e-12;

// One element of the energy: local scalar variables, mapped to reduced variables by M (dense
// n_local × n_reduced, rows = P rows), the reduced ids, and the offsets of its Hessian entries.
struct Element {
  std::vector<int> ys;
  Eigen::MatrixXd M;
  std::vector<int> offsets;  // ys.size()² positions in the Hessian value array (sparse) or -1
};

// Element of the local linear forms rows[i] (over reduced variables).
Element make_element(const std::vector<SparseRow>& rows) {
  Element el;
  for (const auto& row : rows)
    for (const auto& [v, a] : row.entries) el.ys.push_back(v);
  std::sort(el.ys.begin(), el.ys.end());
  el.ys.erase(std::unique(el.ys.begin(), el.ys.end()), el.ys.end());
  el.M = Eigen::MatrixXd::Zero(rows.size(), el.ys.size());
  for (size_t i = 0; i < rows.size(); ++i)
    for (const auto& [v, a] : rows[i].entries) {
      const auto pos = std::lower_bound(el.ys.begin(), el.ys.end(), v);
      el.M(i, pos - el.ys.begin()) += a;
    }
  return el;
}

Element make_element(const Reduction& red, const std::vector<int>& xvars) {
  std::vector<SparseRow> rows(xvars.size());
  for (size_t i = 0; i < xvars.size(); ++i)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, xvars[i]); it; ++it)
      rows[i].entries.push_back({static_cast<int>(it.col()), it.value()});
  return make_element(rows);
}

// The element of a face over the four edge-vector coordinates (x1−x0, x2−x0 per axis, local
// variable 2j+d): the energy depends on them only, and the translation parts that the three
// corner expressions share (a copy across a seam is R·x + t with a long t) cancel here.
Element make_face_element(const Reduction& red, const std::array<int, 3>& fc) {
  std::vector<SparseRow> rows(4);
  std::vector<std::pair<int, double>> merged;
  for (int j = 0; j < 2; ++j)
    for (int d = 0; d < 2; ++d) {
      auto& e = rows[2 * j + d].entries;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, 2 * fc[j + 1] + d); it; ++it)
        e.push_back({static_cast<int>(it.col()), it.value()});
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, 2 * fc[0] + d); it; ++it)
        e.push_back({static_cast<int>(it.col()), -it.value()});
      std::sort(e.begin(), e.end());
      merged.clear();
      for (const auto& [v, a] : e) {
        if (!merged.empty() && merged.back().first == v)
          merged.back().second += a;
        else
          merged.push_back({v, a});
      }
      std::erase_if(merged, [](const auto& p) { return std::abs(p.second) <= kCancelledCoefficient; });
      e = merged;
    }
  return make_element(rows);
}

// f(begin, end) over [0, n) in chunks, in parallel with TBB; chunks are independent.
template <typename F>
void parallel_ranges(int n, F&& f) {
#ifdef QUADIFY_WITH_TBB
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024),
                    [&](const tbb::blocked_range<int>& r) { f(r.begin(), r.end()); });
#else
  f(0, n);
#endif
}

}  // namespace

struct LayoutProblem::Impl {
  const LayoutDomain& domain;
  const Reduction& red;
  const std::vector<SparseRow>* penalty_rows;
  std::vector<Element> faces, rows;
  std::vector<Eigen::VectorXd> row_coefs;  // coefficients of each penalty row (local order)
  bool dense = false;
  Eigen::SparseMatrix<double> H;           // pattern (sparse mode)
  Eigen::MatrixXd Hd;                      // dense mode
  std::vector<double> face_value;          // per-face buffers of evaluate()
  std::vector<Eigen::VectorXd> face_gy;
  std::vector<Eigen::MatrixXd> face_hy;
  core::SparseSolver solver;  // symbolic analysis of the pattern H, reused by every optimization
  bool analyzed = false;
  double setup_seconds = 0;   // not yet reported by an optimization
  int max_element_variables = 0;
  long long sum_sq_element_variables = 0;
  // Column → (element, local index) incidences, elements in increasing id within a column
  // (faces 0..#F−1, then the penalty rows).
  std::vector<int> col_start;
  std::vector<std::pair<int, int>> col_elements;

  Impl(const LayoutDomain& d, const Reduction& r, const std::vector<SparseRow>* penalty)
      : domain(d), red(r), penalty_rows(penalty) {
    faces.resize(d.n_faces());
    auto build = [&](int f) {
      const auto& fc = d.face_copies[f];
      faces[f] = make_face_element(r, fc);
    };
#ifdef QUADIFY_WITH_TBB
    tbb::parallel_for(0, d.n_faces(), build);
#else
    for (int f = 0; f < d.n_faces(); ++f) build(f);
#endif
    for (const Element& el : faces) {
      const long long k = static_cast<long long>(el.ys.size());
      max_element_variables = std::max(max_element_variables, static_cast<int>(k));
      sum_sq_element_variables += k * k;
    }
    if (penalty_rows) {
      for (const auto& row : *penalty_rows) {
        std::vector<int> xv;
        Eigen::VectorXd co(row.entries.size());
        for (size_t i = 0; i < row.entries.size(); ++i) {
          xv.push_back(row.entries[i].first);
          co[i] = row.entries[i].second;
        }
        rows.push_back(make_element(r, xv));
        row_coefs.push_back(co);
      }
    }
    const int n = r.n_free();
    dense = n <= kDenseMaxVariables;
    if (dense) {
      Hd = Eigen::MatrixXd::Zero(n, n);
      return;
    }
    build_pattern(n);
  }

  const Element& element(int e) const {
    const int nf = static_cast<int>(faces.size());
    return e < nf ? faces[e] : rows[e - nf];
  }
  Element& element(int e) {
    const int nf = static_cast<int>(faces.size());
    return e < nf ? faces[e] : rows[e - nf];
  }

  // The pattern of H (union of the element cliques, both triangles, with the diagonal) and each
  // element's offsets into it, column by column: Σ_e k_e² work without a triplet list, in
  // parallel over columns (each column's entries are written by one task only).
  void build_pattern(int n) {
    const int n_el = static_cast<int>(faces.size() + rows.size());
    col_start.assign(n + 1, 0);
    for (int e = 0; e < n_el; ++e)
      for (int v : element(e).ys) ++col_start[v + 1];
    for (int j = 0; j < n; ++j) col_start[j + 1] += col_start[j];
    col_elements.resize(col_start[n]);
    {
      std::vector<int> fill(col_start.begin(), col_start.end() - 1);
      for (int e = 0; e < n_el; ++e) {
        const auto& ys = element(e).ys;
        for (int jj = 0; jj < static_cast<int>(ys.size()); ++jj)
          col_elements[fill[ys[jj]]++] = {e, jj};
      }
    }
    for (int e = 0; e < n_el; ++e) {
      Element& el = element(e);
      el.offsets.assign(el.ys.size() * el.ys.size(), -1);
    }
    std::vector<std::vector<int>> col_rows(n);
    auto gather = [&](int j0, int j1) {
      std::vector<char> mark(n, 0);
      for (int j = j0; j < j1; ++j) {
        std::vector<int>& rows_j = col_rows[j];
        rows_j.push_back(j);
        mark[j] = 1;
        for (int q = col_start[j]; q < col_start[j + 1]; ++q)
          for (int v : element(col_elements[q].first).ys)
            if (!mark[v]) {
              mark[v] = 1;
              rows_j.push_back(v);
            }
        for (int v : rows_j) mark[v] = 0;
        std::sort(rows_j.begin(), rows_j.end());
      }
    };
    parallel_ranges(n, gather);
    std::vector<int> outer(n + 1, 0);
    for (int j = 0; j < n; ++j) outer[j + 1] = outer[j] + static_cast<int>(col_rows[j].size());
    H.resize(n, n);
    H.reserve(Eigen::VectorXi::Map(outer.data(), n + 1).tail(n) -
              Eigen::VectorXi::Map(outer.data(), n + 1).head(n));
    for (int j = 0; j < n; ++j)
      for (int i : col_rows[j]) H.insert(i, j) = 0.0;
    H.makeCompressed();
    auto locate = [&](int j0, int j1) {
      std::vector<int> pos(n, -1);
      for (int j = j0; j < j1; ++j) {
        const int base = H.outerIndexPtr()[j];
        const int len = H.outerIndexPtr()[j + 1] - base;
        for (int q = 0; q < len; ++q) pos[H.innerIndexPtr()[base + q]] = base + q;
        for (int q = col_start[j]; q < col_start[j + 1]; ++q) {
          const auto [e, jj] = col_elements[q];
          Element& el = element(e);
          const size_t k = el.ys.size();
          for (size_t i = 0; i < k; ++i) el.offsets[jj * k + i] = pos[el.ys[i]];
        }
        for (int q = 0; q < len; ++q) pos[H.innerIndexPtr()[base + q]] = -1;
      }
    };
    parallel_ranges(n, locate);
  }

  // Energy of x; with gradient g (reduced) and Hessian assembled when `derivatives`.
  double evaluate(const OptimizeSettings& s, const Eigen::VectorXd& x, bool derivatives,
                  Eigen::VectorXd* g) {
    double energy = 0;
    if (derivatives) {
      g->setZero(red.n_free());
      if (dense)
        Hd.setZero();
      else
        std::fill(H.valuePtr(), H.valuePtr() + H.nonZeros(), 0.0);
    }
    auto scatter = [&](const Element& el, const Eigen::VectorXd& gy, const Eigen::MatrixXd& hy) {
      const size_t k = el.ys.size();
      for (size_t i = 0; i < k; ++i) (*g)[el.ys[i]] += gy[i];
      if (dense) {
        for (size_t j = 0; j < k; ++j)
          for (size_t i = 0; i < k; ++i) Hd(el.ys[i], el.ys[j]) += hy(i, j);
      } else {
        double* vals = H.valuePtr();
        for (size_t j = 0; j < k; ++j)
          for (size_t i = 0; i < k; ++i) vals[el.offsets[j * k + i]] += hy(i, j);
      }
    };
    // Per-face work in parallel into per-face slots; sums and scatter in face order, so the
    // result does not depend on the number of threads.
    const int nf = domain.n_faces();
    face_value.resize(nf);
    if (derivatives) {
      face_gy.resize(nf);
      face_hy.resize(nf);
    }
    auto face_work = [&](int f) {
      const auto& fc = domain.face_copies[f];
      Eigen::Matrix2d X;
      for (int d = 0; d < 2; ++d) {
        X(d, 0) = x[2 * fc[1] + d] - x[2 * fc[0] + d];
        X(d, 1) = x[2 * fc[2] + d] - x[2 * fc[0] + d];
      }
      const Eigen::Matrix2d J = X * domain.rest_inverse[f];
      const DensityEval ev = evaluate_density(s.density, s.power, J, derivatives, true);
      const double a = domain.area[f];
      face_value[f] = ev.finite ? a * ev.value : std::numeric_limits<double>::infinity();
      if (!derivatives || !ev.finite) return;
      Eigen::Vector4d g4;
      Eigen::Matrix4d h4;
      edge_vector_derivatives(domain.rest_inverse[f], a, ev, &g4, &h4);
      const Element& el = faces[f];
      face_gy[f].noalias() = el.M.transpose() * g4;
      face_hy[f].noalias() = el.M.transpose() * h4 * el.M;
    };
#ifdef QUADIFY_WITH_TBB
    if (nf >= kParallelMinFaces)
      tbb::parallel_for(tbb::blocked_range<int>(0, nf, 256), [&](const tbb::blocked_range<int>& r) {
        for (int f = r.begin(); f < r.end(); ++f) face_work(f);
      });
    else
      for (int f = 0; f < nf; ++f) face_work(f);
#else
    for (int f = 0; f < nf; ++f) face_work(f);
#endif
    for (int f = 0; f < nf; ++f) {
      energy += face_value[f];
      if (!std::isfinite(face_value[f])) return std::numeric_limits<double>::infinity();
    }
    if (derivatives && dense) {
      for (int f = 0; f < nf; ++f) scatter(faces[f], face_gy[f], face_hy[f]);
    } else if (derivatives) {
        // By column, faces in increasing order within each: parallel and deterministic.
        double* vals = H.valuePtr();
        parallel_ranges(red.n_free(), [&](int j0, int j1) {
          for (int j = j0; j < j1; ++j)
            for (int q = col_start[j]; q < col_start[j + 1]; ++q) {
              const auto [e, jj] = col_elements[q];
              if (e >= nf) break;  // penalty rows follow the faces: scattered below
              const Element& el = faces[e];
              const size_t k = el.ys.size();
              (*g)[j] += face_gy[e][jj];
              const double* hcol = face_hy[e].data() + jj * k;
              const int* off = el.offsets.data() + jj * k;
              for (size_t i = 0; i < k; ++i) vals[off[i]] += hcol[i];
            }
        });
    }
    for (size_t i = 0; i < rows.size(); ++i) {
      const Eigen::VectorXd& co = row_coefs[i];
      double rv = 0;
      for (Eigen::Index j = 0; j < co.size(); ++j) rv += co[j] * x[(*penalty_rows)[i].entries[j].first];
      energy += s.penalty_weight * rv * rv;
      if (!derivatives) continue;
      const Element& el = rows[i];
      scatter(el, el.M.transpose() * (2 * s.penalty_weight * rv * co),
              el.M.transpose() * (2 * s.penalty_weight * co * co.transpose()) * el.M);
    }
    return energy;
  }
};

namespace {

// Largest t in (0, 1] such that det(X + t·dX) stays positive for every face positive now.
double max_flip_free_step(const LayoutDomain& domain, const Eigen::VectorXd& x,
                          const Eigen::VectorXd& dx) {
  double t_max = std::numeric_limits<double>::infinity();
  for (const auto& fc : domain.face_copies) {
    Eigen::Matrix2d X, D;
    for (int d = 0; d < 2; ++d) {
      X(d, 0) = x[2 * fc[1] + d] - x[2 * fc[0] + d];
      X(d, 1) = x[2 * fc[2] + d] - x[2 * fc[0] + d];
      D(d, 0) = dx[2 * fc[1] + d] - dx[2 * fc[0] + d];
      D(d, 1) = dx[2 * fc[2] + d] - dx[2 * fc[0] + d];
    }
    if (!(X.determinant() > 0)) continue;
    t_max = std::min(t_max, flip_root(X, D));
  }
  return t_max;
}

}  // namespace

double flip_root(const Eigen::Matrix2d& X, const Eigen::Matrix2d& D) {
  const double c0 = X.determinant();
  const double c2 = D.determinant();
  const double c1 = X(0, 0) * D(1, 1) + D(0, 0) * X(1, 1) - X(0, 1) * D(1, 0) - D(0, 1) * X(1, 0);
  double root = std::numeric_limits<double>::infinity();
  if (c2 == 0) {
    if (c1 < 0) root = -c0 / c1;
  } else {
    const double disc = c1 * c1 - 4 * c2 * c0;
    if (disc >= 0) {
      const double sq = std::sqrt(disc);
      // Numerically stable roots.
      const double q = -0.5 * (c1 + (c1 >= 0 ? sq : -sq));
      const double r1 = q / c2, r2 = q != 0 ? c0 / q : std::numeric_limits<double>::infinity();
      if (r1 > 0) root = std::min(root, r1);
      if (r2 > 0) root = std::min(root, r2);
    }
  }
  return root;
}

LayoutDomain make_domain(const CutMesh& cut) {
  LayoutDomain d;
  const int nf = static_cast<int>(cut.rest.size());
  d.n_copies = cut.n_copies();
  d.face_copies.resize(nf);
  d.rest_inverse.resize(nf);
  d.area = cut.area;
  for (int f = 0; f < nf; ++f) {
    d.face_copies[f] = {cut.corner_copy[3 * f], cut.corner_copy[3 * f + 1],
                        cut.corner_copy[3 * f + 2]};
    d.rest_inverse[f] = cut.rest[f].inverse();
  }
  return d;
}

Eigen::Matrix2d face_jacobian(const LayoutDomain& domain, int f, const Eigen::VectorXd& x) {
  const auto& fc = domain.face_copies[f];
  Eigen::Matrix2d X;
  for (int d = 0; d < 2; ++d) {
    X(d, 0) = x[2 * fc[1] + d] - x[2 * fc[0] + d];
    X(d, 1) = x[2 * fc[2] + d] - x[2 * fc[0] + d];
  }
  return X * domain.rest_inverse[f];
}

Eigen::Vector2d face_singular_values(const LayoutDomain& domain, int f, const Eigen::VectorXd& x) {
  const Eigen::Matrix2d J = face_jacobian(domain, f, x);
  const double ps = std::hypot(J(0, 0) + J(1, 1), J(1, 0) - J(0, 1));
  const double pa = std::hypot(J(0, 0) - J(1, 1), J(0, 1) + J(1, 0));
  return {0.5 * (ps + pa), 0.5 * (ps - pa)};
}

double max_isometric_distortion(const LayoutDomain& domain, const Eigen::VectorXd& x) {
  double s1max = 0, s2min = std::numeric_limits<double>::infinity();
  for (int f = 0; f < domain.n_faces(); ++f) {
    const Eigen::Vector2d s = face_singular_values(domain, f, x);
    s1max = std::max(s1max, s[0]);
    s2min = std::min(s2min, s[1]);
  }
  return s2min > 0 ? std::sqrt(s1max / s2min) : std::numeric_limits<double>::infinity();
}

Eigen::VectorXd face_densities(const LayoutDomain& domain, const Eigen::VectorXd& x,
                               Density density, double power) {
  Eigen::VectorXd out(domain.n_faces());
  for (int f = 0; f < domain.n_faces(); ++f)
    out[f] = evaluate_density(density, power, face_jacobian(domain, f, x), false, false).value;
  return out;
}

LayoutProblem::LayoutProblem(const LayoutDomain& domain, const Reduction& red,
                             const std::vector<SparseRow>* penalty_rows) {
  const auto t0 = Clock::now();
  impl_ = std::make_unique<Impl>(domain, red, penalty_rows);
  impl_->setup_seconds = seconds_since(t0);
}
LayoutProblem::~LayoutProblem() = default;
LayoutProblem::LayoutProblem(LayoutProblem&&) noexcept = default;
LayoutProblem& LayoutProblem::operator=(LayoutProblem&&) noexcept = default;

const Reduction& LayoutProblem::reduction() const { return impl_->red; }

OptimizeReport optimize_layout(const LayoutDomain& domain, const Reduction& red,
                               const OptimizeSettings& settings, Eigen::VectorXd* y) {
  LayoutProblem problem(domain, red, settings.penalty_rows);
  return optimize_layout(problem, settings, y);
}

OptimizeReport optimize_layout(LayoutProblem& problem, const OptimizeSettings& settings,
                               Eigen::VectorXd* y) {
  OptimizeReport rep;
  LayoutProblem::Impl& prob = *problem.impl_;
  const LayoutDomain& domain = prob.domain;
  const Reduction& red = prob.red;
  rep.timers.setup += prob.setup_seconds;  // reported once, by the first optimization
  prob.setup_seconds = 0;
  rep.hessian_nonzeros = prob.dense ? 0 : prob.H.nonZeros();
  rep.max_element_variables = prob.max_element_variables;
  rep.sum_sq_element_variables = prob.sum_sq_element_variables;
  const int n = red.n_free();
  Eigen::VectorXd x = red.expand(*y);
  Eigen::VectorXd g;
  auto tc = Clock::now();
  double energy = prob.evaluate(settings, x, true, &g);
  rep.timers.assembly += seconds_since(tc);
  rep.initial_energy = energy;
  if (!std::isfinite(energy)) {
    rep.status = core::Status::numerical_failure("layout optimization: start is flipped");
    rep.energy = energy;
    return rep;
  }
  if (n == 0) {
    rep.energy = energy;
    return rep;
  }
  core::SparseSolver& solver = prob.solver;
  bool& analyzed = prob.analyzed;
  for (int it = 0; it < settings.max_iterations; ++it) {
    // Newton direction with the PSD-projected Hessian (+ a tiny shift for the rotation mode).
    Eigen::VectorXd dy;
    tc = Clock::now();
    double mean_diag = prob.dense ? prob.Hd.diagonal().mean()
                                  : Eigen::VectorXd(prob.H.diagonal()).mean();
    if (!(mean_diag > 0)) mean_diag = 1;
    double shift = kRegularization * mean_diag;
    bool solved = false;
    for (int attempt = 0; attempt < 6 && !solved; ++attempt, shift *= 100) {
      if (prob.dense) {
        Eigen::MatrixXd A = prob.Hd;
        A.diagonal().array() += shift;
        Eigen::LLT<Eigen::MatrixXd> llt(A);
        if (llt.info() != Eigen::Success) continue;
        dy = -llt.solve(g);
        solved = true;
      } else {
        Eigen::SparseMatrix<double> A = prob.H;
        for (int i = 0; i < n; ++i) A.coeffRef(i, i) += shift;
        if (!analyzed) {
          const auto ta = Clock::now();
          if (!solver.analyze(A).is_ok()) break;
          analyzed = true;
          rep.timers.analyze += seconds_since(ta);
          tc = Clock::now();
        }
        if (!solver.factorize(A).is_ok()) continue;
        dy = -solver.solve(g);
        solved = true;
      }
    }
    rep.timers.factorize += seconds_since(tc);
    if (!solved || !dy.allFinite()) {
      rep.status = core::Status::numerical_failure("layout optimization: Newton system failed");
      break;
    }
    const double decrement = -g.dot(dy);
    if (decrement <= settings.relative_tolerance * std::abs(energy)) break;
    tc = Clock::now();
    const Eigen::VectorXd dx = red.P * dy;
    double alpha = std::min(1.0, kFlipFreeStepFraction * max_flip_free_step(domain, x, dx));
    double trial = std::numeric_limits<double>::infinity();
    Eigen::VectorXd x_trial;
    int bt = 0;
    for (; bt < kMaxBacktracks; ++bt, alpha *= 0.5) {
      x_trial = x + alpha * dx;
      trial = prob.evaluate(settings, x_trial, false, nullptr);
      if (trial <= energy - kArmijo * alpha * decrement) break;
    }
    rep.timers.line_search += seconds_since(tc);
    if (bt == kMaxBacktracks) break;  // no decrease possible: converged to round-off
    *y += alpha * dy;
    x = red.expand(*y);
    ++rep.iterations;
    const double previous = energy;
    tc = Clock::now();
    energy = prob.evaluate(settings, x, true, &g);
    rep.timers.assembly += seconds_since(tc);
    if (previous - energy <= 1e-3 * settings.relative_tolerance * std::abs(previous)) break;
  }
  rep.energy = energy;
  return rep;
}

}  // namespace quadify::param

namespace quadify::param {
namespace {

// Penalty weights tried (dimensionless, see move_into_constraints), in increasing order.
constexpr double kFirstPenalty = 1e3, kPenaltyGrowth = 10, kLastPenalty = 1e10;
// Newton iterations per penalty stage.
constexpr int kPenaltyIterations = 10;
// Newton-decrement stop of a penalty stage, relative to the energy (tight: the penalty stage
// must bring the new rows close before the projection).
constexpr double kPenaltyTolerance = 1e-10;
// Projection is attempted once every new row's residual is below this fraction of the mean
// seam edge length (the projection then moves vertices by about as much).
constexpr double kProjectResidual = 1e-3;

// Least-squares y with P·y + c ≈ x on the first n_fitted entries (−1: all).
Eigen::VectorXd project(const Reduction& red, const Eigen::VectorXd& x, int n_fitted,
                        core::Status* status, double* seconds) {
  const auto t0 = Clock::now();
  struct AddTime {
    Clock::time_point t0;
    double* s;
    ~AddTime() { *s += seconds_since(t0); }
  } add_time{t0, seconds};
  const Eigen::Index rows = n_fitted < 0 ? red.P.rows() : n_fitted;
  const Eigen::SparseMatrix<double> P = red.P.topRows(rows);
  Eigen::SparseMatrix<double> PtP = P.transpose() * P;
  core::SparseSolver solver;
  *status = solver.factorize(PtP);
  if (!status->is_ok()) return red.restrict(x);
  return solver.solve(P.transpose() * (x - red.c).head(rows));
}

}  // namespace

int count_flipped(const LayoutDomain& domain, const Eigen::VectorXd& x) {
  int n = 0;
  for (const auto& fc : domain.face_copies)
    if (core::orient2d(x.segment<2>(2 * fc[0]), x.segment<2>(2 * fc[1]), x.segment<2>(2 * fc[2])) <= 0)
      ++n;
  return n;
}

TransitionReport move_into_constraints(const LayoutDomain& domain, const Reduction& old_red,
                                       const ConstraintEliminator& elim,
                                       const std::vector<SparseRow>& new_rows, double weight_unit,
                                       Eigen::VectorXd* x, int n_fitted, int max_penalty_stages) {
  TransitionReport rep;
  const auto t_red = Clock::now();
  rep.reduction = elim.reduction(*x);
  rep.timers.setup += seconds_since(t_red);
  // weight_unit = area / Σ edge²: recover the mean squared length of the new seam edges.
  double area = 0;
  for (double a : domain.area) area += a;
  const double mean_edge_sq = area / weight_unit / std::max<size_t>(1, new_rows.size() / 2);
  double residual_tol = kProjectResidual * std::sqrt(mean_edge_sq);
  auto max_residual = [&](const Eigen::VectorXd& xx) {
    double r = 0;
    for (const auto& row : new_rows) {
      double v = 0;
      for (const auto& [var, coef] : row.entries) v += coef * xx[var];
      r = std::max(r, std::abs(v));
    }
    return r;
  };
  Eigen::VectorXd y_old = old_red.restrict(*x);
  Eigen::VectorXd x_cur = *x;
  Eigen::VectorXd x_best;
  int best_flips = INT32_MAX;
  // Cheapest first: the least-squares projection of the current layout (usually flip-free when
  // the new matchings are close to the measured rotations).
  {
    core::Status ps;
    const Eigen::VectorXd y_new =
        project(rep.reduction, x_cur, n_fitted, &ps, &rep.timers.projection);
    if (!ps.is_ok()) {
      rep.status = ps;
      return rep;
    }
    x_best = rep.reduction.expand(y_new);
    best_flips = count_flipped(domain, x_best);
  }
  std::unique_ptr<LayoutProblem> penalty_problem;  // shared by the penalty stages
  int stage = 0;
  for (double w = kFirstPenalty;
       w <= kLastPenalty && best_flips > 0 && (max_penalty_stages < 0 || stage < max_penalty_stages);
       w *= kPenaltyGrowth, ++stage) {
    if (max_residual(x_cur) > residual_tol) {
      OptimizeSettings st;
      st.max_iterations = kPenaltyIterations;
      st.relative_tolerance = kPenaltyTolerance;
      st.penalty_weight = w * weight_unit;
      if (!penalty_problem) penalty_problem = std::make_unique<LayoutProblem>(domain, old_red, &new_rows);
      const OptimizeReport r = optimize_layout(*penalty_problem, st, &y_old);
      rep.iterations += r.iterations;
      rep.timers += r.timers;
      if (!r.status.is_ok()) {
        rep.status = r.status;
        break;
      }
      x_cur = old_red.expand(y_old);
      if (max_residual(x_cur) > residual_tol) continue;
    }
    core::Status ps;
    const Eigen::VectorXd y_new =
        project(rep.reduction, x_cur, n_fitted, &ps, &rep.timers.projection);
    if (!ps.is_ok()) {
      rep.status = ps;
      break;
    }
    const Eigen::VectorXd x_new = rep.reduction.expand(y_new);
    const int flips = count_flipped(domain, x_new);
    if (flips < best_flips) {
      best_flips = flips;
      x_best = x_new;
    }
    if (flips == 0) break;
    residual_tol *= 0.1;  // still flipped: get closer to the new space before projecting
  }
  if (best_flips == INT32_MAX) {
    core::Status ps;
    x_best = rep.reduction.expand(
        project(rep.reduction, x_cur, n_fitted, &ps, &rep.timers.projection));
    best_flips = count_flipped(domain, x_best);
  }
  rep.n_flipped = best_flips;
  *x = x_best;
  if (rep.status.is_ok() && best_flips > 0)
    rep.status = core::Status::not_converged("could not enter the seamless constraint space "
                                             "without flips (" + std::to_string(best_flips) +
                                             " flipped faces)");
  return rep;
}

}  // namespace quadify::param
