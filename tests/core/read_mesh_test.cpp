// Readers: round trips of every format from bytes written here, and a corpus of broken files
// that must each end in an InputError naming the file.
#include <libcore/read_mesh.h>
#include <libcore/status.h>

#include <gtest/gtest.h>

#include "read_mesh_samples.h"
#include "test_util.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace quadify::core {
namespace {

namespace fs = std::filesystem;
using namespace test_samples;

void expect_tet(const PolyMesh& m, const std::string& what) {
  ASSERT_EQ(m.n_vertices(), 4) << what;
  ASSERT_EQ(m.n_faces(), 4) << what;
  for (int v = 0; v < 4; ++v)
    for (int d = 0; d < 3; ++d) EXPECT_DOUBLE_EQ(m.V(v, d), kTetV[v][d]) << what << " v" << v;
  for (int f = 0; f < 4; ++f) {
    ASSERT_EQ(m.degree(f), 3) << what;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(m.vertex(f, k), kTetF[f][k]) << what << " f" << f;
  }
}

void expect_transformed_tet(const PolyMesh& m, const std::string& what) {
  ASSERT_EQ(m.n_vertices(), 4) << what;
  ASSERT_EQ(m.n_faces(), 4) << what;
  for (int v = 0; v < 4; ++v)
    for (int d = 0; d < 3; ++d)  // world = scale 2 · (translate 10 · p)
      EXPECT_DOUBLE_EQ(m.V(v, d), 2.0 * (kTetV[v][d] + (d == 0 ? 10.0 : 0.0))) << what << " v" << v;
  for (int f = 0; f < 4; ++f)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(m.vertex(f, k), kTetF[f][k]) << what;
}

void write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(ReadMesh, FormatFromExtension) {
  EXPECT_EQ(format_from_extension("a/b.OBJ"), MeshFormat::kObj);
  EXPECT_EQ(format_from_extension("x.off"), MeshFormat::kOff);
  EXPECT_EQ(format_from_extension("x.Ply"), MeshFormat::kPly);
  EXPECT_EQ(format_from_extension("x.stl"), MeshFormat::kStl);
  EXPECT_EQ(format_from_extension("x.gltf"), MeshFormat::kGltf);
  EXPECT_EQ(format_from_extension("x.glb"), MeshFormat::kGlb);
  EXPECT_EQ(format_from_extension("x.txt"), MeshFormat::kUnknown);
  EXPECT_STREQ(format_name(MeshFormat::kPly), "PLY");
}

TEST(ReadMesh, ObjIndexFormsUvsAndLines) {
  const PolyMesh m = read_mesh_from_memory(tet_obj(), MeshFormat::kObj, "tet.obj");
  expect_tet(m, "obj");
  ASSERT_TRUE(m.has_uv());
  EXPECT_EQ(m.uv.rows(), 3);
  EXPECT_EQ(m.face_uv[0], 0);
  EXPECT_EQ(m.face_uv[1], 2);
  ASSERT_EQ(m.lines.size(), 2u);
  EXPECT_EQ(m.lines[1][0], 1);
  EXPECT_EQ(m.lines[1][1], 2);
}

TEST(ReadMesh, ObjKeepsPolygons) {
  const PolyMesh m = read_mesh_from_memory("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
                                           MeshFormat::kObj, "quad.obj");
  ASSERT_EQ(m.n_faces(), 1);
  EXPECT_EQ(m.degree(0), 4);
  EXPECT_FALSE(m.has_uv());
}

TEST(ReadMesh, OffPlyStl) {
  expect_tet(read_mesh_from_memory(tet_off(), MeshFormat::kOff, "tet.off"), "off");
  expect_tet(read_mesh_from_memory("COFF 4 4 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n"
                                   "0 0 1 1 1 1 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
                                   MeshFormat::kOff, "tet_c.off"),
             "coff");
  expect_tet(read_mesh_from_memory(tet_ply_ascii(), MeshFormat::kPly, "a.ply"), "ply ascii");
  expect_tet(read_mesh_from_memory(tet_ply_binary(false), MeshFormat::kPly, "le.ply"), "ply le");
  expect_tet(read_mesh_from_memory(tet_ply_binary(true), MeshFormat::kPly, "be.ply"), "ply be");
  for (const std::string& bytes : {tet_stl_ascii(), tet_stl_binary()}) {
    const PolyMesh m = read_mesh_from_memory(bytes, MeshFormat::kStl, "tet.stl");
    ASSERT_EQ(m.n_faces(), 4);
    ASSERT_EQ(m.n_vertices(), 12);  // STL corners are stored per triangle
    for (int f = 0; f < 4; ++f)
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d)
          EXPECT_DOUBLE_EQ(m.V(m.vertex(f, k), d), kTetV[kTetF[f][k]][d]) << "stl f" << f;
  }
}

TEST(ReadMesh, GltfAndGlbWithNodeTransforms) {
#ifdef QUADIFY_TEST_NO_GLTF
  GTEST_SKIP() << "built without glTF";
#endif
  try {
    expect_transformed_tet(read_mesh_from_memory(tet_gltf(), MeshFormat::kGltf, "tet.gltf"), "gltf");
    expect_transformed_tet(read_mesh_from_memory(tet_glb(), MeshFormat::kGlb, "tet.glb"), "glb");
  } catch (const InputError& e) {
    if (std::string(e.what()).find("QUADIFY_WITH_GLTF=OFF") != std::string::npos) GTEST_SKIP();
    FAIL() << e.what();
  }
}

TEST(ReadMesh, GltfNonIndexedFanAndMatrixNode) {
  // A unit square as a non-indexed TRIANGLE_FAN, under a node matrix translating by (0, 0, 5).
  std::string buffer;
  const float square[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (const auto& p : square)
    for (float x : p) put<float>(&buffer, x, false);
  const std::string json = R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],
    "nodes":[{"matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1],"mesh":0}],
    "meshes":[{"primitives":[{"attributes":{"POSITION":0},"mode":6}]}],
    "buffers":[{"byteLength":48,"uri":"data:application/octet-stream;base64,)" + base64(buffer) + R"("}],
    "bufferViews":[{"buffer":0,"byteLength":48}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]})";
  PolyMesh m;
  try {
    m = read_mesh_from_memory(json, MeshFormat::kGltf, "fan.gltf");
  } catch (const InputError& e) {
    if (std::string(e.what()).find("QUADIFY_WITH_GLTF=OFF") != std::string::npos) GTEST_SKIP();
    FAIL() << e.what();
  }
  ASSERT_EQ(m.n_faces(), 2);
  ASSERT_EQ(m.n_vertices(), 4);
  for (int v = 0; v < 4; ++v) EXPECT_DOUBLE_EQ(m.V(v, 2), 5.0) << "v" << v;
  EXPECT_EQ(m.vertex(1, 0), 0);  // fan: (0,1,2), (0,2,3)
  EXPECT_EQ(m.vertex(1, 1), 2);
  EXPECT_EQ(m.vertex(1, 2), 3);
}

TEST(ReadMesh, FilesOnDiskAndDataMeshes) {
  const fs::path dir = test::make_temp_dir("read_mesh");
  ASSERT_FALSE(dir.empty());
  write_file(dir / "tet.ply", tet_ply_binary(false));
  expect_tet(read_mesh(dir / "tet.ply"), "ply file");
  struct Expect { const char* file; int faces; };
  for (const Expect& e : {Expect{"tet.obj", 4}, Expect{"cube.obj", 12}, Expect{"sphere.obj", 1280},
                          Expect{"disk.obj", 198}, Expect{"torus.obj", 800}, Expect{"spot.obj", 5856}}) {
    const PolyMesh m = read_mesh(test::data_path(e.file));
    EXPECT_EQ(m.n_faces(), e.faces) << e.file;
  }
  fs::remove_all(dir);
}

// Each broken input must throw InputError whose message names the file.
void expect_input_error(const fs::path& path, const std::string& why) {
  try {
    const PolyMesh m = read_mesh(path);
    ADD_FAILURE() << why << ": read " << path << " without error (" << m.n_faces() << " faces)";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path.filename().string()), std::string::npos)
        << why << ": message does not name the file: " << e.what();
  }
}

TEST(ReadMesh, BrokenCorpusGivesInputErrorNamingTheFile) {
  const fs::path dir = test::make_temp_dir("broken");
  ASSERT_FALSE(dir.empty());
  std::string truncated_stl = tet_stl_binary();
  truncated_stl.resize(truncated_stl.size() - 7);
  std::string huge_stl = tet_stl_binary();
  huge_stl[80] = '\xff', huge_stl[81] = '\xff', huge_stl[82] = '\xff', huge_stl[83] = '\x7f';
  std::string ply_huge = tet_ply_ascii();
  ply_huge.replace(ply_huge.find("vertex 4"), 8, "vertex 4000000000");
  std::string ply_trunc = tet_ply_binary(false);
  ply_trunc.resize(ply_trunc.size() - 5);
  std::string glb_trunc = tet_glb();
  glb_trunc.resize(glb_trunc.size() / 2);
  std::string garbage;
  for (int i = 0; i < 1000; ++i) garbage += static_cast<char>((i * 7919 + 13) % 256);
  const std::vector<std::pair<std::string, std::string>> corpus = {
      {"empty.obj", ""},
      {"empty.stl", ""},
      {"trunc.stl", truncated_stl},
      {"hugecount.stl", huge_stl},
      {"huge.ply", ply_huge},
      {"trunc.ply", ply_trunc},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"},
      {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"},
      {"nan.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"inf.off", "OFF\n3 1 0\n0 0 inf\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"noface.obj", "v 0 0 0\nv 1 0 0\n"},
      {"negative.off", "OFF\n-3 -1 0\n"},
      {"trunc.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n"},
      {"trunc.glb", glb_trunc},
      {"bad.gltf", "{\"asset\":{\"version\":\"2.0\"},\"meshes\":[{\"primitives\":[{\"attributes\":"
                   "{\"POSITION\":3}}]}]}"},
      {"garbage.obj", garbage}, {"garbage.off", garbage}, {"garbage.ply", garbage},
      {"garbage.stl", garbage}, {"garbage.gltf", garbage}, {"garbage.glb", garbage},
  };
  for (const auto& [file, bytes] : corpus) {
    write_file(dir / file, bytes);
    expect_input_error(dir / file, file);
  }
  fs::create_directory(dir / "folder.obj");
  expect_input_error(dir / "folder.obj", "directory");
  expect_input_error(dir / "missing.obj", "missing file");
  expect_input_error(dir / "mesh.xyz", "unknown extension");

  ReadOptions small;
  small.max_elements = 3;
  EXPECT_THROW((void)read_mesh_from_memory(tet_off(), MeshFormat::kOff, "capped.off", small), InputError);
  fs::remove_all(dir);
}

TEST(ReadMesh, MessageNamesTheLine) {
  try {
    (void)read_mesh_from_memory("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9\n", MeshFormat::kObj, "bad.obj");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.obj: line 5: face index 9 out of range"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace quadify::core
