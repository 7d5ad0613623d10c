#include <libcore/topology.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace quadify::core {
namespace {

struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

}  // namespace

EdgeTopology build_edge_topology(const TriMesh& mesh) {
  const int nf = mesh.n_faces();
  EdgeTopology topo;
  topo.face_edge.resize(nf, 3);
  topo.twin.assign(3 * nf, -1);
  std::unordered_map<long long, int> edge_of;
  edge_of.reserve(3 * nf);
  std::vector<std::array<int, 2>> ev;
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      const int h = 3 * f + k;
      auto [it, inserted] = edge_of.try_emplace(edge_key(a, b), static_cast<int>(ev.size()));
      if (inserted) {
        ev.push_back({std::min(a, b), std::max(a, b)});
        topo.edge_halfedge.push_back(h);
      } else {
        const int e = it->second;
        const int h0 = topo.edge_halfedge[e];
        if (topo.twin[h0] >= 0)
          throw std::invalid_argument("edge (" + std::to_string(a) + ", " + std::to_string(b) +
                                      ") has more than two faces");
        if (mesh.F(h0 / 3, h0 % 3) != b)
          throw std::invalid_argument("faces " + std::to_string(h0 / 3) + " and " + std::to_string(f) +
                                      " are inconsistently oriented across edge (" + std::to_string(a) +
                                      ", " + std::to_string(b) + ")");
        topo.twin[h0] = h;
        topo.twin[h] = h0;
      }
      topo.face_edge(f, k) = it->second;
    }
  }
  topo.edge_vertex.resize(static_cast<int>(ev.size()), 2);
  for (size_t e = 0; e < ev.size(); ++e) topo.edge_vertex.row(e) << ev[e][0], ev[e][1];
  return topo;
}

int face_components(const TriMesh& mesh, const EdgeTopology& topo, std::vector<int>* component) {
  const int nf = mesh.n_faces();
  DisjointSets sets(nf);
  for (int h = 0; h < 3 * nf; ++h)
    if (topo.twin[h] >= 0) sets.unite(h / 3, topo.twin[h] / 3);
  std::vector<int> label(nf, -1), root_label(nf, -1);
  int n = 0;
  for (int f = 0; f < nf; ++f) {
    const int r = sets.find(f);
    if (root_label[r] < 0) root_label[r] = n++;
    label[f] = root_label[r];
  }
  if (component) *component = std::move(label);
  return n;
}

TopologyStats topology_stats(const TriMesh& mesh) {
  TopologyStats s;
  const int nf = mesh.n_faces(), nv = mesh.n_vertices();
  s.n_faces = nf;
  // Undirected edges with their incident half-edges (works for non-manifold input too).
  std::unordered_map<long long, std::vector<int>> edge_faces;
  edge_faces.reserve(3 * nf);
  std::vector<char> used(nv, 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      used[mesh.F(f, k)] = 1;
      edge_faces[edge_key(mesh.F(f, k), mesh.F(f, (k + 1) % 3))].push_back(3 * f + k);
    }
  s.n_vertices = static_cast<int>(std::count(used.begin(), used.end(), 1));
  s.n_edges = static_cast<int>(edge_faces.size());
  s.euler_characteristic = s.n_vertices - s.n_edges + s.n_faces;

  DisjointSets face_sets(std::max(nf, 1));
  DisjointSets corner_sets(std::max(3 * nf, 1));  // corners of one vertex in one fan
  // Boundary half-edges: next boundary half-edge chains give the loops.
  std::vector<int> boundary_halfedges;
  bool oriented = true;
  for (auto& [key, hs] : edge_faces) {
    if (hs.size() > 2) ++s.n_nonmanifold_edges;
    if (hs.size() == 1) boundary_halfedges.push_back(hs[0]);
    if (hs.size() == 2) {
      const int h0 = hs[0], h1 = hs[1];
      face_sets.unite(h0 / 3, h1 / 3);
      const int a0 = mesh.F(h0 / 3, h0 % 3), a1 = mesh.F(h1 / 3, h1 % 3);
      if (a0 == a1) oriented = false;
      // Join the corners of the same vertex on both sides of the edge.
      const int c0a = h0, c0b = 3 * (h0 / 3) + (h0 % 3 + 1) % 3;
      const int c1a = h1, c1b = 3 * (h1 / 3) + (h1 % 3 + 1) % 3;
      auto vert = [&](int c) { return mesh.F(c / 3, c % 3); };
      for (int ca : {c0a, c0b})
        for (int cb : {c1a, c1b})
          if (vert(ca) == vert(cb)) corner_sets.unite(ca, cb);
    }
    if (hs.size() > 2)
      for (size_t i = 1; i < hs.size(); ++i) face_sets.unite(hs[0] / 3, hs[i] / 3);
  }
  // Components over faces connected through edges.
  std::vector<char> is_root(nf, 0);
  for (int f = 0; f < nf; ++f) is_root[face_sets.find(f)] = 1;
  s.n_components = static_cast<int>(std::count(is_root.begin(), is_root.end(), 1));
  // Non-manifold vertices: more than one corner fan.
  std::vector<int> fans(nv, 0);
  for (int c = 0; c < 3 * nf; ++c)
    if (corner_sets.find(c) == c) ++fans[mesh.F(c / 3, c % 3)];
  for (int v = 0; v < nv; ++v)
    if (fans[v] > 1) ++s.n_nonmanifold_vertices;
  // Boundary loops: connected groups of boundary edges (through shared vertices).
  if (!boundary_halfedges.empty()) {
    DisjointSets vsets(nv);
    std::vector<char> on_boundary(nv, 0);
    for (int h : boundary_halfedges) {
      const int a = mesh.F(h / 3, h % 3), b = mesh.F(h / 3, (h % 3 + 1) % 3);
      vsets.unite(a, b);
      on_boundary[a] = on_boundary[b] = 1;
    }
    std::vector<char> root(nv, 0);
    for (int v = 0; v < nv; ++v)
      if (on_boundary[v]) root[vsets.find(v)] = 1;
    s.n_boundary_loops = static_cast<int>(std::count(root.begin(), root.end(), 1));
  }
  if (s.is_manifold() && oriented) {
    // Σ over components of (2 - χ_c - b_c)/2 = (2·#C - χ - b) / 2.
    const int twice = 2 * s.n_components - s.euler_characteristic - s.n_boundary_loops;
    s.genus = twice >= 0 && twice % 2 == 0 ? twice / 2 : -1;
  }
  return s;
}

namespace {
// Twice the area times the unit normal of face f (zero for a degenerate face).
Eigen::Vector3d face_area_normal(const TriMesh& mesh, int f) {
  const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)),
                        c = mesh.V.row(mesh.F(f, 2));
  return (b - a).cross(c - a);
}
}  // namespace

std::vector<std::vector<int>> vertex_neighbours(const TriMesh& mesh) {
  std::vector<std::vector<int>> nb(mesh.n_vertices());
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      nb[a].push_back(b);
      nb[b].push_back(a);
    }
  for (auto& n : nb) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return nb;
}

std::vector<int> sharp_edges(const TriMesh& mesh, const EdgeTopology& topo, double angle_deg) {
  auto normal = [&](int f) { return face_area_normal(mesh, f); };
  const double cos_threshold = std::cos(angle_deg * std::numbers::pi / 180.0);
  std::vector<int> sharp;
  for (int e = 0; e < topo.n_edges(); ++e) {
    const int h = topo.edge_halfedge[e], t = topo.twin[h];
    if (t < 0) continue;
    const Eigen::Vector3d n0 = normal(h / 3), n1 = normal(t / 3);
    const double len = n0.norm() * n1.norm();
    if (len > 0 && n0.dot(n1) / len < cos_threshold) sharp.push_back(e);
  }
  return sharp;
}

std::vector<int> crease_edges(const TriMesh& mesh, const EdgeTopology& topo, const CreaseOptions& options) {
  std::vector<int> sharp = sharp_edges(mesh, topo, options.angle_deg);
  if (!(options.max_side_angle_deg > 0) || sharp.empty()) return sharp;
  const int ne = topo.n_edges(), nv = mesh.n_vertices();
  // Dihedral angle (degrees) of every interior edge; 0 where a face is degenerate.
  std::vector<double> dihedral(ne, 0);
  auto normal = [&](int f) { return face_area_normal(mesh, f); };
  for (int e = 0; e < ne; ++e) {
    const int h = topo.edge_halfedge[e], t = topo.twin[h];
    if (t < 0) continue;
    const Eigen::Vector3d n0 = normal(h / 3), n1 = normal(t / 3);
    const double len = n0.norm() * n1.norm();
    if (len > 0) dihedral[e] = std::acos(std::clamp(n0.dot(n1) / len, -1.0, 1.0)) * 180 / std::numbers::pi;
  }
  std::vector<char> is_sharp(ne, 0);
  for (const int e : sharp) is_sharp[e] = 1;
  auto side_angle = [&](int e) {
    double m = 0;
    const int h = topo.edge_halfedge[e];
    for (const int he : {h, topo.twin[h]}) {
      if (he < 0) continue;
      for (int k = 0; k < 3; ++k) {
        const int o = topo.face_edge(he / 3, k);
        if (o != e && !is_sharp[o]) m = std::max(m, dihedral[o]);
      }
    }
    return m;
  };
  // Sharp edges at each vertex (CSR).
  std::vector<int> start(nv + 1, 0), at;
  for (const int e : sharp) {
    ++start[topo.edge_vertex(e, 0) + 1];
    ++start[topo.edge_vertex(e, 1) + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  at.resize(start[nv]);
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (const int e : sharp) {
      at[fill[topo.edge_vertex(e, 0)]++] = e;
      at[fill[topo.edge_vertex(e, 1)]++] = e;
    }
  }
  auto degree = [&](int v) { return start[v + 1] - start[v]; };
  auto other = [&](int e, int v) { return topo.edge_vertex(e, 0) == v ? topo.edge_vertex(e, 1) : topo.edge_vertex(e, 0); };
  // Chains: maximal paths through vertices with exactly two sharp edges (or closed loops).
  std::vector<char> seen(ne, 0), keep(ne, 0);
  std::vector<int> chain;
  std::vector<double> sides;
  for (const int e0 : sharp) {
    if (seen[e0]) continue;
    chain.assign(1, e0);
    seen[e0] = 1;
    for (int end = 0; end < 2; ++end) {
      int e = e0, v = topo.edge_vertex(e0, end);
      while (degree(v) == 2) {
        const int next = at[start[v]] == e ? at[start[v] + 1] : at[start[v]];
        if (seen[next]) break;
        seen[next] = 1;
        chain.push_back(next);
        e = next;
        v = other(e, v);
      }
    }
    sides.clear();
    for (const int e : chain) sides.push_back(side_angle(e));
    std::nth_element(sides.begin(), sides.begin() + sides.size() / 2, sides.end());
    double lo = 180, hi = 0;
    for (const int e : chain) {
      lo = std::min(lo, dihedral[e]);
      hi = std::max(hi, dihedral[e]);
    }
    const bool uniform = options.uniform_min_deg > 0 && static_cast<int>(chain.size()) >= options.uniform_min_edges &&
                         lo >= options.uniform_min_deg && hi - lo <= options.uniform_spread_deg;
    if (sides[sides.size() / 2] < options.max_side_angle_deg || uniform)
      for (const int e : chain) keep[e] = 1;
  }
  // Groups of sharp edges connected through vertices: a group made mostly of crease chains is
  // kept whole (a CAD crease network whose chains partly run along curved fillets), elsewhere only
  // the crease chains stay. Then groups of kept edges that are too small are dropped.
  std::vector<int> parent(nv);
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  auto group_sizes = [&](const std::vector<char>& in, std::vector<int>* size) {
    std::iota(parent.begin(), parent.end(), 0);
    for (const int e : sharp)
      if (in[e]) parent[find(topo.edge_vertex(e, 0))] = find(topo.edge_vertex(e, 1));
    size->assign(nv, 0);
    for (const int e : sharp)
      if (in[e]) ++(*size)[find(topo.edge_vertex(e, 0))];
  };
  std::vector<int> n_all, n_kept(nv, 0);
  group_sizes(is_sharp, &n_all);
  for (const int e : sharp)
    if (keep[e]) ++n_kept[find(topo.edge_vertex(e, 0))];
  for (const int e : sharp) {
    const int g = find(topo.edge_vertex(e, 0));
    if (2 * n_kept[g] >= n_all[g]) keep[e] = 1;
  }
  group_sizes(keep, &n_kept);
  // Median dihedral angle of each small group.
  std::map<int, std::vector<double>> small_groups;
  for (const int e : sharp) {
    const int g = find(topo.edge_vertex(e, 0));
    if (keep[e] && n_kept[g] < options.min_group_edges) small_groups[g].push_back(dihedral[e]);
  }
  std::vector<char> sharp_group(nv, 0);
  for (auto& [g, angles] : small_groups) {
    std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
    sharp_group[g] = angles[angles.size() / 2] >= options.keep_small_group_deg;
  }
  std::vector<int> creases;
  for (const int e : sharp) {
    const int g = find(topo.edge_vertex(e, 0));
    if (keep[e] && (n_kept[g] >= options.min_group_edges || sharp_group[g])) creases.push_back(e);
  }
  const double kept_share = static_cast<double>(creases.size()) / static_cast<double>(sharp.size());
  if (kept_share >= options.keep_all_share) return sharp;
  return creases;
}

}  // namespace quadify::core
