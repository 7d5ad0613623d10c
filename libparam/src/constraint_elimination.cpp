#include "constraint_elimination.h"

#include <algorithm>
#include <climits>
#include <cmath>

namespace quadify::param {
namespace {

// Coefficients are sums of products of small integers (and, in rare non-unit pivots, of their
// quotients); anything this small relative to 1 is cancellation round-off, i.e. zero.
constexpr double kZeroCoefficient = 1e-12;

}  // namespace

Eigen::VectorXd Reduction::restrict(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y(n_free());
  for (int j = 0; j < n_free(); ++j) y[j] = x[free_vars[j]];
  return y;
}

ConstraintEliminator::ConstraintEliminator(int n_vars, std::vector<char> never_pivot,
                                           std::vector<int> pivot_priority,
                                           std::vector<char> pivot_last)
    : expr_(n_vars),
      dependent_(n_vars, 0),
      never_pivot_(std::move(never_pivot)),
      pivot_priority_(std::move(pivot_priority)),
      pivot_last_(std::move(pivot_last)),
      users_(n_vars),
      scratch_(n_vars, 0.0) {
  never_pivot_.resize(n_vars, 0);
  pivot_priority_.resize(n_vars, 0);
  pivot_last_.resize(n_vars, 0);
}

int ConstraintEliminator::max_expression_length() const {
  size_t m = 0;
  for (const auto& e : expr_) m = std::max(m, e.size());
  return static_cast<int>(m);
}

bool ConstraintEliminator::add_row(const SparseRow& row) {
  // Substitute the dependent variables: the row over free variables only.
  std::vector<int> touched;
  auto add = [&](int v, double a) {
    if (std::find(touched.begin(), touched.end(), v) == touched.end()) touched.push_back(v);
    scratch_[v] += a;
  };
  for (const auto& [v, a] : row.entries) {
    if (dependent_[v]) {
      for (const auto& [j, b] : expr_[v]) add(j, a * b);
    } else {
      add(v, a);
    }
  }
  std::sort(touched.begin(), touched.end());
  Expr reduced;
  for (int v : touched) {
    if (std::abs(scratch_[v]) > kZeroCoefficient) reduced.push_back({v, scratch_[v]});
    scratch_[v] = 0.0;
  }
  if (reduced.empty()) return false;

  // Pivot: among the variables of highest priority, a unit coefficient, newest variable
  // (pivot_last ones only when no other has a unit coefficient); else the largest coefficient.
  int top = INT_MIN;
  for (const auto& [v, a] : reduced)
    if (!never_pivot_[v]) top = std::max(top, pivot_priority_[v]);
  int best = -1, best_last = -1;
  for (int i = static_cast<int>(reduced.size()) - 1; i >= 0; --i) {
    if (never_pivot_[reduced[i].first] || pivot_priority_[reduced[i].first] != top) continue;
    if (std::abs(std::abs(reduced[i].second) - 1.0) < kZeroCoefficient) {
      if (!pivot_last_[reduced[i].first]) {
        best = i;
        break;
      }
      if (best_last < 0) best_last = i;
      continue;
    }
    if (best < 0 || std::abs(reduced[i].second) > std::abs(reduced[best].second)) best = i;
  }
  if (best_last >= 0 && (best < 0 || std::abs(std::abs(reduced[best].second) - 1.0) >= kZeroCoefficient))
    best = best_last;
  // A translation-free row cannot involve the gauge variables only.
  if (best < 0) return false;
  const int p = reduced[best].first;
  const double ap = reduced[best].second;
  Expr ep;
  for (const auto& [j, a] : reduced)
    if (j != p) ep.push_back({j, -a / ap});

  // Substitute x_p = ep into every dependent expression that references p.
  std::vector<int> users = std::move(users_[p]);
  users_[p].clear();
  std::sort(users.begin(), users.end());
  users.erase(std::unique(users.begin(), users.end()), users.end());
  Expr merged;
  for (int u : users) {
    Expr& eu = expr_[u];
    auto it = std::lower_bound(eu.begin(), eu.end(), std::make_pair(p, -1e300));
    if (it == eu.end() || it->first != p) continue;
    const double alpha = it->second;
    eu.erase(it);
    merged.clear();
    size_t i = 0, k = 0;
    while (i < eu.size() || k < ep.size()) {
      if (k == ep.size() || (i < eu.size() && eu[i].first < ep[k].first)) {
        merged.push_back(eu[i++]);
      } else if (i == eu.size() || ep[k].first < eu[i].first) {
        merged.push_back({ep[k].first, alpha * ep[k].second});
        users_[ep[k].first].push_back(u);
        ++k;
      } else {
        const double s = eu[i].second + alpha * ep[k].second;
        if (std::abs(s) > kZeroCoefficient) merged.push_back({eu[i].first, s});
        ++i;
        ++k;
      }
    }
    eu.swap(merged);
  }
  for (const auto& [j, a] : ep) users_[j].push_back(p);
  expr_[p] = std::move(ep);
  dependent_[p] = 1;
  ++rank_;
  return true;
}

Reduction ConstraintEliminator::reduction(const Eigen::VectorXd& x_fixed) const {
  const int n = n_vars();
  Reduction red;
  std::vector<int> col(n, -1);
  for (int v = 0; v < n; ++v) {
    if (dependent_[v] || never_pivot_[v]) continue;
    col[v] = static_cast<int>(red.free_vars.size());
    red.free_vars.push_back(v);
  }
  red.c = Eigen::VectorXd::Zero(n);
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(n);
  for (int v = 0; v < n; ++v) {
    if (!dependent_[v]) {
      if (never_pivot_[v])
        red.c[v] = x_fixed[v];
      else
        trip.emplace_back(v, col[v], 1.0);
      continue;
    }
    for (const auto& [j, a] : expr_[v]) {
      if (never_pivot_[j])
        red.c[v] += a * x_fixed[j];
      else
        trip.emplace_back(v, col[j], a);
    }
  }
  red.P.resize(n, red.n_free());
  red.P.setFromTriplets(trip.begin(), trip.end());
  return red;
}

}  // namespace quadify::param
