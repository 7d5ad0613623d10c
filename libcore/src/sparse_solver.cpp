#include <libcore/sparse_solver.h>

#include <Eigen/SparseCholesky>
#ifdef QUADIFY_WITH_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

namespace quadify::core {

namespace {
// Below this many unknowns a matrix is factorized by Eigen's simplicial LLT (AMD ordering): no
// BLAS calls, no OpenMP team and no supernodal set-up per call, which dominate on the small
// systems of local estimation (a BFS-5 patch has ~200 unknowns) and would otherwise spin
// CHOLMOD's OpenMP threads inside every TBB task. Measured on elk's parametrization (354 patches,
// 2 cores): see the README design note on the sparse solver.
constexpr Eigen::Index kSimplicialMaxSize = 4000;
}  // namespace

struct SparseSolver::Impl {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> simplicial;
#ifdef QUADIFY_WITH_CHOLMOD
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> supernodal;
#endif
  bool use_supernodal = false;
  bool analyzed = false;
  bool factorized = false;
  Eigen::Index n = 0;
  Eigen::Index nnz = 0;
  Eigen::ComputationInfo info() const {
#ifdef QUADIFY_WITH_CHOLMOD
    if (use_supernodal) return supernodal.info();
#endif
    return simplicial.info();
  }
};

SparseSolver::SparseSolver() : impl_(std::make_unique<Impl>()) {
#ifdef QUADIFY_WITH_CHOLMOD
  impl_->supernodal.cholmod().print = 0;  // failures come back as Status; a library never prints
#endif
}
SparseSolver::~SparseSolver() = default;
SparseSolver::SparseSolver(SparseSolver&&) noexcept = default;
SparseSolver& SparseSolver::operator=(SparseSolver&&) noexcept = default;

const char* SparseSolver::backend() {
#ifdef QUADIFY_WITH_CHOLMOD
  return "cholmod";
#else
  return "eigen-llt";
#endif
}

Status SparseSolver::analyze(const Eigen::SparseMatrix<double>& A) {
  if (A.rows() != A.cols()) return Status::invalid_input("sparse solver: matrix is not square");
#ifdef QUADIFY_WITH_CHOLMOD
  impl_->use_supernodal = A.rows() > kSimplicialMaxSize;
  if (impl_->use_supernodal)
    impl_->supernodal.analyzePattern(A);
  else
#endif
    impl_->simplicial.analyzePattern(A);
  impl_->factorized = false;
  if (impl_->info() != Eigen::Success) {
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
#ifdef QUADIFY_WITH_CHOLMOD
  if (impl_->use_supernodal)
    impl_->supernodal.factorize(A);
  else
#endif
    impl_->simplicial.factorize(A);
  impl_->factorized = impl_->info() == Eigen::Success;
  if (!impl_->factorized)
    return Status::numerical_failure("sparse solver: factorization failed (matrix not positive definite?)");
  return Status::ok();
}

Eigen::MatrixXd SparseSolver::solve(const Eigen::MatrixXd& b) const {
  QUADIFY_CHECK(impl_->factorized, "solve() before a successful factorize()");
#ifdef QUADIFY_WITH_CHOLMOD
  if (impl_->use_supernodal) return impl_->supernodal.solve(b);
#endif
  return impl_->simplicial.solve(b);
}

bool SparseSolver::factorized() const { return impl_->factorized; }

}  // namespace quadify::core
