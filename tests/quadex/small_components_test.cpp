// split_small_components: a tetrahedron smaller than a quad, extracted as four "quads" with a
// repeated vertex, becomes twelve quads on its own faces (also when a caller left it out of the
// extraction); a proper quad component and a large component with a non-quad face stay as they
// are; bad input is rejected.
#include <libquadex/quad_metrics.h>
#include <libquadex/small_components.h>

#include <gtest/gtest.h>

#include <map>
#include <utility>

namespace quadify::quadex {
namespace {

// A unit square (two triangles, vertices 0-3, faces 0-1) and a small tetrahedron beside it
// (vertices 4-7, faces 2-5), with a UV per corner (the corner's x, y: only carried along).
core::UVMesh square_and_tetrahedron() {
  core::UVMesh m;
  m.mesh.V.resize(8, 3);
  m.mesh.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,  //
      3, 0, 0, 3.1, 0, 0, 3, 0.1, 0, 3, 0, 0.1;
  m.mesh.F.resize(6, 3);
  m.mesh.F << 0, 1, 2, 0, 2, 3,  //
      4, 6, 5, 4, 5, 7, 5, 6, 7, 4, 7, 6;
  m.corner_uv.resize(18, 2);
  for (int c = 0; c < 18; ++c) m.corner_uv.row(c) = m.mesh.V.row(m.mesh.F(c / 3, c % 3)).head<2>();
  return m;
}

// Every directed edge appears once: consistently oriented, at most two faces per edge.
void expect_each_directed_edge_once(const core::PolyMesh& q) {
  std::map<std::pair<int, int>, int> directed;
  for (int f = 0; f < q.n_faces(); ++f)
    for (int k = 0; k < q.degree(f); ++k) ++directed[{q.vertex(f, k), q.vertex(f, (k + 1) % q.degree(f))}];
  for (const auto& [e, n] : directed) EXPECT_EQ(n, 1) << "directed edge " << e.first << "-" << e.second;
}

TEST(SmallComponents, ATetrahedronSmallerThanAQuadBecomesTwelveQuads) {
  const core::UVMesh map = square_and_tetrahedron();
  // The extraction: one quad on the square, and on the tetrahedron four faces on six vertices,
  // one of them [a b c b] (as spot_nonmanifold's tetrahedron came out).
  core::PolyMesh q;
  q.V.resize(10, 3);
  q.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,  //
      3, 0, 0, 3.05, 0, 0, 3, 0.05, 0, 3, 0, 0.05, 3.03, 0.03, 0, 3.03, 0, 0.03;
  q.add_face({0, 1, 2, 3});
  q.add_face({4, 6, 8, 5});
  q.add_face({4, 5, 9, 7});
  q.add_face({4, 7, 6, 7});
  q.add_face({5, 8, 6, 9});
  const std::vector<int> vertex_face = {0, 0, 0, 0, 2, 2, 2, 3, 4, 4};
  const SmallComponentResult r = split_small_components(map, q, vertex_face);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_replaced, 1);
  EXPECT_EQ(r.stats.n_faces_removed, 4);
  EXPECT_EQ(r.stats.n_quads_added, 12);
  ASSERT_EQ(r.quads.n_faces(), 13);
  // The square's quad first, unchanged; then 4 corners + 6 midpoints + 4 centroids.
  EXPECT_EQ(r.quads.n_vertices(), 4 + 14);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(r.quads.V.row(r.quads.vertex(0, k)), q.V.row(q.vertex(0, k)));
  expect_each_directed_edge_once(r.quads);
  const QuadMetrics m = compute_quad_metrics(r.quads, &map.mesh);
  EXPECT_EQ(m.n_non_quads, 0);
  EXPECT_EQ(m.n_flipped, 0) << "each quad lies in its triangle, facing the same way";
  EXPECT_GT(m.sj_min, 0.5);
  EXPECT_EQ(m.n_components, 2);
  EXPECT_LT(m.hausdorff_sym, 1e-9) << "the split quads lie on the input";
  // Nothing to do the second time.
  std::vector<int> again(r.quads.n_vertices(), 2);
  for (int k = 0; k < 4; ++k) again[k] = 0;
  EXPECT_EQ(split_small_components(map, r.quads, again).stats.n_replaced, 0);
}

TEST(SmallComponents, KeepsProperQuadsAndLargeComponents) {
  const core::UVMesh map = square_and_tetrahedron();
  core::PolyMesh q;  // a pentagon on the square, a proper quad on the tetrahedron
  q.V.resize(9, 3);
  q.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 1, 0, 3, 0, 0, 3.05, 0, 0, 3, 0.05, 0, 3, 0, 0.05;
  q.add_face({0, 1, 2, 4, 3});
  q.add_face({5, 6, 7, 8});
  const std::vector<int> vertex_face = {0, 0, 0, 1, 1, 2, 2, 2, 3};
  SmallComponentOptions options;
  options.max_triangles = 1;  // the square (2 triangles) is too large to replace
  const SmallComponentResult r = split_small_components(map, q, vertex_face, options);
  ASSERT_TRUE(r.status.is_ok());
  EXPECT_EQ(r.stats.n_replaced, 0);
  EXPECT_EQ(r.quads.face_vertex, q.face_vertex);
  EXPECT_EQ(r.quads.V, q.V);
  // With the default bound the square's pentagon is replaced: 2 triangles → 6 quads.
  const SmallComponentResult d = split_small_components(map, q, vertex_face);
  EXPECT_EQ(d.stats.n_replaced, 1);
  EXPECT_EQ(d.stats.n_quads_added, 6);
  EXPECT_EQ(d.quads.n_faces(), 7);
}

TEST(SmallComponents, ACallerCanHaveAComponentReplacedWhateverItsSize) {
  // The extraction left the tetrahedron out (as the remesher does with a component that keeps a
  // cone of index 3): it must not vanish, even above max_triangles.
  const core::UVMesh map = square_and_tetrahedron();
  core::PolyMesh q;
  q.V.resize(4, 3);
  q.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  q.add_face({0, 1, 2, 3});
  SmallComponentOptions options;
  options.max_triangles = 1;
  EXPECT_EQ(split_small_components(map, q, {0, 0, 0, 1}, options).stats.n_replaced, 0) << "too large";
  options.replace_faces = {3};
  const SmallComponentResult r = split_small_components(map, q, {0, 0, 0, 1}, options);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_replaced, 1);
  EXPECT_EQ(r.stats.n_faces_removed, 0);
  EXPECT_EQ(r.stats.n_quads_added, 12);
  ASSERT_EQ(r.quads.n_faces(), 13);
  expect_each_directed_edge_once(r.quads);
  const QuadMetrics m = compute_quad_metrics(r.quads, &map.mesh);
  EXPECT_EQ(m.n_non_quads, 0);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_EQ(m.n_components, 2);
}

TEST(SmallComponents, RejectsMismatchedInput) {
  const core::UVMesh map = square_and_tetrahedron();
  core::PolyMesh q;
  q.V.resize(4, 3);
  q.V.setZero();
  q.add_face({0, 1, 2, 3});
  EXPECT_EQ(split_small_components(map, q, {0, 0, 0}).status.code(), core::StatusCode::kInvalidInput);
  EXPECT_EQ(split_small_components(map, q, {0, 0, 0, 99}).status.code(), core::StatusCode::kInvalidInput);
  SmallComponentOptions options;
  options.replace_faces = {6};  // the map has faces 0-5
  EXPECT_EQ(split_small_components(map, q, {0, 0, 0, 0}, options).status.code(), core::StatusCode::kInvalidInput);
}

}  // namespace
}  // namespace quadify::quadex
