// Exact elimination of the homogeneous seamlessness constraints (paper eq. 2b): x = P·y + c.
// Internal to libparam.
#pragma once

#include "cut_layout.h"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <utility>
#include <vector>

namespace quadify::param {

// The reduced parametrization x = P·y + c of the constraint space (x: all scalar variables).
struct Reduction {
  Eigen::SparseMatrix<double, Eigen::RowMajor> P;  // n_vars × n_free
  Eigen::VectorXd c;                               // n_vars (values of the fixed variables)
  std::vector<int> free_vars;                      // column j ↔ variable free_vars[j]
  int n_free() const { return static_cast<int>(free_vars.size()); }
  Eigen::VectorXd expand(const Eigen::VectorXd& y) const { return P * y + c; }
  // y with x = expand(y) at the free variables (exact when x satisfies the constraints).
  Eigen::VectorXd restrict(const Eigen::VectorXd& x) const;
};

// Incremental sparse Gaussian elimination of homogeneous rows Σ a_i x_i = 0. Each independent
// row makes one variable dependent: x_p = Σ α_j x_j over the still free variables. The pivot is
// a free variable with coefficient ±1 of highest index (the newest copy: copies are numbered
// away from the root, so expressions reference older copies); with 0/±1 input coefficients
// this keeps every α an integer, so x = P·y satisfies the constraints exactly in exact arithmetic.
// Redundant rows (dependent on earlier ones, e.g. around vertices) are detected and dropped.
// With pivot priorities, the pivot is a variable of highest priority in the row, chosen among
// those by the rule above; a non-unit pivot (e.g. the 2 of I − R² at a cone) then gives
// coefficients in ½ℤ, still exact in binary floating point.
class ConstraintEliminator {
 public:
  // never_pivot[v]: variable v stays free (the translation gauge). pivot_priority[v] (empty: all
  // equal) ranks the variables a row may be solved for, higher first. pivot_last[v] (empty:
  // none): among those, v is pivoted on only when no other variable of the row has a unit
  // coefficient (e.g. variables that will be pinned to integers, which must stay integer
  // combinations of free ones).
  ConstraintEliminator(int n_vars, std::vector<char> never_pivot,
                       std::vector<int> pivot_priority = {}, std::vector<char> pivot_last = {});
  // Returns true if the row was independent of the previous ones.
  bool add_row(const SparseRow& row);
  int rank() const { return rank_; }
  int n_vars() const { return static_cast<int>(expr_.size()); }
  // Largest number of terms in one dependent expression (fill-in measure).
  int max_expression_length() const;
  // x = P·y + c where the never_pivot variables are fixed to x_fixed (other entries ignored).
  Reduction reduction(const Eigen::VectorXd& x_fixed) const;

 private:
  using Expr = std::vector<std::pair<int, double>>;  // sorted by variable
  std::vector<Expr> expr_;                           // empty when free
  std::vector<char> dependent_;
  std::vector<char> never_pivot_;
  std::vector<int> pivot_priority_;
  std::vector<char> pivot_last_;
  std::vector<std::vector<int>> users_;              // dependents that may reference a variable
  std::vector<double> scratch_;
  int rank_ = 0;
};

}  // namespace quadify::param
