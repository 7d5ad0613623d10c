#include "cone_pairs.h"

#include <libcore/topology.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <limits>
#include <cmath>
#include <numbers>
#include <queue>
#include <tuple>
#include <unordered_map>

namespace quadify::param {
namespace {

// Vertices on the mesh boundary (#V flags).
std::vector<char> boundary_vertices(const core::TriMesh& mesh, const CutMesh& cut) {
  std::vector<char> on_boundary(mesh.n_vertices(), 0);
  for (int h = 0; h < 3 * mesh.n_faces(); ++h)
    if (cut.topo.twin[h] < 0)
      on_boundary[mesh.F(h / 3, h % 3)] = on_boundary[mesh.F(h / 3, (h % 3 + 1) % 3)] = 1;
  return on_boundary;
}

// Angle of face f's corner k in the layout x (2·#copies), signed (negative when the face is
// flipped there).
double uv_corner_angle(const CutMesh& cut, const Eigen::VectorXd& x, int f, int k) {
  const Eigen::Vector2d p = x.segment<2>(2 * cut.corner_copy[3 * f + k]);
  const Eigen::Vector2d u = Eigen::Vector2d(x.segment<2>(2 * cut.corner_copy[3 * f + (k + 1) % 3])) - p;
  const Eigen::Vector2d w = Eigen::Vector2d(x.segment<2>(2 * cut.corner_copy[3 * f + (k + 2) % 3])) - p;
  return std::atan2(u.x() * w.y() - u.y() * w.x(), u.dot(w));
}

}  // namespace

std::vector<int> vertex_indices(const core::TriMesh& mesh, const CutMesh& cut,
                                const Eigen::VectorXd& x) {
  const int nv = mesh.n_vertices(), nf = mesh.n_faces();
  std::vector<double> angle_sum(nv, 0.0);
  const std::vector<char> on_boundary = boundary_vertices(mesh, cut);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) angle_sum[mesh.F(f, k)] += uv_corner_angle(cut, x, f, k);
  std::vector<int> index(nv, 0);
  for (int v = 0; v < nv; ++v)
    if (!on_boundary[v] && angle_sum[v] != 0)
      index[v] = 4 - static_cast<int>(std::lround(angle_sum[v] / (0.5 * std::numbers::pi)));
  return index;
}

namespace {

struct SeamStep {
  int to = -1;
  int seam = -1;
  int orientation = 0;  // +1 when the step runs v0 → v1 of the seam
  double length = 0;
};

struct PathSearch {
  const std::vector<std::vector<SeamStep>>& adjacency;
  const std::vector<int>& index;
  const std::vector<char>& excluded;  // vertices no path may touch
  double max_length;
  int max_hops;
  int source;
  std::vector<SeamChange> path;
  std::vector<int> visited;
  std::vector<ConePairCancellation>* found;
  // false: paths end at a negative cone (cancellation); true: every regular vertex on the way
  // is an end (splits).
  bool to_regular = false;

  void extend(int v, double length) {
    for (const SeamStep& st : adjacency[v]) {
      const double l = length + st.length;
      // Splits may always take one seam edge, however long (a coarse tessellation at a tip).
      if ((l > max_length && !(to_regular && path.empty())) || excluded[st.to]) continue;
      if (std::find(visited.begin(), visited.end(), st.to) != visited.end()) continue;
      path.push_back({st.seam, st.orientation});
      if (to_regular && index[st.to] == 0) found->push_back({source, st.to, l, path});
      if (!to_regular && index[st.to] < 0) {
        found->push_back({source, st.to, l, path});
      } else if (index[st.to] == 0 && static_cast<int>(path.size()) < max_hops) {
        visited.push_back(st.to);
        extend(st.to, l);
        visited.pop_back();
      }
      path.pop_back();
    }
  }
};

// Per vertex, the seam edges at it as steps to their other end.
std::vector<std::vector<SeamStep>> seam_adjacency(const core::TriMesh& mesh, const CutMesh& cut) {
  std::vector<std::vector<SeamStep>> adjacency(mesh.n_vertices());
  for (int s = 0; s < static_cast<int>(cut.seams.size()); ++s) {
    const int f = cut.seams[s].he_a / 3, k = cut.seams[s].he_a % 3;
    const int v0 = mesh.F(f, k), v1 = mesh.F(f, (k + 1) % 3);
    const double l = seam_length(cut, s);
    adjacency[v0].push_back({v1, s, +1, l});
    adjacency[v1].push_back({v0, s, -1, l});
  }
  return adjacency;
}

// Vertices no path may touch: the boundary and `avoid` (#V flags, or empty).
std::vector<char> excluded_vertices(const core::TriMesh& mesh, const CutMesh& cut, const std::vector<char>& avoid) {
  std::vector<char> excluded = boundary_vertices(mesh, cut);
  for (int v = 0; v < mesh.n_vertices() && v < static_cast<int>(avoid.size()); ++v)
    if (avoid[v]) excluded[v] = 1;
  return excluded;
}

}  // namespace

std::vector<ConePairCancellation> find_cone_pair_cancellations(const core::TriMesh& mesh,
                                                               const CutMesh& cut,
                                                               const std::vector<int>& index,
                                                               double max_length, int max_hops,
                                                               const std::vector<char>& avoid) {
  std::vector<ConePairCancellation> result;
  if (!(max_length > 0) || max_hops < 1) return result;
  const int nv = mesh.n_vertices();
  const std::vector<char> excluded = excluded_vertices(mesh, cut, avoid);
  const std::vector<std::vector<SeamStep>> adjacency = seam_adjacency(mesh, cut);
  std::vector<ConePairCancellation> candidates;
  for (int p = 0; p < nv; ++p) {
    if (index[p] <= 0 || excluded[p]) continue;
    PathSearch search{adjacency, index, excluded, max_length, max_hops, p, {}, {p}, &candidates};
    search.extend(p, 0.0);
  }
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    return std::tie(a.path_length, a.positive_vertex, a.negative_vertex) <
           std::tie(b.path_length, b.positive_vertex, b.negative_vertex);
  });
  std::vector<char> used_vertex(nv, 0), used_seam(cut.seams.size(), 0);
  for (const ConePairCancellation& c : candidates) {
    if (used_vertex[c.positive_vertex] || used_vertex[c.negative_vertex]) continue;
    if (std::any_of(c.changes.begin(), c.changes.end(), [&](const SeamChange& ch) { return used_seam[ch.seam]; }))
      continue;
    used_vertex[c.positive_vertex] = used_vertex[c.negative_vertex] = 1;
    for (const SeamChange& ch : c.changes) used_seam[ch.seam] = 1;
    result.push_back(c);
  }
  return result;
}

std::vector<ConePairCancellation> find_surface_cone_pairs(const core::TriMesh& mesh,
                                                          const CutMesh& cut,
                                                          const std::vector<int>& index,
                                                          double max_length,
                                                          const std::vector<char>& avoid) {
  std::vector<ConePairCancellation> result;
  if (!(max_length > 0)) return result;
  const int nv = mesh.n_vertices();
  const std::vector<char> excluded = excluded_vertices(mesh, cut, avoid);
  const std::vector<std::vector<SeamStep>> adjacency = seam_adjacency(mesh, cut);
  const std::vector<std::vector<int>> neighbours = core::vertex_neighbours(mesh);
  struct Candidate {
    double distance;
    int positive, negative;
  };
  std::vector<Candidate> candidates;
  std::vector<double> dist(nv, std::numeric_limits<double>::infinity());
  std::vector<int> touched;
  using Item = std::pair<double, int>;
  for (int p = 0; p < nv; ++p) {
    if (index[p] <= 0 || excluded[p]) continue;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    dist[p] = 0;
    touched.push_back(p);
    queue.push({0.0, p});
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > dist[v]) continue;
      if (v != p && index[v] < 0) candidates.push_back({d, p, v});
      for (const int w : neighbours[v]) {
        const double l = (mesh.V.row(v) - mesh.V.row(w)).norm();
        if (excluded[w] || d + l > max_length || !(d + l < dist[w])) continue;
        if (dist[w] == std::numeric_limits<double>::infinity()) touched.push_back(w);
        dist[w] = d + l;
        queue.push({dist[w], w});
      }
    }
    for (const int v : touched) dist[v] = std::numeric_limits<double>::infinity();
    touched.clear();
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(a.distance, a.positive, a.negative) <
           std::tie(b.distance, b.positive, b.negative);
  });
  // The seam path of a chosen pair: the shortest along the seams (any length; its matching
  // changes give the same map as a cut along the surface path would, up to the rotation of the
  // charts between the two paths, when the two paths bound a region: on a surface of genus > 0
  // they may also go round a handle, which the caller's checks of the new map then judge).
  std::vector<int> from_vertex(nv, -1);  // the vertex before v on the seam path
  std::vector<int> from_step(nv, -1);    // and the entry of its seam adjacency that reaches v
  std::vector<char> used_vertex(nv, 0);
  for (const Candidate& c : candidates) {
    if (used_vertex[c.positive] || used_vertex[c.negative]) continue;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    dist[c.positive] = 0;
    touched.push_back(c.positive);
    queue.push({0.0, c.positive});
    bool reached = false;
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > dist[v]) continue;
      if (v == c.negative) {
        reached = true;
        break;
      }
      for (int slot = 0; slot < static_cast<int>(adjacency[v].size()); ++slot) {
        const SeamStep& st = adjacency[v][slot];
        if (excluded[st.to] || !(d + st.length < dist[st.to])) continue;
        if (dist[st.to] == std::numeric_limits<double>::infinity()) touched.push_back(st.to);
        dist[st.to] = d + st.length;
        from_vertex[st.to] = v;
        from_step[st.to] = slot;
        queue.push({dist[st.to], st.to});
      }
    }
    ConePairCancellation pair{c.positive, c.negative, c.distance, {}};
    if (reached)
      for (int v = c.negative; v != c.positive; v = from_vertex[v]) {
        const SeamStep& st = adjacency[from_vertex[v]][from_step[v]];
        pair.changes.push_back({st.seam, st.orientation});
      }
    for (const int v : touched) dist[v] = std::numeric_limits<double>::infinity();
    touched.clear();
    if (!reached) continue;
    std::reverse(pair.changes.begin(), pair.changes.end());
    used_vertex[c.positive] = used_vertex[c.negative] = 1;
    result.push_back(std::move(pair));
  }
  return result;
}

std::vector<ConePairCancellation> find_cone_splits(const core::TriMesh& mesh, const CutMesh& cut,
                                                   const std::vector<int>& index, int max_index,
                                                   double distance, int max_hops,
                                                   const std::vector<char>& avoid) {
  std::vector<ConePairCancellation> result;
  if (!(distance > 0) || max_hops < 1) return result;
  const int nv = mesh.n_vertices();
  const std::vector<char> excluded = excluded_vertices(mesh, cut, avoid);
  const std::vector<std::vector<SeamStep>> adjacency = seam_adjacency(mesh, cut);
  // Positive cones; those above max_index, or crowded by another one closer than half the
  // distance, move.
  std::vector<int> positive;
  for (int v = 0; v < nv; ++v)
    if (index[v] > 0 && !excluded[v]) positive.push_back(v);
  const double crowd = 0.5 * distance;
  auto near_positive = [&](int v, int skip) {
    for (const int q : positive)
      if (q != skip && (mesh.V.row(q) - mesh.V.row(v)).norm() < crowd) return true;
    return false;
  };
  std::vector<ConePairCancellation> candidates;
  for (const int p : positive) {
    if (index[p] <= max_index && !(max_index == 1 && near_positive(p, p))) continue;
    PathSearch search{adjacency, index, excluded, 2 * distance, max_hops, p, {}, {p}, &candidates, true};
    search.extend(p, 0.0);
  }
  // Targets clear of the other positive cones (a cone that keeps some of its index counts).
  std::vector<ConePairCancellation> clear;
  // A cone above max_index none of whose targets is clear (a tentacle's tip crowded with +1
  // cones: octopus with thin-part sizing) takes the target farthest from the positive cones:
  // no quad mesh has its index, a crowded +1 cone is only harder to place.
  auto clearance = [&](int v, int skip) {
    double d = std::numeric_limits<double>::infinity();
    for (const int q : positive)
      if (q != skip) d = std::min(d, (mesh.V.row(q) - mesh.V.row(v)).norm());
    return d;
  };
  std::vector<double> room(candidates.size());
  std::vector<int> roomiest(nv, -1);  // per cone above max_index: its crowded target farthest out
  std::vector<char> has_clear(nv, 0);
  for (size_t i = 0; i < candidates.size(); ++i) {
    const int p = candidates[i].positive_vertex;
    room[i] = clearance(candidates[i].negative_vertex, index[p] > 1 ? -1 : p);
    if (room[i] >= crowd)
      has_clear[p] = 1;
    else if (index[p] > max_index && (roomiest[p] < 0 || room[i] > room[roomiest[p]]))
      roomiest[p] = static_cast<int>(i);
  }
  for (size_t i = 0; i < candidates.size(); ++i) {
    const int p = candidates[i].positive_vertex;
    if (room[i] >= crowd || (!has_clear[p] && roomiest[p] == static_cast<int>(i)))
      clear.push_back(std::move(candidates[i]));
  }
  auto miss = [distance](const ConePairCancellation& c) { return std::abs(c.path_length - distance); };
  std::sort(clear.begin(), clear.end(), [&](const auto& a, const auto& b) {
    return std::make_tuple(miss(a), a.positive_vertex, a.negative_vertex) <
           std::make_tuple(miss(b), b.positive_vertex, b.negative_vertex);
  });
  std::vector<char> used_vertex(nv, 0), used_seam(cut.seams.size(), 0);
  std::vector<int> targets;
  for (const ConePairCancellation& c : clear) {
    if (used_vertex[c.positive_vertex] || used_vertex[c.negative_vertex]) continue;
    if (std::any_of(c.changes.begin(), c.changes.end(), [&](const SeamChange& ch) { return used_seam[ch.seam]; }))
      continue;
    // Two new cones of one pass stay apart too.
    if (std::any_of(targets.begin(), targets.end(), [&](int t) {
          return (mesh.V.row(t) - mesh.V.row(c.negative_vertex)).norm() < crowd;
        }))
      continue;
    used_vertex[c.positive_vertex] = used_vertex[c.negative_vertex] = 1;
    // One cone of a crowded group moves per pass (the next pass sees what is left).
    for (const int q : positive)
      if ((mesh.V.row(q) - mesh.V.row(c.positive_vertex)).norm() < crowd) used_vertex[q] = 1;
    targets.push_back(c.negative_vertex);
    for (const SeamChange& ch : c.changes) used_seam[ch.seam] = 1;
    result.push_back(c);
  }
  return result;
}

namespace {

// A sector between aligned features that a path would open wider than this factor times its angle
// on the surface (a right-angled crease corner laid out flat, 2×) counts as closed: on fandisk and
// block every such pair left hundreds of flipped faces (straight creases turned by a quarter, 1.5×
// and 0.5×, pass).
constexpr double kMaxSectorOpening = 1.75;

}  // namespace

int turned_face(const CutMesh& cut, const SeamChange& change) {
  if (change.delta % 2 == 0) return -1;
  const CutSeam& s = cut.seams[change.seam];
  return (change.delta > 0 ? s.he_b : s.he_a) / 3;
}

bool path_closes_feature_sector(const core::TriMesh& mesh, const CutMesh& cut, const Eigen::VectorXd& x,
                                const ConePairCancellation& pair, const std::vector<int>& feature_row_face) {
  // The rows of the features on the path's edges after their label flips (see turned_face).
  std::unordered_map<int, int> row_face;  // edge → face, where it differs from feature_row_face
  for (const SeamChange& ch : pair.changes) {
    const CutSeam& s = cut.seams[ch.seam];
    const int turned = turned_face(cut, ch);
    if (turned >= 0 && feature_row_face[s.edge] == turned)
      row_face[s.edge] = turned == s.he_a / 3 ? s.he_b / 3 : s.he_a / 3;
  }
  auto row_of = [&](int e) {
    const auto it = row_face.find(e);
    return it == row_face.end() ? feature_row_face[e] : it->second;
  };
  // Quarter turns of map angle each vertex of the path gains at each of its path edges: raising
  // the matching of seam v0 → v1 (in face a) by one lowers v0's index (its angle grows) and
  // raises v1's.
  std::unordered_map<int, std::vector<std::pair<int, int>>> gains;  // vertex → (edge, quarters)
  for (const SeamChange& ch : pair.changes) {
    const CutSeam& s = cut.seams[ch.seam];
    const int f = s.he_a / 3, k = s.he_a % 3;
    gains[mesh.F(f, k)].push_back({s.edge, ch.delta});
    gains[mesh.F(f, (k + 1) % 3)].push_back({s.edge, -ch.delta});
  }
  for (const auto& [v, at_v] : gains) {
    // The faces round v in order from a face of a path edge: per face, its map angle at v, the
    // edge crossed after it and the quarters gained there.
    const int f0 = cut.topo.edge_halfedge[at_v.front().first] / 3;
    int k = 0;
    while (mesh.F(f0, k) != v) ++k;
    std::vector<double> angle, surface_angle;
    std::vector<int> crossed, face;
    int f = f0, steps = 0;
    do {
      if (++steps > mesh.n_faces()) return false;  // not a manifold fan
      angle.push_back(uv_corner_angle(cut, x, f, k));
      const Eigen::Vector3d q = mesh.V.row(mesh.F(f, k));
      const Eigen::Vector3d qa = Eigen::Vector3d(mesh.V.row(mesh.F(f, (k + 1) % 3))) - q;
      const Eigen::Vector3d qb = Eigen::Vector3d(mesh.V.row(mesh.F(f, (k + 2) % 3))) - q;
      surface_angle.push_back(std::atan2(qa.cross(qb).norm(), qa.dot(qb)));
      face.push_back(f);
      crossed.push_back(cut.topo.face_edge(f, (k + 2) % 3));
      const int t = cut.topo.twin[3 * f + (k + 2) % 3];
      if (t < 0) return false;  // a boundary vertex: no path runs there
      f = t / 3;
      k = t % 3;
    } while (f != f0);
    const int n = static_cast<int>(face.size());
    int start = -1;  // the position after the first feature edge crossed
    for (int i = 0; i < n && start < 0; ++i)
      if (row_of(crossed[i]) >= 0) start = (i + 1) % n;
    if (start < 0) continue;  // no feature at v: no sector
    // Sectors between consecutive features, from `start` on. A feature's row lives in one of its
    // two faces; a path edge along the feature turns the frames beyond it, so its gain counts
    // for the sector on the other side of the feature from that face.
    auto gain_at = [&](int e) {
      int gain = 0;
      for (const auto& [edge, q] : at_v)
        if (edge == e) gain += q;
      return gain;
    };
    const int first = (start + n - 1) % n;  // the first feature's position
    double sector = 0, surface_sector = 0;
    int quarters = row_of(crossed[first]) == face[first] ? gain_at(crossed[first]) : 0;
    for (int j = 0; j < n; ++j) {
      const int i = (start + j) % n;
      sector += angle[i];
      surface_sector += surface_angle[i];
      const int e = crossed[i];
      const int gain = gain_at(e);
      if (row_of(e) < 0) {
        quarters += gain;
        continue;
      }
      const bool row_before = row_of(e) == face[i];
      if (!row_before) quarters += gain;  // the sector before the feature is turned
      const double turned = sector + quarters * 0.5 * std::numbers::pi;
      if (turned < 0.25 * std::numbers::pi || (quarters > 0 && turned > kMaxSectorOpening * surface_sector))
        return true;
      sector = surface_sector = 0;
      quarters = row_before ? gain : 0;
    }
  }
  return false;
}

}  // namespace quadify::param
