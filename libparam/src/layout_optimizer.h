// Flip-free Newton minimisation of a distortion energy over the reduced variables of the
// seamlessness constraints (paper eq. 2 with the matchings fixed). Internal to libparam.
#pragma once

#include "constraint_elimination.h"
#include "distortion_energy.h"

#include <libcore/status.h>

#include <Eigen/Core>

#include <array>
#include <memory>
#include <vector>

namespace quadify::param {

// The triangles being laid out: each face's three vertex copies and its isometric rest frame.
struct LayoutDomain {
  std::vector<std::array<int, 3>> face_copies;
  std::vector<Eigen::Matrix2d> rest_inverse;  // Dm⁻¹ (see CutMesh::rest)
  std::vector<double> area;
  int n_copies = 0;
  int n_faces() const { return static_cast<int>(face_copies.size()); }
};

LayoutDomain make_domain(const CutMesh& cut);

// Smallest positive t with det(X + t·D) = 0, X and D the edge matrices of a face and of its
// displacement (+inf when the orientation never changes along the step).
double flip_root(const Eigen::Matrix2d& X, const Eigen::Matrix2d& D);

struct OptimizeSettings {
  Density density = Density::kSymmetricDirichlet;
  double power = 1;             // exponent of the power densities
  int max_iterations = 60;
  // Stop when the Newton decrement −gᵀd falls below this fraction of the energy.
  double relative_tolerance = 1e-9;
  // Quadratic penalty w·Σ(row·x)² added to the energy (used to move into a smaller constraint
  // space without flips).
  const std::vector<SparseRow>* penalty_rows = nullptr;
  double penalty_weight = 0;
};

// Wall-clock seconds spent in the parts of the optimizer (profiling; summed over calls).
struct OptimizeTimers {
  double setup = 0;        // element maps (PᵀHP structure) and Hessian pattern
  double assembly = 0;     // energy, gradient and Hessian evaluations at accepted points
  double analyze = 0;      // symbolic analysis of the sparse solver
  double factorize = 0;    // numeric factorization and solve
  double line_search = 0;  // flip-free step bound and backtracking evaluations
  double projection = 0;   // least-squares projections onto a new constraint space
  OptimizeTimers& operator+=(const OptimizeTimers& o) {
    setup += o.setup;
    assembly += o.assembly;
    analyze += o.analyze;
    factorize += o.factorize;
    line_search += o.line_search;
    projection += o.projection;
    return *this;
  }
};

struct OptimizeReport {
  core::Status status;
  OptimizeTimers timers;
  long long hessian_nonzeros = 0;   // of the reduced Hessian PᵀHP (sparse mode), both triangles
  int max_element_variables = 0;    // reduced variables of the widest face element
  long long sum_sq_element_variables = 0;  // Σ_f k_f² over the face elements (setup/assembly work)
  int iterations = 0;
  double energy = 0;            // area-weighted density sum (+ penalty)
  double initial_energy = 0;
};

// Minimises Σ_f area_f·ψ(J_f) (+ penalty) over y, x = red.expand(y), starting from *y. Steps are
// limited to keep every triangle with positive orientation positive (Smith & Schaefer 2015) and
// accepted by Armijo backtracking. Uses core::SparseSolver, or a dense Cholesky for small problems.
OptimizeReport optimize_layout(const LayoutDomain& domain, const Reduction& red,
                               const OptimizeSettings& settings, Eigen::VectorXd* y);

// The structure of the energy over one reduction: per-face maps to the reduced variables, the
// reduced Hessian's pattern and its symbolic factorization. Building it costs Σ_f k_f² for
// elements of k_f reduced variables (large near cones once every matching is fixed), so
// optimizations that share the reduction and penalty rows — with other densities, powers or
// penalty weights — share one LayoutProblem. `domain`, `red` and `*penalty_rows` must outlive it.
class LayoutProblem {
 public:
  LayoutProblem(const LayoutDomain& domain, const Reduction& red,
                const std::vector<SparseRow>* penalty_rows = nullptr);
  ~LayoutProblem();
  LayoutProblem(LayoutProblem&&) noexcept;
  LayoutProblem& operator=(LayoutProblem&&) noexcept;
  const Reduction& reduction() const;
  struct Impl;

 private:
  friend OptimizeReport optimize_layout(LayoutProblem&, const OptimizeSettings&, Eigen::VectorXd*);
  std::unique_ptr<Impl> impl_;
};

// optimize_layout over a prepared problem; settings.penalty_rows is ignored (the problem's rows
// count, weighted by settings.penalty_weight).
OptimizeReport optimize_layout(LayoutProblem& problem, const OptimizeSettings& settings,
                               Eigen::VectorXd* y);

// Per-face densities ψ(J_f) of the layout x (2·#copies); +inf for a barrier density at a flip.
Eigen::VectorXd face_densities(const LayoutDomain& domain, const Eigen::VectorXd& x,
                               Density density, double power);

// Jacobian of face f (rest frame → UV) in the layout x.
Eigen::Matrix2d face_jacobian(const LayoutDomain& domain, int f, const Eigen::VectorXd& x);

// Signed singular values (σ1 ≥ |σ2|, σ2 < 0 on a flip) of face f's Jacobian in the layout x.
Eigen::Vector2d face_singular_values(const LayoutDomain& domain, int f, const Eigen::VectorXd& x);

// The paper's τ (eq. 3) of the layout x: sqrt(max σ1 / min σ2); +inf when a face is flipped or
// degenerate.
double max_isometric_distortion(const LayoutDomain& domain, const Eigen::VectorXd& x);

}  // namespace quadify::param

namespace quadify::param {

struct TransitionReport {
  core::Status status;
  OptimizeTimers timers;
  Reduction reduction;   // of the new constraint set
  int iterations = 0;
  int n_flipped = 0;     // flipped faces after the move (exact predicate); 0 on success
};

// Moves the layout *x (which satisfies the constraints of `old_red`) into the constraint space of
// `elim` (old rows + `new_rows`) without flips: minimises SD + w·weight_unit·Σ(row·x)² inside the
// old space for increasing w until the new rows are nearly satisfied, then projects (least
// squares) onto the new space and checks orientations exactly; continues with larger w while
// faces are flipped. weight_unit makes w dimensionless (area / Σ edge length²). The projections
// fit the first n_fitted entries of x (−1: all), e.g. the copies when the other variables are
// functions of them (seam translations). max_penalty_stages bounds the penalty stages (−1: up
// to w = 1e10), for callers to whom a failure costs nothing but the attempt.
TransitionReport move_into_constraints(const LayoutDomain& domain, const Reduction& old_red,
                                       const ConstraintEliminator& elim,
                                       const std::vector<SparseRow>& new_rows, double weight_unit,
                                       Eigen::VectorXd* x, int n_fitted = -1,
                                       int max_penalty_stages = -1);

// Faces with non-positive orientation of their three copies in x (exact predicate).
int count_flipped(const LayoutDomain& domain, const Eigen::VectorXd& x);

}  // namespace quadify::param
