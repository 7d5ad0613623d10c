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

}  // namespace quadify::param
