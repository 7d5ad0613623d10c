// relax_bad_quads: repairs reflex corners on a constructed planar grid and quads folded over a
// crease, keeps vertices on the surface and the boundary fixed, leaves good meshes alone, rejects
// bad input; turns quads to the diagonal that follows the surface; unfolds a fold on a thin handle.
#include <libcore/read_mesh.h>
#include <libquadex/quad_metrics.h>
#include <libquadex/relax_quads.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "test_util.h"

namespace quadify::quadex {
namespace {

// An n×n grid of unit quads in the plane z = 0, CCW seen from +z.
core::PolyMesh grid(int n) {
  core::PolyMesh q;
  q.V.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) q.V.row(j * (n + 1) + i) << i, j, 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      q.add_face({a, a + 1, a + n + 2, a + n + 1});
    }
  return q;
}

// The square [0, n]² as two triangles.
core::TriMesh square(int n) {
  core::TriMesh t;
  t.V.resize(4, 3);
  t.V << 0, 0, 0, n, 0, 0, n, n, 0, 0, n, 0;
  t.F.resize(2, 3);
  t.F << 0, 1, 2, 0, 2, 3;
  return t;
}

TEST(RelaxQuads, RepairsAReflexCornerOnThePlane) {
  const int n = 4;
  core::PolyMesh q = grid(n);
  // Interior vertex (1, 1) pushed past its diagonal neighbour's corner: the quad (1,1)-(2,2)
  // gets a reflex corner. By default it jumps (in one move) to one of the surface samples within
  // its mean quad edge (about 1.9) of it: the square's triangles (0,0)-(4,0)-(4,4) and
  // (0,0)-(4,4)-(0,4) have interior samples at 4:1:1 weights. Without jumps (jump_reach 0) the
  // smoothing steps repair it.
  const int v = 1 * (n + 1) + 1;
  q.V.row(v) << 2.3, 2.2, 0;
  const double third = 4.0 / 6.0;
  const Eigen::Vector3d samples[] = {{2 * third, third, 0}, {5 * third, third, 0}, {5 * third, 4 * third, 0},
                                     {third, 2 * third, 0}, {4 * third, 5 * third, 0}, {third, 5 * third, 0}};
  for (const double reach : {RelaxOptions{}.jump_reach, 0.0}) {
    SCOPED_TRACE("jump_reach " + std::to_string(reach));
    RelaxOptions options;
    options.jump_reach = reach;
    const RelaxResult r = relax_bad_quads(q, square(n), options);
    ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
    EXPECT_GE(r.stats.n_flipped_before, 1);
    EXPECT_EQ(r.stats.n_flipped_after, 0);
    EXPECT_EQ(r.stats.n_bad_after, 0);
    for (int w = 0; w < q.n_vertices(); ++w) {
      EXPECT_NEAR(r.quads.V(w, 2), 0.0, 1e-12) << "vertex " << w << " left the surface";
      const int i = w % (n + 1), j = w / (n + 1);
      if (i == 0 || j == 0 || i == n || j == n) {
        EXPECT_EQ(r.quads.V.row(w), q.V.row(w)) << "boundary vertex " << w << " moved";
      }
    }
    EXPECT_EQ(r.quads.face_vertex, q.face_vertex);
    if (reach > 0) {
      EXPECT_GE(r.stats.n_jumps, 1);
      double nearest = std::numeric_limits<double>::infinity();
      for (const Eigen::Vector3d& s : samples) nearest = std::min(nearest, (r.quads.V.row(v).transpose() - s).norm());
      EXPECT_LT(nearest, 1e-12) << "the vertex is not at a surface sample: " << r.quads.V.row(v);
    } else {
      EXPECT_EQ(r.stats.n_jumps, 0);
      EXPECT_GT(r.stats.n_moves, 0);
    }
  }
}

TEST(RelaxQuads, LeavesAGoodGridUnchanged) {
  const core::PolyMesh q = grid(3);
  const RelaxResult r = relax_bad_quads(q, square(3));
  ASSERT_TRUE(r.status.is_ok());
  EXPECT_EQ(r.stats.n_bad_before, 0);
  EXPECT_EQ(r.stats.n_moves, 0);
  EXPECT_EQ(r.quads.V, q.V);
}

TEST(RelaxQuads, LastResortMovesAFeatureVertexOffAFlatCorner) {
  // The diagonal of the square is a feature. Vertex (2, 1) is pulled onto it at (1.5, 1.5): the
  // quad (1,1)-(2,1)-(2,2)-(1,2) gets three vertices on the feature and a flat corner there.
  // Vertices on features stay fixed, so only the last resort (moving it off the feature) repairs
  // the quad.
  const int n = 4;
  core::PolyMesh q = grid(n);
  const int v = 1 * (n + 1) + 2;
  q.V.row(v) << 1.5, 1.5, 0;
  RelaxOptions o;
  o.feature_edges = {{0, 2}};  // square(n) vertex 0 = (0, 0), vertex 2 = (n, n)
  o.release_features_for_flips = false;
  const RelaxResult kept = relax_bad_quads(q, square(n), o);
  ASSERT_TRUE(kept.status.is_ok()) << kept.status.to_string();
  EXPECT_GE(kept.stats.n_flipped_before, 1);
  EXPECT_GE(kept.stats.n_flipped_after, 1) << "the flat corner's vertex is on the feature";
  EXPECT_EQ(kept.quads.V.row(v), q.V.row(v));
  o.release_features_for_flips = true;
  const RelaxResult r = relax_bad_quads(q, square(n), o);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_flipped_after, 0);
  EXPECT_GE(r.stats.n_feature_vertices_moved, 1);
  EXPECT_NE(r.quads.V.row(v), q.V.row(v));
  for (int w = 0; w < q.n_vertices(); ++w) EXPECT_NEAR(r.quads.V(w, 2), 0.0, 1e-12);
}

// Two faces of a box meeting at a convex edge along x: the top (z = 1, normal +z) and the front
// (y = 0, normal -y), for 0 ≤ x ≤ n.
core::TriMesh box_edge(int n) {
  core::TriMesh t;
  t.V.resize(6, 3);
  t.V << 0, 0, 1, n, 0, 1, n, 1, 1, 0, 1, 1, 0, 0, 0, n, 0, 0;
  t.F.resize(4, 3);
  t.F << 0, 1, 2, 0, 2, 3, 4, 1, 0, 4, 5, 1;
  return t;
}

// A point of box_edge at x and arc length s from the back of the top (s ≤ 1 on the top, s ≥ 1
// down the front).
Eigen::Vector3d on_box_edge(double x, double s) {
  return s <= 1 ? Eigen::Vector3d(x, 1 - s, 1) : Eigen::Vector3d(x, 0, 2 - s);
}

TEST(RelaxQuads, TurnsAroundQuadsFoldedOverACrease) {
  // Four rows of quad vertices across the edge at s = 0.5, 0.9, 1.1, 1.5 (columns x = 0..n).
  // Between the boundary columns the two middle rows are swapped: the quads between them are
  // rectangles with perfect corners that face away from the surface (as a sliver folded over a
  // crease does after extraction). The repair must see them as flipped and unfold them.
  const int n = 6;
  const double rows[] = {0.5, 0.9, 1.1, 1.5};
  core::PolyMesh q;
  q.V.resize(4 * (n + 1), 3);
  for (int r = 0; r < 4; ++r)
    for (int i = 0; i <= n; ++i) {
      const bool swapped = (r == 1 || r == 2) && i > 0 && i < n;
      q.V.row(r * (n + 1) + i) = on_box_edge(i, rows[swapped ? 3 - r : r]).transpose();
    }
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < n; ++i) {
      const int a = r * (n + 1) + i;
      q.add_face({a, a + n + 1, a + n + 2, a + 1});  // along s, then along x: facing outwards
    }
  const core::TriMesh surface = box_edge(n);
  ASSERT_GE(compute_quad_metrics(q, &surface).n_flipped, n - 2);
  const RelaxResult r = relax_bad_quads(q, surface);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_GE(r.stats.n_flipped_before, n - 2);
  EXPECT_EQ(r.stats.n_flipped_after, 0);
  const QuadMetrics m = compute_quad_metrics(r.quads, &surface);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_GT(m.sj_min, 0.0);
}

TEST(RelaxQuads, SnapsTheRowNextToAMissedCreaseOntoIt) {
  // Rows of quad vertices at arc lengths s = 0.3 … 1.5 across box_edge's crease (s = 1), columns
  // x = 0, 0.5, …, 4: the crease runs inside the quads between rows 0.9 and 1.2, which cut it off
  // (as quads do where a feature edge was disabled). With the crease as a feature, the interior
  // vertices of row 0.9 (0.1 from it, a quarter of their mean edge length) move onto it; row 1.2
  // then finds the crease on its quads' edges and stays. The quads become planar rectangles (but
  // at the boundary columns, which stay fixed).
  const int columns = 8;
  const double rows[] = {0.3, 0.6, 0.9, 1.2, 1.5};
  const int n_rows = 5;
  core::PolyMesh q;
  q.V.resize(n_rows * (columns + 1), 3);
  for (int r = 0; r < n_rows; ++r)
    for (int i = 0; i <= columns; ++i) q.V.row(r * (columns + 1) + i) = on_box_edge(0.5 * i, rows[r]).transpose();
  for (int r = 0; r + 1 < n_rows; ++r)
    for (int i = 0; i < columns; ++i) {
      const int a = r * (columns + 1) + i;
      q.add_face({a, a + columns + 1, a + columns + 2, a + 1});
    }
  const core::TriMesh surface = box_edge(4);
  RelaxOptions o;
  o.feature_edges = {{0, 1}};  // the crease y = 0, z = 1
  o.snap_reach = 0;
  const RelaxResult off = relax_bad_quads(q, surface, o);
  ASSERT_TRUE(off.status.is_ok()) << off.status.to_string();
  EXPECT_EQ(off.stats.n_snapped, 0);
  EXPECT_EQ(off.quads.V, q.V);
  o.snap_reach = RelaxOptions{}.snap_reach;
  const RelaxResult r = relax_bad_quads(q, surface, o);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_snapped, columns - 1);
  for (int i = 0; i <= columns; ++i) {
    const int v = 2 * (columns + 1) + i;  // row s = 0.9
    if (i == 0 || i == columns) {
      EXPECT_EQ(r.quads.V.row(v), q.V.row(v)) << "boundary vertex " << v << " moved";
      continue;
    }
    EXPECT_NEAR(r.quads.V(v, 0), 0.5 * i, 1e-12);
    EXPECT_NEAR(r.quads.V(v, 1), 0.0, 1e-12) << "vertex " << v << " is not on the crease";
    EXPECT_NEAR(r.quads.V(v, 2), 1.0, 1e-12) << "vertex " << v << " is not on the crease";
  }
  for (int v = 0; v < q.n_vertices(); ++v)
    if (v / (columns + 1) != 2) {
      EXPECT_EQ(r.quads.V.row(v), q.V.row(v)) << "vertex " << v << " moved";
    }
  const QuadMetrics m = compute_quad_metrics(r.quads, &surface);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_GT(m.sj_min, 0.9) << "only the quads at the fixed boundary columns are not rectangles";
}

// The square [0, n]² as a grid of cells of side 1/k (two triangles each) lifted by a cone of
// height 0.6 and radius 1 whose apex, a grid vertex, is at `apex`.
constexpr double kBumpHeight = 0.6;
double bump(const Eigen::Vector2d& p, const Eigen::Vector2d& apex) {
  return kBumpHeight * std::max(0.0, 1 - (p - apex).norm());
}
core::TriMesh bumped_square(int n, int k, const Eigen::Vector2d& apex) {
  const int m = n * k;
  core::TriMesh t;
  t.V.resize((m + 1) * (m + 1), 3);
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= m; ++i) {
      const Eigen::Vector2d p(static_cast<double>(i) / k, static_cast<double>(j) / k);
      t.V.row(j * (m + 1) + i) << p.x(), p.y(), bump(p, apex);
    }
  t.F.resize(2 * m * m, 3);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      const int a = j * (m + 1) + i;
      t.F.row(2 * (j * m + i)) << a, a + 1, a + m + 2;
      t.F.row(2 * (j * m + i) + 1) << a, a + m + 2, a + m + 1;
    }
  return t;
}
// The height of bumped_square(·, k, ·) over (x, y): its piecewise-linear interpolation.
double bumped_height(double x, double y, int k, const Eigen::Vector2d& apex) {
  const double i = std::floor(x * k), j = std::floor(y * k);
  const double u = x * k - i, w = y * k - j;
  auto h = [&](double a, double b) { return bump(Eigen::Vector2d(a / k, b / k), apex); };
  return u >= w ? h(i, j) + u * (h(i + 1, j) - h(i, j)) + w * (h(i + 1, j + 1) - h(i + 1, j))
                : h(i, j) + w * (h(i, j + 1) - h(i, j)) + u * (h(i + 1, j + 1) - h(i, j + 1));
}

TEST(RelaxQuads, FittingBringsInATipTheQuadsCutOff) {
  // A 4×4 grid of unit quads on a square with a cone-shaped bump whose apex (2.2, 1.9) lies
  // inside a quad of vertex (2, 2): the quads cut the tip off. The fitting must move that vertex
  // onto the apex (the surface vertex there), lower the distance between the quads and the
  // surface (the bump is as wide as a quad, so its flanks stay cut), keep every vertex on the
  // surface and every corner good, and leave the boundary alone; with fitting off, nothing moves
  // (the grid's quads are all good).
  const int n = 4, k = 10;
  const Eigen::Vector2d apex(2.2, 1.9);
  const core::TriMesh surface = bumped_square(n, k, apex);
  core::PolyMesh q = grid(n);
  for (int v = 0; v < q.n_vertices(); ++v) q.V(v, 2) = bump(q.V.row(v).head<2>().transpose(), apex);
  const QuadMetrics before = compute_quad_metrics(q, &surface);
  ASSERT_GT(before.hausdorff_sym, 0.02);  // × bounding-box diagonal (5.7)

  RelaxOptions off;
  off.fit_fraction = 0;
  const RelaxResult kept = relax_bad_quads(q, surface, off);
  ASSERT_TRUE(kept.status.is_ok()) << kept.status.to_string();
  EXPECT_EQ(kept.stats.n_fitted, 0);
  EXPECT_EQ(kept.quads.V, q.V);

  // The fitting alone (the diagonal choice would make other positions the best).
  RelaxOptions fit_only;
  fit_only.choose_diagonals = false;
  const RelaxResult r = relax_bad_quads(q, surface, fit_only);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_GE(r.stats.n_fitted, 1);
  EXPECT_LT(r.stats.fit_distance_after, 0.9 * r.stats.fit_distance_before);
  const QuadMetrics after = compute_quad_metrics(r.quads, &surface);
  EXPECT_LT(after.hausdorff_sym, 0.9 * before.hausdorff_sym);
  EXPECT_EQ(after.n_flipped, 0);
  EXPECT_GE(after.sj_min, 0.5);
  const int centre = 2 * (n + 1) + 2;
  EXPECT_LT((r.quads.V.row(centre).transpose() - Eigen::Vector3d(apex.x(), apex.y(), kBumpHeight)).norm(), 1e-12)
      << "the vertex next to the apex is at " << r.quads.V.row(centre);
  for (int v = 0; v < q.n_vertices(); ++v) {
    EXPECT_NEAR(r.quads.V(v, 2), bumped_height(r.quads.V(v, 0), r.quads.V(v, 1), k, apex), 1e-9)
        << "vertex " << v << " left the surface";
    const int i = v % (n + 1), j = v / (n + 1);
    if (i == 0 || j == 0 || i == n || j == n) {
      EXPECT_EQ(r.quads.V.row(v), q.V.row(v)) << "boundary vertex " << v << " moved";
    }
  }
  EXPECT_EQ(r.quads.face_vertex, q.face_vertex);

  // With the diagonal choice (the default): the same quads, some starting at another corner,
  // closer still.
  const RelaxResult both = relax_bad_quads(q, surface);
  ASSERT_TRUE(both.status.is_ok()) << both.status.to_string();
  EXPECT_GE(both.stats.n_diagonals_turned, 1);
  const QuadMetrics closer = compute_quad_metrics(both.quads, &surface);
  EXPECT_LT(closer.hausdorff_sym, after.hausdorff_sym);
  EXPECT_EQ(closer.n_flipped, 0);
  ASSERT_EQ(both.quads.n_faces(), q.n_faces());
  for (int f = 0; f < q.n_faces(); ++f) {
    std::vector<int> a(q.face_vertex.begin() + q.face_offset[f], q.face_vertex.begin() + q.face_offset[f + 1]);
    const std::vector<int> b(both.quads.face_vertex.begin() + both.quads.face_offset[f],
                             both.quads.face_vertex.begin() + both.quads.face_offset[f + 1]);
    bool rotation = false;
    for (size_t k = 0; k < a.size() && !rotation; ++k) {
      rotation = a == b;
      std::rotate(a.begin(), a.begin() + 1, a.end());
    }
    EXPECT_TRUE(rotation) << "face " << f << " is not the same quad";
  }
}

TEST(RelaxQuads, StartsAQuadAtTheCornerWhoseDiagonalFollowsTheSurface) {
  // One quad A B C D on a surface folded along its diagonal B–D (two triangles, A B D and
  // B C D): split from its first corner, (A,B,C) and (A,C,D), it cuts across the fold (the
  // metrics see it up to 0.14 away from the surface); split from B it is the surface itself. The
  // diagonal choice turns it to start at B, with its UVs, and nothing else changes; with the
  // choice off, or on a surface folded along A–C, it stays as it is.
  core::TriMesh roof;
  roof.V.resize(4, 3);
  roof.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0.5;
  roof.F.resize(2, 3);
  roof.F << 0, 1, 3, 1, 2, 3;
  core::PolyMesh q;
  q.V = roof.V;
  q.uv.resize(4, 2);
  q.uv << 0, 0, 1, 0, 1, 1, 0, 1;
  q.add_face({0, 1, 2, 3}, {0, 1, 2, 3});
  const QuadMetrics before = compute_quad_metrics(q, &roof);
  ASSERT_GT(before.hausdorff_sym, 0.05);  // × bounding-box diagonal (1.5)

  const RelaxResult r = relax_bad_quads(q, roof);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_diagonals_turned, 1);
  EXPECT_EQ(r.quads.face_vertex, (std::vector<int>{1, 2, 3, 0}));
  EXPECT_EQ(r.quads.face_uv, (std::vector<int>{1, 2, 3, 0}));
  EXPECT_EQ(r.quads.V, q.V);
  EXPECT_EQ(r.quads.uv, q.uv);
  const QuadMetrics after = compute_quad_metrics(r.quads, &roof);
  EXPECT_LT(after.hausdorff_sym, 1e-9);
  EXPECT_EQ(after.n_flipped, 0);
  EXPECT_NEAR(after.sj_min, before.sj_min, 1e-12);  // corners are the same

  RelaxOptions off;
  off.choose_diagonals = false;
  const RelaxResult kept = relax_bad_quads(q, roof, off);
  ASSERT_TRUE(kept.status.is_ok());
  EXPECT_EQ(kept.stats.n_diagonals_turned, 0);
  EXPECT_EQ(kept.quads.face_vertex, q.face_vertex);

  core::TriMesh other = roof;  // folded along A–C: the first split is the surface already
  other.V(3, 2) = 0;
  other.V(2, 2) = 0.5;
  other.F << 0, 1, 2, 0, 2, 3;
  core::PolyMesh on_other = q;
  on_other.V = other.V;
  const RelaxResult same = relax_bad_quads(on_other, other);
  ASSERT_TRUE(same.status.is_ok());
  EXPECT_EQ(same.stats.n_diagonals_turned, 0);
  EXPECT_EQ(same.quads.face_vertex, q.face_vertex);

  core::PolyMesh degenerate = q;  // D on A: the other split has a triangle of zero area
  degenerate.V.row(3) = degenerate.V.row(0);
  const RelaxResult kept_degenerate = relax_bad_quads(degenerate, roof);
  ASSERT_TRUE(kept_degenerate.status.is_ok()) << kept_degenerate.status.to_string();
  EXPECT_EQ(kept_degenerate.stats.n_diagonals_turned, 0);
  EXPECT_EQ(kept_degenerate.quads.face_vertex, q.face_vertex);
}

// The torus of tests/data at 7 quads: a handle one or two quads around, extracted with nine
// flipped quads. Moves of one vertex at a time leave a fold that each of them would make worse
// first; the local pass with raised thresholds (from the extracted positions around the fold)
// opens it: no quad is flipped after, by the relaxation's count and by the metrics', and none is a
// sliver (worst corner below 0.05).
TEST(RelaxQuads, UnfoldsAFoldThatSingleMovesCannotOpen) {
  const core::TriMesh surface = core::to_trimesh(core::read_mesh(test::data_path("torus.obj")));
  const core::PolyMesh extracted = core::read_mesh(test::data_path("torus_7_quads.obj"));
  ASSERT_EQ(extracted.n_faces(), 16);
  const RelaxResult r = relax_bad_quads(extracted, surface);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_GE(r.stats.n_flipped_before, 1);
  EXPECT_GE(r.stats.n_unfolded, 1) << "the fold is left to the unfolding pass";
  EXPECT_EQ(r.stats.n_flipped_after, 0);
  const QuadMetrics m = compute_quad_metrics(r.quads, &surface);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_GE(m.sj_min, 0.05) << "no sliver left either";
  ASSERT_EQ(r.quads.n_faces(), extracted.n_faces());
  for (int f = 0; f < extracted.n_faces(); ++f) {  // the same quads (one may start at another corner)
    bool rotation = false;
    for (int s = 0; s < 4 && !rotation; ++s) {
      rotation = true;
      for (int k = 0; k < 4; ++k) rotation = rotation && r.quads.vertex(f, (k + s) % 4) == extracted.vertex(f, k);
    }
    EXPECT_TRUE(rotation) << "face " << f;
  }
}

TEST(RelaxQuads, RejectsBadInput) {
  core::PolyMesh q = grid(2);
  q.face_vertex[0] = 99;
  EXPECT_EQ(relax_bad_quads(q, square(2)).status.code(), core::StatusCode::kInvalidInput);
  EXPECT_EQ(relax_bad_quads(grid(2), core::TriMesh{}).status.code(), core::StatusCode::kInvalidInput);
  RelaxOptions bad;
  bad.max_rounds = -1;
  EXPECT_EQ(relax_bad_quads(grid(2), square(2), bad).status.code(), core::StatusCode::kInvalidInput);
  RelaxOptions bad_snap;
  bad_snap.snap_reach = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(relax_bad_quads(grid(2), square(2), bad_snap).status.code(), core::StatusCode::kInvalidInput);
  bad_snap.snap_reach = -1;
  EXPECT_EQ(relax_bad_quads(grid(2), square(2), bad_snap).status.code(), core::StatusCode::kInvalidInput);
  RelaxOptions bad_jump;
  bad_jump.jump_reach = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(relax_bad_quads(grid(2), square(2), bad_jump).status.code(), core::StatusCode::kInvalidInput);
}

}  // namespace
}  // namespace quadify::quadex
