// Small valid files of every readable format (a unit tetrahedron), written from bytes: used by
// read_mesh_test (round trips) and fuzz_readers_test (mutation seeds).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>

namespace quadify::core::test_samples {

// A unit tetrahedron used by every round trip: 4 vertices, 4 outward triangles.
inline const double kTetV[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
inline const int kTetF[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

template <class T>
inline void put(std::string* s, T value, bool big_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if (big_endian) std::reverse(b, b + sizeof(T));  // test host is little endian (x86/arm64)
  s->append(reinterpret_cast<const char*>(b), sizeof(T));
}

inline std::string tet_obj() {
  std::string s = "# tet\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\n";
  // Mixed index forms: plain, v/vt, v//vn, v/vt/vn and negative (relative) indices.
  s += "vn 0 0 1\nf 1/1 3/3 2/2\nf 1/1/1 2/2/1 4/3/1\nf -4/-3 -1/-2 -2/-1\nf 2/1 3/2 4/3\n";
  s += "l 1 2 3\n";
  return s;
}

inline std::string tet_off() {
  return "OFF\n# comment\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n"
         "3 1 2 3 255 0 0\n";
}

inline std::string tet_ply_ascii() {
  return "ply\nformat ascii 1.0\ncomment x\nelement vertex 4\nproperty float x\nproperty float y\n"
         "property float z\nproperty uchar red\nelement face 4\nproperty list uchar int "
         "vertex_indices\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
         "0 0 0 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n0 1\n";
}

inline std::string tet_ply_binary(bool big_endian) {
  std::string s = std::string("ply\nformat ") +
                  (big_endian ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex 4\nproperty double x\nproperty float nx\nproperty double "
                  "y\nproperty double z\nelement face 4\nproperty ushort flags\nproperty list "
                  "int uint vertex_index\nend_header\n";
  for (const auto& v : kTetV) {
    put<double>(&s, v[0], big_endian);
    put<float>(&s, 0.5f, big_endian);
    put<double>(&s, v[1], big_endian);
    put<double>(&s, v[2], big_endian);
  }
  for (const auto& f : kTetF) {
    put<uint16_t>(&s, 7, big_endian);
    put<int32_t>(&s, 3, big_endian);
    for (int k = 0; k < 3; ++k) put<uint32_t>(&s, static_cast<uint32_t>(f[k]), big_endian);
  }
  return s;
}

inline std::string tet_stl_ascii() {
  std::string s = "solid tet\n";
  for (const auto& f : kTetF) {
    s += " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k)
      s += "   vertex " + std::to_string(kTetV[f[k]][0]) + " " + std::to_string(kTetV[f[k]][1]) +
           " " + std::to_string(kTetV[f[k]][2]) + "\n";
    s += "  endloop\n endfacet\n";
  }
  return s + "endsolid tet\n";
}

inline std::string tet_stl_binary() {
  std::string s = "solid but binary";  // a binary header starting with "solid" (common)
  s.resize(80, ' ');
  put<uint32_t>(&s, 4, false);
  for (const auto& f : kTetF) {
    for (int d = 0; d < 3; ++d) put<float>(&s, 0.0f, false);
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) put<float>(&s, static_cast<float>(kTetV[f[k]][d]), false);
    put<uint16_t>(&s, 0, false);
  }
  return s;
}

inline std::string base64(const std::string& in) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t n = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8) | uint8_t(in[i + 2]);
    for (int k = 3; k >= 0; --k) out += kAlphabet[(n >> (6 * k)) & 63];
  }
  if (i + 1 == in.size()) {
    const uint32_t n = uint8_t(in[i]) << 16;
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += "==";
  } else if (i + 2 == in.size()) {
    const uint32_t n = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += kAlphabet[(n >> 6) & 63];
    out += '=';
  }
  return out;
}

// Tet buffer: 4 float positions (48 bytes) + 12 uint16 indices (24 bytes) = 72 bytes.
inline std::string tet_gltf_buffer() {
  std::string b;
  for (const auto& v : kTetV)
    for (double x : v) put<float>(&b, static_cast<float>(x), false);
  for (const auto& f : kTetF)
    for (int k = 0; k < 3; ++k) put<uint16_t>(&b, static_cast<uint16_t>(f[k]), false);
  return b;
}

// A parent node scaling by 2 with a child translating by (10, 0, 0) holding the tet.
inline std::string tet_gltf_json(const std::string& buffer_entry) {
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
  "nodes":[{"scale":[2,2,2],"children":[1]},{"translation":[10,0,0],"mesh":0}],
  "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"mode":4}]}],
  "buffers":[)" + buffer_entry + R"(],
  "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":24}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,1]},
               {"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}]})";
}

inline std::string tet_gltf() {
  const std::string b = tet_gltf_buffer();
  return tet_gltf_json(R"({"byteLength":72,"uri":"data:application/octet-stream;base64,)" + base64(b) +
                       "\"}");
}

inline std::string tet_glb() {
  std::string json = tet_gltf_json(R"({"byteLength":72})");
  while (json.size() % 4) json += ' ';
  const std::string bin = tet_gltf_buffer();  // 72 bytes, already 4-aligned
  std::string s = "glTF";
  put<uint32_t>(&s, 2, false);
  put<uint32_t>(&s, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()), false);
  put<uint32_t>(&s, static_cast<uint32_t>(json.size()), false);
  put<uint32_t>(&s, 0x4E4F534A, false);
  s += json;
  put<uint32_t>(&s, static_cast<uint32_t>(bin.size()), false);
  put<uint32_t>(&s, 0x004E4942, false);
  return s + bin;
}

}  // namespace quadify::core::test_samples
