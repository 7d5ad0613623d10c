#include <libquadex/small_components.h>

#include <libcore/topology.h>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace quadify::quadex {

SmallComponentResult split_small_components(const core::UVMesh& map, const core::PolyMesh& quads,
                                            const std::vector<int>& vertex_face,
                                            const SmallComponentOptions& options) {
  SmallComponentResult res;
  const core::TriMesh& mesh = map.mesh;
  const int nf = mesh.n_faces(), nq = quads.n_faces();
  if (static_cast<int>(vertex_face.size()) != quads.n_vertices() || map.corner_uv.rows() != 3 * nf) {
    res.status = core::Status::invalid_input("split_small_components: " + std::to_string(vertex_face.size()) +
                                             " vertex faces for " + std::to_string(quads.n_vertices()) +
                                             " quad vertices, or corner UVs not 3 per face");
    return res;
  }
  for (const int f : vertex_face)
    if (f < -1 || f >= nf) {
      res.status = core::Status::invalid_input("split_small_components: vertex face out of range");
      return res;
    }
  std::vector<int> component;
  int n_components = 0;
  try {
    n_components = core::face_components(mesh, core::build_edge_topology(mesh), &component);
  } catch (const std::invalid_argument& e) {
    res.status = core::Status::invalid_input(std::string("split_small_components: ") + e.what());
    return res;
  }
  // Extracted faces per component (a face's component is its first vertex's), and whether any
  // of them is not a proper quad.
  std::vector<int> n_faces(n_components, 0), n_triangles(n_components, 0), face_component(nq, -1);
  std::vector<char> broken(n_components, 0);
  for (int f = 0; f < nf; ++f) ++n_triangles[component[f]];
  for (int q = 0; q < nq; ++q) {
    const int d = quads.degree(q);
    if (d == 0) continue;
    const int vf = vertex_face[quads.vertex(q, 0)];
    if (vf < 0) continue;
    const int c = face_component[q] = component[vf];
    ++n_faces[c];
    std::vector<int> vs(quads.face_vertex.begin() + quads.face_offset[q],
                        quads.face_vertex.begin() + quads.face_offset[q + 1]);
    std::sort(vs.begin(), vs.end());
    if (d != 4 || std::unique(vs.begin(), vs.end()) != vs.end()) broken[c] = 1;
  }
  std::vector<char> replace(n_components, 0);
  for (int c = 0; c < n_components; ++c)
    replace[c] = (broken[c] || n_faces[c] == 0) && n_faces[c] <= options.max_faces &&
                 n_triangles[c] <= options.max_triangles;
  for (const int f : options.replace_faces) {
    if (f < 0 || f >= nf) {
      res.status = core::Status::invalid_input("split_small_components: replace_faces holds face " +
                                               std::to_string(f) + " of " + std::to_string(nf));
      return res;
    }
    replace[component[f]] = 1;
  }
  for (int c = 0; c < n_components; ++c) res.stats.n_replaced += replace[c];
  if (res.stats.n_replaced == 0) {
    res.quads = quads;
    return res;
  }
  res.quads = core::PolyMesh{};
  core::PolyMesh& out = res.quads;
  const bool uv = quads.has_uv();
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector2d> uvs;
  if (uv)
    for (int i = 0; i < quads.uv.rows(); ++i) uvs.push_back(quads.uv.row(i).transpose());
  // Kept faces, with their vertices renumbered in order of first use.
  std::vector<int> new_id(quads.n_vertices(), -1);
  std::vector<std::pair<std::vector<int>, std::vector<int>>> faces;
  for (int q = 0; q < nq; ++q) {
    if (face_component[q] >= 0 && replace[face_component[q]]) {
      ++res.stats.n_faces_removed;
      continue;
    }
    std::vector<int> vs, ts;
    for (int k = 0; k < quads.degree(q); ++k) {
      const int v = quads.vertex(q, k);
      if (new_id[v] < 0) {
        new_id[v] = static_cast<int>(positions.size());
        positions.push_back(quads.V.row(v).transpose());
      }
      vs.push_back(new_id[v]);
      if (uv) ts.push_back(quads.face_uv[quads.face_corner(q, k)]);
    }
    faces.emplace_back(std::move(vs), std::move(ts));
  }
  // Split triangles: corners, edge midpoints (one vertex per edge) and centroids.
  std::map<int, int> corner_vertex;
  std::map<std::pair<int, int>, int> midpoint_vertex;
  auto vertex_of = [&](int v) {
    auto [it, added] = corner_vertex.try_emplace(v, static_cast<int>(positions.size()));
    if (added) positions.push_back(mesh.V.row(v).transpose());
    return it->second;
  };
  auto midpoint_of = [&](int a, int b) {
    auto [it, added] = midpoint_vertex.try_emplace({std::min(a, b), std::max(a, b)}, static_cast<int>(positions.size()));
    if (added) positions.push_back(0.5 * (mesh.V.row(a) + mesh.V.row(b)).transpose());
    return it->second;
  };
  for (int f = 0; f < nf; ++f) {
    if (!replace[component[f]]) continue;
    int corner[3], mid[3];
    Eigen::Vector2d corner_uv[3], mid_uv[3];
    for (int k = 0; k < 3; ++k) {
      corner[k] = vertex_of(mesh.F(f, k));
      mid[k] = midpoint_of(mesh.F(f, k), mesh.F(f, (k + 1) % 3));  // on the edge k → k+1
      corner_uv[k] = map.corner_uv.row(3 * f + k).transpose();
    }
    for (int k = 0; k < 3; ++k) mid_uv[k] = 0.5 * (corner_uv[k] + corner_uv[(k + 1) % 3]);
    const int centroid = static_cast<int>(positions.size());
    positions.push_back((mesh.V.row(mesh.F(f, 0)) + mesh.V.row(mesh.F(f, 1)) + mesh.V.row(mesh.F(f, 2))).transpose() / 3);
    const Eigen::Vector2d centroid_uv = (corner_uv[0] + corner_uv[1] + corner_uv[2]) / 3;
    for (int k = 0; k < 3; ++k) {
      // Corner k, the midpoint after it, the centroid, the midpoint before it: CCW as the triangle.
      const int prev = (k + 2) % 3;
      std::vector<int> ts;
      if (uv) {
        for (const Eigen::Vector2d& t : {corner_uv[k], mid_uv[k], centroid_uv, mid_uv[prev]}) {
          ts.push_back(static_cast<int>(uvs.size()));
          uvs.push_back(t);
        }
      }
      faces.emplace_back(std::vector<int>{corner[k], mid[k], centroid, mid[prev]}, std::move(ts));
      ++res.stats.n_quads_added;
    }
  }
  out.V.resize(static_cast<int>(positions.size()), 3);
  for (size_t i = 0; i < positions.size(); ++i) out.V.row(static_cast<int>(i)) = positions[i].transpose();
  if (uv) {
    out.uv.resize(static_cast<int>(uvs.size()), 2);
    for (size_t i = 0; i < uvs.size(); ++i) out.uv.row(static_cast<int>(i)) = uvs[i].transpose();
  }
  for (const auto& [vs, ts] : faces) out.add_face(vs, ts);
  // Lines refer to vertex ids: keep those whose ends survive.
  for (const auto& [a, b] : quads.lines)
    if (a >= 0 && b >= 0 && a < quads.n_vertices() && b < quads.n_vertices() && new_id[a] >= 0 && new_id[b] >= 0)
      out.lines.push_back({new_id[a], new_id[b]});
  return res;
}

}  // namespace quadify::quadex
