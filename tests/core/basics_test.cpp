// Tests of the small libcore pieces: mesh.h conversions, topology.h, predicates.h,
// sparse_solver.h, atomic_file.h, status.h.
#include "test_meshes.h"
#include "test_util.h"
#include "writer_samples.h"

#include <libcore/atomic_file.h>
#include <libcore/mesh.h>
#include <libcore/predicates.h>
#include <libcore/read_mesh.h>
#include <libcore/sparse_solver.h>
#include <libcore/status.h>
#include <libcore/topology.h>

#include <gtest/gtest.h>

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace quadify::core {
namespace {
namespace fs = std::filesystem;

// Solver residuals are relative to ‖b‖; a well-conditioned SPD system solves to ~1e-15.
constexpr double kSolveRelTol = 1e-10;

TriMesh octahedron_tri() { return to_trimesh(test::octahedron()); }

// n×n grid torus: (n·n) vertices, 2n² triangles, genus 1.
TriMesh grid_torus(int n) {
  TriMesh mesh;
  mesh.V.resize(n * n, 3);
  mesh.F.resize(2 * n * n, 3);
  auto id = [n](int i, int j) { return ((i + n) % n) * n + (j + n) % n; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double a = 2 * M_PI * i / n, b = 2 * M_PI * j / n;
      mesh.V.row(id(i, j)) << (2 + std::cos(b)) * std::cos(a), (2 + std::cos(b)) * std::sin(a), std::sin(b);
      const int f = 2 * (i * n + j);
      mesh.F.row(f) << id(i, j), id(i + 1, j), id(i + 1, j + 1);
      mesh.F.row(f + 1) << id(i, j), id(i + 1, j + 1), id(i, j + 1);
    }
  return mesh;
}

// --- mesh.h ---

TEST(MeshTest, ToPolyKeepsTrianglesAndCornerUvs) {
  UVMesh uv_mesh;
  uv_mesh.mesh = octahedron_tri();
  uv_mesh.corner_uv.resize(24, 2);
  for (int c = 0; c < 24; ++c) uv_mesh.corner_uv.row(c) << c, -c;
  const PolyMesh poly = to_poly(uv_mesh);
  ASSERT_EQ(poly.n_faces(), 8);
  ASSERT_TRUE(poly.has_uv());
  for (int f = 0; f < 8; ++f) {
    EXPECT_EQ(poly.degree(f), 3);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(poly.vertex(f, k), uv_mesh.mesh.F(f, k)) << "face " << f;
      EXPECT_EQ(poly.uv.row(poly.face_uv[poly.face_corner(f, k)]), uv_mesh.corner_uv.row(3 * f + k));
    }
  }
  EXPECT_FALSE(to_poly(uv_mesh.mesh).has_uv());
}

TEST(MeshTest, ToTrimeshFanTriangulatesAndSkipsDegenerateFaces) {
  PolyMesh poly;
  poly.V.setZero(6, 3);
  poly.add_face({0, 1, 2, 3});     // quad → 2
  poly.add_face({0, 1, 2, 3, 4});  // pentagon → 3
  poly.add_face({4, 5});           // degree 2 → skipped
  const TriMesh tri = to_trimesh(poly);
  ASSERT_EQ(tri.n_faces(), 5);
  EXPECT_EQ(tri.F.row(0), Eigen::RowVector3i(0, 1, 2));
  EXPECT_EQ(tri.F.row(1), Eigen::RowVector3i(0, 2, 3));
  EXPECT_EQ(tri.F.row(4), Eigen::RowVector3i(0, 3, 4));
  EXPECT_EQ(tri.n_vertices(), 6);
}

TEST(MeshTest, ToUvmeshCarriesUvsThroughFanTriangulation) {
  const PolyMesh cube = test::cube_quads(true);
  const UVMesh uv = to_uvmesh(cube);
  ASSERT_EQ(uv.mesh.n_faces(), 12);
  ASSERT_EQ(uv.corner_uv.rows(), 36);
  for (int t = 0; t < 12; ++t) {
    const int f = t / 2, ks[2][3] = {{0, 1, 2}, {0, 2, 3}};
    for (int j = 0; j < 3; ++j) {
      const int k = ks[t % 2][j];
      EXPECT_EQ(uv.mesh.F(t, j), cube.vertex(f, k));
      EXPECT_EQ(uv.corner_uv.row(3 * t + j), cube.uv.row(cube.face_uv[cube.face_corner(f, k)])) << "tri " << t;
    }
  }
  // Without UVs the corner table is zero (documented fallback).
  EXPECT_TRUE(to_uvmesh(test::cube_quads(false)).corner_uv.isZero());
}

TEST(MeshTest, AddFaceRejectsMixingFacesWithAndWithoutUvs) {
  PolyMesh poly;
  poly.V.setZero(4, 3);
  poly.uv.setZero(4, 2);
  poly.add_face({0, 1, 2}, {0, 1, 2});
  EXPECT_THROW(poly.add_face({0, 2, 3}), InternalError);
  EXPECT_THROW(poly.add_face({0, 2, 3}, {0, 1}), InternalError);
}

TEST(MeshTest, BboxDiagonal) {
  EXPECT_DOUBLE_EQ(bbox_diagonal(test::cube_quads(false).V), std::sqrt(3.0));
  EXPECT_EQ(bbox_diagonal(Eigen::MatrixX3d()), 0.0);
}

// --- topology.h ---

TEST(TopologyTest, OctahedronTwinsAreConsistent) {
  const TriMesh mesh = octahedron_tri();
  const EdgeTopology topo = build_edge_topology(mesh);
  ASSERT_EQ(topo.n_edges(), 12);
  for (int h = 0; h < 24; ++h) {
    const int t = topo.twin[h];
    ASSERT_GE(t, 0) << "closed mesh, half-edge " << h;
    EXPECT_EQ(topo.twin[t], h);
    // Twin runs the other way.
    EXPECT_EQ(mesh.F(t / 3, t % 3), mesh.F(h / 3, (h % 3 + 1) % 3));
    EXPECT_EQ(topo.face_edge(h / 3, h % 3), topo.face_edge(t / 3, t % 3));
    const int e = topo.face_edge(h / 3, h % 3);
    EXPECT_LT(topo.edge_vertex(e, 0), topo.edge_vertex(e, 1));
    EXPECT_FALSE(topo.is_boundary_edge(e));
  }
  std::vector<int> comp;
  EXPECT_EQ(face_components(mesh, topo, &comp), 1);
  const TopologyStats s = topology_stats(mesh);
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_EQ(s.genus, 0);
  EXPECT_EQ(s.n_boundary_loops, 0);
  EXPECT_TRUE(s.is_manifold());
}

TEST(TopologyTest, TorusHasGenusOne) {
  const TopologyStats s = topology_stats(grid_torus(4));
  EXPECT_EQ(s.n_vertices, 16);
  EXPECT_EQ(s.n_edges, 48);
  EXPECT_EQ(s.euler_characteristic, 0);
  EXPECT_EQ(s.genus, 1);
  EXPECT_EQ(s.n_components, 1);
}

TEST(TopologyTest, DisksComponentsAndBoundaries) {
  TriMesh mesh;
  mesh.V.setZero(7, 3);
  mesh.F.resize(3, 3);
  mesh.F << 0, 1, 2, 0, 2, 3,  // a square disk
      4, 5, 6;                 // a separate triangle
  const EdgeTopology topo = build_edge_topology(mesh);
  EXPECT_EQ(topo.n_edges(), 8);
  int n_boundary = 0;
  for (int e = 0; e < topo.n_edges(); ++e) n_boundary += topo.is_boundary_edge(e);
  EXPECT_EQ(n_boundary, 7);
  std::vector<int> comp;
  EXPECT_EQ(face_components(mesh, topo, &comp), 2);
  EXPECT_EQ(comp[0], comp[1]);
  EXPECT_NE(comp[0], comp[2]);
  const TopologyStats s = topology_stats(mesh);
  EXPECT_EQ(s.n_boundary_loops, 2);
  EXPECT_EQ(s.n_components, 2);
  EXPECT_EQ(s.genus, 0);
}

TEST(TopologyTest, NonManifoldInputIsCountedOrRejected) {
  TriMesh fin;  // three triangles on edge (0,1)
  fin.V.setZero(5, 3);
  fin.F.resize(3, 3);
  fin.F << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  EXPECT_THROW(build_edge_topology(fin), std::invalid_argument);
  const TopologyStats s = topology_stats(fin);
  EXPECT_EQ(s.n_nonmanifold_edges, 1);
  EXPECT_FALSE(s.is_manifold());
  EXPECT_EQ(s.genus, -1);

  TriMesh bowtie;  // two triangles sharing only vertex 0
  bowtie.V.setZero(5, 3);
  bowtie.F.resize(2, 3);
  bowtie.F << 0, 1, 2, 0, 3, 4;
  EXPECT_EQ(topology_stats(bowtie).n_nonmanifold_vertices, 1);

  TriMesh flipped;  // two triangles with the same orientation of their shared edge
  flipped.V.setZero(4, 3);
  flipped.F.resize(2, 3);
  flipped.F << 0, 1, 2, 0, 1, 3;
  EXPECT_THROW(build_edge_topology(flipped), std::invalid_argument);
}

// --- predicates.h ---

TriMesh load_data_mesh(const std::string& name) { return to_trimesh(read_mesh(test::data_path(name))); }

TEST(TopologyTest, CreasesOfACadBoxAreAllItsSharpEdges) {
  const TriMesh box = load_data_mesh("box.obj");
  const EdgeTopology topo = build_edge_topology(box);
  const std::vector<int> sharp = sharp_edges(box, topo, 40);
  ASSERT_EQ(sharp.size(), 72u) << "the box's 12 edges of 4–8 mesh edges each";
  EXPECT_EQ(crease_edges(box, topo, CreaseOptions{}), sharp) << "flat sides: every sharp edge is a crease";
  const TriMesh cube = load_data_mesh("cube.obj");
  const EdgeTopology cube_topo = build_edge_topology(cube);
  EXPECT_EQ(crease_edges(cube, cube_topo, CreaseOptions{}).size(), 12u) << "12 triangles, 12 creases";
}

TEST(TopologyTest, CreaseFilterLeavesOutTheSharpEdgesOfAnOrganicMesh) {
  const TriMesh spot = load_data_mesh("spot.obj");
  const EdgeTopology topo = build_edge_topology(spot);
  const std::vector<int> sharp = sharp_edges(spot, topo, 40);
  CreaseOptions off;
  off.max_side_angle_deg = 0;
  EXPECT_EQ(crease_edges(spot, topo, off), sharp) << "0 turns the filter off";
  const std::vector<int> creases = crease_edges(spot, topo, CreaseOptions{});
  // spot's 73 sharp edges are mostly single edges at its coarsely tessellated ears, horns and
  // hooves, where the sides are curved too; what stays is one group of ≥ 6 creases.
  EXPECT_EQ(sharp.size(), 73u);
  EXPECT_GE(creases.size(), 6u);
  EXPECT_LE(creases.size(), 20u);
  EXPECT_TRUE(std::includes(sharp.begin(), sharp.end(), creases.begin(), creases.end()))
      << "creases are sharp edges, in increasing order";
  CreaseOptions strict;
  strict.max_side_angle_deg = 1;
  EXPECT_TRUE(crease_edges(spot, topo, strict).empty()) << "no sharp edge of spot has flat sides";
}

// A closed prism of n sides (a coarsely faceted cylinder of radius 1 and height 1, capped by
// fans): its two rims are rings of n edges at 90°, its sides meet at 360°/n.
TriMesh capped_prism(int n) {
  TriMesh m;
  m.V.resize(2 + 2 * n, 3);
  m.V.row(0) << 0, 0, 0;
  m.V.row(1) << 0, 0, 1;
  for (int j = 0; j < n; ++j) {
    const double a = 2 * std::numbers::pi * j / n;
    m.V.row(2 + j) << std::cos(a), std::sin(a), 0;
    m.V.row(2 + n + j) << std::cos(a), std::sin(a), 1;
  }
  m.F.resize(4 * n, 3);
  for (int j = 0; j < n; ++j) {
    const int b0 = 2 + j, b1 = 2 + (j + 1) % n, t0 = b0 + n, t1 = b1 + n;
    m.F.row(4 * j) << 0, b1, b0;
    m.F.row(4 * j + 1) << 1, t0, t1;
    m.F.row(4 * j + 2) << b0, b1, t1;
    m.F.row(4 * j + 3) << b0, t1, t0;
  }
  return m;
}

TEST(TopologyTest, TheEvenRimsOfAFacetedCylinderAreCreases) {
  // The rims' sides are curved (facets at 22.5°, above the 15° side angle), but every rim edge is
  // at 90°: a machined edge, kept by the uniform-chain rule, and only by it.
  const TriMesh prism = capped_prism(16);
  const EdgeTopology topo = build_edge_topology(prism);
  const std::vector<int> sharp = sharp_edges(prism, topo, 40);
  ASSERT_EQ(sharp.size(), 32u);
  EXPECT_EQ(crease_edges(prism, topo, CreaseOptions{}), sharp);
  CreaseOptions no_uniform;
  no_uniform.uniform_min_deg = 0;
  EXPECT_TRUE(crease_edges(prism, topo, no_uniform).empty()) << "by the side angle alone, no crease";
  CreaseOptions strict;
  strict.uniform_min_deg = 95;  // the rims are at 90°
  EXPECT_TRUE(crease_edges(prism, topo, strict).empty());
}

using test::folded_strips;

TEST(TopologyTest, AShortKnifeEdgeIsACreaseAShortFoldIsNot) {
  // Three sharp edges with flat sides: too few for a group, unless they are a knife edge.
  const TriMesh knife = folded_strips(3, 10);  // dihedral angle 170°
  const EdgeTopology knife_topo = build_edge_topology(knife);
  ASSERT_EQ(sharp_edges(knife, knife_topo, 40).size(), 3u);
  EXPECT_EQ(crease_edges(knife, knife_topo, CreaseOptions{}).size(), 3u);
  CreaseOptions no_exception;
  no_exception.keep_small_group_deg = 180;
  EXPECT_TRUE(crease_edges(knife, knife_topo, no_exception).empty());
  const TriMesh fold = folded_strips(3, 110);  // dihedral angle 70°
  const EdgeTopology fold_topo = build_edge_topology(fold);
  ASSERT_EQ(sharp_edges(fold, fold_topo, 40).size(), 3u);
  EXPECT_TRUE(crease_edges(fold, fold_topo, CreaseOptions{}).empty());
}

// A CAD part (the faceted cylinder's 32 rim creases) with a short fold beside it (3 sharp edges at
// 70° between curved sides, dropped on its own): 32 of 35 sharp edges are creases, above
// keep_all_share (0.9), so the fold is kept too.
TEST(TopologyTest, AFewSharpEdgesBesideACadPartAreKept) {
  const TriMesh prism = capped_prism(16);
  const TriMesh fold = folded_strips(3, 110);
  TriMesh both;
  both.V.resize(prism.V.rows() + fold.V.rows(), 3);
  both.V << prism.V, fold.V.rowwise() + Eigen::RowVector3d(5, 0, 0);
  both.F.resize(prism.F.rows() + fold.F.rows(), 3);
  both.F << prism.F, fold.F.array() + static_cast<int>(prism.V.rows());
  const EdgeTopology topo = build_edge_topology(both);
  const std::vector<int> sharp = sharp_edges(both, topo, 40);
  ASSERT_EQ(sharp.size(), 35u);
  EXPECT_EQ(crease_edges(both, topo, CreaseOptions{}), sharp);
  CreaseOptions off;
  off.keep_all_share = 1.01;
  EXPECT_EQ(crease_edges(both, topo, off).size(), 32u) << "the fold alone is no crease";
  CreaseOptions strict;
  strict.keep_all_share = 0.95;  // 32 / 35 = 0.914
  EXPECT_EQ(crease_edges(both, topo, strict).size(), 32u);
}

TEST(PredicatesTest, Orient2dSignsAndExactness) {
  EXPECT_EQ(orient2d({0, 0}, {1, 0}, {0, 1}), 1);
  EXPECT_EQ(orient2d({0, 0}, {0, 1}, {1, 0}), -1);
  EXPECT_EQ(orient2d({0, 0}, {1, 1}, {3, 3}), 0);
  // 3·0.1 rounds up, so c lies exactly above the line y = 3x, although the naive double
  // determinant 1·c.y - 3·c.x evaluates to exactly 0.
  const Eigen::Vector2d c(0.1, 0.1 * 3);
  ASSERT_EQ(1.0 * c.y() - 3.0 * c.x(), 0.0) << "test premise: the naive determinant must evaluate to 0";
  EXPECT_EQ(orient2d({0, 0}, {1, 3}, c), 1);
  // One ulp off the line decides the sign.
  const double up = std::nextafter(24.0, 25.0);
  EXPECT_EQ(orient2d({0.5, 0.5}, {12, 12}, {24, up}), 1);
  EXPECT_EQ(orient2d({0.5, 0.5}, {12, 12}, {up, 24}), -1);
}

TEST(PredicatesTest, Orient3dFollowsTheDocumentedConvention) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);  // CCW seen from +z
  EXPECT_EQ(orient3d(a, b, c, {0, 0, 1}), 1) << "on the side where abc is CCW";
  EXPECT_EQ(orient3d(a, b, c, {0, 0, -1}), -1) << "on the other side";
  EXPECT_EQ(orient3d(a, b, c, {5, -7, 0}), 0);
  // Exactly coplanar points with non-representable-looking coordinates.
  EXPECT_EQ(orient3d({0.1, 0.2, 0.3}, {1.1, 0.2, 0.3}, {0.1, 1.2, 0.3}, {1e8, -3e7, 0.3}), 0);
  EXPECT_EQ(orient3d(a, b, c, {0.3, 0.3, -std::numeric_limits<double>::denorm_min()}), -1);
}

TEST(PredicatesTest, Collinear3d) {
  EXPECT_TRUE(collinear3d({0, 0, 0}, {1, 2, 3}, {2, 4, 6}));
  EXPECT_FALSE(collinear3d({0, 0, 0}, {1, 2, 3}, {2, 4, std::nextafter(6.0, 7.0)}));
}

// --- sparse_solver.h ---

Eigen::SparseMatrix<double> path_laplacian_plus_identity(int n, double diag_shift) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, diag_shift + (i > 0) + (i + 1 < n));
    if (i + 1 < n) {
      t.emplace_back(i, i + 1, -1.0);
      t.emplace_back(i + 1, i, -1.0);
    }
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

TEST(SparseSolverTest, SolvesSpdSystemsAndRefactorizes) {
  const std::string backend = SparseSolver::backend();
  EXPECT_TRUE(backend == "cholmod" || backend == "eigen-llt") << backend;
  // Small systems take the simplicial path, large ones the backend's; one solver object may go
  // from one to the other when the size changes.
  SparseSolver solver;
  EXPECT_FALSE(solver.factorized());
  for (const int n : {50, 20000, 50}) {
    Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, 3);
    for (double shift : {1.0, 0.25}) {  // same pattern, new values
      const Eigen::SparseMatrix<double> A = path_laplacian_plus_identity(n, shift);
      ASSERT_TRUE(solver.factorize(A).is_ok());
      ASSERT_TRUE(solver.factorized());
      const Eigen::MatrixXd x = solver.solve(b);
      const double rel = (A * x - b).norm() / b.norm();
      EXPECT_LT(rel, kSolveRelTol) << "n " << n << " shift " << shift << " backend " << backend;
    }
  }
}

TEST(SparseSolverTest, ReportsBadInputAsStatus) {
  SparseSolver solver;
  Eigen::SparseMatrix<double> rect(3, 4);
  EXPECT_EQ(solver.analyze(rect).code(), StatusCode::kInvalidInput);
  EXPECT_THROW((void)solver.solve(Eigen::VectorXd::Ones(3)), InternalError);
  for (const int n : {10, 20000}) {  // both paths
    const Eigen::SparseMatrix<double> negative = -path_laplacian_plus_identity(n, 1.0);
    const Status s = solver.factorize(negative);
    EXPECT_EQ(s.code(), StatusCode::kNumericalFailure) << n << ": " << s.to_string();
    EXPECT_FALSE(solver.factorized());
  }
}

// CHOLMOD's OpenMP regions must reach libcore's serial GOMP_parallel, not libgomp's (a team and
// a futex system call per region: a third of a remesh's time). The dynamic linker resolves
// CHOLMOD's reference to the first definition in the global scope: the executable's, if the
// linker exported it; otherwise libgomp's, and this test fails.
TEST(SparseSolverTest, OpenMpRegionsRunOnTheCallingThread) {
  if (std::string(SparseSolver::backend()) != "cholmod") GTEST_SKIP() << "no CHOLMOD";
  SparseSolver solver;  // links sparse_solver.o, as every user of the solver does
  using Parallel = void (*)(void (*)(void*), void*, unsigned, unsigned);
  const auto gomp_parallel = reinterpret_cast<Parallel>(dlsym(RTLD_DEFAULT, "GOMP_parallel"));
  ASSERT_NE(gomp_parallel, nullptr);
  Dl_info found{}, here{};
  ASSERT_NE(dladdr(reinterpret_cast<void*>(gomp_parallel), &found), 0);
  ASSERT_NE(dladdr(reinterpret_cast<void*>(&path_laplacian_plus_identity), &here), 0);
  EXPECT_EQ(found.dli_fbase, here.dli_fbase) << "GOMP_parallel comes from " << found.dli_fname;
  struct Seen {
    std::thread::id id;
    int calls = 0;
  } seen;
  gomp_parallel([](void* p) {
    auto* s = static_cast<Seen*>(p);
    s->id = std::this_thread::get_id();
    ++s->calls;
  }, &seen, 4, 0);
  EXPECT_EQ(seen.calls, 1);
  EXPECT_EQ(seen.id, std::this_thread::get_id());
  // And a large factorization (supernodal, with its regions) still solves.
  const int n = 20000;
  const Eigen::SparseMatrix<double> A = path_laplacian_plus_identity(n, 0.5);
  ASSERT_TRUE(solver.factorize(A).is_ok());
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(n);
  EXPECT_LT((A * solver.solve(b) - b).norm() / b.norm(), kSolveRelTol);
}

// --- atomic_file.h ---

TEST(AtomicFileTest, WritesReplacesAndCleansUp) {
  const fs::path dir = test::make_temp_dir("atomic");
  ASSERT_FALSE(dir.empty());
  const fs::path path = dir / "x.txt";
  write_file_atomically(path, [](std::ostream& out) { out << "one"; });
  write_file_atomically(path, [](std::ostream& out) { out << "two"; });
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_EQ(s.str(), "two");
  write_files_atomically({{dir / "a", [](std::ostream& out) { out << "a"; }},
                          {dir / "b", [](std::ostream& out) { out << "b"; }}});
  EXPECT_TRUE(fs::exists(dir / "a"));
  EXPECT_TRUE(fs::exists(dir / "b"));
  // A throwing callback surfaces as OutputError naming the file; nothing is left behind.
  try {
    write_file_atomically(dir / "c", [](std::ostream&) { throw std::runtime_error("callback failed"); });
    ADD_FAILURE() << "no exception";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("callback failed"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find((dir / "c").string()), std::string::npos) << e.what();
  }
  size_t n_files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n_files;
  EXPECT_EQ(n_files, 3u) << "x.txt, a, b only";
  fs::remove_all(dir);
}

// --- status.h ---

TEST(StatusTest, CodesMessagesAndChecks) {
  EXPECT_TRUE(Status::ok().is_ok());
  EXPECT_EQ(Status().to_string(), "ok");
  const Status s = Status::invalid_input("face 3 is degenerate");
  EXPECT_FALSE(s.is_ok());
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_EQ(s.message(), "face 3 is degenerate");
  EXPECT_EQ(s.to_string(), "invalid input: face 3 is degenerate");
  EXPECT_EQ(Status::io_error("x").code(), StatusCode::kIoError);
  EXPECT_EQ(Status::not_converged("x").code(), StatusCode::kNotConverged);
  EXPECT_EQ(Status::numerical_failure("x").code(), StatusCode::kNumericalFailure);
  EXPECT_EQ(Status::internal("x").to_string(), "internal error: x");
  EXPECT_STREQ(status_code_name(StatusCode::kNotConverged), "not converged");
  try {
    QUADIFY_CHECK(1 + 1 == 3, "arithmetic");
    ADD_FAILURE() << "QUADIFY_CHECK did not throw";
  } catch (const InternalError& e) {
    EXPECT_NE(std::string(e.what()).find("1 + 1 == 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("arithmetic"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace quadify::core
