#include <libcore/sparse_solver.h>

#ifdef QUADIFY_WITH_CHOLMOD
#include <Eigen/CholmodSupport>
#else
#include <Eigen/SparseCholesky>
#endif

namespace quadify::core {

struct SparseSolver::Impl {
#ifdef QUADIFY_WITH_CHOLMOD
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
#else
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
#endif
  bool analyzed = false;
  bool factorized = false;
  Eigen::Index n = 0;
  Eigen::Index nnz = 0;
};

SparseSolver::SparseSolver() : impl_(std::make_unique<Impl>()) {
#ifdef QUADIFY_WITH_CHOLMOD
  impl_->solver.cholmod().print = 0;  // failures come back as Status; a library never prints
#endif
}
SparseSolver::~SparseSolver() = default;
SparseSolver::SparseSolver(SparseSolver&&) noexcept = default;
SparseSolver& SparseSolver::operator=(SparseSolver&&) noexcept = default;

const char* SparseSolver::backend() {
#ifdef QUADIFY_WITH_CHOLMOD
  return "cholmod";
#else
  return "eigen-ldlt";
#endif
}

Status SparseSolver::analyze(const Eigen::SparseMatrix<double>& A) {
  if (A.rows() != A.cols()) return Status::invalid_input("sparse solver: matrix is not square");
  impl_->solver.analyzePattern(A);
  impl_->factorized = false;
  if (impl_->solver.info() != Eigen::Success) {
    impl_->analyzed = false;
    return Status::numerical_failure("sparse solver: symbolic analysis failed");
  }
  impl_->analyzed = true;
  impl_->n = A.rows();
  impl_->nnz = A.nonZeros();
  return Status::ok();
}

Status SparseSolver::factorize(const Eigen::SparseMatrix<double>& A) {
  if (!impl_->analyzed || A.rows() != impl_->n || A.nonZeros() != impl_->nnz) {
    Status s = analyze(A);
    if (!s.is_ok()) return s;
  }
  impl_->solver.factorize(A);
  impl_->factorized = impl_->solver.info() == Eigen::Success;
  if (!impl_->factorized)
    return Status::numerical_failure("sparse solver: factorization failed (matrix not positive definite?)");
  return Status::ok();
}

Eigen::MatrixXd SparseSolver::solve(const Eigen::MatrixXd& b) const {
  QUADIFY_CHECK(impl_->factorized, "solve() before a successful factorize()");
  return impl_->solver.solve(b);
}

bool SparseSolver::factorized() const { return impl_->factorized; }

}  // namespace quadify::core
