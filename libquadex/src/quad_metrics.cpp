#include <libquadex/quad_metrics.h>

#include <libcore/curvature.h>

#include <libcore/predicates.h>
#include <libcore/topology.h>

#include "parallel.h"
#include "quad_corners.h"

#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <Eigen/Geometry>


#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>
#include <stdexcept>
#include <unordered_map>

namespace quadify::quadex {
using core::edge_key;
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Segment = Kernel::Segment_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using SegmentIterator = std::vector<Segment>::const_iterator;
using TriangleTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>>>;
using SegmentTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_segment_primitive<Kernel, SegmentIterator>>>;

// Spacing of the samples along a sharp reference edge, × reference bbox diagonal: a tenth of the
// default capture tolerance would be finer than needed; this resolves a 1e-3 offset along an edge.
constexpr double kFeatureSampleSpacing = 1e-3;

Point to_point(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }
Eigen::Vector3d to_eigen(const Point& p) { return {p.x(), p.y(), p.z()}; }

struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

// The non-degenerate triangles of a triangle mesh as CGAL triangles, with their face ids.
struct TriangleSurface {
  std::vector<Triangle> triangles;
  std::vector<int> face;  // face id in the source mesh, per triangle
  std::vector<double> cumulative_area;
  std::vector<Point> vertices;  // referenced vertices
  TriangleTree tree;

  explicit TriangleSurface(const core::TriMesh& mesh) {
    std::vector<char> used(mesh.n_vertices(), 0);
    double total = 0;
    for (int f = 0; f < mesh.n_faces(); ++f) {
      const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)),
                            c = mesh.V.row(mesh.F(f, 2));
      for (int k = 0; k < 3; ++k) used[mesh.F(f, k)] = 1;
      if (core::collinear3d(a, b, c)) continue;  // exact: no area, no closest point of its own
      triangles.emplace_back(to_point(a), to_point(b), to_point(c));
      face.push_back(f);
      total += 0.5 * (b - a).cross(c - a).norm();
      cumulative_area.push_back(total);
    }
    for (int v = 0; v < mesh.n_vertices(); ++v)
      if (used[v]) vertices.push_back(to_point(mesh.V.row(v)));
    if (triangles.empty()) return;
    tree.insert(triangles.begin(), triangles.end());
    tree.build();
    tree.accelerate_distance_queries();
  }

  bool empty() const { return triangles.empty(); }

  // `n` area-uniform random points (deterministic for a given generator state) plus all vertices.
  std::vector<Point> samples(int n, std::mt19937& rng) const {
    std::vector<Point> out = vertices;
    if (empty() || n <= 0) return out;
    const double total = cumulative_area.back();
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    out.reserve(out.size() + n);
    for (int i = 0; i < n; ++i) {
      const double pick = uniform(rng) * total;
      const size_t t = std::min(
          static_cast<size_t>(std::upper_bound(cumulative_area.begin(), cumulative_area.end(), pick) -
                              cumulative_area.begin()),
          triangles.size() - 1);
      const double s = std::sqrt(uniform(rng)), r = uniform(rng);
      const Triangle& tri = triangles[t];
      const Eigen::Vector3d p = (1 - s) * to_eigen(tri[0]) + s * (1 - r) * to_eigen(tri[1]) +
                                s * r * to_eigen(tri[2]);
      out.push_back(to_point(p));
    }
    return out;
  }
};

struct DistanceSummary {
  double max = 0, mean = 0;
};

DistanceSummary distances_to(const std::vector<Point>& points, const TriangleTree& tree) {
  std::vector<double> dist(points.size());
  parallel_for_each_index(points.size(),
                          [&](size_t i) { dist[i] = std::sqrt(CGAL::to_double(tree.squared_distance(points[i]))); });
  DistanceSummary s;
  for (double d : dist) {
    s.max = std::max(s.max, d);
    s.mean += d;
  }
  if (!dist.empty()) s.mean /= static_cast<double>(dist.size());
  return s;
}

// Sharp-edge feature capture against the edges of the quad mesh (see QuadMetrics).
void feature_capture(const core::PolyMesh& quads, const core::TriMesh& reference, double diag,
                     const QuadMetricsOptions& options, QuadMetrics* m) {
  core::EdgeTopology topo;
  try {
    topo = core::build_edge_topology(reference);
  } catch (const std::invalid_argument&) {
    return;  // non-manifold or inconsistently oriented reference: no reliable dihedral angles
  }
  std::vector<std::array<Eigen::Vector3d, 2>> sharp;
  for (const int e : core::sharp_edges(reference, topo, options.feature_angle_deg))
    sharp.push_back({reference.V.row(topo.edge_vertex(e, 0)).transpose(),
                     reference.V.row(topo.edge_vertex(e, 1)).transpose()});
  if (sharp.empty()) return;

  // Quad-mesh edges (unique, non-degenerate) in a segment tree.
  std::vector<Segment> segments;
  std::unordered_map<long long, char> seen;
  for (int f = 0; f < quads.n_faces(); ++f)
    for (int k = 0; k < quads.degree(f); ++k) {
      const int a = quads.vertex(f, k), b = quads.vertex(f, (k + 1) % quads.degree(f));
      if (a == b || !seen.emplace(edge_key(a, b), 1).second) continue;
      const Point pa = to_point(quads.V.row(a)), pb = to_point(quads.V.row(b));
      if (pa != pb) segments.emplace_back(pa, pb);
    }
  if (segments.empty()) {
    m->feature_capture = 0;
    m->feature_hausdorff = std::numeric_limits<double>::infinity();
    return;
  }
  SegmentTree tree(segments.begin(), segments.end());
  tree.accelerate_distance_queries();

  // Midpoints of equal sub-segments of each sharp edge, each standing for its sub-length.
  const double spacing = kFeatureSampleSpacing * diag;
  std::vector<Point> samples;
  std::vector<double> weight;
  for (const auto& [a, b] : sharp) {
    const double len = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / spacing)));
    for (int i = 0; i < n; ++i) {
      samples.push_back(to_point(a + (b - a) * ((i + 0.5) / n)));
      weight.push_back(len / n);
    }
  }
  std::vector<double> dist(samples.size());
  parallel_for_each_index(samples.size(),
                          [&](size_t i) { dist[i] = std::sqrt(CGAL::to_double(tree.squared_distance(samples[i]))); });
  const double tolerance = options.feature_capture_tolerance * diag;
  double captured = 0, total = 0, worst = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    total += weight[i];
    if (dist[i] <= tolerance) captured += weight[i];
    worst = std::max(worst, dist[i]);
  }
  m->feature_capture = total > 0 ? captured / total : -1;
  m->feature_hausdorff = worst / diag;
}

}  // namespace

QuadMetrics compute_quad_metrics(const core::PolyMesh& quads, const core::TriMesh* reference,
                                 const QuadMetricsOptions& options) {
  QuadMetrics m;
  const int nf = quads.n_faces(), nv = quads.n_vertices();
  m.n_faces = nf;
  for (int f = 0; f < nf; ++f) {
    ++m.faces_by_degree[quads.degree(f)];
    if (quads.degree(f) != 4) ++m.n_non_quads;
    std::vector<int> corners(quads.face_vertex.begin() + quads.face_offset[f],
                             quads.face_vertex.begin() + quads.face_offset[f + 1]);
    std::sort(corners.begin(), corners.end());
    if (std::adjacent_find(corners.begin(), corners.end()) != corners.end()) ++m.n_degenerate;
  }

  // Undirected edges with their half-edges (face corner ids of the tails).
  std::unordered_map<long long, std::vector<int>> edge_halfedges;
  edge_halfedges.reserve(quads.face_vertex.size());
  std::vector<int> corner_face(quads.face_vertex.size());
  std::vector<char> used(nv, 0);
  auto next_corner = [&](int c) {
    const int f = corner_face[c];
    return c + 1 < quads.face_offset[f + 1] ? c + 1 : quads.face_offset[f];
  };
  for (int f = 0; f < nf; ++f)
    for (int c = quads.face_offset[f]; c < quads.face_offset[f + 1]; ++c) corner_face[c] = f;
  for (int f = 0; f < nf; ++f)
    for (int c = quads.face_offset[f]; c < quads.face_offset[f + 1]; ++c) {
      const int a = quads.face_vertex[c], b = quads.face_vertex[next_corner(c)];
      used[a] = 1;
      if (a != b) edge_halfedges[edge_key(a, b)].push_back(c);
    }
  m.n_vertices = static_cast<int>(std::count(used.begin(), used.end(), 1));

  DisjointSets face_sets(std::max(nf, 1));
  DisjointSets corner_sets(std::max<size_t>(quads.face_vertex.size(), 1));
  std::vector<int> valence(nv, 0);
  std::vector<char> on_boundary(nv, 0);
  std::vector<std::array<int, 2>> boundary_edges;
  std::vector<double> edge_lengths;
  edge_lengths.reserve(edge_halfedges.size());
  bool edge_manifold = true, oriented = true;
  for (const auto& [key, hs] : edge_halfedges) {
    const int a = quads.face_vertex[hs[0]], b = quads.face_vertex[next_corner(hs[0])];
    ++valence[a];
    ++valence[b];
    edge_lengths.push_back((quads.V.row(a) - quads.V.row(b)).norm());
    for (size_t i = 1; i < hs.size(); ++i) face_sets.unite(corner_face[hs[0]], corner_face[hs[i]]);
    if (hs.size() == 1) {
      on_boundary[a] = on_boundary[b] = 1;
      boundary_edges.push_back({a, b});
    } else if (hs.size() > 2) {
      edge_manifold = false;
    } else {
      if (quads.face_vertex[hs[1]] == a) oriented = false;
      // Corners of the same vertex on both sides belong to the same fan.
      for (int ca : {hs[0], next_corner(hs[0])})
        for (int cb : {hs[1], next_corner(hs[1])})
          if (quads.face_vertex[ca] == quads.face_vertex[cb]) corner_sets.unite(ca, cb);
    }
  }
  std::vector<int> fans(nv, 0);
  for (size_t c = 0; c < quads.face_vertex.size(); ++c)
    if (corner_sets.find(static_cast<int>(c)) == static_cast<int>(c)) ++fans[quads.face_vertex[c]];
  const bool vertex_manifold = std::none_of(fans.begin(), fans.end(), [](int n) { return n > 1; });
  m.manifold = edge_manifold && vertex_manifold && m.n_degenerate == 0;

  for (int v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    if (on_boundary[v]) {
      if (valence[v] != 3 && valence[v] != 2) ++m.n_irregular;
    } else {
      ++m.valence_histogram[valence[v]];
      if (valence[v] != 4) ++m.n_irregular;
    }
  }
  {
    std::vector<char> root(std::max(nf, 1), 0);
    for (int f = 0; f < nf; ++f) root[face_sets.find(f)] = 1;
    m.n_components = nf == 0 ? 0 : static_cast<int>(std::count(root.begin(), root.end(), 1));
  }
  if (!boundary_edges.empty()) {
    DisjointSets vertex_sets(nv);
    for (const auto& [a, b] : boundary_edges) vertex_sets.unite(a, b);
    std::vector<char> root(nv, 0);
    for (int v = 0; v < nv; ++v)
      if (on_boundary[v]) root[vertex_sets.find(v)] = 1;
    m.n_boundary_loops = static_cast<int>(std::count(root.begin(), root.end(), 1));
  }
  m.euler_characteristic = m.n_vertices - static_cast<int>(edge_halfedges.size()) + nf;
  if (m.manifold && oriented) {
    const int twice = 2 * m.n_components - m.euler_characteristic - m.n_boundary_loops;
    m.genus = twice >= 0 && twice % 2 == 0 ? twice / 2 : -1;
  }

  // Edge lengths.
  if (!edge_lengths.empty()) {
    const double n = static_cast<double>(edge_lengths.size());
    const double mean = std::accumulate(edge_lengths.begin(), edge_lengths.end(), 0.0) / n;
    double var = 0;
    for (double l : edge_lengths) var += (l - mean) * (l - mean);
    m.edge_len_mean = mean;
    m.edge_len_cv = mean > 0 ? std::sqrt(var / n) / mean : 0;
  }

  // Per-quad scaled Jacobians and corner angles against the quad's area vector.
  std::vector<int> quad_faces;
  std::vector<QuadCorners> quad_geometry;
  std::vector<char> quad_flipped;
  double sj_sum = 0, angle_dev_sum = 0;
  int n_corners = 0;
  m.sj_min = nf > 0 ? 1.0 : 0.0;
  for (int f = 0; f < nf; ++f) {
    if (quads.degree(f) != 4) continue;
    const QuadCorners corners = quad_corners(quads, f);
    const std::array<Eigen::Vector3d, 4>& p = corners.p;
    bool flipped = false;
    double quad_sj_min = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d e1 = p[(k + 1) % 4] - p[k], e2 = p[(k + 3) % 4] - p[k];
      const double lengths = e1.norm() * e2.norm();
      const double sj = corners.scaled_jacobian[k];
      if (sj <= 0) flipped = true;
      // Unsigned corner angle in [0°, 180°] as in the peers' table (a reflex corner reads as
      // 360° minus its interior angle; the scaled Jacobian flags it).
      const double cos_angle = lengths > 0 ? std::clamp(e1.dot(e2) / lengths, -1.0, 1.0) : 0.0;
      const double dev = std::abs(std::acos(cos_angle) * 180.0 / std::numbers::pi - 90.0);
      angle_dev_sum += dev;
      quad_sj_min = std::min(quad_sj_min, sj);
      m.angle_dev_max = std::max(m.angle_dev_max, dev);
      ++n_corners;
    }
    sj_sum += quad_sj_min;
    m.sj_min = std::min(m.sj_min, quad_sj_min);
    quad_faces.push_back(f);
    quad_geometry.push_back(corners);
    quad_flipped.push_back(flipped);
  }
  if (n_corners > 0) {
    m.sj_mean = sj_sum / static_cast<double>(quad_faces.size());
    m.angle_dev_mean = angle_dev_sum / n_corners;
  } else {
    m.sj_min = 0;
  }

  if (reference && reference->n_faces() > 0) {
    const double diag = core::bbox_diagonal(reference->V);
    const TriangleSurface ref(*reference);
    const TriangleSurface quad_surface(core::to_trimesh(quads));
    if (!ref.empty() && !quad_surface.empty() && diag > 0) {
      m.has_reference = true;
      // Orientation against the reference: the reference face closest to the quad centroid; and
      // there, the principal directions for the alignment measure.
      core::VertexCurvature curvature;
      if (options.curvature_alignment) curvature = core::estimate_curvature(*reference);
      std::vector<char> facing_away(quad_faces.size(), 0);
      std::vector<double> angle_sum(quad_faces.size(), -1);
      parallel_for_each_index(quad_faces.size(), [&](size_t i) {
        const int f = quad_faces[i];
        const Eigen::Vector3d centroid = quad_geometry[i].centroid();
        const auto hit = ref.tree.closest_point_and_primitive(to_point(centroid));
        const Triangle& t = *hit.second;
        const Eigen::Vector3d a = to_eigen(t[0]);
        const Eigen::Vector3d ref_normal = (to_eigen(t[1]) - a).cross(to_eigen(t[2]) - a);
        facing_away[i] = quad_geometry[i].facing_cosine(ref_normal) < 0;
        if (!options.curvature_alignment || !(ref_normal.norm() > 0)) return;
        const int rf = ref.face[static_cast<size_t>(hit.second - ref.triangles.begin())];
        int best = reference->F(rf, 0);
        for (int k = 1; k < 3; ++k)
          if ((reference->V.row(reference->F(rf, k)).transpose() - centroid).squaredNorm() <
              (reference->V.row(best).transpose() - centroid).squaredNorm())
            best = reference->F(rf, k);
        const double k1 = std::abs(curvature.k_max[best]), k2 = std::abs(curvature.k_min[best]);
        const double big = std::max(k1, k2), small = std::min(k1, k2);
        if (!(big >= 2 * small) || !(big * diag >= 4)) return;
        const Eigen::Vector3d n = ref_normal.normalized();
        Eigen::Vector3d d = k1 >= k2 ? curvature.d_max.row(best).transpose() : curvature.d_min.row(best).transpose();
        d -= d.dot(n) * n;
        if (!(d.norm() > 0)) return;
        d.normalize();
        const Eigen::Vector3d d_perp = n.cross(d);
        double sum = 0;
        for (int k = 0; k < 4; ++k) {
          const Eigen::Vector3d e = quads.V.row(quads.vertex(f, (k + 1) % 4)) - quads.V.row(quads.vertex(f, k));
          const double theta = std::atan2(std::abs(e.dot(d_perp)), std::abs(e.dot(d))) * 180 / M_PI;
          sum += std::min(theta, 90 - theta);
        }
        angle_sum[i] = sum / 4;
      });
      for (size_t i = 0; i < quad_faces.size(); ++i) quad_flipped[i] |= facing_away[i];
      double angle_total = 0;
      for (const double s : angle_sum)
        if (s >= 0) {
          angle_total += s;
          ++m.n_anisotropic_quads;
        }
      if (m.n_anisotropic_quads > 0) m.principal_angle_mean = angle_total / m.n_anisotropic_quads;

      std::mt19937 rng(options.seed);
      const std::vector<Point> quad_samples = quad_surface.samples(options.hausdorff_samples, rng);
      const std::vector<Point> ref_samples = ref.samples(options.hausdorff_samples, rng);
      const DistanceSummary to_ref = distances_to(quad_samples, ref.tree);
      const DistanceSummary from_ref = distances_to(ref_samples, quad_surface.tree);
      m.hausdorff_to_ref = to_ref.max / diag;
      m.hausdorff_from_ref = from_ref.max / diag;
      m.hausdorff_sym = std::max(m.hausdorff_to_ref, m.hausdorff_from_ref);
      m.mean_dist_sym = 0.5 * (to_ref.mean + from_ref.mean) / diag;
      feature_capture(quads, *reference, diag, options, &m);
    }
  }
  m.n_flipped = static_cast<int>(std::count(quad_flipped.begin(), quad_flipped.end(), 1));
  return m;
}

}  // namespace quadify::quadex
