#include "feature_alignment.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>

namespace quadify::param {
namespace {

// k-means iterations of Alg. 4 (four groups on the unit circle converge in a few).
constexpr int kRotationIterations = 20;
// Two features at a vertex whose target directions are closer than this (radians) would be laid
// along one direction: their wedge closes.
constexpr double kMinWedge = std::numbers::pi / 4;
// A feature in a wedge conflict is given its other axis only if that turns it by at most this
// (radians; 0.6 of a quarter turn): a feature near 45° (local estimation's coin toss) switches,
// one clearly on its axis is disabled instead.
constexpr double kMaxRelabelTurn = 0.6 * std::numbers::pi / 2;
// Two features at a vertex whose surface angle is within this of 180° (radians) continue one
// curve; there a conflict is where the label must switch, and no relabeling is tried.
constexpr double kStraightContinuation = std::numbers::pi / 6;

int next_in_face(int halfedge) { return 3 * (halfedge / 3) + (halfedge % 3 + 1) % 3; }
int prev_in_face(int halfedge) { return 3 * (halfedge / 3) + (halfedge % 3 + 2) % 3; }

Eigen::Vector2d copy_uv(const CutMesh& cut, const Eigen::VectorXd& x, int corner) {
  return x.segment<2>(2 * cut.corner_copy[corner]);
}

Eigen::Vector2d edge_vector(const CutMesh& cut, const Eigen::VectorXd& x, int halfedge) {
  return copy_uv(cut, x, next_in_face(halfedge)) - copy_uv(cut, x, halfedge);
}

}  // namespace

FeatureSet make_feature_set(const CutMesh& cut, const std::vector<int>& edges) {
  FeatureSet fs;
  fs.edge_feature.assign(cut.topo.n_edges(), -1);
  std::vector<int> sorted = edges;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  for (const int e : sorted) {
    fs.edge_feature[e] = fs.size();
    fs.halfedge.push_back(cut.topo.edge_halfedge[e]);
  }
  return fs;
}

double feature_measure(const CutMesh& cut, const Eigen::VectorXd& x, int halfedge) {
  const Eigen::Vector2d e = edge_vector(cut, x, halfedge);
  double q = std::atan2(e.y(), e.x()) / (std::numbers::pi / 2);
  if (q <= -2) q += 4;
  return q;
}

SparseRow feature_row(const CutMesh& cut, int halfedge, int constant_coord) {
  const int a = cut.corner_copy[halfedge], b = cut.corner_copy[next_in_face(halfedge)];
  SparseRow row;
  const int va = 2 * a + constant_coord, vb = 2 * b + constant_coord;
  if (va < vb)
    row.entries = {{va, -1.0}, {vb, 1.0}};
  else
    row.entries = {{vb, 1.0}, {va, -1.0}};
  return row;
}

double label_turn(double q, int label) {
  double target = std::round(q);
  if ((label == 0 || label == 1) && nearest_label(q) != label) target += q < target ? -1 : 1;
  return (target - q) * (std::numbers::pi / 2);
}

namespace {

// The mesh vertices of a feature's edge.
std::array<int, 2> feature_vertices(const core::TriMesh& mesh, const FeatureSet& fs, int i) {
  const int h = fs.halfedge[i];
  return {mesh.F(h / 3, h % 3), mesh.F(h / 3, (h % 3 + 1) % 3)};
}

// The features at each vertex, with the other end of their edge.
std::vector<std::vector<std::pair<int, int>>> features_at_vertices(const core::TriMesh& mesh,
                                                                   const FeatureSet& fs) {
  std::vector<std::vector<std::pair<int, int>>> at(mesh.n_vertices());
  for (int i = 0; i < fs.size(); ++i) {
    const auto [a, b] = feature_vertices(mesh, fs, i);
    at[a].push_back({i, b});
    at[b].push_back({i, a});
  }
  return at;
}

// UV angle of corner c in the layout x (positive when its face is not flipped).
double corner_uv_angle(const CutMesh& cut, const Eigen::VectorXd& x, int c) {
  const Eigen::Vector2d p = copy_uv(cut, x, c);
  const Eigen::Vector2d a = copy_uv(cut, x, next_in_face(c)) - p;
  const Eigen::Vector2d b = copy_uv(cut, x, prev_in_face(c)) - p;
  return std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
}

// Counter-clockwise UV angle around vertex v from edge ea to edge eb (both at v), or NaN when a
// boundary lies in between or ea has no corner at v on its left.
double fan_angle_ccw(const core::TriMesh& mesh, const CutMesh& cut, const Eigen::VectorXd& x, int v, int ea,
                     int eb) {
  const auto& topo = cut.topo;
  int start = topo.edge_halfedge[ea];
  if (mesh.F(start / 3, start % 3) != v) start = topo.twin[start];
  if (start < 0) return std::numeric_limits<double>::quiet_NaN();
  double total = 0;
  int c = start;
  for (int guard = 0; guard < 3 * mesh.n_faces(); ++guard) {
    total += corner_uv_angle(cut, x, c);
    const int hp = prev_in_face(c);
    if (topo.face_edge(hp / 3, hp % 3) == eb) return total;
    c = topo.twin[hp];
    if (c < 0 || c == start) break;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

std::vector<FeatureCurve> smooth_feature_curves(const core::TriMesh& mesh, const FeatureSet& fs,
                                                double max_bend, double corner_length, double corner_turn) {
  const std::vector<std::vector<std::pair<int, int>>> at = features_at_vertices(mesh, fs);
  // partner[i][end]: the feature continuing i at its vertex `end` (0: first, 1: second), or -1.
  std::vector<std::array<int, 2>> partner(fs.size(), {-1, -1});
  for (int v = 0; v < mesh.n_vertices(); ++v) {
    const auto& list = at[v];
    if (list.size() < 2) continue;
    const Eigen::Vector3d p = mesh.V.row(v);
    std::vector<int> other(list.size(), -1), n_straight(list.size(), 0);
    for (size_t j = 0; j < list.size(); ++j)
      for (size_t k = j + 1; k < list.size(); ++k) {
        const Eigen::Vector3d a = Eigen::Vector3d(mesh.V.row(list[j].second)) - p;
        const Eigen::Vector3d b = Eigen::Vector3d(mesh.V.row(list[k].second)) - p;
        if (std::atan2(a.cross(b).norm(), a.dot(b)) < std::numbers::pi - max_bend) continue;
        ++n_straight[j];
        ++n_straight[k];
        other[j] = static_cast<int>(k);
        other[k] = static_cast<int>(j);
      }
    for (size_t j = 0; j < list.size(); ++j) {
      const int k = other[j];
      if (k < 0 || n_straight[j] != 1 || n_straight[k] != 1) continue;
      const int i = list[j].first;
      partner[i][feature_vertices(mesh, fs, i)[0] == v ? 0 : 1] = list[k].first;
    }
  }
  // Walks: from the features with a free end first (open curves), then the loops left.
  std::vector<FeatureCurve> curves;
  std::vector<char> used(fs.size(), 0);
  auto walk = [&](int first, int from_end) {
    FeatureCurve curve;
    int i = first, end = from_end;  // leave feature i through its vertex 1 − end
    while (true) {
      used[i] = 1;
      curve.features.push_back(i);
      const int v = feature_vertices(mesh, fs, i)[1 - end];
      const int next = partner[i][1 - end];
      if (next < 0) break;
      curve.joints.push_back(v);
      if (next == first) {
        curve.closed = true;
        break;
      }
      if (used[next]) break;
      i = next;
      end = feature_vertices(mesh, fs, i)[0] == v ? 0 : 1;
    }
    if (curve.features.size() >= 2) curves.push_back(std::move(curve));
  };
  for (int i = 0; i < fs.size(); ++i)
    if (!used[i] && (partner[i][0] < 0 || partner[i][1] < 0)) walk(i, partner[i][0] < 0 ? 0 : 1);
  for (int i = 0; i < fs.size(); ++i)
    if (!used[i]) walk(i, 0);
  if (!(corner_length > 0)) return curves;
  // Corners of the quad scale: a curve that turns by corner_turn or more within corner_length is
  // split there (see below which joint).
  std::vector<FeatureCurve> split;
  for (FeatureCurve& curve : curves) {
    const size_t nj = curve.joints.size();
    auto length = [&](size_t k) {
      const auto [a, b] = feature_vertices(mesh, fs, curve.features[k]);
      return (mesh.V.row(a) - mesh.V.row(b)).norm();
    };
    // Arc position and bend of each joint (joint k between features k and k + 1 mod n).
    std::vector<double> pos(nj), bend(nj);
    double s = 0;
    for (size_t k = 0; k < nj; ++k) {
      s += length(k);
      pos[k] = s;
      const int v = curve.joints[k];
      const auto other = [&](int i) {
        const auto [a, b] = feature_vertices(mesh, fs, i);
        return Eigen::Vector3d(mesh.V.row(a == v ? b : a) - mesh.V.row(v));
      };
      const Eigen::Vector3d a = other(curve.features[k]);
      const Eigen::Vector3d b = other(curve.features[(k + 1) % curve.features.size()]);
      bend[k] = std::numbers::pi - std::atan2(a.cross(b).norm(), a.dot(b));
    }
    const double total = s;  // a closed curve's joints include the last one
    auto distance = [&](size_t j, size_t k) {
      const double d = std::abs(pos[j] - pos[k]);
      return curve.closed ? std::min(d, total - d) : d;
    };
    // The turn within `reach` of joint k.
    auto turn_within = [&](size_t k, double reach) {
      double turn = 0;
      for (size_t j = 0; j < nj; ++j)
        if (distance(j, k) <= reach) turn += bend[j];
      return turn;
    };
    // The corner is the joint whose turn within a quarter of corner_length is largest among the
    // joints within half of it (the middle of a rounded corner; ties to the first joint).
    std::vector<double> score(nj);
    for (size_t k = 0; k < nj; ++k) score[k] = turn_within(k, corner_length / 4);
    std::vector<size_t> corners;
    for (size_t k = 0; k < nj; ++k) {
      if (!(turn_within(k, corner_length / 2) >= corner_turn)) continue;
      bool largest = true;
      for (size_t j = 0; j < nj && largest; ++j)
        if (j != k && distance(j, k) <= corner_length / 2 &&
            (score[j] > score[k] || (score[j] == score[k] && j < k)))
          largest = false;
      if (largest) corners.push_back(k);
    }
    if (corners.empty()) {
      split.push_back(std::move(curve));
      continue;
    }
    // Pieces between consecutive corners (a closed curve starts after its first corner).
    const size_t n = curve.features.size();
    std::vector<char> is_corner(nj, 0);
    for (const size_t k : corners) is_corner[k] = 1;
    const size_t first = curve.closed ? (corners.front() + 1) % n : 0;
    FeatureCurve piece;
    for (size_t t = 0; t < n; ++t) {
      const size_t k = (first + t) % n;
      piece.features.push_back(curve.features[k]);
      if (t + 1 == n || (k < nj && is_corner[k])) {
        if (piece.features.size() >= 2) split.push_back(std::move(piece));
        piece = FeatureCurve{};
      } else {
        piece.joints.push_back(curve.joints[k]);
      }
    }
  }
  return split;
}

std::vector<FeatureCurve> curves_at_acute_corners(const core::TriMesh& mesh, const FeatureSet& fs,
                                                  const std::vector<FeatureCurve>& curves,
                                                  double min_angle, double max_angle,
                                                  double max_bend) {
  const std::vector<std::vector<std::pair<int, int>>> at = features_at_vertices(mesh, fs);
  auto direction = [&](int from, int to) {
    return (Eigen::Vector3d(mesh.V.row(to)) - Eigen::Vector3d(mesh.V.row(from))).normalized();
  };
  auto angle = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::acos(std::clamp(a.dot(b), -1.0, 1.0));
  };
  std::vector<int> curve_of(fs.size(), -1);
  for (size_t c = 0; c < curves.size(); ++c)
    for (const int i : curves[c].features) curve_of[i] = static_cast<int>(c);
  std::vector<FeatureCurve> out;
  for (size_t c = 0; c < curves.size(); ++c) {
    const FeatureCurve& curve = curves[c];
    const size_t n = curve.features.size();
    if (curve.closed || n < 2 || curve.joints.size() + 1 != n) continue;
    // The curve's vertices in order: its first end, the joints, its last end.
    std::vector<int> path(n + 1);
    const auto first = feature_vertices(mesh, fs, curve.features.front());
    const auto last = feature_vertices(mesh, fs, curve.features.back());
    path.front() = first[0] == curve.joints.front() ? first[1] : first[0];
    path.back() = last[0] == curve.joints.back() ? last[1] : last[0];
    for (size_t k = 0; k + 1 < n; ++k) path[k + 1] = curve.joints[k];
    // Edges [lo, hi) of the curve to take: the straight run from each acute end.
    size_t lo = n, hi = 0;
    for (const bool at_front : {true, false}) {
      const int v = at_front ? path.front() : path.back();
      const int next = at_front ? path[1] : path[n - 1];
      const Eigen::Vector3d d = direction(v, next);
      const bool acute = std::any_of(at[v].begin(), at[v].end(), [&](const auto& feature) {
        const double a = angle(d, direction(v, feature.second));
        return curve_of[feature.first] != static_cast<int>(c) && a >= min_angle && a < max_angle;
      });
      if (!acute) continue;
      size_t k = 1;  // edges of the run
      while (k < n) {
        const size_t e = at_front ? k : n - 1 - k;  // edge e joins path[e] and path[e + 1]
        const Eigen::Vector3d de = at_front ? direction(path[e], path[e + 1]) : direction(path[e + 1], path[e]);
        if (angle(d, de) >= max_bend) break;
        ++k;
      }
      if (at_front) {
        lo = 0;
        hi = std::max(hi, k);
      } else {
        lo = std::min(lo, n - k);
        hi = n;
      }
    }
    if (hi < lo + 2) continue;  // nothing acute, or a single edge (labeled edge by edge anyway)
    FeatureCurve run;
    run.features.assign(curve.features.begin() + lo, curve.features.begin() + hi);
    run.joints.assign(curve.joints.begin() + lo, curve.joints.begin() + hi - 1);
    out.push_back(std::move(run));
  }
  return out;
}

std::vector<double> curve_turns(const core::TriMesh& mesh, const CutMesh& cut, const Eigen::VectorXd& x,
                                const FeatureSet& fs, const FeatureCurve& curve) {
  const auto& topo = cut.topo;
  const size_t n = curve.features.size();
  std::vector<double> psi(n, 0);
  auto edge_of = [&](int i) {
    const int h = fs.halfedge[i];
    return topo.face_edge(h / 3, h % 3);
  };
  for (size_t k = 0; k + 1 < n; ++k) {
    const int v = curve.joints[k];
    const int ea = edge_of(curve.features[k]), eb = edge_of(curve.features[k + 1]);
    // θ: from the outgoing direction of the previous feature at v to that of the next; a straight
    // continuation has θ = ±π, and the curve turns by θ ∓ π.
    double theta = fan_angle_ccw(mesh, cut, x, v, ea, eb);
    if (std::isnan(theta)) {
      const double back = fan_angle_ccw(mesh, cut, x, v, eb, ea);
      theta = std::isnan(back) ? back : -back;
    }
    psi[k + 1] = psi[k] + (theta > 0 ? theta - std::numbers::pi : theta + std::numbers::pi);
  }
  return psi;
}

CurveLabels label_curves(const core::TriMesh& mesh, const CutMesh& cut, const Eigen::VectorXd& x,
                         const FeatureSet& fs, const std::vector<FeatureCurve>& curves,
                         const std::vector<int>& label, double max_turn,
                         const std::function<bool(double)>& take) {
  CurveLabels out;
  out.label.assign(fs.size(), kUnlabeled);
  out.handled.assign(fs.size(), 0);
  auto length = [&](int i) {
    const auto [a, b] = feature_vertices(mesh, fs, i);
    return (mesh.V.row(a) - mesh.V.row(b)).norm();
  };
  for (const FeatureCurve& curve : curves) {
    const size_t n = curve.features.size();
    bool any_unlabeled = false;
    for (const int i : curve.features) any_unlabeled |= label[i] == kUnlabeled;
    if (!any_unlabeled) continue;
    const std::vector<double> psi = curve_turns(mesh, cut, x, fs, curve);
    std::vector<double> q(n);
    for (size_t k = 0; k < n; ++k) q[k] = feature_measure(cut, x, fs.halfedge[curve.features[k]]);
    // The target direction: that of the longest labeled run's axis, else from the grid of the
    // features' axes (their 4-fold mean), the one of least largest turn.
    double target = std::numeric_limits<double>::quiet_NaN();
    double held = 0;
    std::unordered_map<long long, double> held_by;  // target in quarter turns → labeled length
    Eigen::Vector2d fourfold = Eigen::Vector2d::Zero();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (size_t k = 0; k < n; ++k) {
      const int i = curve.features[k];
      if (!std::isfinite(psi[k])) continue;
      if (label[i] == 0 || label[i] == 1) {
        const double t = psi[k] + label_turn(q[k], label[i]);
        const long long key = std::llround(t / (std::numbers::pi / 2));
        if ((held_by[key] += length(i)) > held) {
          held = held_by[key];
          target = t;
        }
      } else if (label[i] == kUnlabeled) {
        const double g = 4 * (psi[k] - q[k] * std::numbers::pi / 2);
        fourfold += length(i) * Eigen::Vector2d(std::cos(g), std::sin(g));
        lo = std::min(lo, psi[k]);
        hi = std::max(hi, psi[k]);
      }
    }
    if (std::isnan(target)) {
      if (!(lo <= hi)) continue;
      const double quarter = std::numbers::pi / 2;
      const double grid = std::atan2(fourfold.y(), fourfold.x()) / 4;
      const double mid = (lo + hi) / 2;
      target = grid + quarter * std::round((mid - grid) / quarter);
    }
    for (size_t k = 0; k < n; ++k) {
      const int i = curve.features[k];
      if (label[i] != kUnlabeled || !std::isfinite(psi[k])) continue;
      const double turn = target - psi[k];
      if (!(std::abs(turn) < max_turn)) continue;
      out.handled[i] = 1;
      const long n_quarters = std::lround(q[k] + turn / (std::numbers::pi / 2));
      const int l = n_quarters % 2 == 0 ? 1 : 0;
      if (!take(std::abs(label_turn(q[k], l)) / (std::numbers::pi / 2))) continue;
      out.label[i] = l;
      out.taken.push_back(i);
    }
  }
  std::sort(out.taken.begin(), out.taken.end());
  return out;
}

double feature_rotation_angle(const CutMesh& cut, const Eigen::VectorXd& x, const FeatureSet& fs) {
  std::vector<Eigen::Vector2d> dir;
  std::vector<double> weight;
  Eigen::Vector2d fourfold = Eigen::Vector2d::Zero();
  for (const int h : fs.halfedge) {
    const Eigen::Vector2d e = edge_vector(cut, x, h);
    const double len = e.norm();
    if (!(len > 0)) continue;
    dir.push_back(e / len);
    weight.push_back(len);
    const double a = 4 * std::atan2(e.y(), e.x());
    fourfold += len * Eigen::Vector2d(std::cos(a), std::sin(a));
  }
  if (dir.empty()) return 0;
  const double phi = std::atan2(fourfold.y(), fourfold.x()) / 4;
  std::array<Eigen::Vector2d, 4> center;
  for (int k = 0; k < 4; ++k)
    center[k] = {std::cos(phi + k * std::numbers::pi / 2), std::sin(phi + k * std::numbers::pi / 2)};
  std::vector<int> group(dir.size(), 0);
  std::array<double, 4> mass{};
  for (int it = 0; it < kRotationIterations; ++it) {
    std::array<Eigen::Vector2d, 4> sum;
    for (auto& s : sum) s.setZero();
    mass.fill(0);
    for (size_t i = 0; i < dir.size(); ++i) {
      int best = 0;
      for (int k = 1; k < 4; ++k)
        if (dir[i].dot(center[k]) > dir[i].dot(center[best])) best = k;
      group[i] = best;
      sum[best] += weight[i] * dir[i];
      mass[best] += weight[i];
    }
    for (int k = 0; k < 4; ++k)
      if (sum[k].norm() > 0) center[k] = sum[k].normalized();
  }
  const int largest = static_cast<int>(std::max_element(mass.begin(), mass.end()) - mass.begin());
  return std::atan2(center[largest].y(), center[largest].x());
}

WedgeResolution resolve_wedge_conflicts(const core::TriMesh& mesh, const CutMesh& cut,
                                        const Eigen::VectorXd& x, const FeatureSet& fs,
                                        const std::vector<int>& label,
                                        const std::vector<char>& is_new, double max_ratio,
                                        double max_boundary_ratio) {
  const auto& topo = cut.topo;
  const int nv = mesh.n_vertices();
  std::vector<char> check(nv, 0);
  for (int i = 0; i < fs.size(); ++i)
    if (is_new[i] && (label[i] == 0 || label[i] == 1)) {
      const int h = fs.halfedge[i];
      check[mesh.F(h / 3, h % 3)] = check[mesh.F(h / 3, (h % 3 + 1) % 3)] = 1;
    }
  // A corner per vertex to start from: on a boundary, the corner whose outgoing half-edge is a
  // boundary half-edge (the first of its fan in counter-clockwise order).
  std::vector<int> start(nv, -1);
  for (int c = 0; c < 3 * mesh.n_faces(); ++c) {
    const int v = mesh.F(c / 3, c % 3);
    if (check[v] && (start[v] < 0 || topo.twin[c] < 0)) start[v] = c;
  }
  std::vector<int> lab = label;
  std::vector<double> measure(fs.size(), 0), delta(fs.size(), 0);
  // The turn that brings a labeled feature onto its axis: to the nearest quarter of its label's
  // parity (local estimation may have chosen the farther axis).
  auto turn = [&](int i, int l) { return label_turn(measure[i], l); };
  for (int i = 0; i < fs.size(); ++i) {
    measure[i] = feature_measure(cut, x, fs.halfedge[i]);
    delta[i] = turn(i, label[i]);
  }
  WedgeResolution out;
  std::vector<char> tried(fs.size(), 0);  // given the other axis once already
  struct Entry {
    double angle;    // unwrapped, from the fan's first outgoing edge
    double angle3d;  // the same on the surface
    int feature;
    int corner = 0;  // position in the fan (corners before it)
    bool boundary = false;  // the first or last edge of an open fan
  };
  auto corner_angle3d = [&](int c) {
    const Eigen::Vector3d p = mesh.V.row(mesh.F(c / 3, c % 3));
    const Eigen::Vector3d a = Eigen::Vector3d(mesh.V.row(mesh.F(c / 3, (c % 3 + 1) % 3))) - p;
    const Eigen::Vector3d b = Eigen::Vector3d(mesh.V.row(mesh.F(c / 3, (c % 3 + 2) % 3))) - p;
    return std::atan2(a.cross(b).norm(), a.dot(b));
  };
  struct Fan {
    int v;
    std::vector<Entry> entries;
    double total = 0, total3d = 0;
    bool closed = false;
  };
  std::vector<Fan> fans;
  for (int v = 0; v < nv; ++v) {
    if (start[v] < 0) continue;
    std::vector<Entry> fan;
    double total = 0, total3d = 0;
    bool closed = false;
    int c = start[v];
    for (int guard = 0; guard < 3 * mesh.n_faces(); ++guard) {
      fan.push_back({total, total3d, fs.edge_feature[topo.face_edge(c / 3, c % 3)]});
      total += corner_uv_angle(cut, x, c);
      total3d += corner_angle3d(c);
      const int next = topo.twin[prev_in_face(c)];
      if (next < 0) {
        fan.push_back({total, total3d, fs.edge_feature[topo.face_edge(c / 3, (c % 3 + 2) % 3)], 0, true});
        break;
      }
      if (next == start[v]) {
        closed = true;
        break;
      }
      c = next;
    }
    if (!closed && !fan.empty()) fan.front().boundary = true;
    fans.push_back({v, std::move(fan), total, total3d, closed});
  }
  // A victim of a conflict first gets the other axis (when that turns it by at most
  // kMaxRelabelTurn), then is disabled if it still conflicts; every fan is checked again until
  // none changes (each feature changes at most twice).
  for (bool any = true; any;) {
    any = false;
    for (const Fan& fn : fans) {
      const std::vector<Entry>& fan = fn.entries;
      const double total = fn.total, total3d = fn.total3d;
      const bool closed = fn.closed;
      for (bool changed = true; changed;) {
        changed = false;
        std::vector<Entry> on;
        for (size_t i = 0; i < fan.size(); ++i)
          if (fan[i].feature >= 0 && (lab[fan[i].feature] == 0 || lab[fan[i].feature] == 1)) {
            on.push_back(fan[i]);
            on.back().corner = static_cast<int>(i);
          }
        if (on.size() < 2) break;
        const size_t n_pairs = closed ? on.size() : on.size() - 1;
        const int n_corners = static_cast<int>(closed ? fan.size() : fan.size() - 1);
        for (size_t j = 0; j < n_pairs && !changed; ++j) {
          const Entry& a = on[j];
          const Entry& b = on[(j + 1) % on.size()];
          const double target_a = a.angle + delta[a.feature];
          const bool wraps = j + 1 == on.size();
          const double target_b = b.angle + (wraps ? total : 0) + delta[b.feature];
          const double gap = target_b - target_a;
          const double quarters = std::max(1.0, std::round(gap / (std::numbers::pi / 2)));
          const double gap3d = b.angle3d + (wraps ? total3d : 0) - a.angle3d;
          const double ratio = std::max(quarters * (std::numbers::pi / 2) / gap3d,
                                        gap3d / (quarters * (std::numbers::pi / 2)));
          // Each triangle corner of the wedge opens less than 180°.
          const int corners = b.corner + (wraps ? n_corners : 0) - a.corner;
          const double bound = a.boundary || b.boundary ? max_boundary_ratio : max_ratio;
          if (gap >= kMinWedge && ratio <= bound && quarters < 2 * corners) continue;
          int victim = -1;
          if (is_new[a.feature] && is_new[b.feature])
            victim = std::abs(delta[a.feature]) >= std::abs(delta[b.feature]) ? a.feature : b.feature;
          else if (is_new[a.feature])
            victim = a.feature;
          else if (is_new[b.feature])
            victim = b.feature;
          if (victim < 0 || a.feature == b.feature) continue;
          changed = any = true;
          // Where a curve continues almost straight, a conflict is where its label must switch
          // (a smooth curve turning past 45°): relabeling would only move the switch along it.
          const bool straight = std::abs(gap3d - std::numbers::pi) < kStraightContinuation;
          if (!tried[victim] && !straight) {
            tried[victim] = 1;
            const double other = turn(victim, 1 - lab[victim]);
            if (std::abs(other) <= kMaxRelabelTurn) {
              lab[victim] = 1 - lab[victim];
              delta[victim] = other;
              continue;
            }
          }
          lab[victim] = kDisabled;
          out.disabled.push_back(victim);
        }
      }
    }
  }
  std::sort(out.disabled.begin(), out.disabled.end());
  out.disabled.erase(std::unique(out.disabled.begin(), out.disabled.end()), out.disabled.end());
  for (int i = 0; i < fs.size(); ++i)
    if (tried[i] && lab[i] != label[i] && (lab[i] == 0 || lab[i] == 1)) out.relabeled.push_back(i);
  return out;
}

}  // namespace quadify::param
