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
// OpenBLAS runs its own threads for the dense blocks; on our 2-core machines, next to TBB's
// workers, they oversubscribe the cores (under load a factorization took 4× longer: fandisk with
// soft features, load 6, 30.8 s of factorization against 7.1 s single-threaded). So it runs
// single-threaded; the parallelism is TBB's (components, patches, per-face work). The symbol is
// looked up at run time: nothing changes with another BLAS, or when the user sets
// OPENBLAS_NUM_THREADS. CHOLMOD's own OpenMP regions: see GOMP_parallel below.
void limit_library_threads() {
  static std::once_flag once;
  std::call_once(once, [] {
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
  // The upper triangle: with a fill-reducing permutation CHOLMOD's supernodal factorization
  // makes S = tril(P·A·Pᵀ) from an upper-stored A in one transpose, from a lower-stored one in
  // two (cholmod_factorize.c); both triangles are stored, so either view is the same matrix.
  // Measured: README design note "Heap reuse and one transpose per factorization".
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Upper> supernodal;
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

#ifdef QUADIFY_WITH_CHOLMOD
// CHOLMOD of SuiteSparse 5 opens an OpenMP parallel region (`#pragma omp parallel for` with
// num_threads(4) compiled in) for every supernode of every factorization, several per supernode,
// most of them too small to split. libgomp runs even a region of one thread through a new team
// and a closing barrier whose futex wake-up is a system call, tens of thousands per factorization.
// With the regions serial (before: omp_set_max_active_levels(0)) that still cost a third of a
// remesh of casting at 5,000 quads: 82 s wall, 13 s of it system time, 0.9 million futex calls.
// This definition replaces libgomp's entry point for the whole program (the linker exports it to
// libcholmod, which references it; a definition in the executable wins over the shared
// library's): every region runs on the calling thread, as one thread of a team of one, which is
// what a parallel loop without a team does (omp_get_num_threads() = 1, omp_get_thread_num() = 0).
// casting: 82 → 56 s, output byte-identical. We parallelize with TBB, never with OpenMP; CHOLMOD
// and OpenBLAS are the only callers, and both only run parallel loops (no synchronization
// between threads that a single thread could deadlock on).
extern "C" void GOMP_parallel(void (*fn)(void*), void* data, unsigned /*num_threads*/, unsigned /*flags*/) {
  fn(data);
}
#endif
