// make_pure_quads: a grid whose corner a boundary cut off (a pentagon on the boundary), odd faces
// of a closed mesh side by side merged, a hexagon, triangles whose paths end in quads on the boundary
// (split around their centroids), UVs carried along; a pure-quad mesh is returned as it is and
// bad input is rejected.
#include <libquadex/pure_quads.h>
#include <libquadex/quad_metrics.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>

#include <map>
#include <utility>

namespace quadify::quadex {
namespace {

// Every directed edge appears once: consistently oriented, at most two faces per edge.
void expect_each_directed_edge_once(const core::PolyMesh& q) {
  std::map<std::pair<int, int>, int> directed;
  for (int f = 0; f < q.n_faces(); ++f)
    for (int k = 0; k < q.degree(f); ++k) ++directed[{q.vertex(f, k), q.vertex(f, (k + 1) % q.degree(f))}];
  for (const auto& [e, n] : directed) EXPECT_EQ(n, 1) << "directed edge " << e.first << "-" << e.second;
}

// Faces whose worst corner scaled Jacobian (against the face's diagonal cross product) is below t.
int n_faces_below(const core::PolyMesh& q, double t) {
  int n = 0;
  for (int f = 0; f < q.n_faces(); ++f) {
    const int d = q.degree(f);
    if (d != 4) continue;
    const Eigen::Vector3d a = q.V.row(q.vertex(f, 0)), b = q.V.row(q.vertex(f, 1)), c = q.V.row(q.vertex(f, 2)),
                          e = q.V.row(q.vertex(f, 3));
    const Eigen::Vector3d nrm = (c - a).cross(e - b).normalized();
    double worst = 1;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = q.V.row(q.vertex(f, k)), u = q.V.row(q.vertex(f, (k + 1) % 4)) - p.transpose(),
                            w = q.V.row(q.vertex(f, (k + 3) % 4)) - p.transpose();
      worst = std::min(worst, u.cross(w).dot(nrm) / (u.norm() * w.norm()));
    }
    n += worst < t;
  }
  return n;
}

// Boundary length (sum over edges of one face): the outline is kept.
double boundary_length(const core::PolyMesh& q) {
  std::map<std::pair<int, int>, int> n;
  for (int f = 0; f < q.n_faces(); ++f)
    for (int k = 0; k < q.degree(f); ++k) {
      const int a = q.vertex(f, k), b = q.vertex(f, (k + 1) % q.degree(f));
      ++n[{std::min(a, b), std::max(a, b)}];
    }
  double l = 0;
  for (const auto& [e, c] : n)
    if (c == 1) l += (q.V.row(e.first) - q.V.row(e.second)).norm();
  return l;
}

// A 3×3 grid of unit quads on [0,3]² whose corner at (3,3) a boundary cuts off along the line
// x + y = 5.5, as the extraction gives it: the pentagon (2,2) (3,2) (3,2.5) (2.5,3) (2,3).
core::PolyMesh grid_with_cut_corner() {
  core::PolyMesh q;
  std::vector<Eigen::Vector3d> v;
  for (int j = 0; j <= 3; ++j)
    for (int i = 0; i <= 3; ++i) v.emplace_back(i, j, 0);
  auto id = [](int i, int j) { return 4 * j + i; };
  v[id(3, 3)] = Eigen::Vector3d(3, 2.5, 0);  // (3,3) moves to the cut on the right side
  v.emplace_back(2.5, 3, 0);                 // 16: the cut on the top side
  q.V.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) q.V.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      if (i == 2 && j == 2) continue;
      q.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  q.add_face({id(2, 2), id(3, 2), id(3, 3), 16, id(2, 3)});
  return q;
}

TEST(PureQuads, APentagonOnTheBoundaryBecomesTwoQuadsAtItsBoundaryEdgesMidpoint) {
  const core::PolyMesh in = grid_with_cut_corner();
  const PureQuadResult r = make_pure_quads(in);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_non_quads_before, 1);
  EXPECT_EQ(r.stats.n_non_quads_after, 0);
  EXPECT_EQ(r.stats.n_boundary_splits, 1);
  EXPECT_EQ(r.stats.n_paths, 0);
  EXPECT_EQ(r.stats.n_centers, 0);
  EXPECT_EQ(r.quads.n_faces(), 8 + 2);
  EXPECT_EQ(r.quads.n_vertices(), in.n_vertices() + 1);
  // The pentagon's longest boundary edge is the cut (0.71 long; the others 0.5): split there.
  EXPECT_TRUE(r.quads.V.row(in.n_vertices()).isApprox(Eigen::RowVector3d(2.75, 2.75, 0)));
  const QuadMetrics m = compute_quad_metrics(r.quads);
  EXPECT_EQ(m.n_non_quads, 0);
  EXPECT_TRUE(m.manifold);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_GT(m.sj_min, 0.3);
  EXPECT_NEAR(boundary_length(r.quads), boundary_length(in), 1e-12);
  expect_each_directed_edge_once(r.quads);
  // The untouched quads come first, as they were.
  for (int f = 0; f < 8; ++f)
    for (int k = 0; k < 4; ++k) EXPECT_EQ(r.quads.vertex(f, k), in.vertex(f, k));
}

// A cube of quads with a vertex (8) on the top's back edge: the back face is a pentagon, and the
// top a quad and a triangle.
core::PolyMesh cube_with_odd_top() {
  core::PolyMesh q;
  q.V.resize(9, 3);
  q.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,  //
      0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1,     //
      0.5, 1, 1.3;                            // 8: a ridge on the top's back edge 6-7
  q.add_face({0, 3, 2, 1});  // bottom
  q.add_face({0, 1, 5, 4});  // front
  q.add_face({1, 2, 6, 5});  // right
  q.add_face({2, 3, 7, 8, 6});  // back, with 8 on its top edge: a pentagon
  q.add_face({3, 0, 4, 7});  // left
  q.add_face({4, 5, 6, 8});  // top: the quad 4 5 6 8 and the triangle 4 8 7
  q.add_face({4, 8, 7});
  return q;
}

TEST(PureQuads, OddFacesSideBySideMerge) {
  const core::PolyMesh in = cube_with_odd_top();
  const PureQuadResult r = make_pure_quads(in);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_non_quads_before, 2);
  EXPECT_EQ(r.stats.n_non_quads_after, 0);
  EXPECT_EQ(r.stats.n_boundary_splits, 0);
  // The pentagon and the triangle share the edge 7-8: it goes, and their hexagon is split.
  EXPECT_EQ(r.stats.n_merged, 1);
  EXPECT_EQ(r.stats.n_paths, 0);
  EXPECT_EQ(r.stats.n_edges_split, 0);
  EXPECT_LE(r.quads.n_vertices(), in.n_vertices());  // no new vertex
  const QuadMetrics m = compute_quad_metrics(r.quads);
  EXPECT_EQ(m.n_non_quads, 0);
  EXPECT_TRUE(m.manifold);
  EXPECT_EQ(m.n_boundary_loops, 0);
  EXPECT_EQ(m.euler_characteristic, 2);
  EXPECT_GT(r.stats.worst_quality, 0.3);
  EXPECT_EQ(n_faces_below(r.quads, 0.3), 0);
  EXPECT_EQ(m.n_flipped, 0);
  expect_each_directed_edge_once(r.quads);
}

TEST(PureQuads, AHexagonIsSplitAlongItsBestDiagonal) {
  // A 2×1 rectangle whose long sides bend out at their midpoints (turns of 53°, kept): the split
  // joins the two bends, two quads.
  core::PolyMesh q;
  q.V.resize(6, 3);
  q.V << 0, 0, 0, 1, -0.5, 0, 2, 0, 0, 2, 1, 0, 1, 1.5, 0, 0, 1, 0;
  q.add_face({0, 1, 2, 3, 4, 5});
  const PureQuadResult r = make_pure_quads(q);
  ASSERT_TRUE(r.status.is_ok());
  ASSERT_EQ(r.quads.n_faces(), 2);
  EXPECT_EQ(r.stats.n_vertices_removed, 0);
  EXPECT_EQ(r.stats.n_centers, 0);
  EXPECT_GT(r.stats.worst_quality, 0.5);
  for (int f = 0; f < 2; ++f) {
    std::vector<int> vs(r.quads.face_vertex.begin() + 4 * f, r.quads.face_vertex.begin() + 4 * f + 4);
    EXPECT_TRUE(std::find(vs.begin(), vs.end(), 1) != vs.end() && std::find(vs.begin(), vs.end(), 4) != vs.end());
  }
}

TEST(PureQuads, FlatCornersOnTheBoundaryAreRemoved) {
  // The same rectangle with straight sides (the midpoints are where grid lines crossed them): one
  // quad, the two flat corners gone, the outline the same.
  core::PolyMesh q;
  q.V.resize(6, 3);
  q.V << 0, 0, 0, 1, 0, 0, 2, 0, 0, 2, 1, 0, 1, 1, 0, 0, 1, 0;
  q.add_face({0, 1, 2, 3, 4, 5});
  const PureQuadResult r = make_pure_quads(q);
  ASSERT_TRUE(r.status.is_ok());
  ASSERT_EQ(r.quads.n_faces(), 1);
  EXPECT_EQ(r.stats.n_vertices_removed, 2);
  EXPECT_EQ(r.quads.n_vertices(), 4);
  EXPECT_NEAR(boundary_length(r.quads), boundary_length(q), 1e-12);
  EXPECT_EQ(n_faces_below(r.quads, 0.99), 0);
}

TEST(PureQuads, TrianglesPathsEndInQuadsOnTheBoundarySplitAroundTheirCentroids) {
  // An L of three unit quads, A = [0,1]², B = [1,2]×[0,1], C = [1,2]², with a triangle left of A
  // and one above C. Each triangle's path ends in its quad (which has a boundary edge), whose
  // boundary edge is split too: midpoints on two adjacent edges, which no diagonal split keeps
  // off a flat corner, so the quad is split around its centroid.
  core::PolyMesh q;
  q.V.resize(10, 3);
  q.V << 0, 0, 0, 1, 0, 0, 2, 0, 0, 2, 1, 0, 1, 1, 0, 0, 1, 0,  //
      2, 2, 0, 1, 2, 0, -1, 0.5, 0, 1.5, 3, 0;
  q.add_face({0, 1, 4, 5});  // A
  q.add_face({1, 2, 3, 4});  // B
  q.add_face({4, 3, 6, 7});  // C
  q.add_face({8, 0, 5});
  q.add_face({7, 6, 9});
  const PureQuadResult r = make_pure_quads(q);
  ASSERT_TRUE(r.status.is_ok());
  EXPECT_EQ(r.stats.n_non_quads_before, 2);
  EXPECT_EQ(r.stats.n_non_quads_after, 0);
  EXPECT_EQ(r.stats.n_paths, 2);
  EXPECT_EQ(r.stats.n_edges_split, 2);
  EXPECT_EQ(r.stats.n_boundary_splits, 2);
  EXPECT_EQ(r.stats.n_centers, 2);
  // The triangles' quads had a flat corner at their midpoint, which moved into A and C.
  EXPECT_EQ(r.stats.n_midpoints_shifted, 2);
  EXPECT_EQ(n_faces_below(r.quads, 0.3), 0);
  const QuadMetrics m = compute_quad_metrics(r.quads);
  EXPECT_EQ(m.n_flipped, 0);
  EXPECT_EQ(m.n_non_quads, 0);
  EXPECT_TRUE(m.manifold);
  EXPECT_EQ(m.n_boundary_loops, 1);
  EXPECT_NEAR(boundary_length(r.quads), boundary_length(q), 1e-12);
  expect_each_directed_edge_once(r.quads);
}

TEST(PureQuads, UVsAreInterpolatedForTheNewCorners) {
  core::PolyMesh in = grid_with_cut_corner();
  in.uv = in.V.leftCols(2);
  in.face_uv = in.face_vertex;
  const PureQuadResult r = make_pure_quads(in);
  ASSERT_TRUE(r.status.is_ok());
  ASSERT_TRUE(r.quads.has_uv());
  ASSERT_EQ(r.quads.face_uv.size(), r.quads.face_vertex.size());
  for (size_t c = 0; c < r.quads.face_vertex.size(); ++c)
    EXPECT_TRUE(r.quads.uv.row(r.quads.face_uv[c]).isApprox(r.quads.V.row(r.quads.face_vertex[c]).leftCols(2)))
        << "corner " << c;
}

TEST(PureQuads, APureQuadMeshIsReturnedAsItIs) {
  core::PolyMesh q;
  q.V.resize(4, 3);
  q.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  q.add_face({0, 1, 2, 3});
  const PureQuadResult r = make_pure_quads(q);
  ASSERT_TRUE(r.status.is_ok());
  EXPECT_EQ(r.quads.face_vertex, q.face_vertex);
  EXPECT_EQ(r.stats.n_non_quads_before, 0);
  EXPECT_EQ(r.stats.n_faces_split, 0);
}

TEST(PureQuads, BadInputIsRejected) {
  core::PolyMesh q;
  q.V.resize(3, 3);
  q.V.setZero();
  q.add_face({0, 1, 7});
  EXPECT_EQ(make_pure_quads(q).status.code(), core::StatusCode::kInvalidInput);
  PureQuadOptions o;
  o.max_path_faces = -1;
  EXPECT_EQ(make_pure_quads(grid_with_cut_corner(), o).status.code(), core::StatusCode::kInvalidInput);
}

}  // namespace
}  // namespace quadify::quadex
