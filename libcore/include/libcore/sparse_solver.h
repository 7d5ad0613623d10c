// The one sparse SPD solver wrapper: CHOLMOD (supernodal LLT) for large systems when built with it,
// Eigen's SimplicialLLT for small ones (and without CHOLMOD). Analyse a pattern once, factorize
// many times, solve many times.
#pragma once

#include <libcore/status.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>

namespace quadify::core {

class SparseSolver {
 public:
  SparseSolver();
  ~SparseSolver();
  SparseSolver(SparseSolver&&) noexcept;
  SparseSolver& operator=(SparseSolver&&) noexcept;

  // Symbolic analysis of A's pattern (A symmetric, both triangles stored). Reused by factorize()
  // as long as the pattern is the same.
  Status analyze(const Eigen::SparseMatrix<double>& A);
  // Numeric factorization; calls analyze() first if no pattern was analysed.
  Status factorize(const Eigen::SparseMatrix<double>& A);
  Status compute(const Eigen::SparseMatrix<double>& A) { return factorize(A); }
  // Solves A x = b with the last factorization. b: n×k.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  bool factorized() const;
  // The backend of large systems: "cholmod" or "eigen-llt".
  static const char* backend();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace quadify::core
