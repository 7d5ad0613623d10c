#include <libcore/sparse_solver.h>

#include <Eigen/SparseCholesky>
#ifdef QUADIFY_WITH_CHOLMOD
#include <Eigen/CholmodSupport>

#include <dlfcn.h>

#include <cstdlib>
#include <mutex>
#endif

namespace quadify::core {

namespace {
// Below this many unknowns a matrix is factorized by Eigen's simplicial LLT (AMD ordering): no
// BLAS calls, no OpenMP team and no supernodal set-up per call, which dominate on the small
// systems of local estimation (a BFS-5 patch has ~200 unknowns) and would otherwise spin
// CHOLMOD's OpenMP threads inside every TBB task. Measured on elk's parametrization (354 patches,
// 2 cores): see the README design note on the sparse solver.
constexpr Eigen::Index kSimplicialMaxSize = 4000;

#ifdef QUADIFY_WITH_CHOLMOD
// CHOLMOD of SuiteSparse 5 opens an OpenMP team of CHOLMOD_OMP_NUM_THREADS (compiled in: 4) for
// the scatter of every large supernode, and OpenBLAS runs its own threads for the dense blocks.
// On our 2-core machines, next to TBB's workers, those teams oversubscribe the cores: their
// threads spin and yield (a remesh of spot made 1.1 million futex and 0.2 million sched_yield
// calls), and under load a factorization took 4× longer (fandisk with soft features, load 6:
// 30.8 s of factorization against 7.1 s single-threaded). So both run single-threaded; the
// parallelism is TBB's (components, patches, per-face work). The symbols are looked up at run
// time: nothing changes with another BLAS or a CHOLMOD without OpenMP, or when the user sets
// OMP_NUM_THREADS, OMP_THREAD_LIMIT or OPENBLAS_NUM_THREADS.
void limit_library_threads() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!std::getenv("OMP_NUM_THREADS") && !std::getenv("OMP_THREAD_LIMIT"))
      if (auto* set_levels = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels")))
        set_levels(0);  // every parallel region runs on the calling thread alone
    if (!std::getenv("OPENBLAS_NUM_THREADS"))
      if (auto* set_threads = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")))
        set_threads(1);
  });
}
#endif
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
  limit_library_threads();
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
