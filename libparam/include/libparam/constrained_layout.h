// Flip-free layout optimization of a seamless map under extra affine constraints: the part of
// libparam's optimizer (paper eq. 2 with fixed matchings, section 4) that later stages need, e.g.
// the integer quantization of libquantize (paper Def. 3.2), in plain data.
//
// Variables: the UVs of the vertex copies of the map, scalar variable 2·copy + d (d = 0: u,
// d = 1: v), followed by the seam translations t_s = x_b0 − R^r x_a0, variable
// 2·#copies + 2·s + d for seam s of CopyLayout::seams. Copies are the corners merged across
// interior edges whose two faces agree on the UVs of both endpoints; every other interior edge is a
// seam with a matching r, where the homogeneous constraint e_b = R_90^r e_a (paper eq. 2b) always
// holds.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>
#include <libparam/seamless_param.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <utility>
#include <vector>

namespace quadify::param {

// A seam between vertex copies: edge (v0, v1) has copies a0, a1 in face_a and b0, b1 in face_b,
// and (x_b1 − x_b0) = R_90^matching (x_a1 − x_a0). Its translation is t = x_b0 − R^r x_a0.
struct CopySeam {
  int face_a = -1, face_b = -1;
  int a0 = -1, a1 = -1, b0 = -1, b1 = -1;
  int matching = 0;  // quarter turns, 0..3
};

struct CopyLayout {
  std::vector<int> corner_copy;     // #F·3, vertex copy of each corner
  std::vector<int> copy_vertex;     // #copies, mesh vertex of each copy
  std::vector<int> copy_component;  // #copies, face component (core::face_components) of each copy
  int n_components = 0;
  std::vector<CopySeam> seams;
  Eigen::VectorXd x;  // 2·#copies, the copies' UVs
  int n_copies() const { return static_cast<int>(copy_vertex.size()); }
};

// Builds the copies of a seamless map. `seams` lists the seam edges with their matchings (as in
// ParamResult); interior edges not listed must have equal UVs on both sides. Listed edges with
// matching 0 whose UVs agree exactly are merged (no seam). Every remaining seam must satisfy
// |e_b − R^r e_a| ≤ seam_tol × UV bbox diagonal.
// Returns kInvalidInput (naming the edge) for wrong sizes, non-finite UVs, a non-manifold or
// inconsistently oriented mesh, a seam entry that is not an interior edge of the mesh, an unlisted
// edge whose sides disagree, or a seam violating its matching.
[[nodiscard]] core::Status build_copy_layout(const core::TriMesh& mesh,
                                             const Eigen::MatrixX2d& corner_uv,
                                             const std::vector<SeamMatching>& seams,
                                             double seam_tol, CopyLayout* out);

// An affine constraint Σ coef·x_var = rhs over the scalar variables (copies and translations).
struct AffineRow {
  std::vector<std::pair<int, double>> entries;  // (variable, coefficient)
  double rhs = 0;
};

struct ConstrainedLayoutOptions {
  Energy energy = Energy::kSymmetricDirichlet;  // kTau is optimized as symmetric Dirichlet
  // Rest shapes are the 3D triangles scaled by this factor (UV units per model unit), so the
  // energy prefers a map of that scale.
  double rest_scale = 1;
  // Isotropic sizing (param::ParamOptions::face_size): rest shapes of face f are further scaled
  // by 1/face_size[f] (#F positive values, or empty).
  std::vector<double> face_size;
  // Anisotropic sizing (param::ParamOptions::face_metric): face f's 3D edge vectors are mapped by
  // face_metric[f] before its rest shape is taken (#F, or empty).
  std::vector<Eigen::Matrix3d> face_metric;
  int max_newton_iters = 60;
  // Newton stop: decrement below this fraction of the energy.
  double relative_tolerance = 1e-6;
  // Newton iterations per stage of an extra penalty homotopy (weights 1, 1e2, 1e4, 1e6 × area /
  // Σ edge²) inside the old space before the transition; 0 = none. For new rows far from the
  // current layout.
  int homotopy_iterations = 0;
  // Only eliminate: fill result.reduction and result.independent and return x0 projected onto
  // the old space, without moving into the new rows (no optimization, n_flipped not counted).
  // Cheap; used to check which values new rows imply before paying for a solve.
  bool reduce_only = false;
  // One copy per component keeps its current position (the translation gauge); -1 = the first
  // copy of the component.
  std::vector<int> gauge_copies;
  // After the symmetric Dirichlet solve: L^p stages (density (SD/4)^p) at these powers, each a
  // few Newton iterations from the previous one, towards the map's largest distortion (τ, as the
  // continuation of param::compute_seamless_param). Empty = none.
  std::vector<double> tau_powers;
};

// The reduced parametrization of the final constraint space: x = P·y + c over all variables
// (copies, then translations). Copies are eliminated before translations (x_b0 = R^r x_a0 + t),
// so with 0/±1 rows on translations and cone copies the pivots are units (P, c integer) except
// where a cone position is fixed by translations through (I − R^r), which may leave halves.
struct ConstrainedReduction {
  Eigen::SparseMatrix<double, Eigen::RowMajor> P;  // (2·#copies + 2·#seams) × n_free
  Eigen::VectorXd c;                               // 2·#copies + 2·#seams
  std::vector<int> free_vars;                      // column j ↔ scalar variable free_vars[j]
};

struct ConstrainedLayoutResult {
  core::Status status;
  Eigen::VectorXd x;              // 2·#copies + 2·#seams, the new layout and its translations
  std::vector<char> independent;  // per new row: 1 if it was independent of all previous rows
                                  // (dependent rows are dropped and not checked for consistency)
  int n_flipped = 0;              // faces with non-positive orientation (exact predicate)
  int iterations = 0;             // Newton iterations
  ConstrainedReduction reduction;
};

// Moves the layout x0 (2·#copies, optionally followed by the translations, which are recomputed;
// it satisfies the seam constraints of `copies` and `old_rows`) into the
// space of those constraints plus `new_rows` without flips (penalty homotopy followed by a
// projection, libparam's move_into_constraints), then minimises the energy there flip-free.
// old_rows must be independent of each other and of the seam rows (e.g. the rows a previous call
// reported independent). Faces of x0 must be positively oriented.
// Returns kInvalidInput for wrong sizes, kNotConverged when flips remain (result.n_flipped > 0,
// result.x is the least-flipped layout found), kNumericalFailure when a factorization fails.
[[nodiscard]] ConstrainedLayoutResult solve_constrained_layout(
    const core::TriMesh& mesh, const CopyLayout& copies, const Eigen::VectorXd& x0,
    const std::vector<AffineRow>& old_rows, const std::vector<AffineRow>& new_rows,
    const ConstrainedLayoutOptions& options = {});


// Flip-free layout optimization with pinned variables, for rounding free variables to integers
// one batch after another (paper Def. 3.2) without rebuilding anything between batches.
//
// The seam constraints are eliminated once, x = P·y + c. The elimination keeps the coordinates of
// the `prefer_free` copies (cone copies) free wherever it can and pivots on translations before
// them, so that a seam translation becomes an integer combination of cone coordinates and free
// translations (the loop around a cone, (I − R)·x_cone = Σ R·t, is solved for one t with a unit
// coefficient instead of for x_cone with determinant 2 or 4). Rounding then pins free variables
// y_j: a pinned row and column of the Hessian become the identity, so the Hessian pattern over y
// never changes and its symbolic factorization and per-face element maps are computed once.
struct PinnedLayoutOptions {
  Energy energy = Energy::kSymmetricDirichlet;  // kTau is optimized as symmetric Dirichlet
  // Rest shapes are the 3D triangles scaled by this factor (UV units per model unit).
  double rest_scale = 1;
  // Sizing, as ConstrainedLayoutOptions::face_size and face_metric.
  std::vector<double> face_size;
  std::vector<Eigen::Matrix3d> face_metric;
  // One copy per component keeps its position (the translation gauge); -1 = the first copy.
  std::vector<int> gauge_copies;
  // Per copy (#copies, or empty): keep its coordinates as free variables where possible.
  std::vector<char> prefer_free;
  // Per copy variable (2·#copies, or empty): pivot on it only when no other variable of a row has
  // a unit coefficient (coordinates that will be pinned to integers, e.g. of aligned features,
  // then stay integer combinations of free ones).
  std::vector<char> prefer_free_coords;
  // Further homogeneous rows Σ coef·x_var = 0 over copy variables (2·copy + d), e.g. feature
  // alignment x_b[c] − x_a[c] = 0, eliminated after the seam rows (dependent ones are dropped).
  // The start x0 must satisfy them.
  std::vector<AffineRow> extra_rows;
  // Direction alignment (param::ParamOptions::face_direction and direction_weight): #F 3D
  // directions or empty. Each face's energy gets weight·area·(component of the direction's image
  // across the UV axis it is nearest to in x0)²; the axis is fixed at init.
  std::vector<Eigen::Vector3d> face_direction;
  double direction_weight = 3;
  // Limit on Σ over faces of (free variables the face depends on)², the size of the element
  // Hessians (about 32 bytes each): init fails (kNumericalFailure, naming the figures) above it.
  // A map with very many cones can couple thousands of unknowns per triangle after the
  // elimination (linkCup's 1,481 cones: 8.9e8, which ran out of 24 GB); spot at 5,000 quads has
  // 6.4e5.
  double max_element_entries = 4e7;
  // A face that depends on more free variables than this is assembled in the copies' coordinates
  // and mapped by the elimination once per evaluation (H += Pᵀ·H_x·P over those faces), instead
  // of storing its own k×k Hessian: the faces along a seam whose translation depends on hundreds
  // of cones share one product. Below it, per-face Hessians assembled by a gather (faster).
  size_t wide_face_variables = 64;
};

// Outcome of PinnedLayout::pin: targets that were reached flip-free are pinned; the others stay
// free where the layout stopped (still flip-free).
struct PinReport {
  core::Status status;          // kNumericalFailure when a factorization failed
  std::vector<char> pinned;     // per target
  std::vector<char> blocking;   // per target not pinned: its move was limited by a face that
                                // would flip (a cone collision or a fold), not by the budget
  int iterations = 0;           // Newton steps (one factorization each)
};

struct PinSettings {
  // Newton steps that move the targets (each the largest flip-free fraction of the remaining
  // displacement, with the free variables re-optimized along).
  int max_steps = 30;
  // A step shorter than this fraction of the remaining displacement counts as stalled; after
  // kStalledSteps of them the targets whose faces limit the step are dropped.
  double stall_fraction = 0.05;
  // Steps without reaching the targets after which the targets whose faces limit the step are
  // dropped (they squeeze some region to zero area).
  int approach_steps = 6;
  // Penalty homotopy (0 stages = off) for targets that one flip-free step cannot reach: up to
  // stage_iterations Newton iterations on energy + w·unit·Σ (y_j − target)², w from
  // first_penalty growing by penalty_growth (unit: one triangle's stiffness), until every
  // residual is below snap_residual (UV units) or the residuals stop shrinking.
  int penalty_stages = 0;
  int stage_iterations = 8;
  double first_penalty = 1;
  double penalty_growth = 10;
  double snap_residual = 1e-3;
};

class PinnedLayout {
 public:
  PinnedLayout();
  ~PinnedLayout();
  PinnedLayout(PinnedLayout&&) noexcept;
  PinnedLayout& operator=(PinnedLayout&&) noexcept;

  // Eliminates the seam constraints of `copies` around the layout x0 (2·#copies, positively
  // oriented faces, seamless up to round-off: it is projected onto the constraint space), builds
  // the element maps and analyses the Hessian pattern.
  // Returns kInvalidInput for wrong sizes or a flipped start, kNumericalFailure when the
  // analysis fails.
  [[nodiscard]] core::Status init(const core::TriMesh& mesh, const CopyLayout& copies,
                                  const Eigen::VectorXd& x0, const PinnedLayoutOptions& options);

  // x = P·y + c in the external order (2·#copies + 2·#seams, see solve_constrained_layout).
  const ConstrainedReduction& reduction() const;
  int n_free() const;
  const Eigen::VectorXd& y() const;
  Eigen::VectorXd x() const;  // external order
  bool is_pinned(int j) const;
  int n_flipped() const;  // exact predicate; 0 after init and after every call

  // Moves free variables y_j to targets (j, value) flip-free, the other free variables following
  // by Newton steps on energy with the targets' displacement prescribed, then pins the reached
  // ones and relaxes with relax_iterations Newton iterations. A call without penalty stages that
  // pins no target leaves y exactly as it was.
  PinReport pin(const std::vector<std::pair<int, double>>& targets, const PinSettings& settings,
                int relax_iterations, double relax_tolerance);

  // Whether pinning `targets` (on top of the pinned variables) keeps every face that they alone
  // determine positively oriented (exact predicate); pin() drops targets that fail this.
  bool determined_faces_valid(const std::vector<std::pair<int, double>>& targets) const;

  // Faces (mesh face ids) that flip or degenerate along the linear response to moving the free
  // variables of `targets` to their values (one Newton solve with their displacement prescribed,
  // the other free variables following): where the layout resists the move. Used to locate what
  // blocks a target that pin() could not reach. Empty when nothing limits the full step.
  std::vector<int> limiting_faces(const std::vector<std::pair<int, double>>& targets);

  // Flip-free Newton minimisation of the energy over the unpinned variables. Returns the number
  // of iterations; *status is kNumericalFailure when a factorization fails.
  int minimize(int max_iterations, double relative_tolerance, core::Status* status);

  // Frees the pinned variable y_j (pin() may then move it to another value).
  void unpin(int j);
  // The variables and which of them are pinned: a trial (unpin, pin, minimize) can be undone
  // exactly by restore(saved()).
  struct Saved {
    Eigen::VectorXd y, x;
    std::vector<char> state;
  };
  Saved saved() const;
  void restore(const Saved& s);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace quadify::param
