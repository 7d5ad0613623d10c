// relax_bad_quads: repairs reflex corners on a constructed planar grid, keeps vertices on the
// surface and the boundary fixed, leaves good meshes alone, rejects bad input.
#include <libquadex/relax_quads.h>

#include <gtest/gtest.h>

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
  // gets a reflex corner.
  const int v = 1 * (n + 1) + 1;
  q.V.row(v) << 2.3, 2.2, 0;
  const RelaxResult r = relax_bad_quads(q, square(n));
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_GE(r.stats.n_flipped_before, 1);
  EXPECT_EQ(r.stats.n_flipped_after, 0);
  EXPECT_EQ(r.stats.n_bad_after, 0);
  EXPECT_GT(r.stats.n_moves, 0);
  for (int w = 0; w < q.n_vertices(); ++w) {
    EXPECT_NEAR(r.quads.V(w, 2), 0.0, 1e-12) << "vertex " << w << " left the surface";
    const int i = w % (n + 1), j = w / (n + 1);
    if (i == 0 || j == 0 || i == n || j == n) {
      EXPECT_EQ(r.quads.V.row(w), q.V.row(w)) << "boundary vertex " << w << " moved";
    }
  }
  EXPECT_EQ(r.quads.face_vertex, q.face_vertex);
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

TEST(RelaxQuads, RejectsBadInput) {
  core::PolyMesh q = grid(2);
  q.face_vertex[0] = 99;
  EXPECT_EQ(relax_bad_quads(q, square(2)).status.code(), core::StatusCode::kInvalidInput);
  EXPECT_EQ(relax_bad_quads(grid(2), core::TriMesh{}).status.code(), core::StatusCode::kInvalidInput);
  RelaxOptions bad;
  bad.max_rounds = -1;
  EXPECT_EQ(relax_bad_quads(grid(2), square(2), bad).status.code(), core::StatusCode::kInvalidInput);
}

}  // namespace
}  // namespace quadify::quadex
