// Unit tests of libparam internals: cut + isometric unfold, matching measurement, constraint
// elimination (copies only and in the seam-translation basis), energy derivatives, the layout
// optimizer, local estimation and the cone-pair search.
#include "cone_pairs.h"
#include "constraint_elimination.h"
#include "cut_layout.h"
#include "distortion_energy.h"
#include "feature_alignment.h"
#include "layout_optimizer.h"
#include "local_estimation.h"
#include "seam_basis.h"

#include <libcore/predicates.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <climits>
#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "test_meshes.h"

namespace quadify::param {
namespace {

Eigen::VectorXd flatten(const Eigen::MatrixX2d& x) {
  Eigen::VectorXd v(2 * x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) v.segment<2>(2 * i) = x.row(i).transpose();
  return v;
}

// Singular values of J via the similarity/anti-similarity split (σ2 signed).
std::pair<double, double> singular_values(const Eigen::Matrix2d& J) {
  const double ps = std::hypot(J(0, 0) + J(1, 1), J(1, 0) - J(0, 1));
  const double pa = std::hypot(J(0, 0) - J(1, 1), J(0, 1) + J(1, 0));
  return {0.5 * (ps + pa), 0.5 * (ps - pa)};
}

TEST(CutLayout, DualTreeCutIsADiskWithFPlus2Copies) {
  const core::TriMesh m = test::make_icosphere(2);
  const CutMesh cut = cut_along_dual_tree(m, 0);
  EXPECT_EQ(cut.n_copies(), m.n_faces() + 2) << "a tree of triangles has F+2 vertices";
  EXPECT_EQ(static_cast<int>(cut.seams.size()), cut.topo.n_edges() - (m.n_faces() - 1));
}

// A +1 and a −1 cone at the ends of a seam edge pair up, unless one end is to be avoided (a
// vertex of an aligned feature): then no path may start, end or pass there.
TEST(ConePairs, PathsAvoidFlaggedVertices) {
  const core::TriMesh m = test::make_icosphere(2);
  const CutMesh cut = cut_along_dual_tree(m, 0);
  ASSERT_FALSE(cut.seams.empty());
  const int f = cut.seams[0].he_a / 3, k = cut.seams[0].he_a % 3;
  const int a = m.F(f, k), b = m.F(f, (k + 1) % 3);
  std::vector<int> index(m.n_vertices(), 0);
  index[a] = 1;
  index[b] = -1;
  const double far = 10;  // longer than any seam path of the unit sphere
  const std::vector<ConePairCancellation> found = find_cone_pair_cancellations(m, cut, index, far, 1);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].positive_vertex, a);
  EXPECT_EQ(found[0].negative_vertex, b);
  ASSERT_EQ(found[0].changes.size(), 1u);
  EXPECT_EQ(found[0].changes[0].seam, 0);
  std::vector<char> avoid(m.n_vertices(), 0);
  avoid[b] = 1;
  EXPECT_TRUE(find_cone_pair_cancellations(m, cut, index, far, 3, avoid).empty());
  // An avoided regular vertex: the direct pair stays, and no path of up to 3 seam edges runs
  // through it.
  avoid.assign(m.n_vertices(), 0);
  const int c = a == 0 || b == 0 ? (a == 1 || b == 1 ? 2 : 1) : 0;
  avoid[c] = 1;
  const std::vector<ConePairCancellation> around = find_cone_pair_cancellations(m, cut, index, far, 3, avoid);
  ASSERT_EQ(around.size(), 1u);
  for (const SeamChange& ch : around[0].changes) {
    const int g = cut.seams[ch.seam].he_a / 3, j = cut.seams[ch.seam].he_a % 3;
    EXPECT_NE(m.F(g, j), c);
    EXPECT_NE(m.F(g, (j + 1) % 3), c);
  }
}

// Pairs by surface distance: a +1 and a −1 cone at the ends of an edge of the dual tree (not a
// seam; the seams join them by a longer path) pair up when the edge is within the distance; the
// changes run along the seams and move exactly one unit of index from the +1 to the −1 cone
// (inner vertices unchanged). Too far, or one end avoided: no pair.
TEST(ConePairs, SurfacePairsTakeTheSeamPathOfANearPair) {
  const core::TriMesh m = test::make_icosphere(3);
  const CutMesh cut = cut_along_dual_tree(m, 0);
  std::vector<char> seam_edge(cut.topo.n_edges(), 0);
  for (const CutSeam& s : cut.seams) seam_edge[s.edge] = 1;
  int e = 0;
  while (seam_edge[e]) ++e;
  const int a = cut.topo.edge_vertex(e, 0), b = cut.topo.edge_vertex(e, 1);
  const double length = (m.V.row(a) - m.V.row(b)).norm();
  std::vector<int> index(m.n_vertices(), 0);
  index[a] = 1;
  index[b] = -1;
  const std::vector<ConePairCancellation> found = find_surface_cone_pairs(m, cut, index, 1.01 * length);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].positive_vertex, a);
  EXPECT_EQ(found[0].negative_vertex, b);
  EXPECT_DOUBLE_EQ(found[0].path_length, length);
  EXPECT_GE(found[0].changes.size(), 2u) << "a dual-tree edge is no seam: the seam path is longer";
  std::vector<int> moved(m.n_vertices(), 0);
  for (const SeamChange& ch : found[0].changes) {
    const int g = cut.seams[ch.seam].he_a / 3, j = cut.seams[ch.seam].he_a % 3;
    moved[m.F(g, j)] -= ch.delta;
    moved[m.F(g, (j + 1) % 3)] += ch.delta;
  }
  for (int v = 0; v < m.n_vertices(); ++v) EXPECT_EQ(moved[v], v == a ? -1 : v == b ? 1 : 0) << v;
  EXPECT_TRUE(find_surface_cone_pairs(m, cut, index, 0.99 * length).empty());
  std::vector<char> avoid(m.n_vertices(), 0);
  avoid[b] = 1;
  EXPECT_TRUE(find_surface_cone_pairs(m, cut, index, 10, avoid).empty());
}

// The sectors between aligned features round a path's vertices. Raising seam 0's matching turns
// its face b against face a (turned_face), lowers v's index (v gains a quarter of map angle) and
// raises w's (w loses one), in the sectors on the turned side of the path's edge. With a feature
// along the path's edge and another on the other edge at w of one of the seam's faces, the
// one-face sector (about 60° here) is on the fixed side (face a: the wide sector loses, fine) or
// on the turned side (face b: it closes); at v, the one-face sector on the turned side opened to
// 150° is more than 1.75 times its surface angle. A row of the path's feature in face b counts as
// in face a (its label flips with the change); one feature alone bounds no sector.
TEST(ConePairs, APathMayNotCloseOrFlattenAFeatureSector) {
  const core::TriMesh m = test::make_icosphere(2);
  const CutMesh cut = cut_along_dual_tree(m, 0);
  const Eigen::VectorXd x = flatten(isometric_unfold(m, cut));
  const CutSeam& seam = cut.seams[0];
  const int fa = seam.he_a / 3, ka = seam.he_a % 3, fb = seam.he_b / 3, kb = seam.he_b % 3;
  const int v = m.F(fa, ka), w = m.F(fa, (ka + 1) % 3);
  ASSERT_EQ(m.F(fb, kb), w);
  EXPECT_EQ(turned_face(cut, {0, 1}), fb);
  EXPECT_EQ(turned_face(cut, {0, -1}), fa);
  EXPECT_EQ(turned_face(cut, {0, 2}), -1);
  ConePairCancellation pair;
  pair.positive_vertex = v;
  pair.negative_vertex = w;
  pair.changes = {{0, 1}};
  std::vector<int> row_face(cut.topo.n_edges(), -1);
  EXPECT_FALSE(path_closes_feature_sector(m, cut, x, pair, row_face)) << "no features";
  row_face[seam.edge] = fa;
  EXPECT_FALSE(path_closes_feature_sector(m, cut, x, pair, row_face)) << "one feature bounds no sector";
  const int a_at_w = cut.topo.face_edge(fa, (ka + 1) % 3);  // w → third vertex of face a
  const int b_at_w = cut.topo.face_edge(fb, (kb + 2) % 3);  // third vertex of face b → w
  const int a_at_v = cut.topo.face_edge(fa, (ka + 2) % 3);
  const int b_at_v = cut.topo.face_edge(fb, (kb + 1) % 3);
  for (const int path_row : {fa, fb}) {
    SCOPED_TRACE(path_row == fa ? "path feature's row in face a" : "in face b (flipped)");
    std::vector<int> rows(cut.topo.n_edges(), -1);
    rows[seam.edge] = path_row;
    rows[a_at_w] = fa;
    EXPECT_FALSE(path_closes_feature_sector(m, cut, x, pair, rows)) << "w: the wide sector loses a quarter";
    rows[a_at_w] = -1;
    rows[b_at_w] = fb;
    EXPECT_TRUE(path_closes_feature_sector(m, cut, x, pair, rows)) << "w: face b's sector closes";
    rows[b_at_w] = -1;
    rows[a_at_v] = fa;
    EXPECT_FALSE(path_closes_feature_sector(m, cut, x, pair, rows)) << "v: the wide sector opens a little";
    rows[a_at_v] = -1;
    rows[b_at_v] = fb;
    EXPECT_TRUE(path_closes_feature_sector(m, cut, x, pair, rows)) << "v: face b's sector opens 2.5x";
  }
}

// Splits: a cone of index 3 gives one unit per call to a regular vertex about `distance` away
// along the seams; two +1 cones closer than distance/2 are crowded and the one with the larger
// id moves; every target is regular, at least distance/2 from every other positive cone, and
// the moves change the index by the path's ends only (the sign rule of the header: −1 at the
// start, +1 at the end). Of a crowded pair one cone moves.
TEST(ConeSplits, MoveUnitsOffHighIndexAndCrowdedCones) {
  const core::TriMesh m = test::make_icosphere(3);
  const CutMesh cut = cut_along_dual_tree(m, 0);
  const double distance = 0.5;  // the unit sphere's edges are about 0.08 long at 3 subdivisions
  std::vector<int> index(m.n_vertices(), 0);
  index[0] = 3;
  const std::vector<ConePairCancellation> one = find_cone_splits(m, cut, index, 1, distance, 64);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].positive_vertex, 0);
  EXPECT_EQ(index[one[0].negative_vertex], 0);
  EXPECT_LE(one[0].path_length, 2 * distance);
  EXPECT_GE((m.V.row(one[0].negative_vertex) - m.V.row(0)).norm(), 0.5 * distance);
  // The changes move one unit from the start to the end: per vertex, +delta lowers the seam's
  // first vertex and raises its second.
  std::vector<int> moved(m.n_vertices(), 0);
  for (const SeamChange& ch : one[0].changes) {
    const int g = cut.seams[ch.seam].he_a / 3, j = cut.seams[ch.seam].he_a % 3;
    moved[m.F(g, j)] -= ch.delta;
    moved[m.F(g, (j + 1) % 3)] += ch.delta;
  }
  for (int v = 0; v < m.n_vertices(); ++v)
    EXPECT_EQ(moved[v], v == 0 ? -1 : v == one[0].negative_vertex ? 1 : 0) << v;
  // A crowded pair of +1 cones (a seam edge apart): one moves, away from the other.
  index.assign(m.n_vertices(), 0);
  const int f = cut.seams[0].he_a / 3, k = cut.seams[0].he_a % 3;
  const int a = m.F(f, k), b = m.F(f, (k + 1) % 3);
  index[a] = index[b] = 1;
  const std::vector<ConePairCancellation> crowd = find_cone_splits(m, cut, index, 1, distance, 64);
  ASSERT_EQ(crowd.size(), 1u);
  const int stays = crowd[0].positive_vertex == a ? b : a;
  EXPECT_TRUE(crowd[0].positive_vertex == a || crowd[0].positive_vertex == b);
  EXPECT_GE((m.V.row(crowd[0].negative_vertex) - m.V.row(stays)).norm(), 0.5 * distance);
  // Far apart, nothing to do.
  index.assign(m.n_vertices(), 0);
  index[0] = 1;
  EXPECT_TRUE(find_cone_splits(m, cut, index, 1, distance, 64).empty());
}

TEST(CutLayout, IsometricUnfoldHasUnitSingularValues) {
  for (const core::TriMesh& m : {test::make_icosphere(2), test::make_torus(20, 8), test::make_disk(5, 12)}) {
    const CutMesh cut = cut_along_dual_tree(m, 0);
    const LayoutDomain dom = make_domain(cut);
    const Eigen::VectorXd x = flatten(isometric_unfold(m, cut));
    // Round-off of the face-by-face layout accumulates slowly; 1e-9 is far above it.
    constexpr double kIsometryTol = 1e-9;
    double worst = 0;
    for (int f = 0; f < m.n_faces(); ++f) {
      const auto [s1, s2] = singular_values(face_jacobian(dom, f, x));
      worst = std::max({worst, std::abs(s1 - 1), std::abs(s2 - 1)});
    }
    EXPECT_LT(worst, kIsometryTol) << "max |σ−1| over faces";
    EXPECT_EQ(count_flipped(dom, x), 0);
  }
}

TEST(CutLayout, MatchingOfAFlatSquareIsZeroAndOfACubeCornerIsAQuarter) {
  // Flat: two triangles sharing every edge through a tree… use a flat disk: all seams match 0.
  core::TriMesh flat = test::make_disk(3, 8);
  flat.V.col(2).setZero();
  const CutMesh cut = cut_along_dual_tree(flat, 0);
  const auto m = measure_matchings(cut, isometric_unfold(flat, cut));
  for (double v : m) EXPECT_NEAR(v, 0.0, 1e-12) << "flat disk seams are untwisted";
  // The three faces around a cube corner: angle defect π/2, so the one seam matches ±1.
  const core::TriMesh corner = test::make_cube_corner();
  const CutMesh cc = cut_along_dual_tree(corner, 0);
  ASSERT_EQ(cc.seams.size(), 1u);
  const auto mc = measure_matchings(cc, isometric_unfold(corner, cc));
  EXPECT_NEAR(std::abs(mc[0]), 1.0, 1e-12) << "cube corner: a quarter turn, got " << mc[0];
}

TEST(ConstraintElimination, ResidualIsZeroAndRedundantRowsAreDropped) {
  const core::TriMesh m = test::make_icosphere(2);
  const CutMesh cut = cut_along_dual_tree(m, 0);
  const Eigen::VectorXd x0 = flatten(isometric_unfold(m, cut));
  std::vector<char> gauge(x0.size(), 0);
  gauge[2 * cut.root_copy] = gauge[2 * cut.root_copy + 1] = 1;
  ConstraintEliminator elim(static_cast<int>(x0.size()), gauge);
  const auto meas = measure_matchings(cut, isometric_unfold(m, cut));
  std::vector<SparseRow> rows;
  for (size_t s = 0; s < cut.seams.size(); ++s)
    for (const auto& r : seam_constraint_rows(cut, static_cast<int>(s), std::lround(meas[s])))
      rows.push_back(r);
  int independent = 0;
  for (const auto& r : rows) independent += elim.add_row(r);
  EXPECT_EQ(independent, elim.rank());
  // Sphere: 2·#seams = F+2 rows, all independent (the cut disk has F+2 copies and the closure of
  // its boundary is not implied by the matchings); so F free scalars remain besides the gauge.
  EXPECT_EQ(elim.rank(), m.n_faces() + 2);
  // Adding all rows again: all redundant.
  for (const auto& r : rows) EXPECT_FALSE(elim.add_row(r));
  const Reduction red = elim.reduction(x0);
  EXPECT_EQ(red.n_free(), static_cast<int>(x0.size()) - elim.rank() - 2);
  // Any y gives an exactly seamless x (integer coefficients).
  Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(red.n_free(), -1.0, 2.0);
  const Eigen::VectorXd x = red.expand(y);
  double worst = 0;
  for (const auto& r : rows) {
    double v = 0;
    for (const auto& [var, c] : r.entries) v += c * x[var];
    worst = std::max(worst, std::abs(v));
  }
  EXPECT_LT(worst, 1e-12) << "constraint residual of P·y + c";
  // The gauge copy keeps its position.
  EXPECT_EQ(x[2 * cut.root_copy], x0[2 * cut.root_copy]);
  EXPECT_LE(elim.max_expression_length(), red.n_free());
}

// Reduced variables of face f's edge vectors x1 − x0, x2 − x0 (what its energy element reads).
int face_element_variables(const Reduction& red, const CutMesh& cut, int f) {
  std::vector<int> ys;
  for (int j = 1; j < 3; ++j)
    for (int d = 0; d < 2; ++d) {
      std::map<int, double> acc;
      using It = Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator;
      for (It it(red.P, 2 * cut.corner_copy[3 * f + j] + d); it; ++it) acc[it.col()] += it.value();
      for (It it(red.P, 2 * cut.corner_copy[3 * f] + d); it; ++it) acc[it.col()] -= it.value();
      for (const auto& [v, a] : acc)
        if (a != 0) ys.push_back(v);
    }
  std::sort(ys.begin(), ys.end());
  return static_cast<int>(std::unique(ys.begin(), ys.end()) - ys.begin());
}

// The seam basis spans the same seamless space as the copies-only elimination, exactly (P in ½ℤ),
// for every seam or for half of them, and keeps face elements small.
TEST(SeamBasis, SameSpaceAsCopiesOnlyExactAndLocal) {
  const std::pair<const char*, core::TriMesh> meshes[] = {{"icosphere3", test::make_icosphere(3)},
                                                          {"torus", test::make_torus(24, 10)},
                                                          {"disk", test::make_disk(6, 14)}};
  for (const auto& [name, m] : meshes) {
    const CutMesh cut = cut_along_dual_tree(m, 0);
    const Eigen::VectorXd x0 = flatten(isometric_unfold(m, cut));
    const auto meas = measure_matchings(cut, isometric_unfold(m, cut));
    const int n_seams = static_cast<int>(cut.seams.size());
    for (int part = 1; part <= 2; ++part) {
      std::vector<int> matching(n_seams, INT_MIN);
      for (int s = 0; s < n_seams; ++s)
        if (s % part == 0) matching[s] = static_cast<int>(std::lround(meas[s]));
      std::vector<char> gauge(x0.size(), 0);
      gauge[2 * cut.root_copy] = gauge[2 * cut.root_copy + 1] = 1;
      ConstraintEliminator copies_only(static_cast<int>(x0.size()), gauge);
      std::vector<SparseRow> rows;
      for (int s = 0; s < n_seams; ++s)
        if (matching[s] != INT_MIN)
          for (const auto& r : seam_constraint_rows(cut, s, matching[s])) {
            copies_only.add_row(r);
            rows.push_back(r);
          }
      const Reduction old_red = copies_only.reduction(x0);
      SeamBasisInfo info;
      const ConstraintEliminator elim = eliminate_seams(cut, matching, &info);
      Eigen::VectorXd xb = Eigen::VectorXd::Zero(n_seam_basis_vars(cut));
      xb.head(x0.size()) = x0;
      const Reduction red = elim.reduction(xb);
      EXPECT_EQ(red.n_free(), old_red.n_free()) << name << " part " << part;
      for (int k = 0; k < red.P.outerSize(); ++k)
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, k); it; ++it)
          ASSERT_EQ(2 * it.value(), std::round(2 * it.value())) << name << ": P entry not in ½ℤ";
      const Eigen::VectorXd x = red.expand(Eigen::VectorXd::LinSpaced(red.n_free(), -1.0, 2.0));
      double worst = 0;
      for (const auto& r : rows) {
        double v = 0;
        for (const auto& [var, c] : r.entries) v += c * x[var];
        worst = std::max(worst, std::abs(v));
      }
      for (int s = 0; s < n_seams; ++s)
        if (matching[s] != INT_MIN)
          for (const auto& r : seam_translation_rows(cut, s, matching[s])) {
            double v = 0;
            for (const auto& [var, c] : r.entries) v += c * x[var];
            worst = std::max(worst, std::abs(v));
          }
      EXPECT_LT(worst, 1e-12) << name << " part " << part << ": seam residual of P·y + c";
      EXPECT_EQ(x.segment<2>(2 * info.gauge_copy), x0.segment<2>(2 * info.gauge_copy)) << name;
      int widest = 0, widest_old = 0;
      for (int f = 0; f < m.n_faces(); ++f) {
        widest = std::max(widest, face_element_variables(red, cut, f));
        widest_old = std::max(widest_old, face_element_variables(old_red, cut, f));
      }
      // 3 copies' edge vectors plus the free translations of a few BFS regions.
      EXPECT_LE(widest, 24) << name << " part " << part << " (copies only: " << widest_old << ")";
      if (part == 1 && std::string(name) == "icosphere3") {
        EXPECT_GT(info.n_cones, 8) << "rounded isometric matchings put cones everywhere";
        EXPECT_LT(widest, widest_old) << "cones: copies-only elements grow";
      }
    }
  }
}

// At a cube corner the root face's first vertex is a cone, whose copy the elimination solves for:
// the gauge moves to a copy of another vertex and the space stays the copies-only one.
TEST(SeamBasis, GaugeLeavesAConeAtTheRoot) {
  const core::TriMesh corner = test::make_cube_corner();
  const CutMesh cut = cut_along_dual_tree(corner, 0);
  ASSERT_EQ(cut.seams.size(), 1u);
  ASSERT_EQ(cut.copy_vertex[cut.root_copy], 0);
  const Eigen::VectorXd x0 = flatten(isometric_unfold(corner, cut));
  const int r =
      static_cast<int>(std::lround(measure_matchings(cut, isometric_unfold(corner, cut))[0]));
  SeamBasisInfo info;
  const ConstraintEliminator elim = eliminate_seams(cut, {r}, &info);
  EXPECT_EQ(info.n_closed_vertices, 1);
  EXPECT_EQ(info.n_cones, 1);
  EXPECT_NE(cut.copy_vertex[info.gauge_copy], 0) << "the gauge must not sit on the cone";
  Eigen::VectorXd xb = Eigen::VectorXd::Zero(n_seam_basis_vars(cut));
  xb.head(x0.size()) = x0;
  const Reduction red = elim.reduction(xb);
  std::vector<char> gauge(x0.size(), 0);
  gauge[2 * cut.root_copy] = gauge[2 * cut.root_copy + 1] = 1;
  ConstraintEliminator copies_only(static_cast<int>(x0.size()), gauge);
  for (const auto& row : seam_constraint_rows(cut, 0, r)) copies_only.add_row(row);
  EXPECT_EQ(red.n_free(), copies_only.reduction(x0).n_free());
  const Eigen::VectorXd x = red.expand(Eigen::VectorXd::LinSpaced(red.n_free(), -1.0, 2.0));
  for (const auto& row : seam_translation_rows(cut, 0, r)) {
    double v = 0;
    for (const auto& [var, c] : row.entries) v += c * x[var];
    EXPECT_LT(std::abs(v), 1e-12) << "end row residual";
  }
}

TEST(DistortionEnergy, DerivativesMatchFiniteDifferences) {
  const Eigen::Matrix2d J = (Eigen::Matrix2d() << 1.3, 0.2, -0.4, 0.9).finished();
  const std::pair<Density, double> kinds[] = {{Density::kSymmetricDirichlet, 1},
                                              {Density::kPowerSD, 3},
                                              {Density::kArap, 1},
                                              {Density::kPowerArap, 8},
                                              {Density::kMips, 1}};
  constexpr double kStep = 1e-6;    // central differences: error O(h²)
  constexpr double kRelTol = 1e-5;  // relative to the derivative magnitude
  for (const auto& [kind, p] : kinds) {
    const DensityEval ev = evaluate_density(kind, p, J, true, false);
    for (int i = 0; i < 4; ++i) {
      Eigen::Matrix2d Jp = J, Jm = J;
      Jp(i / 2, i % 2) += kStep;
      Jm(i / 2, i % 2) -= kStep;
      const DensityEval ep = evaluate_density(kind, p, Jp, true, false);
      const DensityEval em = evaluate_density(kind, p, Jm, true, false);
      const double fd = (ep.value - em.value) / (2 * kStep);
      EXPECT_NEAR(ev.gradient[i], fd, kRelTol * (1 + std::abs(fd))) << "kind " << int(kind) << " i " << i;
      const Eigen::Vector4d hfd = (ep.gradient - em.gradient) / (2 * kStep);
      for (int j = 0; j < 4; ++j)
        EXPECT_NEAR(ev.hessian(j, i), hfd[j], kRelTol * (1 + hfd.norm()))
            << "kind " << int(kind) << " H(" << j << "," << i << ")";
    }
    const DensityEval pr = evaluate_density(kind, p, J, true, true);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(pr.hessian);
    EXPECT_GE(es.eigenvalues().minCoeff(), -1e-10) << "projected Hessian must be PSD";
  }
  EXPECT_NEAR(evaluate_density(Density::kSymmetricDirichlet, 1, Eigen::Matrix2d::Identity(), false, false).value, 4, 1e-15);
  EXPECT_FALSE(evaluate_density(Density::kSymmetricDirichlet, 1, Eigen::Vector2d(1, -1).asDiagonal().toDenseMatrix(), false, false).finite);
}

// The analytic projection of symmetric Dirichlet's Hessians (and of their powers) equals the
// eigensolver's clamp of the exact Hessian, on stretched, squashed, near-isometric and
// near-conformal Jacobians.
TEST(DistortionEnergy, AnalyticProjectionMatchesTheEigensolver) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Eigen::Matrix2d> jacobians = {Eigen::Matrix2d::Identity(),
                                            0.5 * Eigen::Matrix2d::Identity(),
                                            (Eigen::Matrix2d() << 0, -2, 2, 0).finished(),
                                            (Eigen::Matrix2d() << 3, 0, 0, 0.2).finished()};
  for (int k = 0; k < 200; ++k) {
    Eigen::Matrix2d J;
    J << unit(rng), unit(rng), unit(rng), unit(rng);
    J *= std::exp(1.5 * unit(rng));
    if (J.determinant() < 0) J.col(0) *= -1;
    jacobians.push_back(J);
  }
  int indefinite = 0;
  for (const Eigen::Matrix2d& J : jacobians) {
    if (!(J.determinant() > 1e-6 * J.squaredNorm())) continue;
    for (const auto& [kind, p] : {std::pair{Density::kSymmetricDirichlet, 1.0}, std::pair{Density::kPowerSD, 4.0},
                                  std::pair{Density::kPowerSD, 64.0}}) {
      const DensityEval exact = evaluate_density(kind, p, J, true, false);
      if (!exact.hessian.allFinite()) continue;  // (ψ/4)^64 overflows on the most distorted
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(exact.hessian);
      indefinite += es.eigenvalues().minCoeff() < 0;
      const Eigen::Matrix4d reference =
          es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose();
      const DensityEval projected = evaluate_density(kind, p, J, true, true);
      EXPECT_EQ(projected.value, exact.value);
      EXPECT_EQ(projected.gradient, exact.gradient);
      EXPECT_LE((projected.hessian - reference).norm(), 1e-9 * (1 + reference.norm()))
          << "kind " << int(kind) << " p " << p << " J\n" << J;
    }
  }
  EXPECT_GT(indefinite, 100) << "the cases must exercise the clamp";
}

// The isometric unfold of m moved into the constraints of its nearest-integer matchings.
struct RoundedStart {
  CutMesh cut;
  LayoutDomain dom;
  Eigen::VectorXd x;
  std::vector<SparseRow> rows;
  TransitionReport tr;
};
RoundedStart move_into_rounded_constraints(const core::TriMesh& m) {
  RoundedStart r;
  r.cut = cut_along_dual_tree(m, 0);
  r.dom = make_domain(r.cut);
  r.x = flatten(isometric_unfold(m, r.cut));
  std::vector<char> gauge(r.x.size(), 0);
  gauge[2 * r.cut.root_copy] = gauge[2 * r.cut.root_copy + 1] = 1;
  ConstraintEliminator elim(static_cast<int>(r.x.size()), gauge);
  const Reduction red0 = elim.reduction(r.x);
  const auto meas = measure_matchings(r.cut, isometric_unfold(m, r.cut));
  double edge_sq = 0, area = 0;
  for (size_t s = 0; s < r.cut.seams.size(); ++s) {
    for (const auto& row : seam_constraint_rows(r.cut, static_cast<int>(s), std::lround(meas[s]))) {
      elim.add_row(row);
      r.rows.push_back(row);
    }
    edge_sq += seam_length(r.cut, static_cast<int>(s)) * seam_length(r.cut, static_cast<int>(s));
  }
  for (double a : r.cut.area) area += a;
  r.tr = move_into_constraints(r.dom, red0, elim, r.rows, area / edge_sq, &r.x);
  return r;
}

TEST(LayoutOptimizer, SeamlessSphereIsFlipFreeWithExactSeams) {
  RoundedStart r = move_into_rounded_constraints(test::make_icosphere(2));
  const TransitionReport& tr = r.tr;
  ASSERT_TRUE(tr.status.is_ok()) << tr.status.to_string();
  Eigen::VectorXd y = tr.reduction.restrict(r.x);
  OptimizeSettings st;
  const OptimizeReport rep = optimize_layout(r.dom, tr.reduction, st, &y);
  ASSERT_TRUE(rep.status.is_ok()) << rep.status.to_string();
  EXPECT_LE(rep.energy, rep.initial_energy);
  const Eigen::VectorXd x = tr.reduction.expand(y);
  EXPECT_EQ(count_flipped(r.dom, x), 0);
  double worst = 0;
  for (const auto& row : r.rows) {
    double v = 0;
    for (const auto& [var, c] : row.entries) v += c * x[var];
    worst = std::max(worst, std::abs(v));
  }
  EXPECT_LT(worst, 1e-12);
}

// One LayoutProblem reused over a sequence of optimizations (other densities and powers, as the τ
// continuation runs them) gives bit-identical layouts to building the problem for each one.
TEST(LayoutOptimizer, ReusedProblemMatchesFreshProblems) {
  RoundedStart r = move_into_rounded_constraints(test::make_icosphere(3));  // > 250 variables
  const TransitionReport& tr = r.tr;
  ASSERT_TRUE(tr.status.is_ok()) << tr.status.to_string();
  ASSERT_GT(tr.reduction.n_free(), 250) << "sparse mode";
  std::vector<OptimizeSettings> sequence(4);
  sequence[1].density = Density::kPowerSD;
  sequence[1].power = 2;
  sequence[2].density = Density::kPowerSD;
  sequence[2].power = 8;
  sequence[3].density = Density::kArap;
  for (OptimizeSettings& st : sequence) st.max_iterations = 8;
  Eigen::VectorXd y_fresh = tr.reduction.restrict(r.x), y_reused = y_fresh;
  LayoutProblem problem(r.dom, tr.reduction);
  for (const OptimizeSettings& st : sequence) {
    const OptimizeReport fresh = optimize_layout(r.dom, tr.reduction, st, &y_fresh);
    const OptimizeReport reused = optimize_layout(problem, st, &y_reused);
    ASSERT_TRUE(fresh.status.is_ok()) << fresh.status.to_string();
    ASSERT_TRUE(reused.status.is_ok()) << reused.status.to_string();
    EXPECT_EQ(fresh.iterations, reused.iterations);
    EXPECT_EQ(fresh.hessian_nonzeros, reused.hessian_nonzeros);
    EXPECT_GT(reused.hessian_nonzeros, 0);
    EXPECT_EQ(fresh.energy, reused.energy);
    ASSERT_EQ((y_fresh - y_reused).cwiseAbs().maxCoeff(), 0.0);
  }
  EXPECT_EQ(count_flipped(r.dom, tr.reduction.expand(y_reused)), 0);
}

TEST(LocalEstimation, PicksTheSideMatchingTheAngleDefect) {
  // Cube corner (defect π/2): the seam measures ±1 exactly. Perturb the layout so that the measure
  // is ambiguous is not needed: ask for a choice given a measure of 0.5 (between 0 and 1 in the
  // direction of the true rotation); the side equal to the true rotation yields a flat, lower
  // distortion patch.
  const core::TriMesh corner = test::make_cube_corner();
  const CutMesh cut = cut_along_dual_tree(corner, 0);
  const LayoutDomain dom = make_domain(cut);
  const Eigen::VectorXd x = flatten(isometric_unfold(corner, cut));
  const double truth = measure_matchings(cut, isometric_unfold(corner, cut))[0];
  const LocalEstimator est(corner, cut, dom, 2);
  const std::vector<int> rounded(cut.seams.size(), INT_MIN);
  const double ambiguous = truth > 0 ? 0.5 : -0.5;
  const PatchChoice pc = est.choose(0, ambiguous, rounded, {}, x, Density::kSymmetricDirichlet, 1);
  EXPECT_EQ(pc.matching, std::lround(truth))
      << "distortions floor " << pc.distortion[0] << " ceil " << pc.distortion[1];
  EXPECT_LT(std::min(pc.distortion[0], pc.distortion[1]), 4 * 1.5 + 1e-9);
  EXPECT_EQ(pc.n_faces, 3);
}

// The edges from the centre of test::make_disk(·, 12) to ring vertex 1 and to the vertex `sectors`
// sectors on (-1 when missing).
std::vector<int> disk_spokes(const CutMesh& cut, int sectors) {
  std::vector<int> spokes(2, -1);
  for (int e = 0; e < cut.topo.n_edges(); ++e)
    for (int k = 0; k < 2; ++k)
      if (cut.topo.edge_vertex(e, k) == 0) {
        const int w = cut.topo.edge_vertex(e, 1 - k);
        if (w == 1) spokes[0] = e;
        if (w == 1 + sectors) spokes[1] = e;
      }
  return spokes;
}

TEST(FeatureAlignment, WedgeCheckUsesTheChosenAxisNotTheNearest) {
  // Two opposite spokes of a disk's centre continue each other (180° on the surface). Labeled
  // alike they stay straight; if local estimation gives one of them the other axis, the pair
  // would turn by 90° (a stretch of 2, a flat quad corner): the wedge check must see that turn.
  const core::TriMesh mesh = test::make_disk(4, 12);
  const CutMesh cut = cut_along_dual_tree(mesh, 0);
  const Eigen::VectorXd x = flatten(isometric_unfold(mesh, cut));
  const std::vector<int> spokes = disk_spokes(cut, 6);  // sector 6 of 12: the opposite direction
  ASSERT_GE(spokes[0], 0);
  ASSERT_GE(spokes[1], 0);
  const FeatureSet fs = make_feature_set(cut, spokes);
  ASSERT_EQ(fs.size(), 2);
  std::vector<int> label(2);
  for (int i = 0; i < 2; ++i) label[i] = nearest_label(feature_measure(cut, x, fs.halfedge[i]));
  ASSERT_EQ(label[0], label[1]) << "opposite directions share an axis";
  const std::vector<char> is_new = {1, 1};
  constexpr double kMaxStretch = 1.8;
  const WedgeResolution alike = resolve_wedge_conflicts(mesh, cut, x, fs, label, is_new, kMaxStretch, kMaxStretch);
  EXPECT_TRUE(alike.disabled.empty());
  EXPECT_TRUE(alike.relabeled.empty());
  label[1] = 1 - label[1];
  const WedgeResolution r = resolve_wedge_conflicts(mesh, cut, x, fs, label, is_new, kMaxStretch, kMaxStretch);
  ASSERT_EQ(r.disabled.size(), 1u);
  EXPECT_EQ(r.disabled[0], 1) << "the feature off its nearest axis is the one turned farthest";
  EXPECT_TRUE(r.relabeled.empty()) << "a straight continuation is a label switch, not a coin toss";
}

TEST(LocalEstimation, AFeatureWhosePatchTurnsFreelyTakesItsNearestAxis) {
  // A lone spoke of a flat disk, the layout turned so that it points 0.3 to 0.45 of a quarter
  // turn off an axis (local estimation runs from 0.3 on). Its patch holds no other row, so it
  // turns rigidly onto either axis at the same distortion: a tie, which must go to the nearest
  // axis (the smaller turn), not to whichever side round-off favours.
  const core::TriMesh mesh = test::make_disk(4, 12);
  const CutMesh cut = cut_along_dual_tree(mesh, 0);
  const LayoutDomain dom = make_domain(cut);
  const Eigen::VectorXd x0 = flatten(isometric_unfold(mesh, cut));
  const std::vector<int> spokes = disk_spokes(cut, 6);
  ASSERT_GE(spokes[0], 0);
  const FeatureSet fs = make_feature_set(cut, {spokes[0]});
  const LocalEstimator est(mesh, cut, dom, 5, &fs);
  const std::vector<int> rounded(cut.seams.size(), INT_MIN);
  const std::vector<int> labels(1, kUnlabeled);
  for (const double target : {0.3, 0.35, 0.4, 0.45, 0.55, 0.6, 0.65, 0.7, -0.35, 1.4, -1.6}) {
    Eigen::VectorXd x = x0;
    const double turn = (target - feature_measure(cut, x, fs.halfedge[0])) * std::numbers::pi / 2;
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(turn).toRotationMatrix();
    for (int c = 0; c < x.size() / 2; ++c) x.segment<2>(2 * c) = R * x.segment<2>(2 * c);
    const double measure = feature_measure(cut, x, fs.halfedge[0]);
    ASSERT_NEAR(measure, target, 1e-9);
    const FeatureChoice fc = est.choose_feature(0, rounded, labels, x, Density::kSymmetricDirichlet, 1);
    ASSERT_TRUE(std::isfinite(fc.distortion[0]) && std::isfinite(fc.distortion[1]));
    EXPECT_NEAR(fc.distortion[0], fc.distortion[1], 1e-6 * fc.distortion[0]) << "a rigid turn costs nothing";
    EXPECT_EQ(fc.label, nearest_label(measure)) << "at " << target << " quarter turns";
  }
}

TEST(FeatureAlignment, WedgeCheckGivesACornerFeatureNear45DegreesItsOtherAxis) {
  // Two spokes at 90° on the surface, the layout turned so that they lie at 40° and 130° from u.
  // Labeled by their nearest axes they make a corner; if the second gets the first's axis (a coin
  // toss of local estimation at 45°), the wedge would open to 180°: it gets the other axis back
  // rather than being disabled.
  const core::TriMesh mesh = test::make_disk(4, 12);
  const CutMesh cut = cut_along_dual_tree(mesh, 0);
  Eigen::VectorXd x = flatten(isometric_unfold(mesh, cut));
  const std::vector<int> spokes = disk_spokes(cut, 3);  // sector 3 of 12: a quarter turn on
  ASSERT_GE(spokes[0], 0);
  ASSERT_GE(spokes[1], 0);
  const FeatureSet fs = make_feature_set(cut, spokes);
  ASSERT_EQ(fs.size(), 2);
  // Turn the layout so that spoke 0 points at 40° from u.
  const double q0 = feature_measure(cut, x, fs.halfedge[0]);
  const double turn = (40.0 / 90.0 - q0) * std::numbers::pi / 2;
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(turn).toRotationMatrix();
  for (int c = 0; c < x.size() / 2; ++c) x.segment<2>(2 * c) = R * x.segment<2>(2 * c);
  std::vector<int> label(2);
  for (int i = 0; i < 2; ++i) label[i] = nearest_label(feature_measure(cut, x, fs.halfedge[i]));
  ASSERT_NE(label[0], label[1]) << "perpendicular spokes take different axes";
  const std::vector<char> is_new = {1, 1};
  constexpr double kMaxStretch = 1.8;
  EXPECT_TRUE(resolve_wedge_conflicts(mesh, cut, x, fs, label, is_new, kMaxStretch, kMaxStretch).disabled.empty());
  label[1] = label[0];
  const WedgeResolution r = resolve_wedge_conflicts(mesh, cut, x, fs, label, is_new, kMaxStretch, kMaxStretch);
  EXPECT_TRUE(r.disabled.empty());
  ASSERT_EQ(r.relabeled.size(), 1u);
  EXPECT_EQ(r.relabeled[0], 1);
}

// Sum of the 3D corner angles of `mesh` at vertex v (over all its faces).
double angle_sum_3d(const core::TriMesh& mesh, int v) {
  double sum = 0;
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.F(f, k) == v) {
        const Eigen::Vector3d p = mesh.V.row(v);
        const Eigen::Vector3d a = Eigen::Vector3d(mesh.V.row(mesh.F(f, (k + 1) % 3))) - p;
        const Eigen::Vector3d b = Eigen::Vector3d(mesh.V.row(mesh.F(f, (k + 2) % 3))) - p;
        sum += std::atan2(a.cross(b).norm(), a.dot(b));
      }
  return sum;
}

TEST(FeatureAlignment, SmoothCurvesAndTheirTurnsInTheLayout) {
  // A disk's boundary (24 edges turning 15° each on the surface) and two opposite spokes of its
  // centre (157° apart) are two smooth curves: a loop and a line through the centre. In the
  // isometric layout the curve turns at each joint by π minus the corner angles swept there.
  const core::TriMesh mesh = test::make_disk(4, 24);
  const CutMesh cut = cut_along_dual_tree(mesh, 0);
  const Eigen::VectorXd x = flatten(isometric_unfold(mesh, cut));
  std::vector<int> edges;
  for (int e = 0; e < cut.topo.n_edges(); ++e)
    if (cut.topo.is_boundary_edge(e)) edges.push_back(e);
  ASSERT_EQ(edges.size(), 24u);
  for (int e = 0; e < cut.topo.n_edges(); ++e)
    for (int k = 0; k < 2; ++k)
      if (cut.topo.edge_vertex(e, k) == 0 && (cut.topo.edge_vertex(e, 1 - k) == 1 || cut.topo.edge_vertex(e, 1 - k) == 13))
        edges.push_back(e);
  ASSERT_EQ(edges.size(), 26u);
  const FeatureSet fs = make_feature_set(cut, edges);
  const std::vector<FeatureCurve> curves = smooth_feature_curves(mesh, fs, std::numbers::pi / 6);
  ASSERT_EQ(curves.size(), 2u);
  const FeatureCurve& loop = curves[0].closed ? curves[0] : curves[1];
  const FeatureCurve& line = curves[0].closed ? curves[1] : curves[0];
  ASSERT_TRUE(loop.closed);
  EXPECT_FALSE(line.closed);
  EXPECT_EQ(loop.features.size(), 24u);
  EXPECT_EQ(loop.joints.size(), 24u);
  ASSERT_EQ(line.features.size(), 2u);
  ASSERT_EQ(line.joints.size(), 1u);
  EXPECT_EQ(line.joints[0], 0);
  // Half the centre's fan lies on either side of the line.
  const std::vector<double> psi_line = curve_turns(mesh, cut, x, fs, line);
  EXPECT_NEAR(std::abs(psi_line[1]), std::numbers::pi - angle_sum_3d(mesh, 0) / 2, 1e-9);
  // Along the loop, every joint turns the same way, by π minus the boundary vertex's angle sum.
  const std::vector<double> psi = curve_turns(mesh, cut, x, fs, loop);
  ASSERT_EQ(psi.size(), 24u);
  for (size_t k = 0; k + 1 < psi.size(); ++k) {
    const double turn = psi[k + 1] - psi[k];
    EXPECT_NEAR(std::abs(turn), std::numbers::pi - angle_sum_3d(mesh, loop.joints[k]), 1e-9) << "joint " << k;
    EXPECT_GT(turn * psi[1], 0) << "joint " << k;
  }
  // At 20° of allowed bend the spokes (23° from straight) are two curves of one edge: only the
  // loop is left.
  const std::vector<FeatureCurve> tighter = smooth_feature_curves(mesh, fs, 20 * std::numbers::pi / 180);
  ASSERT_EQ(tighter.size(), 1u);
  EXPECT_TRUE(tighter[0].closed);
  EXPECT_EQ(tighter[0].features.size(), 24u);
}

// Three spokes of a paraboloid disk (24 sectors, 4 rings) as features: spokes 0 and 2 leave the
// centre 29° apart on the surface (an acute corner), spoke 8 at 88° and 116° from them. Each
// spoke bends upwards by 20°, 14° and 10° at its joints (43° from its first edge to its last).
TEST(FeatureAlignment, CurvesAtAcuteCornersAreTheirStraightRuns) {
  const core::TriMesh mesh = test::make_disk(4, 24);
  const CutMesh cut = cut_along_dual_tree(mesh, 0);
  auto spoke_vertex = [](int j, int ring) { return ring == 0 ? 0 : 1 + (ring - 1) * 24 + j; };
  std::vector<int> edges;
  for (const int j : {0, 2, 8})
    for (int ring = 0; ring < 4; ++ring)
      for (int e = 0; e < cut.topo.n_edges(); ++e) {
        const int a = cut.topo.edge_vertex(e, 0), b = cut.topo.edge_vertex(e, 1);
        const int p = spoke_vertex(j, ring), q = spoke_vertex(j, ring + 1);
        if ((a == p && b == q) || (a == q && b == p)) edges.push_back(e);
      }
  ASSERT_EQ(edges.size(), 12u);
  const FeatureSet fs = make_feature_set(cut, edges);
  const std::vector<FeatureCurve> curves = smooth_feature_curves(mesh, fs, std::numbers::pi / 6);
  ASSERT_EQ(curves.size(), 3u);
  const double deg = std::numbers::pi / 180;
  auto touches_centre = [&](const FeatureCurve& c) {
    for (const int i : c.features) {
      const int h = fs.halfedge[i];
      if (mesh.F(h / 3, h % 3) == 0 || mesh.F(h / 3, (h % 3 + 1) % 3) == 0) return true;
    }
    return false;
  };
  // Two runs (the acute spokes) of `edges` edges each, starting at the centre.
  auto expect_runs = [&](const std::vector<FeatureCurve>& runs, size_t edges) {
    ASSERT_EQ(runs.size(), 2u);
    for (const FeatureCurve& c : runs) {
      EXPECT_EQ(c.features.size(), edges);
      EXPECT_EQ(c.joints.size(), edges - 1);
      EXPECT_TRUE(touches_centre(c));
    }
  };
  // Within 45° of their first edge, the two acute spokes are straight runs of all their edges;
  // within 30°, their runs end after the second edge (34° from the first).
  expect_runs(curves_at_acute_corners(mesh, fs, curves, 15 * deg, 45 * deg, 45 * deg), 4);
  expect_runs(curves_at_acute_corners(mesh, fs, curves, 15 * deg, 45 * deg, 30 * deg), 2);
  // 29° is not acute for a lower bound of 30°, and spoke 8 never is.
  EXPECT_TRUE(curves_at_acute_corners(mesh, fs, curves, 30 * deg, 45 * deg, 45 * deg).empty());
  EXPECT_EQ(curves_at_acute_corners(mesh, fs, curves, 15 * deg, 100 * deg, 45 * deg).size(), 3u);
}

// A rounded square (sides of four unit edges, corners rounded by three edges of 0.2 turning
// 22.5° at each of four joints), fanned from its centre: its boundary is one smooth loop. With a
// corner length of one unit, each rounded corner (90° within 0.6) splits it, at the middle of the
// rounding; with a length below the rounding's joints' spacing the loop stays whole.
TEST(FeatureAlignment, RoundedCornersSplitSmoothCurves) {
  core::TriMesh mesh;
  std::vector<Eigen::Vector2d> ring;
  Eigen::Vector2d p(0, 0);
  double heading = 0;
  std::vector<std::array<int, 2>> fillet_middle;  // the two middle joints of each rounding
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < 4; ++k) {
      ring.push_back(p);
      p += Eigen::Vector2d(std::cos(heading), std::sin(heading));
    }
    for (int k = 0; k < 3; ++k) {
      ring.push_back(p);
      if (k == 2) fillet_middle.push_back({static_cast<int>(ring.size()) - 2, static_cast<int>(ring.size()) - 1});
      heading += std::numbers::pi / 8;
      p += 0.2 * Eigen::Vector2d(std::cos(heading), std::sin(heading));
    }
    heading = std::round(heading / (std::numbers::pi / 2)) * (std::numbers::pi / 2);
  }
  const int n = static_cast<int>(ring.size());
  ASSERT_EQ(n, 28);
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& q : ring) centre += q / n;
  mesh.V.resize(n + 1, 3);
  for (int i = 0; i < n; ++i) mesh.V.row(i) << ring[i].x(), ring[i].y(), 0;
  mesh.V.row(n) << centre.x(), centre.y(), 0;
  mesh.F.resize(n, 3);
  for (int i = 0; i < n; ++i) mesh.F.row(i) << i, (i + 1) % n, n;
  const CutMesh cut = cut_along_dual_tree(mesh, 0);
  std::vector<int> edges;
  for (int e = 0; e < cut.topo.n_edges(); ++e)
    if (cut.topo.is_boundary_edge(e)) edges.push_back(e);
  ASSERT_EQ(edges.size(), 28u);
  const FeatureSet fs = make_feature_set(cut, edges);
  const std::vector<FeatureCurve> whole = smooth_feature_curves(mesh, fs, std::numbers::pi / 6);
  ASSERT_EQ(whole.size(), 1u);
  EXPECT_TRUE(whole[0].closed);
  EXPECT_EQ(smooth_feature_curves(mesh, fs, std::numbers::pi / 6, 0.1).size(), 1u)
      << "no joint turns 60° within 0.1";
  const std::vector<FeatureCurve> pieces = smooth_feature_curves(mesh, fs, std::numbers::pi / 6, 1.0);
  ASSERT_EQ(pieces.size(), 4u);
  size_t n_features = 0;
  std::vector<char> joint(n, 0);
  for (const FeatureCurve& c : pieces) {
    EXPECT_FALSE(c.closed);
    EXPECT_EQ(c.joints.size() + 1, c.features.size());
    n_features += c.features.size();
    for (const int v : c.joints) joint[v] = 1;
  }
  EXPECT_EQ(n_features, 28u) << "every edge in one piece";
  // The split vertices (no piece's joint): one per rounding, at one of its two middle joints.
  std::vector<int> roundings;
  for (int v = 0; v < n; ++v) {
    if (joint[v]) continue;
    for (int r = 0; r < 4; ++r)
      if (v == fillet_middle[r][0] || v == fillet_middle[r][1]) roundings.push_back(r);
  }
  EXPECT_EQ(roundings, (std::vector<int>{0, 1, 2, 3})) << "split at the middle of each rounding";
}

}  // namespace
}  // namespace quadify::param
