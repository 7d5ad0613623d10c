// repair_mesh: polygon soup → manifold, consistently oriented triangle mesh. Steps, in order:
// triangulate, drop invalid faces, weld (hash grid), drop collapsed faces, remove zero-area
// triangles by splitting their neighbour (keeps closed surfaces closed), drop duplicate faces,
// remove fins (small flaps hanging on non-manifold edges), split non-manifold edges and vertices
// (one vertex copy per fan), orient components, drop unreferenced vertices, check with
// build_edge_topology.
#include <libcore/repair.h>

#include <libcore/predicates.h>
#include <libcore/topology.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace quadify::core {
namespace {

using Tri = std::array<int, 3>;

// The largest angle (radians) of the triangle (p, q, r).
double largest_angle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
  auto at = [](const Eigen::Vector3d& o, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const Eigen::Vector3d u = a - o, w = b - o;
    return std::atan2(u.cross(w).norm(), u.dot(w));
  };
  return std::max({at(p, q, r), at(q, r, p), at(r, p, q)});
}

struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  // The smaller root wins, so results do not depend on the union order's details.
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

struct CellKey {
  long long x, y, z;
  bool operator==(const CellKey&) const = default;
};
struct CellHash {
  size_t operator()(const CellKey& k) const {
    return static_cast<size_t>(k.x * 73856093LL ^ k.y * 19349663LL ^ k.z * 83492791LL);
  }
};

// Welds vertices within `tol` of an earlier representative (first in index order). Returns the
// representative of each vertex. O(n) expected: each vertex probes the 27 cells around it.
std::vector<int> weld_vertices(const Eigen::MatrixX3d& V, double tol) {
  const int nv = static_cast<int>(V.rows());
  std::vector<int> rep(nv);
  // Cells of size tol; exact-duplicate hashing (tol = 0) uses the coordinates' bit patterns.
  constexpr double kMaxCellIndex = 1e15;  // beyond this, cell indices lose integer precision
  const double max_abs = V.rows() ? V.cwiseAbs().maxCoeff() : 0.0;
  const bool use_grid = tol > 0 && max_abs / tol < kMaxCellIndex;
  std::unordered_map<CellKey, int, CellHash> head;  // cell → last representative inserted
  std::vector<int> next(nv, -1);                     // chain of representatives in a cell
  head.reserve(nv);
  for (int v = 0; v < nv; ++v) {
    rep[v] = v;
    CellKey key;
    if (use_grid) {
      key = {static_cast<long long>(std::floor(V(v, 0) / tol)),
             static_cast<long long>(std::floor(V(v, 1) / tol)),
             static_cast<long long>(std::floor(V(v, 2) / tol))};
      int best = -1;  // smallest representative id within tol: independent of probe order
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            auto it = head.find({key.x + dx, key.y + dy, key.z + dz});
            if (it == head.end()) continue;
            for (int r = it->second; r >= 0; r = next[r])
              if ((best < 0 || r < best) && (V.row(r) - V.row(v)).norm() <= tol) best = r;
          }
      if (best >= 0) {
        rep[v] = best;
      } else {
        auto [it, inserted] = head.try_emplace(key, v);
        if (!inserted) next[v] = it->second, it->second = v;
      }
    } else {
      // Exact duplicates: the coordinates themselves are the key (+0.0 and -0.0 are equal).
      double c[3] = {V(v, 0) + 0.0, V(v, 1) + 0.0, V(v, 2) + 0.0};
      std::memcpy(&key, c, sizeof(c));
      auto [it, inserted] = head.try_emplace(key, v);
      if (!inserted) rep[v] = it->second;
    }
  }
  return rep;
}

// Faces around each undirected edge, as a sorted (edge key, face) list: much faster than a hash
// map of vectors at 10⁵ faces, and iteration order is deterministic.
class EdgeIndex {
 public:
  explicit EdgeIndex(const std::vector<Tri>& tris) {
    entries_.reserve(3 * tris.size());
    for (int f = 0; f < static_cast<int>(tris.size()); ++f)
      for (int k = 0; k < 3; ++k) entries_.push_back({edge_key(tris[f][k], tris[f][(k + 1) % 3]), f});
    std::sort(entries_.begin(), entries_.end());
  }
  // Calls fn(key, first, last) for each edge, with [first, last) its (key, face) entries.
  template <class Fn>
  void for_each_edge(Fn fn) const {
    for (size_t i = 0; i < entries_.size();) {
      size_t j = i;
      while (j < entries_.size() && entries_[j].first == entries_[i].first) ++j;
      fn(entries_[i].first, entries_.begin() + i, entries_.begin() + j);
      i = j;
    }
  }
  // The faces of one edge, in increasing id order.
  std::vector<int> faces(long long key) const {
    std::vector<int> out;
    auto it = std::lower_bound(entries_.begin(), entries_.end(), std::make_pair(key, -1));
    for (; it != entries_.end() && it->first == key; ++it) out.push_back(it->second);
    return out;
  }
  bool max_faces_per_edge_exceeds(int n) const {
    bool exceeds = false;
    for_each_edge([&](long long, auto first, auto last) { exceeds |= last - first > n; });
    return exceeds;
  }

 private:
  std::vector<std::pair<long long, int>> entries_;
};

bool has_repeat(const Tri& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }

class Repairer {
 public:
  Repairer(const PolyMesh& input, const RepairOptions& options) : in_(input), opt_(options) {}

  RepairResult run() {
    RepairResult result;
    RepairReport& rep = result.report;
    rep.input_vertices = in_.n_vertices();
    rep.input_faces = in_.n_faces();
    V_ = in_.V;
    origin_.resize(V_.rows());
    std::iota(origin_.begin(), origin_.end(), 0);
    for (int v = 0; v < V_.rows(); ++v)
      if (!V_.row(v).allFinite()) {
        result.status = Status::invalid_input("vertex " + std::to_string(v) + " is not finite");
        return result;
      }
    triangulate(&rep);
    diag_ = bbox_diagonal(V_);
    weld(&rep);
    remove_zero_area(&rep);
    remove_duplicates(&rep);
    if (alive_count() == 0) {
      result.status = Status::invalid_input(
          "no faces left after removing " + std::to_string(rep.invalid_faces_removed) +
          " invalid, " + std::to_string(rep.degenerate_faces_removed) + " degenerate and " +
          std::to_string(rep.duplicate_faces_removed) + " duplicate faces");
      return result;
    }
    compact_faces();
    if (opt_.max_fin_faces > 0) {
      remove_fins(&rep);
      compact_faces();
    }
    if (opt_.split_nonmanifold_edges || opt_.split_nonmanifold_vertices) split_nonmanifold(&rep);
    if (opt_.orient_components) {
      Status s = orient(&rep);
      if (!s.is_ok()) {
        result.status = s;
        return result;
      }
    }
    if (opt_.orient_components) {
      flip_folds(&rep);
      // Fold flips can leave slivers folded over their new neighbours.
      remove_zero_area(&rep);
      compact_faces();
    }
    remove_unreferenced(&rep, &result);
    try {
      const EdgeTopology topo = build_edge_topology(result.mesh);
      rep.n_components = face_components(result.mesh, topo, nullptr);
      const TopologyStats stats = topology_stats(result.mesh);
      rep.n_boundary_loops = stats.n_boundary_loops;
    } catch (const std::invalid_argument& e) {
      result.status = Status::invalid_input(std::string("mesh is not usable after repair: ") + e.what());
      return result;
    }
    rep.output_vertices = result.mesh.n_vertices();
    rep.output_faces = result.mesh.n_faces();
    return result;
  }

 private:
  void triangulate(RepairReport* rep) {
    const int nv = in_.n_vertices();
    std::vector<int> poly;
    for (int f = 0; f < in_.n_faces(); ++f) {
      const int d = in_.degree(f);
      poly.clear();
      bool valid = d >= 3;
      for (int k = 0; k < d && valid; ++k) {
        const int v = in_.vertex(f, k);
        valid = v >= 0 && v < nv && std::find(poly.begin(), poly.end(), v) == poly.end();
        poly.push_back(v);
      }
      if (!valid) {
        ++rep->invalid_faces_removed;
        continue;
      }
      if (d > 3) ++rep->polygons_triangulated;
      for (int k = 1; k + 1 < d; ++k) tris_.push_back({poly[0], poly[k], poly[k + 1]});
    }
    alive_.assign(tris_.size(), 1);
  }

  void weld(RepairReport* rep) {
    const double tol = opt_.weld_tolerance * diag_;
    const std::vector<int> to = weld_vertices(V_, tol);
    for (int v = 0; v < static_cast<int>(to.size()); ++v) rep->welded_vertices += to[v] != v;
    for (size_t f = 0; f < tris_.size(); ++f) {
      for (int& v : tris_[f]) v = to[v];
      if (has_repeat(tris_[f])) {
        alive_[f] = 0;
        ++rep->degenerate_faces_removed;
      }
    }
  }

  bool is_zero_area(const Tri& t) const {
    const Eigen::Vector3d a = V_.row(t[0]), b = V_.row(t[1]), c = V_.row(t[2]);
    if (collinear3d(a, b, c)) return true;
    return 0.5 * (b - a).cross(c - a).norm() < opt_.degenerate_area_tolerance * diag_ * diag_;
  }

  double max_angle(const Tri& t) const {
    return largest_angle(V_.row(t[0]), V_.row(t[1]), V_.row(t[2]));
  }
  // A cap: an angle of at least cap_angle_deg.
  bool is_cap(const Tri& t) const {
    return opt_.cap_angle_deg < 180 && max_angle(t) >= opt_.cap_angle_deg * (std::numbers::pi / 180);
  }

  // Removes each zero-area triangle and each cap (a, m, b), m opposite its longest edge (a, b),
  // by splitting the neighbour across (a, b) at m: the neighbour's edge a-b becomes a-m-b, which
  // matches the two short edges of the removed triangle, so a closed surface stays closed.
  void remove_zero_area(RepairReport* rep) {
    std::unordered_map<long long, std::vector<int>> edge_faces;
    auto link = [&](int f) {
      for (int k = 0; k < 3; ++k) edge_faces[edge_key(tris_[f][k], tris_[f][(k + 1) % 3])].push_back(f);
    };
    auto unlink = [&](int f) {
      for (int k = 0; k < 3; ++k) {
        auto& list = edge_faces[edge_key(tris_[f][k], tris_[f][(k + 1) % 3])];
        list.erase(std::find(list.begin(), list.end(), f));
      }
    };
    // A folded sliver (see RepairOptions::folded_sliver_angle_deg): obtuse, flat (its apex within
    // kSliverHeight of its longest edge's length from that edge), and folded back over the
    // neighbours across both its short edges.
    constexpr double kSliverHeight = 0.05;
    constexpr int kSliverPasses = 4;
    const double fold_cos = std::cos(2 * std::numbers::pi / 3);  // normals more than 120° apart
    // The longest edge runs t[k] → t[k+1]: (k, its length).
    auto longest_edge = [&](const Tri& t) {
      int k_long = 0;
      double best = -1.0;
      for (int k = 0; k < 3; ++k) {
        const double len = (V_.row(t[(k + 1) % 3]) - V_.row(t[k])).squaredNorm();
        if (len > best) best = len, k_long = k;
      }
      return std::make_pair(k_long, std::sqrt(best));
    };
    auto sliver_shape = [&](const Tri& t) {
      if (!(opt_.folded_sliver_angle_deg < 180) ||
          max_angle(t) < opt_.folded_sliver_angle_deg * (std::numbers::pi / 180))
        return false;
      const double area2 = normal(t).norm(), length = longest_edge(t).second;
      return area2 > 0 && area2 / length <= kSliverHeight * length;
    };
    bool any = false;
    for (int f = 0; f < static_cast<int>(tris_.size()) && !any; ++f)
      any = alive_[f] && (is_zero_area(tris_[f]) || is_cap(tris_[f]) || sliver_shape(tris_[f]));
    if (!any) return;
    for (int f = 0; f < static_cast<int>(tris_.size()); ++f)
      if (alive_[f]) link(f);
    auto folded_sliver = [&](const Tri& t) {
      if (!sliver_shape(t)) return false;
      const Eigen::Vector3d n = normal(t);
      const int k_long = longest_edge(t).first;
      for (int k = 0; k < 3; ++k) {
        if (k == k_long) continue;
        const auto& faces = edge_faces[edge_key(t[k], t[(k + 1) % 3])];
        if (faces.size() != 2) return false;
        const Tri& u = tris_[faces[0]] == t ? tris_[faces[1]] : tris_[faces[0]];
        const Eigen::Vector3d m = normal(u);
        if (!(m.norm() > 0) || n.normalized().dot(m.normalized()) > fold_cos) return false;
      }
      return true;
    };
    auto degenerate = [&](const Tri& t) { return is_zero_area(t) || is_cap(t) || folded_sliver(t); };
    std::deque<int> queue;
    for (int f = 0; f < static_cast<int>(tris_.size()); ++f)
      if (alive_[f] && degenerate(tris_[f])) queue.push_back(f);
    if (queue.empty()) return;
    // Each split replaces one triangle by two; bound the work on pathological input.
    long long budget = 4 * static_cast<long long>(tris_.size()) + 16;
    // A removal changes the neighbours of the faces around it, which can leave a sliver folded
    // over its new neighbour: the faces are scanned again (a few passes) once the queue is empty.
    for (int pass = 0; pass < kSliverPasses && !queue.empty(); ++pass) {
      while (!queue.empty()) {
        const int f = queue.front();
        queue.pop_front();
        if (!alive_[f]) continue;
        if (!degenerate(tris_[f])) continue;
        const bool zero = is_zero_area(tris_[f]);
        const Tri t = tris_[f];
        const int k_long = longest_edge(t).first;
        const int a = t[k_long], b = t[(k_long + 1) % 3], m = t[(k_long + 2) % 3];
        const auto& across = edge_faces[edge_key(a, b)];
        // A cap is only removed by a split that keeps the surface as it is: one neighbour, whose
        // third vertex is not joined to m yet.
        int g = -1, c = -1;
        if (across.size() == 2) {
          g = across[0] == f ? across[1] : across[0];
          const Tri& u = tris_[g];
          for (int v : u)
            if (v != a && v != b) c = v;
        }
        if (!zero && (g < 0 || c == m || !edge_faces[edge_key(m, c)].empty())) continue;
        if (!zero) {
          // The two new triangles must face like the neighbour they replace.
          const Eigen::Vector3d pa = V_.row(a), pb = V_.row(b), pc = V_.row(c), pm = V_.row(m);
          const Eigen::Vector3d n = (pb - pa).cross(pc - pa);
          if (n.dot((pm - pa).cross(pc - pa)) <= 0 || n.dot((pb - pm).cross(pc - pm)) <= 0) continue;
          // Each removal lowers the largest angle where it acts, so removals cannot cycle.
          if (std::max(max_angle({a, m, c}), max_angle({m, b, c})) >= max_angle(t)) continue;
        }
        unlink(f);
        alive_[f] = 0;
        ++(zero ? rep->degenerate_faces_removed : rep->caps_removed);
        if (g < 0 || --budget < 0) continue;  // boundary or non-manifold: just drop
        const Tri u = tris_[g];
        int j = 0;
        while (!((u[j] == a && u[(j + 1) % 3] == b) || (u[j] == b && u[(j + 1) % 3] == a))) ++j;
        const int x = u[j], y = u[(j + 1) % 3];
        if (c == m) {  // the neighbour is the same triangle reversed: both vanish
          unlink(g);
          alive_[g] = 0;
          ++rep->degenerate_faces_removed;
          continue;
        }
        unlink(g);
        alive_[g] = 0;
        for (const Tri& n : {Tri{x, m, c}, Tri{m, y, c}}) {
          tris_.push_back(n);
          alive_.push_back(1);
          link(static_cast<int>(tris_.size()) - 1);
          if (degenerate(n)) queue.push_back(static_cast<int>(tris_.size()) - 1);
        }
      }
      for (int h = 0; h < static_cast<int>(tris_.size()); ++h)
        if (alive_[h] && folded_sliver(tris_[h])) queue.push_back(h);
    }
  }

  Eigen::Vector3d normal(const Tri& t) const {
    const Eigen::Vector3d a = V_.row(t[0]), b = V_.row(t[1]), c = V_.row(t[2]);
    return (b - a).cross(c - a);
  }

  // Flips the edges of folded triangle pairs (see RepairOptions::fold_angle_deg). Runs on the
  // oriented, edge-manifold triangles.
  void flip_folds(RepairReport* rep) {
    if (!(opt_.fold_angle_deg < 180)) return;
    constexpr double kPlaneTolerance = 0.02;       // relative to the edge length
    const double kAgree = std::cos(std::numbers::pi / 6);  // new pair's normals within 30°
    const double fold_cos = std::cos(opt_.fold_angle_deg * (std::numbers::pi / 180));
    std::unordered_map<long long, std::vector<int>> edge_faces;
    for (int f = 0; f < static_cast<int>(tris_.size()); ++f)
      for (int k = 0; k < 3; ++k) edge_faces[edge_key(tris_[f][k], tris_[f][(k + 1) % 3])].push_back(f);
    std::deque<long long> queue;
    for (const auto& [key, faces] : edge_faces)
      if (faces.size() == 2) queue.push_back(key);
    std::sort(queue.begin(), queue.end());  // deterministic order
    long long budget = static_cast<long long>(tris_.size()) + 16;
    auto plane_distance = [&](const Tri& t, int v) {
      const Eigen::Vector3d n = normal(t).normalized();
      return std::abs(n.dot(Eigen::Vector3d(V_.row(v)) - Eigen::Vector3d(V_.row(t[0]))));
    };
    while (!queue.empty() && budget > 0) {
      const long long key = queue.front();
      queue.pop_front();
      const auto it = edge_faces.find(key);
      if (it == edge_faces.end() || it->second.size() != 2) continue;
      const int f = it->second[0], g = it->second[1];
      const Eigen::Vector3d nf = normal(tris_[f]), ng = normal(tris_[g]);
      if (nf.norm() == 0 || ng.norm() == 0 || nf.normalized().dot(ng.normalized()) > fold_cos) continue;
      // f = (a, b, c), g = (b, a, d).
      int k = 0;
      while (edge_key(tris_[f][k], tris_[f][(k + 1) % 3]) != key) ++k;
      const int a = tris_[f][k], b = tris_[f][(k + 1) % 3], c = tris_[f][(k + 2) % 3];
      int d = -1;
      for (int j = 0; j < 3; ++j)
        if (tris_[g][j] == b && tris_[g][(j + 1) % 3] == a) d = tris_[g][(j + 2) % 3];
      if (d < 0 || d == c || edge_faces.count(edge_key(c, d))) continue;
      const double len = (V_.row(a) - V_.row(b)).norm();
      // One of them is usually a sliver with a noisy normal: its far vertex is in the other's plane.
      if (std::min(plane_distance(tris_[f], d), plane_distance(tris_[g], c)) > kPlaneTolerance * len)
        continue;
      const Tri t1{a, d, c}, t2{d, b, c};
      const Eigen::Vector3d n1 = normal(t1), n2 = normal(t2);
      if (n1.norm() == 0 || n2.norm() == 0 || n1.normalized().dot(n2.normalized()) < kAgree) continue;
      --budget;
      auto unlink = [&](int face) {
        for (int j = 0; j < 3; ++j) {
          auto& list = edge_faces[edge_key(tris_[face][j], tris_[face][(j + 1) % 3])];
          list.erase(std::find(list.begin(), list.end(), face));
        }
      };
      unlink(f);
      unlink(g);
      edge_faces.erase(key);
      tris_[f] = t1;
      tris_[g] = t2;
      for (const int face : {f, g})
        for (int j = 0; j < 3; ++j) {
          const long long e = edge_key(tris_[face][j], tris_[face][(j + 1) % 3]);
          edge_faces[e].push_back(face);
          queue.push_back(e);
        }
      ++rep->folds_flipped;
    }
  }

  void remove_duplicates(RepairReport* rep) {
    std::vector<std::pair<Tri, int>> sorted;  // (sorted vertex ids, face)
    for (int f = 0; f < static_cast<int>(tris_.size()); ++f) {
      if (!alive_[f]) continue;
      Tri t = tris_[f];
      std::sort(t.begin(), t.end());
      sorted.push_back({t, f});
    }
    std::sort(sorted.begin(), sorted.end());
    for (size_t i = 1; i < sorted.size(); ++i)
      if (sorted[i].first == sorted[i - 1].first) {  // keep the lowest face id of each set
        alive_[sorted[i].second] = 0;
        ++rep->duplicate_faces_removed;
      }
  }

  int alive_count() const { return static_cast<int>(std::count(alive_.begin(), alive_.end(), 1)); }

  void compact_faces() {
    std::vector<Tri> kept;
    kept.reserve(tris_.size());
    for (size_t f = 0; f < tris_.size(); ++f)
      if (alive_[f]) kept.push_back(tris_[f]);
    tris_ = std::move(kept);
    alive_.assign(tris_.size(), 1);
  }

  int add_vertex_copy(int v) {
    const int id = static_cast<int>(V_.rows());
    V_.conservativeResize(id + 1, 3);
    V_.row(id) = V_.row(v);
    origin_.push_back(origin_[v]);
    return id;
  }

  // Fins: a small patch of faces (connected through edges with exactly two faces) that hangs on
  // edges with more than two faces and has a free boundary, such that without it each of those
  // edges keeps exactly two faces (a scan's flap glued to a crease, a stray triangle across a
  // corner). Removed: detaching it instead would leave a slit in the surface or a loose flap.
  void remove_fins(RepairReport* rep) {
    const int nf = static_cast<int>(tris_.size());
    const EdgeIndex edges(tris_);
    DisjointSets patch(nf);
    edges.for_each_edge([&](long long, auto first, auto last) {
      if (last - first == 2) patch.unite(first->second, (first + 1)->second);
    });
    std::vector<int> size(nf, 0);
    std::vector<char> free_edge(nf, 0), on_nonmanifold(nf, 0);
    for (int f = 0; f < nf; ++f) ++size[patch.find(f)];
    edges.for_each_edge([&](long long, auto first, auto last) {
      for (auto it = first; it != last; ++it) {
        const int root = patch.find(it->second);
        if (last - first == 1) free_edge[root] = 1;
        if (last - first > 2) on_nonmanifold[root] = 1;
      }
    });
    std::vector<char> candidate(nf, 0);
    for (int f = 0; f < nf; ++f) {
      const int root = patch.find(f);
      candidate[f] = root == f && free_edge[root] && on_nonmanifold[root] &&
                     size[root] <= opt_.max_fin_faces && 2 * size[root] < nf;
    }
    // Each non-manifold edge must keep exactly two faces: a patch is removed only if every such
    // edge it touches has exactly two faces outside the removed patches, and no other fin on it.
    for (bool changed = true; changed;) {
      changed = false;
      std::vector<char> keep(nf, 0);
      edges.for_each_edge([&](long long, auto first, auto last) {
        if (last - first <= 2) return;
        std::vector<int> fins;
        int outside = 0;
        for (auto it = first; it != last; ++it) {
          const int root = patch.find(it->second);
          if (!candidate[root]) {
            ++outside;
          } else if (std::find(fins.begin(), fins.end(), root) == fins.end()) {
            fins.push_back(root);
          }
        }
        if (outside != 2 || fins.size() > 1)
          for (const int r : fins) keep[r] = 1;
      });
      for (int f = 0; f < nf; ++f)
        if (keep[f] && candidate[f]) {
          candidate[f] = 0;
          changed = true;
        }
    }
    for (int f = 0; f < nf; ++f)
      if (candidate[patch.find(f)]) {
        alive_[f] = 0;
        ++rep->fin_faces_removed;
      }
  }

  // Faces of a non-manifold edge beyond one pair are cut off the edge; then every vertex gets one
  // copy per fan (faces around it connected through uncut edges). A second round gives cut faces
  // private corners on edges still shared by more than two faces (fans joined elsewhere).
  void split_nonmanifold(RepairReport* rep) {
    const int nf = static_cast<int>(tris_.size());
    for (int round = 0; round < 2; ++round) {
      const EdgeIndex edges(tris_);
      DisjointSets corners(3 * nf);
      std::vector<char> on_cut_edge(V_.rows(), 0);  // endpoints of edges with > 2 faces
      edges.for_each_edge([&](long long key, auto first, auto last) {
        const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffff);
        const long long n = last - first;
        int f0 = first->second, f1 = -1;
        if (n > 2) {
          if (!opt_.split_nonmanifold_edges) return;
          if (round == 0) ++rep->nonmanifold_edges_split;
          on_cut_edge[a] = on_cut_edge[b] = 1;
          // Keep the first face and the first face traversing the edge the other way.
          const bool f0_ab = runs(tris_[f0], a, b);
          for (auto it = first + 1; it != last && f1 < 0; ++it)
            if (runs(tris_[it->second], a, b) != f0_ab) f1 = it->second;
          if (f1 < 0) f1 = (first + 1)->second;
          if (round == 1)  // fans joined elsewhere: give the extra faces private corners
            for (auto it = first; it != last; ++it)
              if (it->second != f0 && it->second != f1)
                for (int& v : tris_[it->second])
                  if (v == a || v == b) v = add_vertex_copy(v);
        } else if (n == 2) {
          f1 = (first + 1)->second;
        }
        if (f1 < 0 || round == 1) return;
        for (int v : {a, b})
          corners.unite(3 * f0 + corner_of(tris_[f0], v), 3 * f1 + corner_of(tris_[f1], v));
      });
      if (round == 1) {
        // Corners changed: recompute the fans from the edges that now have exactly two faces.
        const EdgeIndex after(tris_);
        after.for_each_edge([&](long long key, auto first, auto last) {
          if (last - first != 2) return;
          const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffff);
          const int f0 = first->second, f1 = (first + 1)->second;
          for (int v : {a, b})
            corners.unite(3 * f0 + corner_of(tris_[f0], v), 3 * f1 + corner_of(tris_[f1], v));
        });
      }
      // One vertex copy per extra fan, in corner order (deterministic).
      std::vector<int> first_root(V_.rows(), -1);  // vertex → root of the fan keeping the id
      std::unordered_map<long long, int> copy_of;   // (vertex, root) → new vertex id
      std::vector<char> counted(V_.rows(), 0);
      for (int c = 0; c < 3 * nf; ++c) {
        const int v = tris_[c / 3][c % 3];
        const int root = corners.find(c);
        if (v < static_cast<int>(first_root.size())) {
          if (first_root[v] < 0) first_root[v] = root;
          if (first_root[v] == root) continue;
        } else {
          continue;  // a private corner made in this round
        }
        const long long key = (static_cast<long long>(v) << 32) | static_cast<unsigned>(root);
        auto [it, new_copy] = copy_of.try_emplace(key, -1);
        if (new_copy) {
          it->second = add_vertex_copy(v);
          // Copies at the ends of cut edges are part of the edge split, not vertex splits.
          if (round == 0 && !counted[v] && !on_cut_edge[v]) {
            counted[v] = 1;
            ++rep->nonmanifold_vertices_split;
          }
        }
        tris_[c / 3][c % 3] = it->second;
      }
      if (!EdgeIndex(tris_).max_faces_per_edge_exceeds(2)) break;
    }
  }

  static bool runs(const Tri& t, int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (t[k] == a && t[(k + 1) % 3] == b) return true;
    return false;
  }
  static int corner_of(const Tri& t, int v) { return t[0] == v ? 0 : (t[1] == v ? 1 : 2); }

  // Makes every component consistently oriented (BFS over manifold edges), each keeping the
  // orientation of the majority of its faces, then outward for closed components with volume.
  Status orient(RepairReport* rep) {
    const int nf = static_cast<int>(tris_.size());
    const EdgeIndex edges(tris_);
    std::vector<int> flip(nf, -1);  // -1 unvisited, 0 keep, 1 flip
    int component = 0;
    for (int seed = 0; seed < nf; ++seed) {
      if (flip[seed] >= 0) continue;
      std::vector<int> members{seed};
      flip[seed] = 0;
      bool closed = true;
      for (size_t i = 0; i < members.size(); ++i) {
        const int f = members[i];
        for (int k = 0; k < 3; ++k) {
          const int a = tris_[f][k], b = tris_[f][(k + 1) % 3];
          const std::vector<int> faces = edges.faces(edge_key(a, b));
          if (faces.size() != 2) {
            closed = false;
            continue;
          }
          const int g = faces[0] == f ? faces[1] : faces[0];
          // f traverses a→b (after its own flip); g must traverse b→a after its flip.
          const bool f_ab = (flip[f] == 0);
          const bool g_ab = runs(tris_[g], a, b);
          const int want = (g_ab == f_ab) ? 1 : 0;
          if (flip[g] < 0) {
            flip[g] = want;
            members.push_back(g);
          } else if (flip[g] != want) {
            return Status::invalid_input("component " + std::to_string(component) + " (containing face " +
                                         std::to_string(seed) + ") is not orientable");
          }
        }
      }
      long long n_flip = 0;
      for (int f : members) n_flip += flip[f];
      bool invert = 2 * n_flip > static_cast<long long>(members.size());
      if (closed) {
        double volume = 0.0;
        for (int f : members) {
          Tri t = tris_[f];
          if (flip[f] != invert) std::swap(t[1], t[2]);
          volume += Eigen::Vector3d(V_.row(t[0])).dot(Eigen::Vector3d(V_.row(t[1])).cross(Eigen::Vector3d(V_.row(t[2]))));
        }
        // Below this (relative to diag³) a closed component encloses no volume worth trusting.
        constexpr double kVolumeTolerance = 1e-12;
        if (volume < -kVolumeTolerance * diag_ * diag_ * diag_) invert = !invert;
      }
      for (int f : members)
        if (flip[f] != static_cast<int>(invert)) {
          std::swap(tris_[f][1], tris_[f][2]);
          ++rep->faces_reoriented;
        }
      ++component;
    }
    return Status::ok();
  }

  void remove_unreferenced(RepairReport* rep, RepairResult* result) {
    std::vector<int> new_id(V_.rows(), -1);
    int n = 0;
    for (const Tri& t : tris_)
      for (int v : t)
        if (new_id[v] < 0) new_id[v] = n++;
    // Keep the input order of vertices (new_id by first use would reorder): renumber by id.
    n = 0;
    for (int v = 0; v < V_.rows(); ++v)
      if (new_id[v] >= 0) new_id[v] = n++;
    // Copies made for splits are not "unreferenced input vertices"; count only input ids.
    for (int v = 0; v < in_.n_vertices(); ++v) rep->unreferenced_vertices_removed += new_id[v] < 0;
    rep->unreferenced_vertices_removed -= rep->welded_vertices;
    result->mesh.V.resize(n, 3);
    result->vertex_origin.resize(n);
    for (int v = 0; v < V_.rows(); ++v)
      if (new_id[v] >= 0) {
        result->mesh.V.row(new_id[v]) = V_.row(v);
        result->vertex_origin[new_id[v]] = origin_[v];
      }
    result->mesh.F.resize(static_cast<int>(tris_.size()), 3);
    for (int f = 0; f < static_cast<int>(tris_.size()); ++f)
      for (int k = 0; k < 3; ++k) result->mesh.F(f, k) = new_id[tris_[f][k]];
  }

  const PolyMesh& in_;
  const RepairOptions& opt_;
  Eigen::MatrixX3d V_;
  std::vector<int> origin_;
  std::vector<Tri> tris_;
  std::vector<char> alive_;
  double diag_ = 0.0;
};

}  // namespace

bool RepairReport::changed() const {
  return polygons_triangulated || invalid_faces_removed || welded_vertices ||
         degenerate_faces_removed || caps_removed || folds_flipped || fin_faces_removed || duplicate_faces_removed ||
         unreferenced_vertices_removed || faces_reoriented || nonmanifold_edges_split || nonmanifold_vertices_split;
}

RepairResult repair_mesh(const PolyMesh& input, const RepairOptions& options) {
  return Repairer(input, options).run();
}

int flip_feature_wedges(TriMesh* mesh, const std::vector<std::array<int, 2>>& feature_edges,
                        double min_angle_deg) {
  constexpr double kFlatTolerance = 0.01;  // of the long edge's length
  std::unordered_set<long long> feature;
  for (const auto& e : feature_edges) feature.insert(edge_key(e[0], e[1]));
  TriMesh& m = *mesh;
  const int nf = m.n_faces();
  std::unordered_map<long long, std::vector<int>> edge_faces;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) edge_faces[edge_key(m.F(f, k), m.F(f, (k + 1) % 3))].push_back(f);
  auto point = [&](int v) { return Eigen::Vector3d(m.V.row(v)); };
  auto angle_at = [&](int p, int q, int r) {  // at p, in triangle (p, q, r)
    const Eigen::Vector3d u = point(q) - point(p), w = point(r) - point(p);
    return std::atan2(u.cross(w).norm(), u.dot(w));
  };
  auto max_angle = [&](int p, int q, int r) { return largest_angle(point(p), point(q), point(r)); };
  const double min_angle = min_angle_deg * (std::numbers::pi / 180);
  std::vector<char> touched(nf, 0);
  int n_flipped = 0;
  for (int f = 0; f < nf; ++f) {
    if (touched[f]) continue;
    for (int k = 0; k < 3; ++k) {
      // f = (a, b, w) with the wide angle at w, between the features w-a and b-w.
      const int a = m.F(f, (k + 1) % 3), b = m.F(f, (k + 2) % 3), w = m.F(f, k);
      if (angle_at(w, a, b) < min_angle || !feature.count(edge_key(w, a)) ||
          !feature.count(edge_key(b, w)) || feature.count(edge_key(a, b)))
        continue;
      const auto it = edge_faces.find(edge_key(a, b));
      if (it == edge_faces.end() || it->second.size() != 2) continue;
      const int g = it->second[0] == f ? it->second[1] : it->second[0];
      if (touched[g]) continue;
      int c = -1;
      for (int j = 0; j < 3; ++j)
        if (m.F(g, j) == b && m.F(g, (j + 1) % 3) == a) c = m.F(g, (j + 2) % 3);
      if (c < 0 || c == w || edge_faces.count(edge_key(w, c))) continue;
      // (b, a, c) flat with w, the new triangles (a, c, w), (c, b, w) facing like it, and smaller
      // angles than the wedge's.
      const Eigen::Vector3d n = (point(a) - point(b)).cross(point(c) - point(b));
      if (std::abs(n.normalized().dot(point(w) - point(a))) > kFlatTolerance * (point(b) - point(a)).norm())
        continue;
      const Eigen::Vector3d n1 = (point(c) - point(a)).cross(point(w) - point(a));
      const Eigen::Vector3d n2 = (point(b) - point(c)).cross(point(w) - point(c));
      if (n.dot(n1) <= 0 || n.dot(n2) <= 0) continue;
      if (std::max(max_angle(a, c, w), max_angle(c, b, w)) >= angle_at(w, a, b)) continue;
      m.F.row(f) << a, c, w;
      m.F.row(g) << c, b, w;
      touched[f] = touched[g] = 1;
      // Edge a-b goes, w-c comes; a-c moves from g to f and b-w from f to g.
      edge_faces.erase(edge_key(a, b));
      edge_faces[edge_key(w, c)] = {f, g};
      for (int& h : edge_faces[edge_key(a, c)]) h = h == g ? f : h;
      for (int& h : edge_faces[edge_key(b, w)]) h = h == f ? g : h;
      ++n_flipped;
      break;
    }
  }
  return n_flipped;
}

}  // namespace quadify::core
