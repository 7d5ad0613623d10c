#include <libquadex/relax_quads.h>

#include <libcore/predicates.h>

#include "parallel.h"
#include "quad_corners.h"

#include <Eigen/Geometry>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <tuple>
#include <vector>

namespace quadify::quadex {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using TriangleTree =
    CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>>>;
using Segment = Kernel::Segment_3;
using SegmentIterator = std::vector<Segment>::const_iterator;
using SegmentTree =
    CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_segment_primitive<Kernel, SegmentIterator>>>;
// Quad vertices closer than this (× bounding-box diagonal) to a feature edge are on it.
constexpr double kOnFeature = 1e-9;

// A feature point within this (× the mean quad edge length around a vertex) of one of the
// vertex's quad edges is met by the quads already: no snapping there.
constexpr double kSnapCovered = 0.02;
// A snap may take a vertex's quads farther from the surface, up to this share of the largest
// distance of any quad before snapping (casting at 5,000 quads: snaps that made no such check
// raised the Hausdorff distance 0.0065 -> 0.0090; teapot lost 2% of its feature capture when
// none could).
constexpr double kSnapDistanceShare = 0.75;
// Tentative snaps (see RelaxOptions::tentative_snaps): those whose feature point has a surface
// sample within the snap's reach at least this share of the largest distance after the repair,
// the farthest first, at most kTentativeMax of them.
constexpr double kTentativeShare = 0.75;
constexpr size_t kTentativeMax = 4;
// This many of the chosen snaps (the farthest first) are tried alone before all of them together.
constexpr size_t kTentativeSingles = 2;
// Fraction of the way to the neighbour centroid tried after the full step is refused.
constexpr double kHalfStep = 0.5;
// Fractions of the way to the centroid of a bad quad the vertex belongs to, tried next.
constexpr double kIntoQuadSteps[] = {0.3, 0.1};
// A move is kept when it raises the local worst scaled Jacobian by more than this (round-off).
constexpr double kMinImprovement = 1e-9;
// Shape fitting: samples per quad triangle side (a barycentric grid of (n+1)(n+2)/2 points) for
// the distance from a quad to the surface.
constexpr int kFitQuadSamples = 4;
// Candidate positions of a vertex: surface samples under its quads within this (× its mean quad
// edge length) of it.
constexpr double kFitReach = 0.5;
// Of those, at most this many are tried: the farthest from the quads (a cut-off tip or ridge is
// among them), and three times as many picked evenly from the rest.
constexpr size_t kFitFarthest = 16, kFitSpread = 48;
// A fitting move is kept when it lowers the local distance by more than this (× diagonal).
constexpr double kFitMinGain = 1e-9;
// Sample jumps (see RelaxOptions::jump_reach): at most this many samples are tried per vertex,
// evenly spread over those in reach by their distance.
constexpr size_t kJumpCandidates = 96;
// A jump does not land within this (× the mean quad edge) of another vertex of the vertex's quads.
constexpr double kJumpApart = 0.05;
// Diagonal choice (see RelaxOptions::choose_diagonals): samples per triangle side of each split,
// and the relative gain in distance a quad's other split must bring for its vertex order to turn.
constexpr int kDiagonalSamples = 6;
constexpr double kDiagonalGain = 0.01;
// Unfolding the quads still flipped or slivers (worst corner below kSliver) after the repair (see
// its use): the vertex rings around them that may move, and the raised thresholds tried in turn.
constexpr int kUnfoldRings = 3;
constexpr double kSliver = 0.05;
constexpr double kUnfoldThresholds[] = {0.25, 0.3, 0.35};

// A quad's corners as a measure sees them: the vertex ids in order and their positions, compared
// bit for bit (faces of degree 4 only).
struct CornerKey {
  std::array<int, 4> ids{};
  std::array<double, 12> xyz{};
  bool operator==(const CornerKey& o) const {
    return ids == o.ids && std::memcmp(xyz.data(), o.xyz.data(), sizeof xyz) == 0;
  }
};

CornerKey corner_key(const core::PolyMesh& q, int f) {
  CornerKey key;
  for (int k = 0; k < 4; ++k) {
    key.ids[k] = q.vertex(f, k);
    for (int d = 0; d < 3; ++d) key.xyz[3 * k + d] = q.V(key.ids[k], d);
  }
  return key;
}

// A quad's last measured value and the corners it was measured at (samples, first: the
// parameters of a distance measure).
struct QuadMemo {
  CornerKey key;
  double value = 0;
  bool valid = false;
  int samples = 0, first = 0;
};

}  // namespace

RelaxResult relax_bad_quads(const core::PolyMesh& quads, const core::TriMesh& surface,
                            const RelaxOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  RelaxResult res;
  res.quads = quads;
  if (!(options.min_scaled_jacobian <= 1) || options.max_rounds < 0 || options.rings < 0 ||
      !(options.snap_reach >= 0) || !(options.snap_min_quality <= 1) || !(options.jump_reach >= 0) ||
      !(options.fit_fraction >= 0) || !(options.fit_min_quality <= 1) || options.fit_rounds < 0) {
    res.status = core::Status::invalid_input(
        "relax options: need min_scaled_jacobian ≤ 1, max_rounds ≥ 0, rings ≥ 0, snap_reach ≥ 0, "
        "snap_min_quality ≤ 1, jump_reach ≥ 0, fit_fraction ≥ 0, fit_min_quality ≤ 1, fit_rounds ≥ 0");
    return res;
  }
  const int nv = quads.n_vertices(), nf = quads.n_faces();
  for (int v : quads.face_vertex)
    if (v < 0 || v >= nv) {
      res.status = core::Status::invalid_input("quad mesh has a vertex id out of range");
      return res;
    }
  std::vector<Triangle> triangles;
  for (int f = 0; f < surface.n_faces(); ++f) {
    const Eigen::Vector3d a = surface.V.row(surface.F(f, 0)), b = surface.V.row(surface.F(f, 1)),
                          c = surface.V.row(surface.F(f, 2));
    if (core::collinear3d(a, b, c)) continue;
    triangles.emplace_back(Point(a.x(), a.y(), a.z()), Point(b.x(), b.y(), b.z()),
                           Point(c.x(), c.y(), c.z()));
  }
  if (triangles.empty()) {
    res.status = core::Status::invalid_input("relax: the surface has no non-degenerate triangle");
    return res;
  }
  TriangleTree tree(triangles.begin(), triangles.end());
  tree.accelerate_distance_queries();

  // Incidence: quads per vertex, edge neighbours, boundary (an edge with one face) and
  // non-manifold (three or more) vertices stay fixed.
  std::vector<std::vector<int>> vertex_quads(nv), neighbours(nv);
  std::map<std::pair<int, int>, int> edge_faces;
  for (int f = 0; f < nf; ++f) {
    const int d = quads.degree(f);
    for (int k = 0; k < d; ++k) {
      const int a = quads.vertex(f, k), b = quads.vertex(f, (k + 1) % d);
      ++edge_faces[{std::min(a, b), std::max(a, b)}];
      if (d == 4) vertex_quads[a].push_back(f);
    }
  }
  std::vector<char> fixed(nv, 0), on_feature(nv, 0), non_manifold(nv, 0);
  for (const auto& [e, count] : edge_faces) {
    neighbours[e.first].push_back(e.second);
    neighbours[e.second].push_back(e.first);
    if (count != 2) fixed[e.first] = fixed[e.second] = 1;
    if (count > 2) non_manifold[e.first] = non_manifold[e.second] = 1;
  }
  for (int v = 0; v < nv; ++v)
    if (vertex_quads[v].empty()) fixed[v] = 1;
  std::vector<Segment> segments, snap_segments;
  std::optional<SegmentTree> feature_tree, snap_tree;
  if (!options.feature_edges.empty()) {
    // Snapping aims at creases only: an interior vertex moved onto the surface's boundary makes
    // a quad fold against it (camelhead at 5,000 quads with the reach at 0.75: Hausdorff 0.0047
    // -> 0.0054, worst corner 0.21 -> 0.06).
    std::map<std::pair<int, int>, int> surface_edge_faces;
    for (int f = 0; f < surface.n_faces(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = surface.F(f, k), b = surface.F(f, (k + 1) % 3);
        ++surface_edge_faces[{std::min(a, b), std::max(a, b)}];
      }
    for (const auto& [a, b] : options.feature_edges) {
      if (a < 0 || b < 0 || a >= surface.n_vertices() || b >= surface.n_vertices()) {
        res.status = core::Status::invalid_input("relax: feature edge vertex out of range");
        return res;
      }
      const Eigen::Vector3d pa = surface.V.row(a), pb = surface.V.row(b);
      if (pa == pb) continue;
      segments.emplace_back(Point(pa.x(), pa.y(), pa.z()), Point(pb.x(), pb.y(), pb.z()));
      const auto it = surface_edge_faces.find({std::min(a, b), std::max(a, b)});
      if (it == surface_edge_faces.end() || it->second != 1) snap_segments.push_back(segments.back());
    }
    if (!snap_segments.empty()) {
      snap_tree.emplace(snap_segments.begin(), snap_segments.end());
      snap_tree->accelerate_distance_queries();
    }
    if (!segments.empty()) {
      feature_tree.emplace(segments.begin(), segments.end());
      feature_tree->accelerate_distance_queries();
      const double diag = (surface.V.colwise().maxCoeff() - surface.V.colwise().minCoeff()).norm();
      const double tol2 = (kOnFeature * diag) * (kOnFeature * diag);
      for (int v = 0; v < nv; ++v)
        if (!fixed[v] &&
            feature_tree->squared_distance(Point(quads.V(v, 0), quads.V(v, 1), quads.V(v, 2))) <= tol2)
          on_feature[v] = 1;
    }
  }

  // Surface samples, the positions the sample jumps and the shape fitting try: the surface's
  // vertices and three interior points per (non-degenerate) triangle. by_x: their indices sorted
  // by x, for range queries.
  std::vector<Eigen::Vector3d> samples;
  {
    std::vector<char> used(surface.n_vertices(), 0);
    for (int f = 0; f < surface.n_faces(); ++f)
      for (int k = 0; k < 3; ++k) used[surface.F(f, k)] = 1;
    for (int v = 0; v < surface.n_vertices(); ++v)
      if (used[v]) samples.push_back(surface.V.row(v).transpose());
    for (const Triangle& t : triangles)
      for (int k = 0; k < 3; ++k) {
        const Point p = CGAL::barycenter(t[k], 4.0, t[(k + 1) % 3], 1.0, t[(k + 2) % 3], 1.0);
        samples.emplace_back(p.x(), p.y(), p.z());
      }
  }
  const int ns = static_cast<int>(samples.size());
  std::vector<int> by_x(static_cast<size_t>(ns));
  for (int s = 0; s < ns; ++s) by_x[s] = s;
  std::stable_sort(by_x.begin(), by_x.end(), [&](int a, int b) { return samples[a].x() < samples[b].x(); });
  // Indices of the samples within r of p, nearest first (ties by index).
  auto samples_near = [&](const Eigen::Vector3d& p, double r) {
    auto lo = std::lower_bound(by_x.begin(), by_x.end(), p.x() - r,
                               [&](int s, double x) { return samples[s].x() < x; });
    std::vector<std::pair<double, int>> found;
    for (auto it = lo; it != by_x.end() && samples[*it].x() <= p.x() + r; ++it) {
      const double d = (samples[*it] - p).norm();
      if (d <= r) found.emplace_back(d, *it);
    }
    std::sort(found.begin(), found.end());
    std::vector<int> out;
    for (const auto& [d, s] : found) out.push_back(s);
    return out;
  };

  core::PolyMesh& q = res.quads;
  // Quality of quad f: its worst corner scaled Jacobian (see RelaxOptions); a quad facing away
  // from the surface (area vector against the normal of the surface triangle closest to its
  // centroid, as `quadify check` counts flips) scores the cosine between the two instead when
  // that is lower, so that a sliver folded onto the wrong side of a crease counts as flipped and
  // moves that turn it around count as improvements.
  // The quality depends on the quad's corners alone (ids in order, positions): each quad keeps
  // them with its last value, bit for bit, and is measured again only when one of them changed.
  // The passes below rescan every quad each round while moving a few vertices (fandisk at 20,000
  // quads: 16 s in the relaxation, most of it in these closest-point queries). Serial use only.
  std::vector<QuadMemo> quality_memo(static_cast<size_t>(nf));
  auto quad_quality = [&](int f) {
    const CornerKey key = corner_key(q, f);
    QuadMemo& memo = quality_memo[f];
    if (memo.valid && memo.key == key) return memo.value;
    const QuadCorners corners = quad_corners(q, f);
    const Eigen::Vector3d c = corners.centroid();
    const Triangle& t = *tree.closest_point_and_primitive(Point(c.x(), c.y(), c.z())).second;
    const Kernel::Vector_3 n = CGAL::cross_product(t[1] - t[0], t[2] - t[0]);
    const double cosine = corners.facing_cosine(Eigen::Vector3d(n.x(), n.y(), n.z()));
    const double value =
        cosine < 0 ? std::min(corners.min_scaled_jacobian(), cosine) : corners.min_scaled_jacobian();
    memo = {key, value, true};
    return value;
  };
  auto count_bad = [&](double threshold) {
    int n = 0;
    for (int f = 0; f < nf; ++f)
      if (q.degree(f) == 4 && quad_quality(f) < threshold) ++n;
    return n;
  };
  const double kFlipped = std::numeric_limits<double>::min();
  res.stats.n_bad_before = count_bad(options.min_scaled_jacobian);
  res.stats.n_flipped_before = count_bad(kFlipped);
  // Mean length of the quad edges at vertex v (its current position).
  auto mean_edge = [&](int v) {
    double h = 0;
    for (int w : neighbours[v]) h += (q.V.row(w) - q.V.row(v)).norm();
    return h / static_cast<double>(neighbours[v].size());
  };
  auto local_worst = [&](int v) {
    double w = std::numeric_limits<double>::infinity();
    for (int f : vertex_quads[v]) w = std::min(w, quad_quality(f));
    return w;
  };
  // Rounds over the vertices of the quads below `threshold` (and `rings` rings around them);
  // `frozen` vertices do not move. Each vertex tries the centroid of its neighbours (full and
  // half step), then steps into each bad quad it belongs to (which opens a flat or reflex corner
  // there); a move is kept when the worst corner around the vertex improves. Returns the moves.
  auto relax_rounds = [&](const std::vector<char>& frozen, double threshold) {
    int total = 0;
    for (int round = 0; round < options.max_rounds; ++round) {
      std::vector<char> in_set(nv, 0);
      std::vector<int> set;
      for (int f = 0; f < nf; ++f)
        if (q.degree(f) == 4 && quad_quality(f) < threshold)
          for (int k = 0; k < 4; ++k)
            if (!in_set[q.vertex(f, k)]) {
              in_set[q.vertex(f, k)] = 1;
              set.push_back(q.vertex(f, k));
            }
      if (set.empty()) break;
      for (int r = 0; r < options.rings; ++r) {
        const size_t n = set.size();
        for (size_t i = 0; i < n; ++i)
          for (int w : neighbours[set[i]])
            if (!in_set[w]) {
              in_set[w] = 1;
              set.push_back(w);
            }
      }
      std::sort(set.begin(), set.end());
      int moves = 0;
      for (int v : set) {
        if (frozen[v]) continue;
        const Eigen::Vector3d old = q.V.row(v).transpose();
        const double before = local_worst(v);
        Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
        for (int w : neighbours[v]) centroid += q.V.row(w).transpose();
        centroid /= static_cast<double>(neighbours[v].size());
        std::vector<Eigen::Vector3d> targets;
        for (const double step : {1.0, kHalfStep}) targets.push_back(old + step * (centroid - old));
        for (int f : vertex_quads[v]) {
          if (quad_quality(f) >= threshold) continue;
          Eigen::Vector3d c = Eigen::Vector3d::Zero();
          for (int k = 0; k < 4; ++k) c += q.V.row(q.vertex(f, k)).transpose();
          for (const double step : kIntoQuadSteps) targets.push_back(old + step * (0.25 * c - old));
        }
        bool kept = false;
        for (const Eigen::Vector3d& target : targets) {
          const Point p = tree.closest_point(Point(target.x(), target.y(), target.z()));
          q.V.row(v) << p.x(), p.y(), p.z();
          if (local_worst(v) > before + kMinImprovement) {
            kept = true;
            break;
          }
        }
        if (kept) {
          ++moves;
        } else {
          q.V.row(v) = old.transpose();
        }
      }
      total += moves;
      if (moves == 0) break;
    }
    return total;
  };
  // Sample jumps (see RelaxOptions::jump_reach) for the quads below `threshold`: each vertex of
  // such a quad (not frozen) tries the surface samples near it, nearest first, and takes the
  // first that lifts every quad around it to `threshold`, else the one that raises their worst
  // quality most; no quad around it may fall below `threshold` (or its quality, if lower).
  // Rounds until nothing moves. Returns the moves.
  auto jump_rounds = [&](const std::vector<char>& frozen, double threshold) {
    int total = 0;
    if (!(options.jump_reach > 0)) return total;
    for (int round = 0; round < options.max_rounds; ++round) {
      std::vector<int> set;
      for (int f = 0; f < nf; ++f)
        if (q.degree(f) == 4 && quad_quality(f) < threshold)
          for (int k = 0; k < 4; ++k) set.push_back(q.vertex(f, k));
      std::sort(set.begin(), set.end());
      set.erase(std::unique(set.begin(), set.end()), set.end());
      int moves = 0;
      for (int v : set) {
        if (frozen[v]) continue;
        const Eigen::Vector3d old = q.V.row(v).transpose();
        const double h = mean_edge(v);
        std::vector<int> candidates = samples_near(old, options.jump_reach * h);
        if (candidates.size() > kJumpCandidates) {  // spread over the disk, nearest first
          for (size_t i = 0; i < kJumpCandidates; ++i) candidates[i] = candidates[i * candidates.size() / kJumpCandidates];
          candidates.resize(kJumpCandidates);
        }
        // Not onto another vertex of its quads (a quad with a zero edge reads as merely flat).
        auto taken = [&](int s) {
          for (int f : vertex_quads[v])
            for (int k = 0; k < 4; ++k)
              if (q.vertex(f, k) != v && (q.V.row(q.vertex(f, k)).transpose() - samples[s]).norm() <= kJumpApart * h)
                return true;
          return false;
        };
        std::vector<double> before;
        for (int f : vertex_quads[v]) before.push_back(quad_quality(f));
        double best = *std::min_element(before.begin(), before.end()) + kMinImprovement;
        int best_sample = -1;
        for (int s : candidates) {
          if (taken(s)) continue;
          q.V.row(v) = samples[s].transpose();
          // The worst quad around v gets better, and no good quad becomes bad.
          double w = std::numeric_limits<double>::infinity();
          for (size_t i = 0; i < before.size() && w > best; ++i) {
            const double quality = quad_quality(vertex_quads[v][i]);
            w = quality < std::min(before[i], threshold) ? -std::numeric_limits<double>::infinity()
                                                          : std::min(w, quality);
          }
          if (w > best) {
            best = w;
            best_sample = s;
            if (w >= threshold) break;  // repaired: the nearest such sample
          }
        }
        if (best_sample < 0) {
          q.V.row(v) = old.transpose();
        } else {
          q.V.row(v) = samples[best_sample].transpose();
          ++moves;
        }
      }
      total += moves;
      if (moves == 0) break;
    }
    return total;
  };
  // Shape fitting (see RelaxOptions::fit_fraction). The quads are measured as two triangles each,
  // (0,1,2) and (0,2,3), as core::to_trimesh and the metrics split them. Surface samples (the
  // vertices and three interior points per triangle) are owned by their closest face at the start
  // of a round; a vertex's local distance is the largest of its quads' distances to the surface
  // (barycentric grid samples) and of its owned samples' distances to its quads.
  // Triangle t of face f's fan from corner `first` (first, first+t+1, first+t+2): for a quad split
  // as the metrics and writers split it (first 0), (0,1,2) and (0,2,3).
  auto quad_triangle = [&](int f, int t, int first = 0) {
    const int d = q.degree(f);
    auto pt = [&](int j) {
      const int v = q.vertex(f, (first + j) % d);
      return Point(q.V(v, 0), q.V(v, 1), q.V(v, 2));
    };
    return Triangle(pt(0), pt(t + 1), pt(t + 2));
  };
  // Largest distance from quad f's samples (a barycentric grid of n per side on each triangle of
  // the split from corner `first`) to the surface.
  // Memoized like quad_quality, per face and (n, first); faces may be measured in parallel, each
  // by one task.
  std::vector<std::vector<QuadMemo>> distance_memo(static_cast<size_t>(nf));
  auto quad_distance = [&](int f, int n = kFitQuadSamples, int first = 0) {
    QuadMemo* memo = nullptr;  // none for a face of another degree: measured each time
    CornerKey key;
    if (q.degree(f) == 4) {
      key = corner_key(q, f);
      for (QuadMemo& m : distance_memo[f])
        if (m.samples == n && m.first == first) memo = &m;
      if (memo && memo->valid && memo->key == key) return memo->value;
      if (!memo) memo = &distance_memo[f].emplace_back();
    }
    double worst = 0;
    for (int t = 0; t < 2; ++t) {
      const Triangle tri = quad_triangle(f, t, first);
      for (int i = 0; i <= n; ++i)
        for (int j = 0; i + j <= n; ++j) {
          const double a = static_cast<double>(i) / n, b = static_cast<double>(j) / n;
          const Point p = CGAL::barycenter(tri[0], 1 - a - b, tri[1], a, tri[2], b);
          worst = std::max(worst, tree.squared_distance(p));
        }
    }
    const double value = std::sqrt(worst);
    if (memo) *memo = {key, value, true, n, first};
    return value;
  };
  // Distance from the surface up to which a snap may take a vertex's quads (set below).
  double snap_distance_allowed = 0;
  // Moves vertex v onto the closest point p of the features when p is within snap_reach of v's
  // mean quad edge, no quad edge around v passes by p already, every quad around v keeps its
  // quality or stays at least snap_min_quality, and its quads get no farther from the surface
  // (see RelaxOptions::snap_reach); true if it moved.
  // With check_quality false the quads' quality is not asked (a tentative snap, see below);
  // *refused_for_quality (if given) tells whether only the quality refused it.
  auto snap_onto_feature = [&](int v, bool check_quality = true, bool* refused_for_quality = nullptr) {
    if (refused_for_quality) *refused_for_quality = false;
    const Eigen::Vector3d old = q.V.row(v).transpose();
    const double h = mean_edge(v);
    const Point cp = snap_tree->closest_point(Point(old.x(), old.y(), old.z()));
    const Eigen::Vector3d p(cp.x(), cp.y(), cp.z());
    if (!((p - old).norm() <= options.snap_reach * h)) return false;
    double covered = std::numeric_limits<double>::infinity();
    for (int f : vertex_quads[v])
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d a = q.V.row(q.vertex(f, k)).transpose();
        const Eigen::Vector3d b = q.V.row(q.vertex(f, (k + 1) % 4)).transpose();
        const Eigen::Vector3d ab = b - a;
        const double t = ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
        covered = std::min(covered, (a + t * ab - p).norm());
      }
    if (covered <= kSnapCovered * h) return false;
    std::vector<double> before;
    double distance_before = 0;
    for (int f : vertex_quads[v]) {
      before.push_back(quad_quality(f));
      distance_before = std::max(distance_before, quad_distance(f));
    }
    q.V.row(v) = p.transpose();
    bool quality_kept = true, distance_kept = true;
    for (size_t i = 0; i < before.size() && quality_kept && check_quality; ++i)
      quality_kept = quad_quality(vertex_quads[v][i]) >= std::min(before[i], options.snap_min_quality);
    for (size_t i = 0; i < before.size() && distance_kept; ++i)
      distance_kept = quad_distance(vertex_quads[v][i]) <= std::max(distance_before, snap_distance_allowed);
    if (refused_for_quality) *refused_for_quality = !quality_kept && distance_kept;
    const bool keep = quality_kept && distance_kept;
    if (!keep) q.V.row(v) = old.transpose();
    return keep;
  };
  // Each surface sample's closest face (owner, -1 when there is no face) and its distance to it,
  // the faces split as the metrics split them; false when there is no face.
  auto assign_owners = [&](std::vector<int>* owner, std::vector<double>* dist) {
    std::vector<Triangle> quad_tris;
    std::vector<int> quad_of;
    for (int f = 0; f < nf; ++f)  // every face: samples under a polygon are not a quad's
      for (int t = 0; t + 2 < q.degree(f); ++t) {
        quad_tris.push_back(quad_triangle(f, t));
        quad_of.push_back(f);
      }
    owner->assign(ns, -1);
    dist->assign(ns, 0);
    if (quad_tris.empty()) return false;
    TriangleTree quad_tree(quad_tris.begin(), quad_tris.end());
    quad_tree.accelerate_distance_queries();
    parallel_for_each_index(static_cast<size_t>(ns), [&](size_t s) {
      const Point p(samples[s].x(), samples[s].y(), samples[s].z());
      const auto hit = quad_tree.closest_point_and_primitive(p);
      (*owner)[s] = quad_of[static_cast<size_t>(hit.second - quad_tris.cbegin())];
      (*dist)[s] = std::sqrt(CGAL::squared_distance(p, hit.first));
    });
    return true;
  };
  // Diagonal choice (see RelaxOptions::choose_diagonals): a quad whose split along its other
  // diagonal (1,2,3), (1,3,0) lies closer to the surface, both ways (its samples' distance to
  // the surface, and the distance of the surface samples it owns to it), by more than
  // kDiagonalGain, and whose two triangles of that split face the same way (the other split of
  // a non-convex quad overlaps itself), starts at its next corner; only the quads with a vertex
  // in `moved`, when given. Returns the quads turned.
  auto choose_diagonals = [&](const std::vector<char>* moved) {
    std::vector<int> owner;
    std::vector<double> owner_dist;
    if (!assign_owners(&owner, &owner_dist)) return 0;
    std::vector<std::vector<int>> owned(nf);
    for (int s = 0; s < ns; ++s)
      if (owner[s] >= 0) owned[owner[s]].push_back(s);
    // The two-sided distance between quad f split from corner `first` and the surface.
    auto split_distance = [&](int f, int first) {
      double d = quad_distance(f, kDiagonalSamples, first);
      const Triangle a = quad_triangle(f, 0, first), b = quad_triangle(f, 1, first);
      for (const int s : owned[f]) {
        const Point p(samples[s].x(), samples[s].y(), samples[s].z());
        d = std::max(d, std::sqrt(std::min(CGAL::squared_distance(p, a), CGAL::squared_distance(p, b))));
      }
      return d;
    };
    std::vector<char> turn(nf, 0);
    parallel_for_each_index(static_cast<size_t>(nf), [&](size_t fi) {
      const int f = static_cast<int>(fi);
      if (q.degree(f) != 4) return;
      if (moved && !(*moved)[q.vertex(f, 0)] && !(*moved)[q.vertex(f, 1)] && !(*moved)[q.vertex(f, 2)] &&
          !(*moved)[q.vertex(f, 3)])
        return;
      const Triangle a = quad_triangle(f, 0, 1), b = quad_triangle(f, 1, 1);
      // (Cross products, not supporting planes: a degenerate quad has no plane.)
      if (CGAL::scalar_product(CGAL::cross_product(a[1] - a[0], a[2] - a[0]),
                               CGAL::cross_product(b[1] - b[0], b[2] - b[0])) <= 0)
        return;
      if (split_distance(f, 1) < (1 - kDiagonalGain) * split_distance(f, 0)) turn[fi] = 1;
    });
    int n = 0;
    for (int f = 0; f < nf; ++f)
      if (turn[f]) {
        const auto begin = q.face_vertex.begin() + q.face_offset[f];
        std::rotate(begin, begin + 1, begin + 4);
        if (q.has_uv()) {
          const auto uv_begin = q.face_uv.begin() + q.face_offset[f];
          std::rotate(uv_begin, uv_begin + 1, uv_begin + 4);
        }
        ++n;
      }
    return n;
  };
  auto fit_to_surface = [&](const std::vector<char>& frozen) {
    const double diag = (surface.V.colwise().maxCoeff() - surface.V.colwise().minCoeff()).norm();
    // Distance from a sample to quad f.
    auto sample_distance = [&](int s, int f) {
      const Point p(samples[s].x(), samples[s].y(), samples[s].z());
      return std::sqrt(std::min(CGAL::squared_distance(p, quad_triangle(f, 0)),
                                CGAL::squared_distance(p, quad_triangle(f, 1))));
    };
    std::vector<double> quad_dist(nf, 0), sample_dist(ns, 0);
    auto largest_distance = [&]() {
      double d = 0;
      for (int f = 0; f < nf; ++f) d = std::max(d, quad_dist[f]);
      for (int s = 0; s < ns; ++s) d = std::max(d, sample_dist[s]);
      return d;
    };
    std::vector<int> owner(ns, -1);
    double threshold = 0;  // local distances above it are fitted
    for (int round = 0; round < options.fit_rounds; ++round) {
      if (!assign_owners(&owner, &sample_dist)) return;
      parallel_for_each_index(static_cast<size_t>(nf), [&](size_t f) {
        quad_dist[f] = q.degree(static_cast<int>(f)) == 4 ? quad_distance(static_cast<int>(f)) : 0.0;
      });
      std::vector<std::vector<int>> owned(nf);
      for (int s = 0; s < ns; ++s) owned[owner[s]].push_back(s);
      // v's local distance and where it is reached (a sample, or the centroid of a quad).
      auto local_distance_at = [&](int v) {
        double d = 0;
        Eigen::Vector3d where = q.V.row(v).transpose();
        for (int f : vertex_quads[v]) {
          if (quad_dist[f] > d) {
            d = quad_dist[f];
            where = quad_corners(q, f).centroid();
          }
          for (int s : owned[f])
            if (sample_dist[s] > d) {
              d = sample_dist[s];
              where = samples[s];
            }
        }
        return std::make_pair(d, where);
      };
      auto local_distance = [&](int v) { return local_distance_at(v).first; };
      if (round == 0) {
        res.stats.fit_distance_before = largest_distance() / diag;
        // Relative to what the movable vertices can change (a boundary cut off, or a polygon's
        // samples, may be farther).
        double movable = 0;
        for (int v = 0; v < nv; ++v)
          if (!frozen[v]) movable = std::max(movable, local_distance(v));
        threshold = options.fit_fraction * movable;
      }
      // Farthest first; among vertices sharing their worst point (the four of a quad), the
      // nearest to it first.
      std::vector<std::tuple<double, double, int>> todo;
      for (int v = 0; v < nv; ++v)
        if (!frozen[v]) {
          const auto [d, where] = local_distance_at(v);
          if (d > threshold) todo.emplace_back(-d, (where - q.V.row(v).transpose()).norm(), v);
        }
      std::sort(todo.begin(), todo.end());
      int moves = 0;
      for (const auto& [neg_d, gap, v] : todo) {
        const Eigen::Vector3d old = q.V.row(v).transpose();
        const double h = mean_edge(v);
        std::vector<int> mine;
        for (int f : vertex_quads[v]) mine.insert(mine.end(), owned[f].begin(), owned[f].end());
        std::vector<double> quality;
        for (int f : vertex_quads[v]) quality.push_back(quad_quality(f));
        // Distance from sample s to v's quads.
        auto star_distance = [&](int s) {
          double ds = std::numeric_limits<double>::infinity();
          for (int f : vertex_quads[v]) ds = std::min(ds, sample_distance(s, f));
          return ds;
        };
        // The local distance with v at its current position, or any value ≥ bound once it
        // reaches bound.
        auto evaluate = [&](double bound) {
          double d = 0;
          for (int f : vertex_quads[v]) {
            d = std::max(d, quad_distance(f));
            if (d >= bound) return d;
          }
          for (int s : mine) {
            d = std::max(d, star_distance(s));
            if (d >= bound) return d;
          }
          return d;
        };
        std::vector<std::pair<double, int>> candidates;
        for (int s : mine)
          if ((samples[s] - old).norm() <= kFitReach * h) candidates.emplace_back(-sample_dist[s], s);
        if (candidates.size() > kFitFarthest + kFitSpread) {
          std::partial_sort(candidates.begin(), candidates.begin() + kFitFarthest, candidates.end());
          const size_t rest = candidates.size() - kFitFarthest;
          for (size_t i = 0; i < kFitSpread; ++i)
            candidates[kFitFarthest + i] = candidates[kFitFarthest + i * rest / kFitSpread];
          candidates.resize(kFitFarthest + kFitSpread);
        }
        const double current = local_distance(v);
        double best = current;
        int best_sample = -1;
        for (const auto& [neg_ds, s] : candidates) {
          q.V.row(v) = samples[s].transpose();
          bool ok = true;
          for (size_t i = 0; i < quality.size() && ok; ++i)
            ok = quad_quality(vertex_quads[v][i]) >= std::min(quality[i], options.fit_min_quality);
          if (!ok) continue;
          const double d = evaluate(best - kFitMinGain * diag);
          if (d < best - kFitMinGain * diag) {
            best = d;
            best_sample = s;
          }
        }
        q.V.row(v) = old.transpose();
        if (best_sample < 0) continue;
        q.V.row(v) = samples[best_sample].transpose();
        ++moves;
        for (int f : vertex_quads[v]) quad_dist[f] = quad_distance(f);
        for (int s : mine) sample_dist[s] = star_distance(s);
      }
      res.stats.n_fitted += moves;
      res.stats.fit_distance_after = largest_distance() / diag;
      if (moves == 0) break;
    }
  };
  // Snapping, in vertex order; vertices of faces that are not quads stay (their shape is not
  // checked).
  std::vector<char> touches_polygon(nv, 0);
  for (int f = 0; f < nf; ++f)
    if (q.degree(f) != 4)
      for (int k = 0; k < q.degree(f); ++k) touches_polygon[q.vertex(f, k)] = 1;
  // Snaps refused only for the quality of the quads around them: the vertex, its feature point,
  // its mean quad edge.
  std::vector<int> tentative;
  std::vector<Eigen::Vector3d> tentative_point;
  std::vector<double> tentative_edge;
  const bool snapping = snap_tree && options.snap_reach > 0;
  if (snapping) {
    for (int f = 0; f < nf; ++f)
      if (q.degree(f) == 4) snap_distance_allowed = std::max(snap_distance_allowed, quad_distance(f));
    snap_distance_allowed *= kSnapDistanceShare;
  }
  // The snapping pass, in vertex order; the vertices in `force` snap without the quality check
  // (see the tentative snaps below). Collects the snaps refused only for quality.
  auto snap_pass = [&](const std::vector<int>& force) {
    for (int v = 0; v < nv; ++v) {
      if (fixed[v] || on_feature[v] || non_manifold[v] || touches_polygon[v]) continue;
      const bool forced = std::find(force.begin(), force.end(), v) != force.end();
      bool refused_for_quality = false;
      if (snap_onto_feature(v, !forced, &refused_for_quality)) {
        on_feature[v] = 1;
        ++res.stats.n_snapped;
        if (forced) ++res.stats.n_tentative_snaps;
      } else if (refused_for_quality && options.tentative_snaps && force.empty()) {
        tentative.push_back(v);
        const Point cp = snap_tree->closest_point(Point(q.V(v, 0), q.V(v, 1), q.V(v, 2)));
        tentative_point.emplace_back(cp.x(), cp.y(), cp.z());
        tentative_edge.push_back(mean_edge(v));
      }
    }
  };
  const core::PolyMesh start_quads = q;
  const std::vector<char> start_on_feature = on_feature;
  const RelaxStats start_stats = res.stats;
  if (snapping) snap_pass({});
  // The repair after snapping (jumps, steps, the last resort, unfolding, fitting); run once, or
  // twice with the tentative snaps (see below).
  auto repair_after_snapping = [&]() {
    std::vector<char> frozen(nv);
    for (int v = 0; v < nv; ++v) frozen[v] = fixed[v] || on_feature[v];
    // Jumps first: where they repair a quad, its neighbours need not slide (which, around a thin
    // tip, pulls the quads off it); the steps then repair what the jumps could not.
    res.stats.n_jumps = jump_rounds(frozen, options.min_scaled_jacobian);
    res.stats.n_moves = relax_rounds(frozen, options.min_scaled_jacobian);
    res.stats.n_jumps += jump_rounds(frozen, options.min_scaled_jacobian);
    // Last resort for quads still flipped: their vertices on features and boundaries may leave
    // them (a flipped or flat quad is worse than a crease or boundary missed by a fraction of a
    // quad: e.g. a boundary corner placed where the boundary runs straight).
    if (options.release_features_for_flips && count_bad(kFlipped) > 0) {
      std::vector<char> released(nv, 0);
      for (int f = 0; f < nf; ++f)
        if (q.degree(f) == 4 && quad_quality(f) < kFlipped)
          for (int k = 0; k < 4; ++k) {
            const int v = q.vertex(f, k);
            if ((on_feature[v] || fixed[v]) && !non_manifold[v] && !vertex_quads[v].empty()) released[v] = 1;
          }
      const Eigen::MatrixX3d v_before = q.V;
      for (int v = 0; v < nv; ++v)
        if (released[v]) frozen[v] = 0;
      res.stats.n_moves += relax_rounds(frozen, kFlipped);
      res.stats.n_jumps += jump_rounds(frozen, kFlipped);
      for (int v = 0; v < nv; ++v)
        if (released[v] && q.V.row(v) != v_before.row(v)) ++res.stats.n_feature_vertices_moved;
    }
    // Quads still flipped sit in a fold that no move of one vertex at a time opens at the
    // threshold (octopus at 5,000 quads: a tentacle tip curling up, thinner than a quad, where the
    // worst quad around each vertex of the fold would get worse first); slivers (below kSliver)
    // are the same kind of knot, one step short of a fold. Around them (kUnfoldRings rings of
    // vertices; the rest stays), the vertices go back to their extracted positions and the jumps
    // and steps run again with raised thresholds, which move the knot's neighbours too; kept when
    // fewer quads are below the target after and no more are flipped. (Raising the threshold
    // everywhere also unfolds it, but pulls quads off every thin tip.) `target`: kFlipped for the
    // folds, first, with the vertices the last resort released; then kSliver for the slivers,
    // with every vertex on a feature or boundary where it is (a crease keeps its quad edges).
    auto unfold = [&](const std::vector<char>& frozen_mask, double target) {
      for (const double threshold : kUnfoldThresholds) {
        const int flipped = count_bad(kFlipped);
        const int below = count_bad(target);
        if (below == 0) break;
        std::vector<char> near(nv, 0);
        for (int f = 0; f < nf; ++f)
          if (q.degree(f) == 4 && quad_quality(f) < target)
            for (int k = 0; k < 4; ++k) near[q.vertex(f, k)] = 1;
        for (int ring = 0; ring < kUnfoldRings; ++ring) {
          const std::vector<char> inner = near;
          for (int v = 0; v < nv; ++v)
            if (inner[v])
              for (const int w : neighbours[v]) near[w] = 1;
        }
        std::vector<char> local_frozen(nv);
        for (int v = 0; v < nv; ++v) local_frozen[v] = frozen_mask[v] || !near[v];
        const Eigen::MatrixX3d saved = q.V;
        for (int v = 0; v < nv; ++v)
          if (!local_frozen[v]) q.V.row(v) = quads.V.row(v);  // from the extracted positions
        int jumps = jump_rounds(local_frozen, threshold);
        const int moves = relax_rounds(local_frozen, threshold);
        jumps += jump_rounds(local_frozen, threshold);
        const int below_after = count_bad(target);
        if (count_bad(kFlipped) <= flipped && below_after < below) {
          res.stats.n_jumps += jumps;
          res.stats.n_moves += moves;
          res.stats.n_unfolded += below - below_after;
        } else {
          q.V = saved;
        }
      }
    };
    unfold(frozen, kFlipped);
    std::vector<char> strict_frozen(nv);
    for (int v = 0; v < nv; ++v) strict_frozen[v] = fixed[v] || on_feature[v];
    unfold(strict_frozen, kSliver);
    // The fitting measures the quads as they will be split, and may change which split is closer.
    if (options.choose_diagonals) res.stats.n_diagonals_turned += choose_diagonals(nullptr);
    if (options.fit_fraction > 0 && options.fit_rounds > 0) {
      std::vector<char> fit_frozen(nv, 0);
      for (int v = 0; v < nv; ++v)
        fit_frozen[v] = fixed[v] || on_feature[v] || non_manifold[v] || touches_polygon[v];
      const Eigen::MatrixX3d v_before = q.V;
      fit_to_surface(fit_frozen);
      std::vector<char> moved(nv, 0);
      for (int v = 0; v < nv; ++v) moved[v] = q.V.row(v) != v_before.row(v);
      if (options.choose_diagonals) res.stats.n_diagonals_turned += choose_diagonals(&moved);
    }
  };
  // Tentative snaps: a snap refused because a quad around the vertex would fold or flatten is
  // often one that the repair then makes good (the neighbours move; fandisk at 5,000 quads: a
  // crease corner cut off by 0.0031 of the diagonal, the largest distance of the mesh, is met).
  // The repair runs first without them; then, for the refused snaps where the repaired quads are
  // farthest from the surface, the snapping pass and the repair run again from the same start
  // with them forced (trials below); a trial is kept if it has no more flipped quads and no more
  // quads below min_scaled_jacobian, a worst quad no worse (or at least snap_min_quality), and a
  // smaller largest two-sided distance to the surface samples.
  if (tentative.empty()) {
    repair_after_snapping();
  } else {
    auto worst_quality = [&]() {
      double w = std::numeric_limits<double>::infinity();
      for (int f = 0; f < nf; ++f)
        if (q.degree(f) == 4) w = std::min(w, quad_quality(f));
      return w;
    };
    // The largest two-sided distance between the quads and the surface samples; *sample_dist
    // (if given) gets each sample's distance to its closest face.
    auto largest_two_sided = [&](std::vector<double>* sample_dist = nullptr) {
      std::vector<int> owner(ns, -1);
      std::vector<double> dist(ns, 0);
      double d = 0;
      if (assign_owners(&owner, &dist))
        for (int s = 0; s < ns; ++s) d = std::max(d, dist[s]);
      for (int f = 0; f < nf; ++f)
        if (q.degree(f) == 4) d = std::max(d, quad_distance(f));
      if (sample_dist) *sample_dist = std::move(dist);
      return d;
    };
    repair_after_snapping();
    const core::PolyMesh plain_quads = q;
    const std::vector<char> plain_on_feature = on_feature;
    const RelaxStats plain_stats = res.stats;
    const int plain_flipped = count_bad(kFlipped);
    const int plain_bad = count_bad(options.min_scaled_jacobian);
    const double plain_worst = worst_quality();
    std::vector<double> plain_sample_dist;
    const double plain_distance = largest_two_sided(&plain_sample_dist);
    // Only the snaps where the repaired quads leave the surface farthest: a sample within the
    // snap's reach of its feature point at least kTentativeShare of the largest distance.
    std::vector<std::pair<double, int>> chosen;  // (local distance, vertex)
    for (size_t i = 0; i < tentative.size(); ++i) {
      double local = 0;
      for (int smp : samples_near(tentative_point[i], options.snap_reach * tentative_edge[i]))
        local = std::max(local, plain_sample_dist[smp]);
      if (local >= kTentativeShare * plain_distance) chosen.emplace_back(local, tentative[i]);
    }
    std::sort(chosen.begin(), chosen.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    if (chosen.size() > kTentativeMax) chosen.resize(kTentativeMax);
    // Trials: each of the first kTentativeSingles chosen snaps alone (the farthest first), then
    // all chosen together; the first one kept ends them.
    std::vector<std::vector<int>> trials;
    for (size_t i = 0; i < std::min(chosen.size(), kTentativeSingles); ++i)
      trials.push_back({chosen[i].second});
    if (chosen.size() > 1) {
      trials.emplace_back();
      for (const auto& [local, v] : chosen) trials.back().push_back(v);
    }
    bool better = false;
    for (size_t t = 0; t < trials.size() && !better; ++t) {
      q = start_quads;
      on_feature = start_on_feature;
      res.stats = start_stats;
      snap_pass(trials[t]);
      repair_after_snapping();
      better = res.stats.n_tentative_snaps > 0 && count_bad(kFlipped) <= plain_flipped &&
               count_bad(options.min_scaled_jacobian) <= plain_bad &&
               worst_quality() >= std::min(plain_worst, options.snap_min_quality) &&
               largest_two_sided() < plain_distance;
    }
    if (!better) {
      q = plain_quads;
      on_feature = plain_on_feature;
      res.stats = plain_stats;
    }
  }
  res.stats.n_bad_after = count_bad(options.min_scaled_jacobian);
  res.stats.n_flipped_after = count_bad(kFlipped);
  res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace quadify::quadex
