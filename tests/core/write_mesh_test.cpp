// Tests of libcore/write_mesh.h: OBJ round trips, UV OBJ seams, glTF structure, atomicity.
#include "test_util.h"
#include "writer_samples.h"

#include <libcore/atomic_file.h>
#include <libcore/read_mesh.h>
#include <libcore/status.h>
#include <libcore/write_mesh.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace quadify::core {
namespace {
namespace fs = std::filesystem;
using test::cube_quads;
using test::octahedron;

// float32 normals are unit length up to float rounding (~6e-8 relative), far below this.
constexpr double kUnitNormalTol = 1e-6;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

size_t count_entries(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

// A cube with coordinates that need all 17 digits, a feature line and an isolated vertex.
PolyMesh awkward_cube() {
  PolyMesh mesh = cube_quads(true);
  for (int v = 0; v < 8; ++v) mesh.V.row(v) = mesh.V.row(v) * M_PI / 3.0 + Eigen::RowVector3d(1e-7, -2.0 / 3.0, 1e5);
  mesh.V.conservativeResize(9, 3);
  mesh.V.row(8) << 0.1, 0.2, 0.3;
  mesh.lines = {{0, 7}, {3, 8}};
  return mesh;
}

class WriteMeshTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir("write_mesh");
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST_F(WriteMeshTest, ObjRoundTripKeepsQuadsUvsLinesAndExactCoordinates) {
  const PolyMesh mesh = awkward_cube();
  const fs::path path = dir_ / "cube.obj";
  write_obj(path, mesh);
  const PolyMesh back = read_mesh(path);
  ASSERT_EQ(back.n_vertices(), mesh.n_vertices());
  for (int v = 0; v < mesh.n_vertices(); ++v)
    for (int d = 0; d < 3; ++d)
      EXPECT_EQ(back.V(v, d), mesh.V(v, d)) << "vertex " << v << " coord " << d << " not round-tripped";
  ASSERT_EQ(back.n_faces(), 6);
  EXPECT_EQ(back.face_vertex, mesh.face_vertex);
  for (int f = 0; f < 6; ++f) EXPECT_EQ(back.degree(f), 4) << "face " << f;
  ASSERT_TRUE(back.has_uv());
  ASSERT_EQ(back.face_uv.size(), mesh.face_uv.size());
  for (size_t c = 0; c < mesh.face_uv.size(); ++c)
    EXPECT_EQ(back.uv.row(back.face_uv[c]), mesh.uv.row(mesh.face_uv[c])) << "corner " << c;
  ASSERT_EQ(back.lines.size(), 2u);
  EXPECT_EQ(back.lines[0], (std::array<int, 2>{0, 7}));
  EXPECT_EQ(back.lines[1], (std::array<int, 2>{3, 8}));
}

TEST_F(WriteMeshTest, ObjTextHasOneStatementPerElement) {
  const PolyMesh mesh = awkward_cube();
  const fs::path path = dir_ / "cube.obj";
  write_obj(path, mesh);
  std::map<std::string, int> count;
  for (const std::string& line : split_lines(slurp(path))) {
    const std::string key = line.substr(0, line.find(' '));
    ++count[key];
    if (key == "f") {
      std::istringstream tok(line.substr(2));
      int n = 0;
      for (std::string corner; tok >> corner; ++n)
        EXPECT_NE(corner.find('/'), std::string::npos) << "corner without vt in '" << line << "'";
      EXPECT_EQ(n, 4) << "quad written as '" << line << "'";
    }
  }
  EXPECT_EQ(count["v"], 9);
  EXPECT_EQ(count["vt"], 12);
  EXPECT_EQ(count["f"], 6);
  EXPECT_EQ(count["l"], 2);

  // Without UVs: plain `f a b c d`, no vt.
  write_obj(path, mesh, WriteOptions{.write_uv = false});
  const std::string text = slurp(path);
  EXPECT_EQ(text.find("vt "), std::string::npos);
  EXPECT_EQ(text.find('/'), std::string::npos);
}

TEST_F(WriteMeshTest, ObjPrecisionOptionLimitsDigits) {
  PolyMesh mesh = octahedron();
  mesh.V(0, 0) = 1.0 / 3.0;
  const fs::path path = dir_ / "oct.obj";
  write_obj(path, mesh, WriteOptions{.precision = 6});
  const std::string text = slurp(path);
  EXPECT_NE(text.find("v 0.333333 0 0\n"), std::string::npos) << text.substr(0, 200);
}

TEST_F(WriteMeshTest, UvObjHasOneVtPerDistinctUvSoSeamsShow) {
  const UVMesh uv_mesh = to_uvmesh(cube_quads(true));
  ASSERT_EQ(uv_mesh.mesh.n_faces(), 12);
  std::set<std::pair<double, double>> distinct;
  for (int c = 0; c < 36; ++c) distinct.insert({uv_mesh.corner_uv(c, 0), uv_mesh.corner_uv(c, 1)});

  const fs::path path = dir_ / "uv.obj";
  write_uv_obj(path, uv_mesh);
  std::vector<std::pair<double, double>> vt;
  std::vector<std::pair<int, int>> corners;  // (v, vt), 0-based
  for (const std::string& line : split_lines(slurp(path))) {
    std::istringstream tok(line);
    std::string key;
    tok >> key;
    if (key == "vt") {
      double u, w;
      tok >> u >> w;
      vt.emplace_back(u, w);
    } else if (key == "f") {
      for (std::string c; tok >> c;) {
        const size_t slash = c.find('/');
        ASSERT_NE(slash, std::string::npos) << line;
        corners.emplace_back(std::stoi(c.substr(0, slash)) - 1, std::stoi(c.substr(slash + 1)) - 1);
      }
    }
  }
  // The atlas cuts the cube apart: more UV rows than the 8 vertices, one per distinct value.
  EXPECT_GT(vt.size(), 8u);
  EXPECT_EQ(vt.size(), distinct.size()) << "vt rows must be exactly the distinct UV values";
  ASSERT_EQ(corners.size(), 36u);
  for (int c = 0; c < 36; ++c) {
    EXPECT_EQ(corners[c].first, uv_mesh.mesh.F(c / 3, c % 3)) << "corner " << c;
    ASSERT_GE(corners[c].second, 0);
    ASSERT_LT(corners[c].second, static_cast<int>(vt.size()));
    EXPECT_EQ(vt[corners[c].second], std::make_pair(uv_mesh.corner_uv(c, 0), uv_mesh.corner_uv(c, 1)))
        << "corner " << c;
  }
  // The reader sees the same: a UV table with the distinct values.
  const PolyMesh back = read_mesh(path);
  EXPECT_EQ(static_cast<size_t>(back.uv.rows()), distinct.size());
  EXPECT_EQ(back.n_faces(), 12);
}

TEST_F(WriteMeshTest, UvObjRejectsWrongCornerCount) {
  UVMesh uv_mesh = to_uvmesh(cube_quads(true));
  uv_mesh.corner_uv.conservativeResize(35, 2);
  const fs::path path = dir_ / "bad.obj";
  EXPECT_THROW(write_uv_obj(path, uv_mesh), OutputError);
  EXPECT_FALSE(fs::exists(path));
}

TEST_F(WriteMeshTest, WriteIntoMissingFolderThrowsAndCreatesNothing) {
  const fs::path missing = dir_ / "no_such_dir";
  for (const char* name : {"m.obj", "m.gltf", "m.glb"}) {
    try {
      write_mesh(missing / name, cube_quads(true));
      ADD_FAILURE() << name << ": no exception";
    } catch (const OutputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << "message must name the file: " << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(missing));
  EXPECT_EQ(count_entries(dir_), 0u);
}

TEST_F(WriteMeshTest, InvalidMeshThrowsBeforeTouchingTheTarget) {
  PolyMesh mesh = cube_quads(false);
  mesh.face_vertex[5] = 42;
  const fs::path path = dir_ / "old.obj";
  write_obj(path, octahedron());
  const std::string before = slurp(path);
  EXPECT_THROW(write_obj(path, mesh), OutputError);
  EXPECT_THROW(write_gltf(dir_ / "x.gltf", mesh), OutputError);
  PolyMesh nan_mesh = cube_quads(false);
  nan_mesh.V(3, 1) = std::nan("");
  EXPECT_THROW(write_obj(path, nan_mesh), OutputError);
  EXPECT_EQ(slurp(path), before) << "a failed write changed the existing file";
  EXPECT_EQ(count_entries(dir_), 1u) << "temporary or partial files left behind";
}

TEST_F(WriteMeshTest, ThrowingCallbackLeavesNoFileAndNoTemp) {
  const fs::path path = dir_ / "f.txt";
  EXPECT_THROW(write_file_atomically(path,
                                     [](std::ostream& out) {
                                       out << "partial";
                                       throw std::runtime_error("boom");
                                     }),
               std::exception);
  EXPECT_EQ(count_entries(dir_), 0u);

  // Over an existing file: untouched.
  write_file_atomically(path, [](std::ostream& out) { out << "old"; });
  EXPECT_THROW(write_file_atomically(path, [](std::ostream&) { throw OutputError("boom"); }), OutputError);
  EXPECT_EQ(slurp(path), "old");
  EXPECT_EQ(count_entries(dir_), 1u);

  // A group whose second part fails creates none of its files.
  EXPECT_THROW(write_files_atomically({{dir_ / "a.bin", [](std::ostream& out) { out << "a"; }},
                                       {dir_ / "b.bin", [](std::ostream&) { throw std::runtime_error("x"); }}}),
               std::exception);
  EXPECT_FALSE(fs::exists(dir_ / "a.bin"));
  EXPECT_EQ(count_entries(dir_), 1u);
}

TEST_F(WriteMeshTest, UnknownExtensionThrows) {
  EXPECT_THROW(write_mesh(dir_ / "m.ply", octahedron()), OutputError);
  write_mesh(dir_ / "UPPER.OBJ", octahedron());
  EXPECT_TRUE(fs::exists(dir_ / "UPPER.OBJ"));
}

// A parsed glTF file: JSON and its binary buffer.
struct Gltf {
  nlohmann::json json;
  std::string bin;

  const nlohmann::json& accessor(int i) const { return json["accessors"][i]; }
  // Values of a float or uint32 accessor (tightly packed, as the writer produces).
  template <typename T>
  std::vector<T> values(int accessor_id, int components) const {
    const auto& acc = accessor(accessor_id);
    const auto& view = json["bufferViews"][acc["bufferView"].get<int>()];
    const size_t offset = view["byteOffset"].get<size_t>() + acc.value("byteOffset", size_t{0});
    const size_t n = acc["count"].get<size_t>() * components;
    if (offset + 4 * n > bin.size()) throw std::runtime_error("accessor beyond buffer");
    std::vector<T> out(n);
    std::memcpy(out.data(), bin.data() + offset, 4 * n);  // little-endian host (x86-64, arm64)
    return out;
  }
};

uint32_t u32_at(const std::string& s, size_t at) {
  uint32_t x;
  std::memcpy(&x, s.data() + at, 4);
  return x;
}

Gltf load_gltf(const fs::path& path) {
  Gltf g;
  const std::string bytes = slurp(path);
  if (path.extension() == ".glb") {
    EXPECT_EQ(u32_at(bytes, 0), 0x46546C67u) << "magic";
    EXPECT_EQ(u32_at(bytes, 4), 2u) << "version";
    EXPECT_EQ(u32_at(bytes, 8), bytes.size()) << "length";
    const uint32_t json_len = u32_at(bytes, 12);
    EXPECT_EQ(json_len % 4, 0u);
    g.json = nlohmann::json::parse(bytes.substr(20, json_len));
    const uint32_t bin_len = u32_at(bytes, 20 + json_len);
    g.bin = bytes.substr(28 + json_len, bin_len);
    EXPECT_EQ(28 + json_len + bin_len, bytes.size());
  } else {
    g.json = nlohmann::json::parse(bytes);
    g.bin = slurp(path.parent_path() / g.json["buffers"][0]["uri"].get<std::string>());
  }
  EXPECT_EQ(g.json["buffers"][0]["byteLength"].get<size_t>(), g.bin.size());
  return g;
}

TEST_F(WriteMeshTest, GltfQuadMeshWithUvsHasSplitVerticesTrianglesAndWireframe) {
  const PolyMesh mesh = cube_quads(true);
  std::set<std::tuple<int, double, double>> distinct_corner;
  for (size_t c = 0; c < mesh.face_vertex.size(); ++c)
    distinct_corner.insert({mesh.face_vertex[c], mesh.uv(mesh.face_uv[c], 0), mesh.uv(mesh.face_uv[c], 1)});

  for (const char* name : {"cube.gltf", "cube.glb"}) {
    SCOPED_TRACE(name);
    write_gltf(dir_ / name, mesh);
    const Gltf g = load_gltf(dir_ / name);
    if (std::string(name) == "cube.gltf") {
      EXPECT_TRUE(fs::exists(dir_ / "cube.bin"));
    }
    const auto& prims = g.json["meshes"][0]["primitives"];
    ASSERT_EQ(prims.size(), 2u);
    EXPECT_EQ(prims[0]["mode"], 4);
    EXPECT_EQ(prims[1]["mode"], 1);
    EXPECT_FALSE(prims[1]["attributes"].contains("TEXCOORD_0"));
    EXPECT_EQ(prims[1]["attributes"]["POSITION"], prims[0]["attributes"]["POSITION"]);
    const auto& attr = prims[0]["attributes"];
    const int pos = attr["POSITION"], nrm = attr["NORMAL"], tex = attr["TEXCOORD_0"];
    const size_t n_out = distinct_corner.size();
    EXPECT_EQ(g.accessor(pos)["count"].get<size_t>(), n_out);
    EXPECT_EQ(g.accessor(nrm)["count"].get<size_t>(), n_out);
    EXPECT_EQ(g.accessor(tex)["count"].get<size_t>(), n_out);
    EXPECT_EQ(g.accessor(pos)["min"], nlohmann::json::array({0.0, 0.0, 0.0}));
    EXPECT_EQ(g.accessor(pos)["max"], nlohmann::json::array({1.0, 1.0, 1.0}));
    const int tri = prims[0]["indices"], lin = prims[1]["indices"];
    EXPECT_EQ(g.accessor(tri)["count"], 36) << "6 quads → 12 triangles";
    EXPECT_EQ(g.accessor(lin)["count"], 24) << "a cube has 12 edges";

    // Every (position, uv) output vertex is one of the mesh's corners; indices in range.
    const auto p = g.values<float>(pos, 3), n = g.values<float>(nrm, 3), t = g.values<float>(tex, 2);
    for (size_t i = 0; i < n_out; ++i) {
      const Eigen::Vector3d normal(n[3 * i], n[3 * i + 1], n[3 * i + 2]);
      EXPECT_NEAR(normal.norm(), 1.0, kUnitNormalTol) << "normal " << i;
      // Cube corner normals point outwards along (±1,±1,±1)/√3.
      const Eigen::Vector3d outward = Eigen::Vector3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]).array() - 0.5;
      EXPECT_NEAR(normal.dot(outward.normalized()), 1.0, kUnitNormalTol) << "normal " << i;
    }
    for (uint32_t idx : g.values<uint32_t>(tri, 1)) EXPECT_LT(idx, n_out);
    std::set<std::pair<uint32_t, uint32_t>> segments;
    const auto l = g.values<uint32_t>(lin, 1);
    for (size_t s = 0; s < l.size(); s += 2) {
      ASSERT_LT(l[s], n_out);
      ASSERT_LT(l[s + 1], n_out);
      // Endpoints of a cube edge differ in exactly one coordinate, by 1.
      const Eigen::Vector3d a(p[3 * l[s]], p[3 * l[s] + 1], p[3 * l[s] + 2]);
      const Eigen::Vector3d b(p[3 * l[s + 1]], p[3 * l[s + 1] + 1], p[3 * l[s + 1] + 2]);
      EXPECT_EQ((a - b).squaredNorm(), 1.0) << "segment " << s / 2 << " is not a cube edge";
      segments.insert(std::minmax(l[s], l[s + 1]));
    }
    EXPECT_EQ(segments.size(), 12u);
    EXPECT_EQ(t.size(), 2 * n_out);
  }
}

TEST_F(WriteMeshTest, GltfTriangleMeshWithoutUvsKeepsVerticesAndHasNoTexcoord) {
  PolyMesh mesh = octahedron();
  mesh.V.conservativeResize(7, 3);
  mesh.V.row(6) << 3, 3, 3;  // isolated vertex: normal falls back to +z
  write_mesh(dir_ / "oct.glb", mesh);
  const Gltf g = load_gltf(dir_ / "oct.glb");
  const auto& prim = g.json["meshes"][0]["primitives"][0];
  EXPECT_FALSE(prim["attributes"].contains("TEXCOORD_0"));
  const int pos = prim["attributes"]["POSITION"], nrm = prim["attributes"]["NORMAL"];
  ASSERT_EQ(g.accessor(pos)["count"], 7);
  EXPECT_EQ(g.accessor(prim["indices"].get<int>())["count"], 24);
  EXPECT_EQ(g.accessor(g.json["meshes"][0]["primitives"][1]["indices"].get<int>())["count"], 24)
      << "an octahedron has 12 edges";
  EXPECT_EQ(g.accessor(pos)["max"], nlohmann::json::array({3.0, 3.0, 3.0}));
  const auto n = g.values<float>(nrm, 3);
  for (int v = 0; v < 6; ++v)  // by symmetry, the area-weighted normal is the vertex direction
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(n[3 * v + d], mesh.V(v, d), kUnitNormalTol) << "vertex " << v;
  EXPECT_EQ(n[18], 0.0f);
  EXPECT_EQ(n[19], 0.0f);
  EXPECT_EQ(n[20], 1.0f);
}

TEST_F(WriteMeshTest, GltfOfEmptyMeshThrows) {
  PolyMesh empty;
  EXPECT_THROW(write_gltf(dir_ / "e.gltf", empty), OutputError);
  EXPECT_EQ(count_entries(dir_), 0u);
}

}  // namespace
}  // namespace quadify::core
