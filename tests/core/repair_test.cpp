// repair_mesh on constructed defects, the tests/data meshes, and (slow) every benchmark mesh.
#include <libcore/read_mesh.h>
#include <libcore/repair.h>
#include <libcore/topology.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "test_util.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace quadify::core {
namespace {

PolyMesh make_poly(const std::vector<std::array<double, 3>>& V, const std::vector<std::vector<int>>& F) {
  PolyMesh m;
  m.V.resize(static_cast<int>(V.size()), 3);
  for (size_t v = 0; v < V.size(); ++v) m.V.row(v) << V[v][0], V[v][1], V[v][2];
  for (const auto& f : F) m.add_face(f);
  return m;
}

// The unit cube as 8 corners and 6 outward quads.
const std::vector<std::array<double, 3>> kCubeV = {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0, 1, 1},
                                                   {1, 0, 0}, {1, 0, 1}, {1, 1, 0}, {1, 1, 1}};
const std::vector<std::vector<int>> kCubeQuads = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                                  {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};

PolyMesh cube_tris() {
  std::vector<std::vector<int>> F;
  for (const auto& q : kCubeQuads) {
    F.push_back({q[0], q[1], q[2]});
    F.push_back({q[0], q[2], q[3]});
  }
  return make_poly(kCubeV, F);
}

// Signed volume (positive when faces are oriented outward).
double signed_volume(const TriMesh& m) {
  double vol = 0.0;
  for (int f = 0; f < m.n_faces(); ++f)
    vol += Eigen::Vector3d(m.V.row(m.F(f, 0))).dot(
               Eigen::Vector3d(m.V.row(m.F(f, 1))).cross(Eigen::Vector3d(m.V.row(m.F(f, 2))))) / 6.0;
  return vol;
}

void expect_closed_genus(const RepairResult& r, int components, int genus_sum, const std::string& what) {
  ASSERT_TRUE(r.status.is_ok()) << what << ": " << r.status.to_string();
  const TopologyStats s = topology_stats(r.mesh);
  EXPECT_TRUE(s.is_manifold()) << what << ": " << s.n_nonmanifold_edges << " nm edges, "
                               << s.n_nonmanifold_vertices << " nm vertices";
  EXPECT_EQ(s.n_boundary_loops, 0) << what;
  EXPECT_EQ(s.n_components, components) << what;
  EXPECT_EQ(s.genus, genus_sum) << what << " chi " << s.euler_characteristic;
  EXPECT_NO_THROW((void)build_edge_topology(r.mesh)) << what;
  EXPECT_EQ(r.vertex_origin.size(), static_cast<size_t>(r.mesh.n_vertices())) << what;
}

TEST(Repair, CleanMeshesUnchanged) {
  struct Case { const char* file; int genus; int boundary; };
  for (const Case& c : {Case{"tet.obj", 0, 0}, Case{"cube.obj", 0, 0}, Case{"sphere.obj", 0, 0},
                        Case{"disk.obj", 0, 1}, Case{"torus.obj", 1, 0}, Case{"spot.obj", 0, 0}}) {
    const PolyMesh in = read_mesh(test::data_path(c.file));
    const RepairResult r = repair_mesh(in);
    ASSERT_TRUE(r.status.is_ok()) << c.file << ": " << r.status.to_string();
    EXPECT_FALSE(r.report.changed()) << c.file << ": reoriented " << r.report.faces_reoriented
                                     << ", welded " << r.report.welded_vertices;
    EXPECT_EQ(r.mesh.n_faces(), in.n_faces()) << c.file;
    const TopologyStats s = topology_stats(r.mesh);
    EXPECT_EQ(s.genus, c.genus) << c.file;
    EXPECT_EQ(s.n_boundary_loops, c.boundary) << c.file;
    EXPECT_EQ(r.report.n_boundary_loops, c.boundary) << c.file;
  }
}

TEST(Repair, StlSoupWeldsToClosedCube) {
  const PolyMesh cube = cube_tris();
  PolyMesh soup;  // every triangle with its own three corners, as binary STL stores them
  soup.V.resize(3 * cube.n_faces(), 3);
  for (int f = 0; f < cube.n_faces(); ++f) {
    std::vector<int> ids;
    for (int k = 0; k < 3; ++k) {
      // Exporter rounding: perturb by far less than the weld tolerance (1e-7 × diagonal).
      soup.V.row(3 * f + k) = cube.V.row(cube.vertex(f, k)).array() + 1e-10 * ((f + k) % 3);
      ids.push_back(3 * f + k);
    }
    soup.add_face(ids);
  }
  const RepairResult r = repair_mesh(soup);
  expect_closed_genus(r, 1, 0, "stl soup cube");
  EXPECT_EQ(r.mesh.n_vertices(), 8);
  EXPECT_EQ(r.report.welded_vertices, 36 - 8);
  EXPECT_EQ(r.report.faces_reoriented, 0);
  EXPECT_NEAR(signed_volume(r.mesh), 1.0, 1e-9);
}

TEST(Repair, QuadsAreTriangulated) {
  const RepairResult r = repair_mesh(make_poly(kCubeV, kCubeQuads));
  expect_closed_genus(r, 1, 0, "quad cube");
  EXPECT_EQ(r.report.polygons_triangulated, 6);
  EXPECT_EQ(r.mesh.n_faces(), 12);
}

// The cube with edge (0,2) split at m = (0, 0.5, z) on one side only: faces (0,3,m),(m,3,2)
// instead of (0,3,2), and the cap (0, m, 2) glued into the T-junction (zero area for z = 0).
PolyMesh cube_with_cap(double z) {
  PolyMesh m = cube_tris();
  const int mid = m.n_vertices();
  PolyMesh out;
  out.V = m.V;
  out.V.conservativeResize(mid + 1, 3);
  out.V.row(mid) << 0, 0.5, z;
  for (int f = 0; f < m.n_faces(); ++f) {
    std::vector<int> t = {m.vertex(f, 0), m.vertex(f, 1), m.vertex(f, 2)};
    if (t == std::vector<int>{0, 3, 2}) {
      out.add_face({0, 3, mid});
      out.add_face({mid, 3, 2});
    } else {
      out.add_face(t);
    }
  }
  out.add_face({0, mid, 2});  // the cap fills the slit between 0→2 and 2→m→0
  return out;
}

TEST(Repair, DegenerateCapIsRemovedKeepingTheSurfaceClosed) {
  const RepairResult r = repair_mesh(cube_with_cap(0));
  expect_closed_genus(r, 1, 0, "cap");
  EXPECT_GE(r.report.degenerate_faces_removed, 1);
}

// Largest triangle angle of a mesh (degrees) and its total area.
double largest_angle_deg(const TriMesh& m) {
  double best = 0;
  for (int f = 0; f < m.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = m.V.row(m.F(f, k));
      const Eigen::Vector3d u = Eigen::Vector3d(m.V.row(m.F(f, (k + 1) % 3))) - p;
      const Eigen::Vector3d w = Eigen::Vector3d(m.V.row(m.F(f, (k + 2) % 3))) - p;
      best = std::max(best, std::atan2(u.cross(w).norm(), u.dot(w)) * 180 / 3.14159265358979);
    }
  return best;
}
Eigen::Vector3d area_vector(const TriMesh& m) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int f = 0; f < m.n_faces(); ++f)
    sum += 0.5 * (Eigen::Vector3d(m.V.row(m.F(f, 1))) - Eigen::Vector3d(m.V.row(m.F(f, 0))))
                     .cross(Eigen::Vector3d(m.V.row(m.F(f, 2))) - Eigen::Vector3d(m.V.row(m.F(f, 0))));
  return sum;
}

TEST(Repair, NearlyDegenerateCapIsRemovedKeepingTheSurface) {
  // The cap's vertex 0.002 off the cube edge (angle 179.5°, not zero area).
  const PolyMesh out = cube_with_cap(0.002);
  RepairOptions keep;
  keep.cap_angle_deg = 180;
  const RepairResult kept = repair_mesh(out, keep);
  EXPECT_EQ(kept.report.caps_removed, 0);
  EXPECT_GT(largest_angle_deg(kept.mesh), 179);
  const RepairResult r = repair_mesh(out);
  expect_closed_genus(r, 1, 0, "cap");
  EXPECT_EQ(r.report.caps_removed, 1);
  EXPECT_EQ(r.report.degenerate_faces_removed, 0);
  EXPECT_EQ(r.mesh.n_vertices(), 9) << "the cap's vertex stays";
  EXPECT_LT(largest_angle_deg(r.mesh), 178);
  EXPECT_NEAR(signed_volume(r.mesh), 1.0, 1e-3);
}

// An open patch: the triangle (a, b, w) with its vertex w 0.18 off the long edge a-b (160°), the
// triangle (b, a, c) across that edge, and two triangles joining a, w, b to d. With d lifted, the
// short edges a-w and w-b are creases: w is a vertex of a feature curve a-w-b whose one triangle
// spans the chord a-b.
PolyMesh wedge_patch(double c_height, double d_height) {
  return make_poly({{0, 0, 0}, {2, 0, 0}, {1, 0.18, 0}, {1, -1, c_height}, {1, 0.68, d_height}},
                   {{0, 1, 2}, {1, 0, 3}, {0, 2, 4}, {2, 1, 4}});
}

TEST(Repair, FeatureWedgeIsFlippedWhereTheSurfaceStays) {
  const std::vector<std::array<int, 2>> curve = {{0, 2}, {2, 1}};
  const RepairResult flat = repair_mesh(wedge_patch(0, 1));
  ASSERT_TRUE(flat.status.is_ok()) << flat.status.to_string();
  EXPECT_EQ(flat.report.caps_removed, 0) << "160° is no cap for the repair";
  TriMesh mesh = flat.mesh;
  EXPECT_EQ(flip_feature_wedges(&mesh, curve), 1);
  EXPECT_EQ(mesh.n_faces(), 4);
  EXPECT_EQ(mesh.n_vertices(), 5);
  EXPECT_LT(largest_angle_deg(mesh), 150);
  EXPECT_NEAR((area_vector(mesh) - area_vector(flat.mesh)).norm(), 0, 1e-12)
      << "a flat re-triangulation keeps the area";
  EXPECT_NO_THROW((void)build_edge_topology(mesh)) << "still manifold and oriented";
  EXPECT_EQ(flip_feature_wedges(&mesh, curve), 0) << "nothing left to flip";
  // Not features: left as it is.
  TriMesh plain = flat.mesh;
  EXPECT_EQ(flip_feature_wedges(&plain, {{0, 2}}), 0);
  // With c lifted by 0.5, the edge a-b is a crease too: flipping it would cut across it.
  TriMesh bent = repair_mesh(wedge_patch(0.5, 1)).mesh;
  EXPECT_EQ(flip_feature_wedges(&bent, curve), 0);
  EXPECT_GT(largest_angle_deg(bent), 159);
}

TEST(Repair, FoldedSliverIsFlippedAway) {
  // The sliver (b, a, d) lies folded over (a, b, c), face to face: d is inside it. Its angle at d
  // (147°) is not a cap's; the fold is found by the normals.
  const PolyMesh fold = make_poly({{0, 0, 0}, {2, 0, 0}, {1, -1, 0}, {1, -0.3, 0}},
                                  {{0, 1, 2}, {1, 0, 3}});
  const RepairResult r = repair_mesh(fold);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.report.folds_flipped, 1);
  EXPECT_EQ(r.report.caps_removed, 0);
  ASSERT_EQ(r.mesh.n_faces(), 2);
  for (int f = 0; f < 2; ++f) {
    const Eigen::Vector3d n = (Eigen::Vector3d(r.mesh.V.row(r.mesh.F(f, 1))) - Eigen::Vector3d(r.mesh.V.row(r.mesh.F(f, 0))))
                                  .cross(Eigen::Vector3d(r.mesh.V.row(r.mesh.F(f, 2))) - Eigen::Vector3d(r.mesh.V.row(r.mesh.F(f, 0))));
    EXPECT_LT(n.z(), 0) << "face " << f << " faces like the big triangle";
  }
  EXPECT_NEAR(area_vector(r.mesh).z(), area_vector(repair_mesh(fold, [] {
                                                       RepairOptions o;
                                                       o.fold_angle_deg = 180;
                                                       return o;
                                                     }()).mesh).z(), 1e-12)
      << "the double-covered part cancels either way";
}

// Largest angle (degrees) between the normals of two triangles on an edge.
double largest_normal_turn_deg(const TriMesh& m) {
  const EdgeTopology topo = build_edge_topology(m);
  auto normal = [&](int f) {
    return (Eigen::Vector3d(m.V.row(m.F(f, 1))) - Eigen::Vector3d(m.V.row(m.F(f, 0))))
        .cross(Eigen::Vector3d(m.V.row(m.F(f, 2))) - Eigen::Vector3d(m.V.row(m.F(f, 0))))
        .normalized();
  };
  double best = 0;
  for (int e = 0; e < topo.n_edges(); ++e) {
    const int h = topo.edge_halfedge[e], t = topo.twin[h];
    if (t < 0) continue;
    best = std::max(best, std::acos(std::clamp(normal(h / 3).dot(normal(t / 3)), -1.0, 1.0)) * 180 / 3.14159265358979);
  }
  return best;
}

TEST(Repair, FoldedSliverAlongACreaseIsRemoved) {
  // A 90° crease a-b between the floor (a, b, c) and the wall (m, a, p), (b, m, p); the sliver
  // (b, a, m) between them has its vertex m 0.05 below the crease (174°, no cap), lies in the
  // wall's plane and faces against it: its short edges would look like 180° creases beside the
  // real one (block's CAD tessellation has such slivers along its creases).
  const PolyMesh sliver = make_poly({{0, 0, 0}, {2, 0, 0}, {1, -1, 0}, {1, 0.001, -0.05}, {1, 0, 1}},
                                    {{0, 1, 2}, {1, 0, 3}, {3, 0, 4}, {1, 3, 4}});
  RepairOptions off;
  off.folded_sliver_angle_deg = 180;
  off.fold_angle_deg = 180;
  const RepairResult kept = repair_mesh(sliver, off);
  ASSERT_TRUE(kept.status.is_ok()) << kept.status.to_string();
  EXPECT_EQ(kept.report.caps_removed, 0);
  EXPECT_GT(largest_normal_turn_deg(kept.mesh), 170) << "the sliver is there, folded";
  RepairOptions on = off;
  on.folded_sliver_angle_deg = RepairOptions{}.folded_sliver_angle_deg;
  const RepairResult r = repair_mesh(sliver, on);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.report.caps_removed, 1);
  EXPECT_EQ(r.mesh.n_faces(), 4) << "the floor is split at the sliver's vertex";
  EXPECT_EQ(r.mesh.n_vertices(), 5);
  EXPECT_LT(largest_normal_turn_deg(r.mesh), 95) << "only the crease is left";
  EXPECT_LT(largest_angle_deg(r.mesh), 150);
  EXPECT_NO_THROW((void)build_edge_topology(r.mesh)) << "manifold and oriented";
  // The defaults remove it too.
  EXPECT_LT(largest_normal_turn_deg(repair_mesh(sliver).mesh), 95);
  // A sliver that is not folded (its vertex just off the crease in the floor's plane) stays.
  const PolyMesh flat = make_poly({{0, 0, 0}, {2, 0, 0}, {1, -1, 0}, {1, 0.05, 0}, {1, 0, 1}},
                                  {{0, 1, 2}, {1, 0, 3}, {3, 0, 4}, {1, 3, 4}});
  EXPECT_EQ(repair_mesh(flat, on).report.caps_removed, 0);
}

TEST(Repair, NeedleCollapsesByWelding) {
  // A vertex coincident with cube vertex 7, splitting edge (3,7): two zero-area triangles.
  PolyMesh m = cube_tris();
  PolyMesh out;
  const int dup = m.n_vertices();
  out.V = m.V;
  out.V.conservativeResize(dup + 1, 3);
  out.V.row(dup) = m.V.row(7);
  for (int f = 0; f < m.n_faces(); ++f) {
    std::vector<int> t = {m.vertex(f, 0), m.vertex(f, 1), m.vertex(f, 2)};
    int k = 0;
    for (; k < 3; ++k)
      if ((t[k] == 3 && t[(k + 1) % 3] == 7) || (t[k] == 7 && t[(k + 1) % 3] == 3)) break;
    if (k == 3) {
      out.add_face(t);
      continue;
    }
    const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
    out.add_face({a, dup, c});
    out.add_face({dup, b, c});
  }
  const RepairResult r = repair_mesh(out);
  expect_closed_genus(r, 1, 0, "needle");
  EXPECT_EQ(r.report.degenerate_faces_removed, 2);
  EXPECT_EQ(r.report.welded_vertices, 1);
  EXPECT_EQ(r.mesh.n_vertices(), 8);
}

TEST(Repair, DuplicateFaceAndInvalidFaceAndIsolatedVertices) {
  PolyMesh m = cube_tris();
  m.add_face({0, 1, 3});   // duplicate
  m.add_face({3, 0, 1});   // same set, rotated
  m.add_face({4, 4, 5});   // repeated id
  m.V.conservativeResize(m.n_vertices() + 2, 3);
  m.V.row(8) << 5, 5, 5;
  m.V.row(9) << -5, 5, 5;
  const RepairResult r = repair_mesh(m);
  expect_closed_genus(r, 1, 0, "duplicates");
  EXPECT_EQ(r.report.duplicate_faces_removed, 2);
  EXPECT_EQ(r.report.invalid_faces_removed, 1);
  EXPECT_EQ(r.report.unreferenced_vertices_removed, 2);
  EXPECT_EQ(r.mesh.n_vertices(), 8);
  for (int v = 0; v < 8; ++v) EXPECT_EQ(r.vertex_origin[v], v);
}

// The unit cube with a fin on its edge (0,1): three faces on the edge.
PolyMesh cube_with_fin() {
  PolyMesh m = cube_tris();
  m.V.conservativeResize(9, 3);
  m.V.row(8) << -1, 0.5, 0.5;
  m.add_face({0, 1, 8});
  return m;
}

TEST(Repair, NonManifoldFinIsRemoved) {
  const RepairResult r = repair_mesh(cube_with_fin());
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  expect_closed_genus(r, 1, 0, "fin");
  EXPECT_EQ(r.report.fin_faces_removed, 1);
  EXPECT_EQ(r.report.nonmanifold_edges_split, 0);
  EXPECT_EQ(r.mesh.n_faces(), 12);
  EXPECT_EQ(r.mesh.n_vertices(), 8);  // the fin's tip is unreferenced now
}

TEST(Repair, NonManifoldFinEdgeIsDetachedWhenFinsAreKept) {
  RepairOptions options;
  options.max_fin_faces = 0;
  const RepairResult r = repair_mesh(cube_with_fin(), options);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  const TopologyStats s = topology_stats(r.mesh);
  EXPECT_TRUE(s.is_manifold()) << s.n_nonmanifold_edges << " " << s.n_nonmanifold_vertices;
  EXPECT_EQ(s.n_components, 2);
  EXPECT_EQ(s.n_boundary_loops, 1);  // the detached fin
  EXPECT_EQ(r.report.fin_faces_removed, 0);
  EXPECT_EQ(r.report.nonmanifold_edges_split, 1);
  EXPECT_EQ(r.mesh.n_faces(), 13);
  EXPECT_EQ(r.mesh.n_vertices(), 11);  // fin gets copies of 0 and 1
}

TEST(Repair, TriangleAcrossACornerIsRemoved) {
  // A stray triangle (q1, q2, q3) over two edges of the cube's quad q, triangulated (q0, q1, q2),
  // (q0, q2, q3): both of its cube edges get three faces, its third edge is free. Without it the
  // cube is closed again; detaching it would leave a slit.
  PolyMesh m = cube_tris();
  const std::vector<int>& q = kCubeQuads[0];
  m.add_face({q[1], q[2], q[3]});
  const RepairResult r = repair_mesh(m);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  expect_closed_genus(r, 1, 0, "corner triangle");
  EXPECT_EQ(r.report.fin_faces_removed, 1);
  EXPECT_EQ(r.report.nonmanifold_edges_split, 0);
  EXPECT_EQ(r.mesh.n_faces(), 12);
}

TEST(Repair, TwoSolidsOnAnEdgeAreDetachedNotRemoved) {
  // Two cubes sharing an edge: neither is a fin (no free boundary, and too big).
  PolyMesh m = cube_tris();
  const int n = m.n_vertices();
  PolyMesh other = cube_tris();
  m.V.conservativeResize(2 * n, 3);
  for (int v = 0; v < n; ++v) m.V.row(n + v) = other.V.row(v) + Eigen::RowVector3d(1, 1, 0);
  for (int f = 0; f < other.n_faces(); ++f)
    m.add_face({other.vertex(f, 0) + n, other.vertex(f, 1) + n, other.vertex(f, 2) + n});
  // Cube 2's corners (1, 1, z) coincide with cube 1's and are welded: edge (6, 7) has 4 faces.
  const RepairResult r = repair_mesh(m);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.report.fin_faces_removed, 0);
  EXPECT_EQ(r.mesh.n_faces(), 24);
  EXPECT_TRUE(topology_stats(r.mesh).is_manifold());
}

TEST(Repair, BowtieVertexIsSplit) {
  // Two triangles touching at one vertex.
  const PolyMesh m = make_poly({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}},
                               {{0, 1, 2}, {0, 3, 4}});
  const RepairResult r = repair_mesh(m);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  const TopologyStats s = topology_stats(r.mesh);
  EXPECT_TRUE(s.is_manifold());
  EXPECT_EQ(r.report.nonmanifold_vertices_split, 1);
  EXPECT_EQ(r.mesh.n_vertices(), 6);
  EXPECT_EQ(s.n_components, 2);
  EXPECT_EQ(r.vertex_origin[5], 0);
}

TEST(Repair, InconsistentOrientationAndInsideOutFixed) {
  PolyMesh m = cube_tris();
  PolyMesh flipped;
  flipped.V = m.V;
  for (int f = 0; f < m.n_faces(); ++f) {
    if (f % 3 == 0) flipped.add_face({m.vertex(f, 0), m.vertex(f, 2), m.vertex(f, 1)});
    else flipped.add_face({m.vertex(f, 0), m.vertex(f, 1), m.vertex(f, 2)});
  }
  RepairResult r = repair_mesh(flipped);
  expect_closed_genus(r, 1, 0, "mixed orientation");
  EXPECT_EQ(r.report.faces_reoriented, 4);
  EXPECT_NEAR(signed_volume(r.mesh), 1.0, 1e-12);

  PolyMesh inside_out;
  inside_out.V = m.V;
  for (int f = 0; f < m.n_faces(); ++f) inside_out.add_face({m.vertex(f, 0), m.vertex(f, 2), m.vertex(f, 1)});
  r = repair_mesh(inside_out);
  expect_closed_genus(r, 1, 0, "inside out");
  EXPECT_EQ(r.report.faces_reoriented, 12);
  EXPECT_NEAR(signed_volume(r.mesh), 1.0, 1e-12);
}

TEST(Repair, MoebiusStripIsReportedNonOrientable) {
  constexpr int kN = 12;
  std::vector<std::array<double, 3>> V;
  std::vector<std::vector<int>> F;
  for (int i = 0; i < kN; ++i) {
    const double a = 2 * M_PI * i / kN, w = 0.3 * std::cos(a / 2), h = 0.3 * std::sin(a / 2);
    V.push_back({(1 + w) * std::cos(a), (1 + w) * std::sin(a), h});
    V.push_back({(1 - w) * std::cos(a), (1 - w) * std::sin(a), -h});
  }
  for (int i = 0; i < kN; ++i) {
    const int a = 2 * i, b = 2 * i + 1;
    const int c = i + 1 < kN ? 2 * (i + 1) : 1, d = i + 1 < kN ? 2 * (i + 1) + 1 : 0;  // half twist
    F.push_back({a, b, d});
    F.push_back({a, d, c});
  }
  const RepairResult r = repair_mesh(make_poly(V, F));
  EXPECT_EQ(r.status.code(), StatusCode::kInvalidInput) << r.status.to_string();
  EXPECT_NE(r.status.message().find("not orientable"), std::string::npos) << r.status.message();
}

TEST(Repair, SeveralComponentsKeptAndNothingLeftIsInvalid) {
  PolyMesh two = cube_tris();
  const PolyMesh cube = cube_tris();
  const int off = two.n_vertices();
  two.V.conservativeResize(2 * off, 3);
  two.V.bottomRows(off) = cube.V.array() + 3.0;
  for (int f = 0; f < cube.n_faces(); ++f)
    two.add_face({cube.vertex(f, 0) + off, cube.vertex(f, 1) + off, cube.vertex(f, 2) + off});
  const RepairResult r = repair_mesh(two);
  expect_closed_genus(r, 2, 0, "two cubes");
  EXPECT_EQ(r.report.n_components, 2);

  const RepairResult bad = repair_mesh(make_poly({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}}));
  EXPECT_EQ(bad.status.code(), StatusCode::kInvalidInput);
  EXPECT_NE(bad.status.message().find("no faces left"), std::string::npos) << bad.status.message();
}

}  // namespace
}  // namespace quadify::core
