// The seamless constraints over copies and explicit seam translations, eliminated so that every
// face depends on O(10) reduced variables (see the README, "Constraint fill"). Internal to
// libparam.
#pragma once

#include "constraint_elimination.h"
#include "cut_layout.h"

#include <array>
#include <vector>

namespace quadify::param {

// Scalar variables of the seam basis: the UVs of the vertex copies (2·copy + d, as everywhere in
// libparam), then one translation per seam, t_s = x_b0 − R^r x_a0 (2·#copies + 2·s + d).
inline int n_seam_basis_vars(const CutMesh& cut) {
  return 2 * cut.n_copies() + 2 * static_cast<int>(cut.seams.size());
}
inline int seam_translation_var(const CutMesh& cut, int seam, int d) {
  return 2 * cut.n_copies() + 2 * seam + d;
}

// The four scalar rows x_b0 − R^r x_a0 − t_s = 0 and x_b1 − R^r x_a1 − t_s = 0 of seam s (rows
// 0, 1: the v0 end; 2, 3: the v1 end). Their difference is seam_constraint_rows(cut, s, r).
std::array<SparseRow, 4> seam_translation_rows(const CutMesh& cut, int seam, int matching);

// What eliminate_seams found (for statistics and tests).
struct SeamBasisInfo {
  int n_closed_vertices = 0;     // interior vertices whose seams are all constrained
  int n_cones = 0;               // closed vertices with a non-trivial rotation around them
  int n_free_translations = 0;   // constrained seams whose translation stays free
  int gauge_copy = -1;           // copy fixed as the translation gauge
};

// Elimination of the seams s with matching[s] != INT_MIN over the seam basis (the translations
// of the other seams are fixed, i.e. never pivoted and unused). Pivots:
//  * the copies of a vertex are expressed by its oldest copy and the translations of its seams;
//  * around a closed vertex without rotation, Σ ±R t = 0 is solved for the translation of the
//    seam towards the nearest cone or open vertex along the constrained seams (BFS tree), the
//    rows being added farthest vertices first; at a cone, (I − R) x_cone = Σ ±R t is solved for
//    the cone's copy (coefficients in ½ℤ);
//  * the translations of the remaining seams (where BFS fronts meet, N_cones − 1 + 2g of them
//    once everything is constrained) are the free ones.
// A translation then depends on the free translations around its BFS region only, where an
// elimination of copies alone makes it a sum over all the cones behind the seam. The gauge is the
// root copy, or the oldest copy of a vertex that is not a cone when the root's vertex is one.
ConstraintEliminator eliminate_seams(const CutMesh& cut, const std::vector<int>& matching,
                                     SeamBasisInfo* info = nullptr);

}  // namespace quadify::param
