// glTF 2.0 (.gltf with embedded or external buffers, and .glb) through tinygltf. This translation
// unit is the only one that compiles the tinygltf implementation (TINYGLTF_IMPLEMENTATION); the
// writer includes tiny_gltf.h for declarations only and links against these symbols.
#include "read_util.h"

#ifdef QUADIFY_WITH_GLTF

#include <Eigen/Geometry>

#include <functional>
#include <vector>

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

namespace quadify::core::detail {
namespace {

constexpr int kMaxNodeDepth = 256;  // deeper node chains are treated as corrupt (cycles)

// Bounds-checked access to the elements of one accessor.
class AccessorView {
 public:
  AccessorView(const tinygltf::Model& model, int accessor_id, int n_components,
               const std::string& name, const ReadOptions& options)
      : name_(name) {
    if (accessor_id < 0 || accessor_id >= static_cast<int>(model.accessors.size()))
      fail(name, "accessor " + std::to_string(accessor_id) + " does not exist");
    const tinygltf::Accessor& acc = model.accessors[accessor_id];
    const std::string what = "accessor " + std::to_string(accessor_id);
    if (acc.sparse.isSparse) fail(name, what + ": sparse accessors are not supported");
    component_type_ = acc.componentType;
    normalized_ = acc.normalized;
    component_size_ = tinygltf::GetComponentSizeInBytes(acc.componentType);
    if (component_size_ <= 0) fail(name, what + ": unknown component type");
    const int n_comp = tinygltf::GetNumComponentsInType(acc.type);
    if (n_comp != n_components)
      fail(name, what + ": expected " + std::to_string(n_components) + " components, got " +
                     std::to_string(n_comp));
    count_ = static_cast<long long>(acc.count);
    if (count_ < 0 || count_ > options.max_elements)
      fail(name, what + ": element count " + std::to_string(count_) + " exceeds the limit");
    if (count_ == 0) return;
    const int view_id = acc.bufferView;
    if (view_id < 0 || view_id >= static_cast<int>(model.bufferViews.size()))
      fail(name, what + ": missing buffer view");
    const tinygltf::BufferView& view = model.bufferViews[view_id];
    if (view.buffer < 0 || view.buffer >= static_cast<int>(model.buffers.size()))
      fail(name, what + ": missing buffer");
    const std::vector<unsigned char>& data = model.buffers[view.buffer].data;
    const long long elem_size = static_cast<long long>(component_size_) * n_components;
    stride_ = view.byteStride > 0 ? static_cast<long long>(view.byteStride) : elem_size;
    const unsigned long long view_end = static_cast<unsigned long long>(view.byteOffset) + view.byteLength;
    if (view_end > data.size() || view_end < view.byteOffset)
      fail(name, "buffer view " + std::to_string(view_id) + " exceeds its buffer");
    const unsigned long long need = static_cast<unsigned long long>(acc.byteOffset) +
                                    static_cast<unsigned long long>(stride_) * (count_ - 1) + elem_size;
    if (stride_ < elem_size || need > view.byteLength)
      fail(name, what + ": " + std::to_string(count_) + " elements exceed buffer view " +
                     std::to_string(view_id));
    base_ = data.data() + view.byteOffset + acc.byteOffset;
  }

  long long count() const { return count_; }

  double get(long long i, int k) const {
    const unsigned char* p = base_ + i * stride_ + static_cast<long long>(k) * component_size_;
    switch (component_type_) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: { float v; std::memcpy(&v, p, 4); return v; }
      case TINYGLTF_COMPONENT_TYPE_DOUBLE: { double v; std::memcpy(&v, p, 8); return v; }
      case TINYGLTF_COMPONENT_TYPE_BYTE: { int8_t v; std::memcpy(&v, p, 1); return norm(v, 127.0); }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: { uint8_t v; std::memcpy(&v, p, 1); return norm(v, 255.0); }
      case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t v; std::memcpy(&v, p, 2); return norm(v, 32767.0); }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; std::memcpy(&v, p, 2); return norm(v, 65535.0); }
      case TINYGLTF_COMPONENT_TYPE_INT: { int32_t v; std::memcpy(&v, p, 4); return norm(v, 2147483647.0); }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t v; std::memcpy(&v, p, 4); return norm(v, 4294967295.0); }
      default: fail(name_, "unknown component type");
    }
  }

 private:
  double norm(double v, double max) const { return normalized_ ? std::max(v / max, -1.0) : v; }

  const std::string& name_;
  const unsigned char* base_ = nullptr;
  long long count_ = 0, stride_ = 0;
  int component_type_ = 0, component_size_ = 0;
  bool normalized_ = false;
};

Eigen::Matrix4d node_transform(const tinygltf::Node& node, const std::string& name) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (node.matrix.size() == 16) {
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = node.matrix[4 * c + r];  // column-major in glTF
  } else {
    if (!node.matrix.empty()) fail(name, "node '" + node.name + "' has a malformed matrix");
    Eigen::Affine3d t = Eigen::Affine3d::Identity();
    if (node.translation.size() == 3)
      t.translate(Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
    if (node.rotation.size() == 4) {
      Eigen::Quaterniond q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
      if (!(q.norm() > 0)) fail(name, "node '" + node.name + "' has a zero rotation quaternion");
      t.rotate(q.normalized());
    }
    if (node.scale.size() == 3) t.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
    m = t.matrix();
  }
  if (!m.allFinite()) fail(name, "node '" + node.name + "' has a non-finite transform");
  return m;
}

void append_primitive(const tinygltf::Model& model, const tinygltf::Primitive& prim,
                      const Eigen::Matrix4d& xf, const std::string& name,
                      const ReadOptions& options, PolyMesh* mesh, std::vector<double>* positions) {
  const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
  if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
      mode != TINYGLTF_MODE_TRIANGLE_FAN)
    return;  // points and lines carry no surface
  const auto pos_it = prim.attributes.find("POSITION");
  if (pos_it == prim.attributes.end()) fail(name, "triangle primitive without POSITION");
  const AccessorView pos(model, pos_it->second, 3, name, options);
  const long long base = static_cast<long long>(positions->size() / 3);
  if (base + pos.count() > options.max_elements) fail(name, "too many vertices");
  for (long long i = 0; i < pos.count(); ++i) {
    const Eigen::Vector4d p(pos.get(i, 0), pos.get(i, 1), pos.get(i, 2), 1.0);
    const Eigen::Vector4d q = xf * p;
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(q[d])) fail(name, "vertex " + std::to_string(base + i) + " is not finite");
      positions->push_back(q[d]);
    }
  }
  std::vector<long long> idx;
  if (prim.indices >= 0) {
    const AccessorView ind(model, prim.indices, 1, name, options);
    idx.reserve(ind.count());
    for (long long i = 0; i < ind.count(); ++i) {
      const double v = ind.get(i, 0);
      if (!(v >= 0 && v < static_cast<double>(pos.count())))
        fail(name, "index " + std::to_string(static_cast<long long>(v)) + " out of range (primitive has " +
                       std::to_string(pos.count()) + " vertices)");
      idx.push_back(static_cast<long long>(v));
    }
  } else {
    idx.resize(pos.count());
    for (long long i = 0; i < pos.count(); ++i) idx[i] = i;
  }
  // A negative determinant mirrors the geometry: swap two corners to keep outward orientation.
  const bool mirrored = xf.topLeftCorner<3, 3>().determinant() < 0;
  auto add = [&](long long a, long long b, long long c) {
    if (mirrored) std::swap(b, c);
    if (static_cast<long long>(mesh->face_vertex.size()) + 3 > std::min(2'000'000'000LL, 3 * options.max_elements))
      fail(name, "too many faces");
    mesh->face_vertex.push_back(static_cast<int>(base + a));
    mesh->face_vertex.push_back(static_cast<int>(base + b));
    mesh->face_vertex.push_back(static_cast<int>(base + c));
    mesh->face_offset.push_back(static_cast<int>(mesh->face_vertex.size()));
  };
  const long long n = static_cast<long long>(idx.size());
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    for (long long i = 0; i + 2 < n; i += 3) add(idx[i], idx[i + 1], idx[i + 2]);
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (long long i = 0; i + 2 < n; ++i)
      if (i % 2 == 0) add(idx[i], idx[i + 1], idx[i + 2]);
      else add(idx[i + 1], idx[i], idx[i + 2]);
  } else {
    for (long long i = 1; i + 1 < n; ++i) add(idx[0], idx[i], idx[i + 1]);
  }
}

}  // namespace

PolyMesh read_gltf(const std::string& bytes, bool binary, const std::string& name,
                   const std::string& base_dir, const ReadOptions& options) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  bool ok = false;
  try {
    if (binary) {
      ok = loader.LoadBinaryFromMemory(&model, &err, &warn,
                                       reinterpret_cast<const unsigned char*>(bytes.data()),
                                       static_cast<unsigned int>(bytes.size()), base_dir);
    } else {
      ok = loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(),
                                      static_cast<unsigned int>(bytes.size()), base_dir);
    }
  } catch (const std::exception& e) {
    fail(name, std::string("glTF parse error: ") + e.what());
  }
  if (!ok) {
    std::string first = err.substr(0, err.find('\n'));
    fail(name, "glTF parse error: " + (first.empty() ? std::string("unknown") : first));
  }

  PolyMesh mesh;
  std::vector<double> positions;
  // glTF nodes form a forest: a node reached twice means a cycle or shared child (corrupt file,
  // and an exponential blow-up if followed).
  std::vector<char> visited(model.nodes.size(), 0);
  std::function<void(int, const Eigen::Matrix4d&, int)> visit = [&](int node_id,
                                                                   const Eigen::Matrix4d& parent,
                                                                   int depth) {
    if (node_id < 0 || node_id >= static_cast<int>(model.nodes.size()))
      fail(name, "node " + std::to_string(node_id) + " does not exist");
    if (depth > kMaxNodeDepth) fail(name, "node hierarchy deeper than " + std::to_string(kMaxNodeDepth));
    if (visited[node_id]) fail(name, "node " + std::to_string(node_id) + " is reached twice (not a tree)");
    visited[node_id] = 1;
    const tinygltf::Node& node = model.nodes[node_id];
    const Eigen::Matrix4d xf = parent * node_transform(node, name);
    if (node.mesh >= 0) {
      if (node.mesh >= static_cast<int>(model.meshes.size()))
        fail(name, "node " + std::to_string(node_id) + " refers to missing mesh");
      for (const tinygltf::Primitive& prim : model.meshes[node.mesh].primitives)
        append_primitive(model, prim, xf, name, options, &mesh, &positions);
    }
    for (int child : node.children) visit(child, xf, depth + 1);
  };

  if (!model.scenes.empty()) {
    const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
    if (scene >= static_cast<int>(model.scenes.size())) fail(name, "default scene does not exist");
    for (int root : model.scenes[scene].nodes) visit(root, Eigen::Matrix4d::Identity(), 0);
  } else {
    // No scene: every mesh once, untransformed.
    for (const tinygltf::Mesh& m : model.meshes)
      for (const tinygltf::Primitive& prim : m.primitives)
        append_primitive(model, prim, Eigen::Matrix4d::Identity(), name, options, &mesh, &positions);
  }
  const long long nv = static_cast<long long>(positions.size() / 3);
  mesh.V.resize(nv, 3);
  for (long long v = 0; v < nv; ++v)
    for (int d = 0; d < 3; ++d) mesh.V(v, d) = positions[3 * v + d];
  return mesh;
}

}  // namespace quadify::core::detail

#else  // QUADIFY_WITH_GLTF

namespace quadify::core::detail {

PolyMesh read_gltf(const std::string&, bool, const std::string& name, const std::string&,
                   const ReadOptions&) {
  fail(name, "glTF/GLB input is not available: quadify was built with QUADIFY_WITH_GLTF=OFF");
}

}  // namespace quadify::core::detail

#endif  // QUADIFY_WITH_GLTF
