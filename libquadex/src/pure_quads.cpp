#include <libquadex/pure_quads.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <unordered_map>
#include <vector>

namespace quadify::quadex {
namespace {

// Polygons up to this degree are split along diagonals by the exhaustive dynamic program (O(n⁴));
// larger ones (none seen: a pentagon gets one or two midpoints) only around their centroid.
constexpr int kMaxDiagonalDegree = 16;
// A vertex of a face that no other face has, between two boundary edges, where the boundary
// turns by at most this (degrees), is removed from a face of more than 4 corners: the extraction
// puts a vertex wherever a grid line crosses the boundary, so a polygon cut by a straight stretch
// of boundary has extra, nearly flat corners on it. Removing one moves the boundary by at most
// sin(turn/2) of the shorter edge beside it (0.13 at 15°).
constexpr double kMaxRemovedTurn = 15;
// A midpoint whose worst quad corner is below kFlatCorner (scaled Jacobian) moves by
// kFlatMidpointShift of the way to the mean of its spokes (see split_faces): a triangle's quad
// with its midpoint halfway between the edge and a spoke one edge long gets a corner of about
// 140° (scaled Jacobian 0.6).
constexpr double kFlatCorner = 0.05;
// Edges of a face that is not a quad shorter than this fraction of the mean edge length, with an
// end on the boundary, are collapsed first (see collapse_short_boundary_edges).
constexpr double kShortEdge = 0.25;
// Splits whose worst corners differ by less than this are equally good (the longer edge is split).
constexpr double kQualityTie = 0.05;
constexpr double kFlatMidpointShift = 0.3;

// Worst corner scaled Jacobian of the quad (a, b, c, d) against its own area vector (the cross
// product of its diagonals): 1 for a rectangle, 0 for a flat corner, negative for a reflex one.
double quad_quality(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d) {
  const Eigen::Vector3d n = (c - a).cross(d - b);
  const double nn = n.norm();
  if (!(nn > 0)) return -1;
  const std::array<const Eigen::Vector3d*, 4> p = {&a, &b, &c, &d};
  double worst = 1;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d e1 = *p[(k + 1) % 4] - *p[k], e2 = *p[(k + 3) % 4] - *p[k];
    const double l = e1.norm() * e2.norm();
    worst = std::min(worst, l > 0 ? e1.cross(e2).dot(n) / (nn * l) : -1.0);
  }
  return worst;
}

// A split of an even polygon into quads: corner lists into the polygon (kCenter: its centroid).
constexpr int kCenter = -1;
struct PolygonSplit {
  std::vector<std::array<int, 4>> quads;
  double quality = -std::numeric_limits<double>::infinity();
};

// The best split along diagonals (largest worst corner), by dynamic programming over the
// sub-polygons i..j (j - i odd; the closing edge j-i lies in the quad (i, a, b, j)).
PolygonSplit split_along_diagonals(const std::vector<Eigen::Vector3d>& x) {
  const int n = static_cast<int>(x.size());
  PolygonSplit out;
  if (n > kMaxDiagonalDegree) return out;
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  std::vector<double> best(n * n, kNone);
  std::vector<std::array<int, 2>> arg(n * n, {-1, -1});
  for (int len = 1; len < n; len += 2)
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      if (len == 1) {
        best[i * n + j] = std::numeric_limits<double>::infinity();
        continue;
      }
      for (int a = i + 1; a < j; a += 2)
        for (int b = a + 1; b < j; b += 2) {
          const double q = std::min({quad_quality(x[i], x[a], x[b], x[j]), best[i * n + a], best[a * n + b],
                                     best[b * n + j]});
          if (q > best[i * n + j]) {
            best[i * n + j] = q;
            arg[i * n + j] = {a, b};
          }
        }
    }
  out.quality = best[n - 1];
  std::vector<std::array<int, 2>> stack = {{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i == 1) continue;
    const auto [a, b] = arg[i * n + j];
    out.quads.push_back({i, a, b, j});
    stack.push_back({i, a});
    stack.push_back({a, b});
    stack.push_back({b, j});
  }
  return out;
}

// The split around the centroid c with spokes at the corners of parity `parity`:
// (c, x[p], x[p+1], x[p+2]) for p = parity, parity + 2, ...
PolygonSplit split_around_center(const std::vector<Eigen::Vector3d>& x, int parity) {
  const int n = static_cast<int>(x.size());
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : x) c += p;
  c /= n;
  PolygonSplit out;
  out.quality = std::numeric_limits<double>::infinity();
  for (int p = parity; p < n + parity; p += 2) {
    const int a = p % n, b = (p + 1) % n, d = (p + 2) % n;
    out.quads.push_back({kCenter, a, b, d});
    out.quality = std::min(out.quality, quad_quality(c, x[a], x[b], x[d]));
  }
  return out;
}

std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
}


// Collapses the short edges of the faces that are not quads where they meet the boundary (see
// kShortEdge): the extraction leaves a sliver where the boundary passes a grid point closely (a
// triangle of edges a fifth of a quad's beside a grid vertex). The boundary vertex keeps its
// position (the other vertex moves onto it); a collapse that would leave an edge of more than two
// faces or a face with a repeated vertex other than the one it removes is not made. Faces become
// proper or go (those that had the edge and fewer than 3 vertices left); vertex ids are kept.
core::PolyMesh collapse_short_boundary_edges(const core::PolyMesh& mesh, std::vector<char>* proper, int* n_collapsed) {
  const int nf = mesh.n_faces();
  const bool uv = mesh.has_uv();
  std::vector<std::vector<int>> faces(nf), faces_uv(nf);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < mesh.degree(f); ++k) {
      faces[f].push_back(mesh.vertex(f, k));
      if (uv) faces_uv[f].push_back(mesh.face_uv[mesh.face_corner(f, k)]);
    }
  const Eigen::MatrixX3d& V = mesh.V;
  auto edge_counts = [&] {
    std::unordered_map<std::uint64_t, int> n;
    for (int f = 0; f < nf; ++f)
      for (size_t k = 0; k < faces[f].size(); ++k) ++n[edge_key(faces[f][k], faces[f][(k + 1) % faces[f].size()])];
    return n;
  };
  double mean = 0;
  int n_edges = 0;
  for (const auto& face : faces)
    for (size_t k = 0; k < face.size(); ++k) {
      mean += (V.row(face[k]) - V.row(face[(k + 1) % face.size()])).norm();
      ++n_edges;
    }
  mean /= std::max(n_edges, 1);
  // Candidates: (length, a, b) of short edges of proper non-quads with a boundary end.
  std::unordered_map<std::uint64_t, int> count = edge_counts();
  std::vector<char> on_boundary(V.rows(), 0);
  for (int f = 0; f < nf; ++f)
    for (size_t k = 0; k < faces[f].size(); ++k) {
      const int a = faces[f][k], b = faces[f][(k + 1) % faces[f].size()];
      if (count[edge_key(a, b)] == 1) on_boundary[a] = on_boundary[b] = 1;
    }
  std::vector<std::tuple<double, int, int>> candidates;
  for (int f = 0; f < nf; ++f) {
    if (!(*proper)[f] || faces[f].size() == 4) continue;
    for (size_t k = 0; k < faces[f].size(); ++k) {
      const int a = faces[f][k], b = faces[f][(k + 1) % faces[f].size()];
      const double l = (V.row(a) - V.row(b)).norm();
      if (l < kShortEdge * mean && (on_boundary[a] || on_boundary[b])) candidates.emplace_back(l, std::min(a, b), std::max(a, b));
    }
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  std::vector<int> gone(V.rows(), 0);
  for (const auto& [l, a0, b0] : candidates) {
    if (gone[a0] || gone[b0]) continue;
    // Keep the boundary end (a), remove b; both on the boundary: only along a boundary edge.
    int a = a0, b = b0;
    if (!on_boundary[a] && on_boundary[b]) std::swap(a, b);
    if (on_boundary[a] && on_boundary[b] && count[edge_key(a, b)] != 1) continue;
    std::vector<std::vector<int>> new_faces = faces, new_uv = faces_uv;
    std::vector<char> new_proper = *proper;
    bool ok = true;
    for (int f = 0; f < nf && ok; ++f) {
      std::vector<int>& face = new_faces[f];
      if (std::find(face.begin(), face.end(), b) == face.end()) continue;
      const bool had_edge = std::find(face.begin(), face.end(), a) != face.end();
      if (had_edge && !new_proper[f]) ok = false;
      std::vector<int> kept, kept_uv;
      for (size_t k = 0; k < face.size(); ++k) {
        const int v = face[k] == b ? a : face[k];
        const int next = face[(k + 1) % face.size()] == b ? a : face[(k + 1) % face.size()];
        if (v == next) continue;  // the collapsed edge
        kept.push_back(v);
        if (uv) kept_uv.push_back(new_uv[f][k]);
      }
      std::vector<int> sorted = kept;
      std::sort(sorted.begin(), sorted.end());
      if (std::unique(sorted.begin(), sorted.end()) != sorted.end()) ok = false;
      if (kept.size() < 3) {
        if (!had_edge) ok = false;
        kept.clear();
        kept_uv.clear();
        new_proper[f] = 0;
      }
      face = std::move(kept);
      if (uv) new_uv[f] = std::move(kept_uv);
    }
    if (!ok) continue;
    std::swap(faces, new_faces);
    const std::unordered_map<std::uint64_t, int> new_count = edge_counts();
    bool manifold = true;
    for (const auto& [e, n] : new_count) manifold = manifold && n <= 2;
    if (!manifold) {
      std::swap(faces, new_faces);
      continue;
    }
    faces_uv = std::move(new_uv);
    *proper = std::move(new_proper);
    count = new_count;
    gone[b] = 1;  // a, on the boundary, keeps its position; b's faces now have a
    ++*n_collapsed;
  }
  core::PolyMesh out;
  out.V = mesh.V;
  out.uv = mesh.uv;
  out.lines = mesh.lines;
  std::vector<char> kept_proper;
  for (int f = 0; f < nf; ++f) {
    if (faces[f].empty()) continue;
    out.add_face(faces[f], faces_uv[f]);
    kept_proper.push_back((*proper)[f]);
  }
  *proper = std::move(kept_proper);
  return out;
}

// Turn (degrees) at b of the polyline a, b, c: 0 when straight.
double turn_degrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d u = b - a, w = c - b;
  const double l = u.norm() * w.norm();
  if (!(l > 0)) return 180;
  return std::acos(std::clamp(u.dot(w) / l, -1.0, 1.0)) * 180 / 3.14159265358979323846;
}

// The faces of `mesh` without their removable boundary vertices (see kMaxRemovedTurn): in a proper
// face of degree above 4, flattest first, while it has more than 4 corners; the last removal is
// undone when the count r of removals leaves an odd degree (an even polygon splits along a
// diagonal). Vertices keep their ids (the removed ones become unreferenced).
core::PolyMesh remove_flat_boundary_vertices(const core::PolyMesh& mesh, const std::vector<char>& proper,
                                             int* n_removed) {
  const int nf = mesh.n_faces();
  std::vector<int> n_faces_of(mesh.n_vertices(), 0);
  std::unordered_map<std::uint64_t, int> n_edge_faces;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < mesh.degree(f); ++k) {
      ++n_faces_of[mesh.vertex(f, k)];
      ++n_edge_faces[edge_key(mesh.vertex(f, k), mesh.vertex(f, (k + 1) % mesh.degree(f)))];
    }
  auto edge_count = [&](int a, int b) {
    const auto it = n_edge_faces.find(edge_key(a, b));
    return it == n_edge_faces.end() ? 0 : it->second;
  };
  core::PolyMesh out;
  out.V = mesh.V;
  out.uv = mesh.uv;
  out.lines = mesh.lines;
  const bool uv = mesh.has_uv();
  for (int f = 0; f < nf; ++f) {
    const int d = mesh.degree(f);
    std::vector<int> poly, poly_uv;
    for (int k = 0; k < d; ++k) {
      poly.push_back(mesh.vertex(f, k));
      if (uv) poly_uv.push_back(mesh.face_uv[mesh.face_corner(f, k)]);
    }
    if (proper[f] && d > 4) {
      // Greedy: the flattest removable vertex of the current polygon, while above 4 corners.
      std::vector<std::vector<int>> states = {poly}, uv_states = {poly_uv};
      while (static_cast<int>(poly.size()) > 4) {
        const int n = static_cast<int>(poly.size());
        int best = -1;
        double best_turn = kMaxRemovedTurn;
        for (int k = 0; k < n; ++k) {
          const int a = poly[(k + n - 1) % n], v = poly[k], b = poly[(k + 1) % n];
          if (n_faces_of[v] != 1 || edge_count(a, v) != 1 || edge_count(v, b) != 1 || edge_count(a, b) != 0) continue;
          const double t = turn_degrees(mesh.V.row(a).transpose(), mesh.V.row(v).transpose(), mesh.V.row(b).transpose());
          if (t <= best_turn) {
            best_turn = t;
            best = k;
          }
        }
        if (best < 0) break;
        const int a = poly[(best + n - 1) % n], v = poly[best], b = poly[(best + 1) % n];
        n_edge_faces[edge_key(a, v)] = 0;
        n_edge_faces[edge_key(v, b)] = 0;
        n_edge_faces[edge_key(a, b)] = 1;
        n_faces_of[v] = 0;
        poly.erase(poly.begin() + best);
        if (uv) poly_uv.erase(poly_uv.begin() + best);
        states.push_back(poly);
        uv_states.push_back(poly_uv);
      }
      // An odd result keeps the last removed vertex.
      int r = static_cast<int>(states.size()) - 1;
      if (r > 0 && (d - r) % 2 == 1) {
        const std::vector<int>& prev = states[r - 1];
        const int n = static_cast<int>(prev.size());
        for (int k = 0; k < n; ++k)
          if (std::find(poly.begin(), poly.end(), prev[k]) == poly.end()) {
            const int a = prev[(k + n - 1) % n], v = prev[k], b = prev[(k + 1) % n];
            n_edge_faces[edge_key(a, b)] = 0;
            n_edge_faces[edge_key(a, v)] = n_edge_faces[edge_key(v, b)] = 1;
            n_faces_of[v] = 1;
          }
        --r;
        poly = states[r];
        poly_uv = uv_states[r];
      }
      *n_removed += r;
    }
    out.add_face(poly, poly_uv);
  }
  return out;
}

// Splits the faces of `mesh` (proper: the faces that take part) into quads; see make_pure_quads.
void split_faces(const core::PolyMesh& mesh, const std::vector<char>& proper, const PureQuadOptions& options,
                 PureQuadResult* result) {
  PureQuadResult& res = *result;
  const int nf = mesh.n_faces(), nv = mesh.n_vertices();
  const bool uv = mesh.has_uv();
  // Edges: their faces (face, corner of the edge's first vertex in that face).
  std::unordered_map<std::uint64_t, int> edge_id;
  std::vector<std::array<int, 2>> edge_vertices;
  std::vector<std::vector<std::array<int, 2>>> edge_faces;
  std::vector<int> corner_edge(mesh.face_vertex.size(), -1);
  for (int f = 0; f < nf; ++f) {
    if (!proper[f]) continue;
    const int d = mesh.degree(f);
    for (int k = 0; k < d; ++k) {
      const int a = mesh.vertex(f, k), b = mesh.vertex(f, (k + 1) % d);
      const auto [it, inserted] = edge_id.try_emplace(edge_key(a, b), static_cast<int>(edge_vertices.size()));
      if (inserted) {
        edge_vertices.push_back({std::min(a, b), std::max(a, b)});
        edge_faces.emplace_back();
      }
      edge_faces[it->second].push_back({f, k});
      corner_edge[mesh.face_corner(f, k)] = it->second;
    }
  }
  const int ne = static_cast<int>(edge_vertices.size());
  // Edges of the faces left alone (no midpoint there: it would hang on their side).
  std::vector<char> blocked(ne, 0);
  for (int f = 0; f < nf; ++f) {
    if (proper[f]) continue;
    for (int k = 0; k < mesh.degree(f); ++k) {
      const auto it = edge_id.find(edge_key(mesh.vertex(f, k), mesh.vertex(f, (k + 1) % mesh.degree(f))));
      if (it != edge_id.end()) blocked[it->second] = 1;
    }
  }
  auto is_boundary = [&](int e) { return edge_faces[e].size() == 1 && !blocked[e]; };
  auto crossable = [&](int e) { return edge_faces[e].size() == 2 && !blocked[e]; };
  auto edge_length = [&](int e) { return (mesh.V.row(edge_vertices[e][0]) - mesh.V.row(edge_vertices[e][1])).norm(); };
  // The face's longest boundary edge (-1: none).
  auto longest_boundary_edge = [&](int f) {
    int best = -1;
    for (int k = 0; k < mesh.degree(f); ++k) {
      const int e = corner_edge[mesh.face_corner(f, k)];
      if (is_boundary(e) && (best < 0 || edge_length(e) > edge_length(best))) best = e;
    }
    return best;
  };

  // Parity: midpoints per edge, so that every proper face ends with an even degree.
  std::vector<int> n_mid(ne, 0);
  std::vector<char> odd(nf, 0);
  for (int f = 0; f < nf; ++f) odd[f] = proper[f] && mesh.degree(f) % 2 == 1;
  // Face f's corner positions with the midpoints of its edges (n_mid, one more on each of
  // `extra` and `path_edge`).
  auto polygon_positions = [&](int f, int extra, int path_edge) {
    std::vector<Eigen::Vector3d> x;
    const int d = mesh.degree(f);
    for (int k = 0; k < d; ++k) {
      const int a = mesh.vertex(f, k), b = mesh.vertex(f, (k + 1) % d);
      const Eigen::Vector3d pa = mesh.V.row(a).transpose(), pb = mesh.V.row(b).transpose();
      x.push_back(pa);
      const int e = corner_edge[mesh.face_corner(f, k)];
      const int m = n_mid[e] + (e == extra) + (e == path_edge);
      for (int i = 1; i <= m; ++i) x.push_back(pa + (pb - pa) * (static_cast<double>(i) / (m + 1)));
    }
    return x;
  };
  // The boundary edge of f whose midpoint gives the best split (worst corner; with a path's
  // midpoint on path_edge too), the longer on ties, and that split's worst corner (edge -1: none).
  // An edge that has a midpoint already only where no other is free (a second one is a flat
  // corner of some quad).
  auto best_boundary_edge = [&](int f, int path_edge) {
    int best = -1;
    double best_quality = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < mesh.degree(f); ++k) {
      const int e = corner_edge[mesh.face_corner(f, k)];
      if (!is_boundary(e)) continue;
      if (n_mid[e] > 0 && best >= 0 && n_mid[best] == 0) continue;
      const std::vector<Eigen::Vector3d> x = polygon_positions(f, e, path_edge);
      if (x.size() % 2 == 1) continue;
      double q = split_along_diagonals(x).quality;
      for (const int parity : {0, 1}) q = std::max(q, split_around_center(x, parity).quality);
      if (best < 0 || (n_mid[best] > 0 && n_mid[e] == 0) || q > best_quality + kQualityTie ||
          (q > best_quality - kQualityTie && edge_length(e) > edge_length(best))) {
        best_quality = best < 0 || q > best_quality ? q : best_quality;
        best = e;
      }
    }
    return std::pair(best, best_quality);
  };
  // Merges of two odd faces across an edge (see below): the edge is then neither crossed nor split.
  std::vector<int> merged_with(nf, -1);
  std::vector<char> merged_edge(ne, 0);
  // Faces f and g sharing only the edge e, with no other vertex in common (the merged polygon is
  // simple), neither merged already.
  auto can_merge = [&](int f, int g, int e) {
    if (n_mid[e] > 0) return false;
    int n_common = 0;
    for (int i = 0; i < mesh.degree(f); ++i)
      for (int j = 0; j < mesh.degree(g); ++j) n_common += mesh.vertex(f, i) == mesh.vertex(g, j);
    return n_common == 2;
  };
  // Odd faces side by side merge first (their shared edge goes): an even polygon, no new vertex.
  for (int f = 0; f < nf; ++f) {
    if (!odd[f] || merged_with[f] >= 0) continue;
    for (int k = 0; k < mesh.degree(f); ++k) {
      const int e = corner_edge[mesh.face_corner(f, k)];
      if (!crossable(e)) continue;
      const int g = edge_faces[e][0][0] == f ? edge_faces[e][1][0] : edge_faces[e][0][0];
      if (g == f || !odd[g] || merged_with[g] >= 0 || !can_merge(f, g, e)) continue;
      merged_with[f] = g;
      merged_with[g] = f;
      merged_edge[e] = 1;
      odd[f] = odd[g] = 0;
      ++res.stats.n_merged;
      break;
    }
  }
  // An odd face of degree 5 or more on the boundary: a midpoint on the boundary edge that gives
  // the best split (the hexagon is then split along a diagonal from the midpoint), where that
  // split keeps every corner off flat (at least kFlatCorner); else the face is left to the paths
  // below. Not a triangle: the quad it would become has a flat corner at a midpoint that must
  // stay on the boundary; its path leaves through an interior edge, whose midpoint moves.
  for (int f = 0; f < nf; ++f) {
    if (!odd[f] || mesh.degree(f) < 5) continue;
    const auto [e, quality] = best_boundary_edge(f, -1);
    if (e < 0 || quality < kFlatCorner) continue;
    ++n_mid[e];
    ++res.stats.n_boundary_splits;
    odd[f] = 0;
  }
  // The others: breadth-first over the faces, through edges of two faces, to the nearest other
  // odd face or face with a boundary edge (first only one whose split then keeps its corners off
  // flat; then any).
  std::vector<int> parent_edge(nf, -1), visited(nf, -1);
  for (const bool strict : {true, false})
    for (int f = 0; f < nf; ++f) {
      if (!odd[f]) continue;
      std::deque<int> queue = {f};
      visited[f] = 2 * f + strict;
      parent_edge[f] = -1;
      int sink = -1, sink_edge = -1, n_visited = 0;
      while (!queue.empty() && sink < 0 && n_visited < options.max_path_faces) {
        const int g = queue.front();
        queue.pop_front();
        ++n_visited;
        if (g != f && odd[g]) {
          sink = g;
          break;
        }
        if (g != f && longest_boundary_edge(g) >= 0) {
          const auto [e, quality] = best_boundary_edge(g, parent_edge[g]);
          if (!strict || (e >= 0 && quality >= kFlatCorner)) {
            sink = g;
            sink_edge = e >= 0 ? e : longest_boundary_edge(g);
            break;
          }
        }
        for (int k = 0; k < mesh.degree(g); ++k) {
          const int e = corner_edge[mesh.face_corner(g, k)];
          if (!crossable(e) || merged_edge[e]) continue;
          const int h = edge_faces[e][0][0] == g ? edge_faces[e][1][0] : edge_faces[e][0][0];
          if (h == g || visited[h] == 2 * f + strict) continue;
          visited[h] = 2 * f + strict;
          parent_edge[h] = e;
          queue.push_back(h);
        }
      }
      if (sink < 0) continue;
      // Two odd faces side by side (one made so by a path's end) merge.
      if (odd[sink] && parent_edge[sink] >= 0 && merged_with[f] < 0 && merged_with[sink] < 0 &&
          can_merge(f, sink, parent_edge[sink])) {
        merged_with[f] = sink;
        merged_with[sink] = f;
        merged_edge[parent_edge[sink]] = 1;
        odd[f] = odd[sink] = 0;
        ++res.stats.n_merged;
        continue;
      }
      ++res.stats.n_paths;
      for (int g = sink; g != f;) {
        const int e = parent_edge[g];
        ++n_mid[e];
        ++res.stats.n_edges_split;
        g = edge_faces[e][0][0] == g ? edge_faces[e][1][0] : edge_faces[e][0][0];
      }
      odd[f] = 0;
      if (odd[sink]) {
        odd[sink] = 0;
      } else {
        ++n_mid[sink_edge];
        ++res.stats.n_boundary_splits;
      }
    }

  // The new vertices: midpoints (evenly spaced along their edge, from its smaller vertex id).
  std::vector<Eigen::Vector3d> positions;
  positions.reserve(nv);
  for (int v = 0; v < nv; ++v) positions.push_back(mesh.V.row(v).transpose());
  std::vector<int> first_mid(ne, -1);
  for (int e = 0; e < ne; ++e) {
    if (n_mid[e] == 0) continue;
    first_mid[e] = static_cast<int>(positions.size());
    const Eigen::Vector3d a = mesh.V.row(edge_vertices[e][0]).transpose(), b = mesh.V.row(edge_vertices[e][1]).transpose();
    for (int i = 1; i <= n_mid[e]; ++i) positions.push_back(a + (b - a) * (static_cast<double>(i) / (n_mid[e] + 1)));
  }
  std::vector<Eigen::Vector2d> uvs;
  if (uv)
    for (int i = 0; i < mesh.uv.rows(); ++i) uvs.push_back(mesh.uv.row(i).transpose());

  core::PolyMesh& out = res.quads;
  out = core::PolyMesh{};
  out.lines = mesh.lines;
  std::vector<int> created;  // faces of `out` made by a split
  // Face f's corners with the midpoints of its edges, from corner `start`.
  auto face_polygon = [&](int f, int start, std::vector<int>* poly, std::vector<int>* poly_uv) {
    const int d = mesh.degree(f);
    for (int j = 0; j < d; ++j) {
      const int k = (start + j) % d;
      const int c = mesh.face_corner(f, k);
      poly->push_back(mesh.face_vertex[c]);
      if (uv) poly_uv->push_back(mesh.face_uv[c]);
      const int e = proper[f] ? corner_edge[c] : -1;
      if (e < 0 || n_mid[e] == 0) continue;
      const int a = mesh.face_vertex[c];
      const bool forward = a == edge_vertices[e][0];
      for (int i = 0; i < n_mid[e]; ++i) {
        const int m = forward ? i : n_mid[e] - 1 - i;  // midpoint index along a→b
        poly->push_back(first_mid[e] + m);
        if (uv) {
          const double t = static_cast<double>(i + 1) / (n_mid[e] + 1);
          const int cb = mesh.face_corner(f, (k + 1) % d);
          uvs.push_back(uvs[mesh.face_uv[c]] + (uvs[mesh.face_uv[cb]] - uvs[mesh.face_uv[c]]) * t);
          poly_uv->push_back(static_cast<int>(uvs.size()) - 1);
        }
      }
    }
  };
  for (int f = 0; f < nf; ++f) {
    const int d = mesh.degree(f);
    std::vector<int> poly, poly_uv;
    const int g = merged_with[f];
    if (g >= 0 && g < f) continue;  // emitted with g
    if (g < 0) {
      face_polygon(f, 0, &poly, &poly_uv);
    } else {
      // f from the shared edge's second vertex round to its first, then g's corners between.
      int kf = 0, kg = 0;
      while (!merged_edge[corner_edge[mesh.face_corner(f, kf)]] ||
             !(edge_faces[corner_edge[mesh.face_corner(f, kf)]][0][0] == g ||
               edge_faces[corner_edge[mesh.face_corner(f, kf)]][1][0] == g))
        ++kf;
      while (corner_edge[mesh.face_corner(g, kg)] != corner_edge[mesh.face_corner(f, kf)]) ++kg;
      std::vector<int> pg, pg_uv;
      face_polygon(f, (kf + 1) % d, &poly, &poly_uv);
      face_polygon(g, (kg + 1) % mesh.degree(g), &pg, &pg_uv);
      poly.insert(poly.end(), pg.begin() + 1, pg.end() - 1);
      if (uv) poly_uv.insert(poly_uv.end(), pg_uv.begin() + 1, pg_uv.end() - 1);
    }
    const int n = static_cast<int>(poly.size());
    if (!proper[f] || n % 2 == 1 || (n == 4 && d == 4 && g < 0)) {
      out.face_offset.push_back(out.face_offset.back() + n);
      out.face_vertex.insert(out.face_vertex.end(), poly.begin(), poly.end());
      if (uv) out.face_uv.insert(out.face_uv.end(), poly_uv.begin(), poly_uv.end());
      if (n != 4) ++res.stats.n_non_quads_after;
      continue;
    }
    std::vector<Eigen::Vector3d> x;
    for (const int v : poly) x.push_back(positions[v]);
    PolygonSplit split = split_along_diagonals(x);
    if (split.quality < options.min_diagonal_quality)
      for (const int parity : {0, 1}) {
        PolygonSplit around = split_around_center(x, parity);
        if (around.quality > split.quality) split = std::move(around);
      }
    int center = -1, center_uv = -1;
    for (const auto& q : split.quads) {
      std::vector<int> quad, quad_uv;
      for (const int i : q) {
        if (i == kCenter && center < 0) {
          Eigen::Vector3d c = Eigen::Vector3d::Zero();
          for (const Eigen::Vector3d& p : x) c += p;
          center = static_cast<int>(positions.size());
          positions.push_back(c / n);
          ++res.stats.n_centers;
          if (uv) {
            Eigen::Vector2d t = Eigen::Vector2d::Zero();
            for (const int r : poly_uv) t += uvs[r];
            uvs.push_back(t / n);
            center_uv = static_cast<int>(uvs.size()) - 1;
          }
        }
        quad.push_back(i == kCenter ? center : poly[i]);
        if (uv) quad_uv.push_back(i == kCenter ? center_uv : poly_uv[i]);
      }
      created.push_back(out.n_faces());
      out.face_offset.push_back(out.face_offset.back() + 4);
      out.face_vertex.insert(out.face_vertex.end(), quad.begin(), quad.end());
      if (uv) out.face_uv.insert(out.face_uv.end(), quad_uv.begin(), quad_uv.end());
    }
    ++res.stats.n_faces_split;
    res.stats.n_quads_added += static_cast<int>(split.quads.size());
  }
  // A midpoint inside the surface that is a flat corner of a quad (a triangle's, whose path left
  // through that edge) moves towards the far ends of its other edges (its spokes into the faces
  // on the edge's other side) by kFlatMidpointShift of the way: the flat corner opens, the quads
  // on the other side stay convex.
  std::vector<int> mid_edge(positions.size(), -1);
  for (int e = 0; e < ne; ++e)
    for (int i = 0; i < n_mid[e]; ++i) mid_edge[first_mid[e] + i] = e;
  std::vector<std::vector<int>> neighbours(positions.size());
  std::vector<double> worst_corner(positions.size(), 1);
  for (int f = 0; f < out.n_faces(); ++f) {
    const int d = out.degree(f);
    for (int k = 0; k < d; ++k) {
      const int v = out.vertex(f, k);
      if (v < nv || mid_edge[v] < 0) continue;
      const int a = out.vertex(f, (k + d - 1) % d), b = out.vertex(f, (k + 1) % d);
      neighbours[v].push_back(a);
      neighbours[v].push_back(b);
      if (d == 4) {
        const Eigen::Vector3d& c = positions[out.vertex(f, (k + 2) % 4)];
        worst_corner[v] = std::min(worst_corner[v], quad_quality(positions[v], positions[b], c, positions[a]));
      }
    }
  }
  std::vector<std::pair<int, Eigen::Vector3d>> shifts;
  for (int v = nv; v < static_cast<int>(positions.size()); ++v) {
    const int e = mid_edge[v];
    if (e < 0 || !crossable(e) || worst_corner[v] >= kFlatCorner) continue;
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    int n_spokes = 0;
    std::vector<int> seen;
    for (const int w : neighbours[v]) {
      if (w == edge_vertices[e][0] || w == edge_vertices[e][1] || (w >= nv && mid_edge[w] == e)) continue;
      if (std::find(seen.begin(), seen.end(), w) != seen.end()) continue;
      seen.push_back(w);
      target += positions[w];
      ++n_spokes;
    }
    if (n_spokes > 0) shifts.emplace_back(v, positions[v] + kFlatMidpointShift * (target / n_spokes - positions[v]));
  }
  for (const auto& [v, p] : shifts) positions[v] = p;
  res.stats.n_midpoints_shifted = static_cast<int>(shifts.size());
  // Doublets: a vertex of the new quads inside the surface with two quads only, (v, a, x, b) and
  // (v, b, y, a) (a midpoint that both sides' splits left as a corner), goes: the two become
  // (a, x, b, y).
  std::vector<std::vector<int>> faces(out.n_faces()), faces_uv(out.n_faces());
  for (int f = 0; f < out.n_faces(); ++f)
    for (int k = 0; k < out.degree(f); ++k) {
      faces[f].push_back(out.vertex(f, k));
      if (uv) faces_uv[f].push_back(out.face_uv[out.face_corner(f, k)]);
    }
  std::vector<char> is_created(faces.size(), 0);
  for (const int f : created) is_created[f] = 1;
  std::vector<std::vector<int>> vertex_faces(positions.size());
  for (int f = 0; f < static_cast<int>(faces.size()); ++f)
    for (const int v : faces[f]) vertex_faces[v].push_back(f);
  for (int v = 0; v < static_cast<int>(positions.size()); ++v) {
    if (vertex_faces[v].size() != 2) continue;
    const int f = vertex_faces[v][0], g = vertex_faces[v][1];
    if (f == g || (!is_created[f] && !is_created[g])) continue;
    if (faces[f].size() != 4 || faces[g].size() != 4) continue;
    const int kf = static_cast<int>(std::find(faces[f].begin(), faces[f].end(), v) - faces[f].begin());
    const int kg = static_cast<int>(std::find(faces[g].begin(), faces[g].end(), v) - faces[g].begin());
    const int a = faces[f][(kf + 1) % 4], x = faces[f][(kf + 2) % 4], b = faces[f][(kf + 3) % 4];
    if (faces[g][(kg + 1) % 4] != b || faces[g][(kg + 3) % 4] != a) continue;
    const int y = faces[g][(kg + 2) % 4];
    if (x == y) continue;
    std::vector<int> merged_uv;
    if (uv) merged_uv = {faces_uv[f][(kf + 1) % 4], faces_uv[f][(kf + 2) % 4], faces_uv[f][(kf + 3) % 4],
                         faces_uv[g][(kg + 2) % 4]};
    faces[f] = {a, x, b, y};
    faces_uv[f] = merged_uv;
    faces[g].clear();
    faces_uv[g].clear();
    is_created[f] = 1;
    for (const int w : {a, b}) std::erase(vertex_faces[w], g);
    std::replace(vertex_faces[y].begin(), vertex_faces[y].end(), g, f);
    vertex_faces[v].clear();
    ++res.stats.n_doublets_removed;
  }
  if (res.stats.n_doublets_removed > 0) {
    core::PolyMesh kept;
    kept.lines = out.lines;
    created.clear();
    for (size_t f = 0; f < faces.size(); ++f)
      if (!faces[f].empty()) {
        if (is_created[f]) created.push_back(kept.n_faces());
        kept.add_face(faces[f], faces_uv[f]);
      }
    out = std::move(kept);
    res.stats.n_quads_added -= res.stats.n_doublets_removed;
  }
  res.stats.worst_quality = 1;
  for (const int f : created)
    res.stats.worst_quality =
        std::min(res.stats.worst_quality, quad_quality(positions[out.vertex(f, 0)], positions[out.vertex(f, 1)],
                                                       positions[out.vertex(f, 2)], positions[out.vertex(f, 3)]));
  out.V.resize(static_cast<Eigen::Index>(positions.size()), 3);
  for (size_t v = 0; v < positions.size(); ++v) out.V.row(static_cast<Eigen::Index>(v)) = positions[v].transpose();
  if (uv) {
    out.uv.resize(static_cast<Eigen::Index>(uvs.size()), 2);
    for (size_t i = 0; i < uvs.size(); ++i) out.uv.row(static_cast<Eigen::Index>(i)) = uvs[i].transpose();
  }
}

}  // namespace

PureQuadResult make_pure_quads(const core::PolyMesh& mesh, const PureQuadOptions& options) {
  PureQuadResult res;
  const int nf = mesh.n_faces(), nv = mesh.n_vertices();
  if (options.max_path_faces < 0 || !(options.min_diagonal_quality <= 1)) {
    res.status = core::Status::invalid_input("make_pure_quads: max_path_faces < 0 or min_diagonal_quality > 1");
    return res;
  }
  for (const int v : mesh.face_vertex)
    if (v < 0 || v >= nv) {
      res.status = core::Status::invalid_input("make_pure_quads: vertex id " + std::to_string(v) + " out of range [0, " +
                                               std::to_string(nv) + ")");
      return res;
    }
  const bool uv = mesh.has_uv();
  if (uv && mesh.face_uv.size() != mesh.face_vertex.size()) {
    res.status = core::Status::invalid_input("make_pure_quads: face_uv is not one row per corner");
    return res;
  }
  if (uv)
    for (const int t : mesh.face_uv)
      if (t < 0 || t >= mesh.uv.rows()) {
        res.status = core::Status::invalid_input("make_pure_quads: uv row " + std::to_string(t) + " out of range");
        return res;
      }
  // Faces that take part: at least 3 distinct vertices.
  std::vector<char> proper(nf, 0);
  for (int f = 0; f < nf; ++f) {
    const int d = mesh.degree(f);
    std::vector<int> vs(mesh.face_vertex.begin() + mesh.face_offset[f], mesh.face_vertex.begin() + mesh.face_offset[f + 1]);
    std::sort(vs.begin(), vs.end());
    proper[f] = d >= 3 && std::unique(vs.begin(), vs.end()) == vs.end();
    if (d != 4) ++res.stats.n_non_quads_before;
  }
  res.quads = mesh;
  if (res.stats.n_non_quads_before == 0) return res;
  const core::PolyMesh collapsed = collapse_short_boundary_edges(mesh, &proper, &res.stats.n_edges_collapsed);
  const core::PolyMesh reduced = remove_flat_boundary_vertices(collapsed, proper, &res.stats.n_vertices_removed);
  split_faces(reduced, proper, options, &res);
  // Unreferenced vertices (the collapsed and removed ones) go; the others keep their order.
  std::vector<int> new_id(res.quads.n_vertices(), -1);
  for (const int v : res.quads.face_vertex) new_id[v] = 0;
  int n_kept = 0;
  for (int& id : new_id)
    if (id == 0) id = n_kept++;
  if (n_kept < res.quads.n_vertices()) {
    Eigen::MatrixX3d V(n_kept, 3);
    for (int v = 0; v < res.quads.n_vertices(); ++v)
      if (new_id[v] >= 0) V.row(new_id[v]) = res.quads.V.row(v);
    res.quads.V = std::move(V);
    for (int& v : res.quads.face_vertex) v = new_id[v];
    std::erase_if(res.quads.lines, [&](const std::array<int, 2>& l) { return new_id[l[0]] < 0 || new_id[l[1]] < 0; });
    for (auto& l : res.quads.lines)
      for (int& v : l) v = new_id[v];
  }

  return res;
}

}  // namespace quadify::quadex
