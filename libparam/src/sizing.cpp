#include <libparam/sizing.h>
#include <libcore/topology.h>

#include <libcore/curvature.h>

#include "cut_layout.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <queue>
#include <stdexcept>
#include <string>


namespace quadify::param {

double sized_area(const core::TriMesh& mesh, const std::vector<double>& face_size,
                  const std::vector<Eigen::Matrix3d>& face_metric) {
  double total = 0;
  for (int f = 0; f < mesh.n_faces(); ++f) {
    double a = 0;
    (void)sized_rest_frame(mesh, f, 1.0, face_size, face_metric, &a);
    total += a;
  }
  return total;
}

std::vector<double> face_size_from_vertices(const core::TriMesh& mesh,
                                            const std::vector<double>& vertex_size) {
  if (static_cast<int>(vertex_size.size()) != mesh.n_vertices())
    throw std::invalid_argument("the size field has " + std::to_string(vertex_size.size()) +
                                " values for " + std::to_string(mesh.n_vertices()) + " vertices");
  for (size_t v = 0; v < vertex_size.size(); ++v)
    if (!(vertex_size[v] > 0) || !std::isfinite(vertex_size[v]))
      throw std::invalid_argument("size field value " + std::to_string(v + 1) +
                                  " is not a positive number");
  const int nf = mesh.n_faces();
  std::vector<double> size(nf);
  for (int f = 0; f < nf; ++f) {
    double log_sum = 0;
    for (int k = 0; k < 3; ++k) log_sum += std::log(vertex_size[mesh.F(f, k)]);
    size[f] = std::exp(log_sum / 3);
  }
  // Normalize (as adaptive_face_metric does): Σ area/size² = Σ area.
  const double area = sized_area(mesh, {}, {}), sized = sized_area(mesh, size, {});
  if (area > 0 && sized > 0) {
    const double c = std::sqrt(sized / area);
    for (double& s : size) s *= c;
  }
  return size;
}

namespace {

std::vector<double> vertex_areas(const core::TriMesh& mesh) {
  std::vector<double> vertex_area(mesh.n_vertices(), 0);
  for (int f = 0; f < mesh.n_faces(); ++f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)),
                          p2 = mesh.V.row(mesh.F(f, 2));
    const double a = 0.5 * (p1 - p0).cross(p2 - p0).norm() / 3;
    for (int k = 0; k < 3; ++k) vertex_area[mesh.F(f, k)] += a;
  }
  return vertex_area;
}

// The area-weighted median of per-vertex values.
double weighted_median(const std::vector<double>& value, const std::vector<double>& weight) {
  std::vector<int> order;
  double total = 0;
  for (size_t v = 0; v < value.size(); ++v)
    if (weight[v] > 0) {
      order.push_back(static_cast<int>(v));
      total += weight[v];
    }
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return value[a] < value[b] || (value[a] == value[b] && a < b); });
  double acc = 0;
  for (const int v : order) {
    acc += weight[v];
    if (acc >= 0.5 * total) return value[v];
  }
  return 0;
}

// log(edge length) for a curvature magnitude, relative to the reference curvature, clamped.
double log_length(double kappa, double kappa_ref, double half_range) {
  if (!(kappa_ref > 0)) return 0;
  return std::clamp(0.5 * (std::log(kappa_ref) - std::log(std::max(kappa, 1e-300))), -half_range,
                    half_range);
}

// Passes of averaging each vertex's values with its neighbours' mean (weights ½, ½).
template <class T>
void smooth(const std::vector<std::vector<int>>& nb, int passes, std::vector<T>* values) {
  std::vector<T> next(values->size());
  for (int pass = 0; pass < passes; ++pass) {
    for (size_t v = 0; v < values->size(); ++v) {
      if (nb[v].empty()) {
        next[v] = (*values)[v];
        continue;
      }
      T sum = (*values)[nb[v][0]];
      for (size_t i = 1; i < nb[v].size(); ++i) sum = sum + (*values)[nb[v][i]];
      next[v] = 0.5 * (*values)[v] + (0.5 / static_cast<double>(nb[v].size())) * sum;
    }
    values->swap(next);
  }
}

// The feature edges at each vertex (#V sorted lists of the other ends); `who` names the caller in
// the error for a vertex out of range.
std::vector<std::vector<int>> feature_neighbours(const core::TriMesh& mesh,
                                                 const std::vector<std::array<int, 2>>& feature_edges,
                                                 const char* who) {
  const int nv = mesh.n_vertices();
  std::vector<std::vector<int>> curve_nb(nv);
  for (const auto& [a, b] : feature_edges) {
    if (a < 0 || a >= nv || b < 0 || b >= nv)
      throw std::invalid_argument(std::string(who) + ": feature edge (" + std::to_string(a) + ", " +
                                  std::to_string(b) + ") has a vertex out of range");
    if (a == b) continue;
    curve_nb[a].push_back(b);
    curve_nb[b].push_back(a);
  }
  for (std::vector<int>& nb : curve_nb) {
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
  }
  return curve_nb;
}

// Multi-source Dijkstra from the vertices whose size is below 1: size(v) = min over them c of
// size(c) + per_length · d(v, c), d along mesh edges.
void grade_from_sources(const core::TriMesh& mesh, double per_length, std::vector<double>* size) {
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (int v = 0; v < mesh.n_vertices(); ++v)
    if ((*size)[v] < 1) queue.push({(*size)[v], v});
  const std::vector<std::vector<int>> nb = core::vertex_neighbours(mesh);
  while (!queue.empty()) {
    const auto [s, v] = queue.top();
    queue.pop();
    if (s > (*size)[v]) continue;
    for (const int w : nb[v]) {
      const double sw = s + per_length * (mesh.V.row(w) - mesh.V.row(v)).norm();
      if (sw < (*size)[w]) {
        (*size)[w] = sw;
        queue.push({sw, w});
      }
    }
  }
}

}  // namespace

std::vector<double> adaptive_face_size(const core::TriMesh& mesh, const AdaptiveSizingOptions& options) {
  const int nv = mesh.n_vertices();
  if (!(options.max_ratio >= 1)) throw std::invalid_argument("max_ratio must be >= 1");
  const core::VertexCurvature curvature = core::estimate_curvature(mesh);
  std::vector<double> kappa(nv);
  for (int v = 0; v < nv; ++v)
    kappa[v] = std::max(std::abs(curvature.k_max[v]), std::abs(curvature.k_min[v]));
  const double kappa_ref = weighted_median(kappa, vertex_areas(mesh));
  const double half_range = 0.5 * std::log(options.max_ratio);
  std::vector<double> log_size(nv);
  for (int v = 0; v < nv; ++v) log_size[v] = log_length(kappa[v], kappa_ref, half_range);
  smooth(core::vertex_neighbours(mesh), options.smoothing_passes, &log_size);
  std::vector<double> vertex_size(nv);
  for (int v = 0; v < nv; ++v) vertex_size[v] = std::exp(log_size[v]);
  return face_size_from_vertices(mesh, vertex_size);
}

std::vector<double> thin_part_vertex_size(const core::TriMesh& mesh, double edge_length,
                                          const ThinPartSizingOptions& options) {
  if (!(edge_length > 0) || !(options.max_edge_over_radius > 0) || !(options.min_ratio > 0) ||
      !(options.min_ratio <= 1))
    throw std::invalid_argument("thin_part_vertex_size: edge_length > 0, max_edge_over_radius > 0 "
                                "and min_ratio in (0, 1] required");
  const int nv = mesh.n_vertices();
  const core::VertexCurvature curvature = core::estimate_curvature(mesh);
  std::vector<double> log_size(nv, 0);
  const double lo = std::log(options.min_ratio);
  for (int v = 0; v < nv; ++v) {
    // A tube of radius r has mean curvature 1/(2r); a saddle (where a tentacle leaves the body)
    // has a small one, and is not thin.
    const double radius = 1 / std::abs(curvature.k_max[v] + curvature.k_min[v]);
    if (!(radius > 0) || !std::isfinite(radius)) continue;
    // Relative length r · max_edge_over_radius / edge_length, clamped to [min_ratio, 1].
    log_size[v] = std::clamp(std::log(options.max_edge_over_radius * radius / edge_length), lo, 0.0);
  }
  smooth(core::vertex_neighbours(mesh), options.smoothing_passes, &log_size);
  std::vector<double> size(nv);
  for (int v = 0; v < nv; ++v) size[v] = std::exp(log_size[v]);
  return size;
}

std::vector<double> feature_loop_vertex_size(const core::TriMesh& mesh,
                                              const std::vector<std::array<int, 2>>& feature_edges,
                                              double edge_length, const FeatureLoopSizingOptions& options) {
  if (!(edge_length > 0) || !(options.min_loop_edges > 0) || !(options.min_ratio > 0) ||
      !(options.min_ratio <= 1) || !(options.grade > 0))
    throw std::invalid_argument("feature_loop_vertex_size: edge_length, min_loop_edges and grade > 0 and "
                                "min_ratio in (0, 1] required");
  const int nv = mesh.n_vertices();
  const std::vector<std::vector<int>> curve_nb =
      feature_neighbours(mesh, feature_edges, "feature_loop_vertex_size");
  auto point = [&](int v) -> Eigen::Vector3d { return mesh.V.row(v); };
  // Closed loops: connected sets of curve vertices that all lie on exactly two curve edges.
  std::vector<double> size(nv, 1.0);
  std::vector<char> seen(nv, 0);
  for (int start = 0; start < nv; ++start) {
    if (seen[start] || curve_nb[start].empty()) continue;
    std::vector<int> loop = {start};
    seen[start] = 1;
    bool closed = true;
    double length = 0;
    for (size_t i = 0; i < loop.size(); ++i) {
      const int v = loop[i];
      if (curve_nb[v].size() != 2) closed = false;
      for (const int w : curve_nb[v]) {
        if (v < w) length += (point(w) - point(v)).norm();
        if (!seen[w]) {
          seen[w] = 1;
          loop.push_back(w);
        }
      }
    }
    const double relative = length / (options.min_loop_edges * edge_length);
    if (!closed || !(relative < 1)) continue;
    for (const int v : loop) size[v] = std::max(options.min_ratio, relative);
  }
  grade_from_sources(mesh, options.grade / edge_length, &size);
  return size;
}

std::vector<double> feature_strip_vertex_size(const core::TriMesh& mesh,
                                              const std::vector<std::array<int, 2>>& feature_edges,
                                              double edge_length, const FeatureStripSizingOptions& options) {
  if (!(edge_length > 0) || !(options.min_width_edges >= 0) ||
      !(options.max_width_edges > options.min_width_edges) || !(options.max_turn_deg >= 0) ||
      !(options.min_ratio > 0) || !(options.min_ratio <= 1) || !(options.grade > 0))
    throw std::invalid_argument(
        "feature_strip_vertex_size: edge_length and grade > 0, 0 <= min_width_edges < "
        "max_width_edges, max_turn_deg >= 0 and min_ratio in (0, 1] required");
  const double min_cos = std::cos(options.max_turn_deg * std::numbers::pi / 180);
  const int nv = mesh.n_vertices();
  const std::vector<std::vector<int>> curve_nb =
      feature_neighbours(mesh, feature_edges, "feature_strip_vertex_size");
  auto joined = [&](int a, int b) {
    return std::binary_search(curve_nb[a].begin(), curve_nb[a].end(), b);
  };
  auto point = [&](int v) -> Eigen::Vector3d { return mesh.V.row(v); };
  std::vector<double> size(nv, 1.0);
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3), o = mesh.F(f, (k + 2) % 3);
      if (!joined(a, b) || curve_nb[o].empty() || joined(o, a) || joined(o, b)) continue;
      const Eigen::Vector3d ab = point(b) - point(a);
      const double len = ab.norm();
      if (!(len > 0)) continue;
      const double width = ab.cross(point(o) - point(a)).norm() / len;
      if (!(width >= options.min_width_edges * edge_length &&
            width < options.max_width_edges * edge_length))
        continue;
      bool parallel = false;
      for (const int w : curve_nb[o]) {
        const Eigen::Vector3d ow = point(w) - point(o);
        const double n = ow.norm();
        if (n > 0 && std::abs(ow.dot(ab)) >= min_cos * n * len) parallel = true;
      }
      if (!parallel) continue;
      const double relative = std::max(options.min_ratio, width / edge_length);
      for (int j = 0; j < 3; ++j) size[mesh.F(f, j)] = std::min(size[mesh.F(f, j)], relative);
    }
  grade_from_sources(mesh, options.grade / edge_length, &size);
  return size;
}

std::vector<Eigen::Matrix3d> adaptive_face_metric(const core::TriMesh& mesh,
                                                  const AdaptiveSizingOptions& options) {
  const int nv = mesh.n_vertices(), nf = mesh.n_faces();
  if (!(options.max_ratio >= 1)) throw std::invalid_argument("max_ratio must be >= 1");
  const core::VertexCurvature c = core::estimate_curvature(mesh);
  std::vector<double> kappa(nv);
  for (int v = 0; v < nv; ++v) kappa[v] = std::max(std::abs(c.k_max[v]), std::abs(c.k_min[v]));
  // The reference is the median of the larger curvature, as for isotropic sizing; the direction
  // of lesser curvature may get up to √max_ratio longer edges than that.
  const double kappa_ref = weighted_median(kappa, vertex_areas(mesh));
  const double half_range = 0.5 * std::log(options.max_ratio);
  const std::vector<std::vector<int>> nb = core::vertex_neighbours(mesh);
  // Per vertex: log lengths along the two principal directions, and the directions' outer
  // products (sign-free, so they average across neighbours).
  std::vector<Eigen::Vector2d> log_len(nv, Eigen::Vector2d::Zero());
  std::vector<Eigen::Matrix3d> frame(nv, Eigen::Matrix3d::Zero());
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d d1 = c.d_max.row(v), d2 = c.d_min.row(v);
    if (d1.squaredNorm() == 0) continue;  // no estimate: isotropic, length 1
    log_len[v] = {log_length(std::abs(c.k_max[v]), kappa_ref, half_range),
                  log_length(std::abs(c.k_min[v]), kappa_ref, half_range)};
    // frame = P1 − P2: +1 along d_max, −1 along d_min; a projector pair recovered after averaging.
    frame[v] = d1 * d1.transpose() - d2 * d2.transpose();
  }
  smooth(nb, options.smoothing_passes, &log_len);
  smooth(nb, options.smoothing_passes, &frame);
  std::vector<Eigen::Matrix3d> metric(nf);
  std::vector<double> no_size;
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)),
                          p2 = mesh.V.row(mesh.F(f, 2));
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0).normalized();
    Eigen::Matrix3d fr = Eigen::Matrix3d::Zero();
    Eigen::Vector2d ll = Eigen::Vector2d::Zero();
    for (int k = 0; k < 3; ++k) {
      fr += frame[mesh.F(f, k)] / 3.0;
      ll += log_len[mesh.F(f, k)] / 3.0;
    }
    // The direction of larger curvature: the top eigenvector of the averaged frame, projected
    // into the face's plane; the other is n × d1.
    const Eigen::Matrix3d tangent = Eigen::Matrix3d::Identity() - n * n.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(tangent * fr * tangent);
    Eigen::Vector3d d1 = tangent * es.eigenvectors().col(2);
    // Anisotropy fades where the averaged directions disagree (small eigenvalue spread).
    const double coherence = std::clamp(es.eigenvalues()(2) - es.eigenvalues()(0), 0.0, 2.0) / 2;
    if (d1.norm() < 1e-9) d1 = (p1 - p0);
    d1.normalize();
    const Eigen::Vector3d d2 = n.cross(d1);
    const double mean = 0.5 * (ll(0) + ll(1));
    const double l1 = std::exp(mean + coherence * (ll(0) - mean));
    const double l2 = std::exp(mean + coherence * (ll(1) - mean));
    metric[f] = d1 * d1.transpose() / l1 + d2 * d2.transpose() / l2 +
                n * n.transpose() / std::sqrt(l1 * l2);
  }
  // Normalize: the sized area equals the surface area.
  const double area = sized_area(mesh, {}, {});
  const double sized = sized_area(mesh, no_size, metric);
  if (area > 0 && sized > 0) {
    const double lambda = std::sqrt(area / sized);
    for (auto& m : metric) m *= lambda;
  }
  return metric;
}

std::vector<Eigen::Vector3d> principal_face_directions(const core::TriMesh& mesh,
                                                       const PrincipalDirectionOptions& options) {
  const int nv = mesh.n_vertices(), nf = mesh.n_faces();
  std::vector<Eigen::Vector3d> direction(nf, Eigen::Vector3d::Zero());
  if (nf == 0) return direction;
  const core::VertexCurvature c = core::estimate_curvature(mesh);
  const double diag = core::bbox_diagonal(mesh.V);
  std::vector<char> anisotropic(nv, 0);
  std::vector<Eigen::Matrix3d> frame(nv, Eigen::Matrix3d::Zero());
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d d1 = c.d_max.row(v), d2 = c.d_min.row(v);
    if (d1.squaredNorm() == 0) continue;
    const double k1 = std::abs(c.k_max[v]), k2 = std::abs(c.k_min[v]);
    const double big = std::max(k1, k2), small = std::min(k1, k2);
    anisotropic[v] = big >= options.min_ratio * small && big * diag >= options.min_curvature;
    // +1 along the direction of larger magnitude, −1 across it (sign-free, averages).
    frame[v] = k1 >= k2 ? Eigen::Matrix3d(d1 * d1.transpose() - d2 * d2.transpose())
                        : Eigen::Matrix3d(d2 * d2.transpose() - d1 * d1.transpose());
  }
  smooth(core::vertex_neighbours(mesh), options.smoothing_passes, &frame);
  for (int f = 0; f < nf; ++f) {
    if (!anisotropic[mesh.F(f, 0)] || !anisotropic[mesh.F(f, 1)] || !anisotropic[mesh.F(f, 2)])
      continue;
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)),
                          p2 = mesh.V.row(mesh.F(f, 2));
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0).normalized();
    if (!n.allFinite()) continue;
    Eigen::Matrix3d fr = Eigen::Matrix3d::Zero();
    for (int k = 0; k < 3; ++k) fr += frame[mesh.F(f, k)] / 3.0;
    const Eigen::Matrix3d tangent = Eigen::Matrix3d::Identity() - n * n.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(tangent * fr * tangent);
    // Coherent directions: the averaged frame keeps a clear +1/−1 split (1 when all agree).
    if (es.eigenvalues()(2) - es.eigenvalues()(0) < 1) continue;
    const Eigen::Vector3d d = tangent * es.eigenvectors().col(2);
    if (d.norm() > 1e-9) direction[f] = d.normalized();
  }
  return direction;
}

}  // namespace quadify::param
