#include <libcore/sparse_solver.h>

#include <Eigen/SparseCholesky>
#ifdef QUADIFY_WITH_CHOLMOD
#include <cholmod.h>

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <tuple>
#include <utility>
#include <vector>
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

#ifdef QUADIFY_WITH_CHOLMOD
// CHOLMOD's supernodal factorization of a matrix stored in the order of its fill-reducing
// permutation P, lower triangle: cholmod_factorize then reads it as it is (S = A), where from an
// A in the original order it makes tril(P·A·Pᵀ) anew on every call (cholmod_ptranspose, a
// transpose of the whole matrix and an allocation; cholmod_factorize.c). analyze() takes P from
// CHOLMOD's own analysis of A (its ordering methods and postorder), builds the pattern of
// tril(P·A·Pᵀ) once with the source of every entry, and analyses that in the natural order
// without a postorder (P is postordered already); factorize() gathers the values, solve() permutes
// the right-hand sides. The factors agree with CHOLMOD's own to round-off (1e-12 relative), not to
// the bit. Measured: README design note "One transpose per factorization, then none".
struct PermutedCholmod {
  cholmod_common cc{};
  cholmod_factor* L = nullptr;
  cholmod_sparse* B = nullptr;  // tril(P·A·Pᵀ), sorted columns, stype −1
  std::vector<int> perm;        // B's row i is A's row perm[i]
  std::vector<int> src;         // B's value k is A's value src[k]

  PermutedCholmod() {
    cholmod_start(&cc);
    cc.print = 0;  // failures come back as Status; a library never prints
    cc.supernodal = CHOLMOD_SUPERNODAL;
    cc.final_asis = 1;
  }
  ~PermutedCholmod() {
    clear();
    cholmod_finish(&cc);
  }
  PermutedCholmod(const PermutedCholmod&) = delete;
  PermutedCholmod& operator=(const PermutedCholmod&) = delete;

  void clear() {
    if (L) cholmod_free_factor(&L, &cc);
    if (B) cholmod_free_sparse(&B, &cc);
  }

  bool analyze(const Eigen::SparseMatrix<double>& A) {
    clear();
    const int n = static_cast<int>(A.rows());
    // P from CHOLMOD's default analysis of A (upper triangle read, as a symmetric matrix).
    cholmod_sparse view{};
    view.nrow = view.ncol = static_cast<size_t>(n);
    view.nzmax = static_cast<size_t>(A.nonZeros());
    view.p = const_cast<int*>(A.outerIndexPtr());
    view.i = const_cast<int*>(A.innerIndexPtr());
    view.x = const_cast<double*>(A.valuePtr());
    view.stype = 1;
    view.itype = CHOLMOD_INT;
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    view.sorted = 1;
    view.packed = 1;
    cc.nmethods = 0;
    cc.postorder = 1;
    cholmod_factor* L0 = cholmod_analyze(&view, &cc);
    if (!L0 || cc.status != CHOLMOD_OK) {
      if (L0) cholmod_free_factor(&L0, &cc);
      return false;
    }
    perm.assign(static_cast<const int*>(L0->Perm), static_cast<const int*>(L0->Perm) + n);
    cholmod_free_factor(&L0, &cc);
    std::vector<int> inv(n);
    for (int i = 0; i < n; ++i) inv[perm[i]] = i;
    // Pattern of tril(P·A·Pᵀ): entry (r, c) of A goes to (inv[r], inv[c]) when that is on or
    // below the diagonal (both triangles of A are stored, so each pair is met once so).
    std::vector<int> count(n + 1, 0);
    for (int c = 0; c < n; ++c)
      for (int e = A.outerIndexPtr()[c]; e < A.outerIndexPtr()[c + 1]; ++e)
        if (inv[A.innerIndexPtr()[e]] >= inv[c]) ++count[inv[c] + 1];
    for (int c = 0; c < n; ++c) count[c + 1] += count[c];
    const size_t nnz = static_cast<size_t>(count[n]);
    B = cholmod_allocate_sparse(static_cast<size_t>(n), static_cast<size_t>(n), nnz, 1, 1, -1,
                                CHOLMOD_REAL, &cc);
    if (!B) return false;
    int* bp = static_cast<int*>(B->p);
    int* bi = static_cast<int*>(B->i);
    std::copy(count.begin(), count.end(), bp);
    src.assign(nnz, 0);
    std::vector<int> fill(count.begin(), count.end() - 1);
    for (int c = 0; c < n; ++c)
      for (int e = A.outerIndexPtr()[c]; e < A.outerIndexPtr()[c + 1]; ++e) {
        const int r = inv[A.innerIndexPtr()[e]], cc_ = inv[c];
        if (r < cc_) continue;
        bi[fill[cc_]] = r;
        src[fill[cc_]++] = e;
      }
    std::vector<std::pair<int, int>> col;
    for (int c = 0; c < n; ++c) {
      col.clear();
      for (int k = bp[c]; k < bp[c + 1]; ++k) col.push_back({bi[k], src[k]});
      std::sort(col.begin(), col.end());
      for (int k = bp[c]; k < bp[c + 1]; ++k) std::tie(bi[k], src[k]) = col[k - bp[c]];
    }
    // The natural order, without a postorder: P·A·Pᵀ is already in CHOLMOD's order.
    cc.nmethods = 1;
    cc.method[0].ordering = CHOLMOD_NATURAL;
    cc.postorder = 0;
    L = cholmod_analyze(B, &cc);
    return L && cc.status == CHOLMOD_OK;
  }

  bool factorize(const Eigen::SparseMatrix<double>& A) {
    double* bx = static_cast<double*>(B->x);
    const double* ax = A.valuePtr();
    for (size_t k = 0; k < src.size(); ++k) bx[k] = ax[src[k]];
    cholmod_factorize(B, L, &cc);
    return cc.status == CHOLMOD_OK && L->minor == L->n;
  }

  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) {
    const Eigen::Index n = b.rows();
    Eigen::MatrixXd bp(n, b.cols());
    for (Eigen::Index i = 0; i < n; ++i) bp.row(i) = b.row(perm[i]);
    cholmod_dense view{};
    view.nrow = static_cast<size_t>(n);
    view.ncol = static_cast<size_t>(b.cols());
    view.nzmax = view.nrow * view.ncol;
    view.d = view.nrow;
    view.x = bp.data();
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* X = cholmod_solve(CHOLMOD_A, L, &view, &cc);
    Eigen::MatrixXd out(n, b.cols());
    if (!X) {
      out.setConstant(std::numeric_limits<double>::quiet_NaN());
      return out;
    }
    const Eigen::Map<const Eigen::MatrixXd> xs(static_cast<const double*>(X->x), n, b.cols());
    for (Eigen::Index i = 0; i < n; ++i) out.row(perm[i]) = xs.row(i);
    cholmod_free_dense(&X, &cc);
    return out;
  }
};
#endif

struct SparseSolver::Impl {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> simplicial;
#ifdef QUADIFY_WITH_CHOLMOD
  std::unique_ptr<PermutedCholmod> supernodal;
#endif
  bool use_supernodal = false;
  bool analyzed = false;
  bool factorized = false;
  Eigen::Index n = 0;
  Eigen::Index nnz = 0;
};

SparseSolver::SparseSolver() : impl_(std::make_unique<Impl>()) {
#ifdef QUADIFY_WITH_CHOLMOD
  limit_library_threads();
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
  Impl& m = *impl_;
  m.factorized = false;
  m.analyzed = false;
  bool ok = false;
#ifdef QUADIFY_WITH_CHOLMOD
  m.use_supernodal = A.rows() > kSimplicialMaxSize;
  if (m.use_supernodal) {
    if (!m.supernodal) m.supernodal = std::make_unique<PermutedCholmod>();
    // The entries' sources index the compressed value array.
    ok = A.isCompressed() ? m.supernodal->analyze(A)
                          : m.supernodal->analyze(Eigen::SparseMatrix<double>(A));
  } else
#endif
  {
    m.simplicial.analyzePattern(A);
    ok = m.simplicial.info() == Eigen::Success;
  }
  if (!ok) return Status::numerical_failure("sparse solver: symbolic analysis failed");
  m.analyzed = true;
  m.n = A.rows();
  m.nnz = A.nonZeros();
  return Status::ok();
}

Status SparseSolver::factorize(const Eigen::SparseMatrix<double>& A) {
  Impl& m = *impl_;
  if (!m.analyzed || A.rows() != m.n || A.nonZeros() != m.nnz) {
    Status s = analyze(A);
    if (!s.is_ok()) return s;
  }
#ifdef QUADIFY_WITH_CHOLMOD
  if (m.use_supernodal) {
    m.factorized = A.isCompressed() ? m.supernodal->factorize(A)
                                    : m.supernodal->factorize(Eigen::SparseMatrix<double>(A));
  } else
#endif
  {
    m.simplicial.factorize(A);
    m.factorized = m.simplicial.info() == Eigen::Success;
  }
  if (!m.factorized)
    return Status::numerical_failure("sparse solver: factorization failed (matrix not positive definite?)");
  return Status::ok();
}

Eigen::MatrixXd SparseSolver::solve(const Eigen::MatrixXd& b) const {
  QUADIFY_CHECK(impl_->factorized, "solve() before a successful factorize()");
#ifdef QUADIFY_WITH_CHOLMOD
  if (impl_->use_supernodal) return impl_->supernodal->solve(b);
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
