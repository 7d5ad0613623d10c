#include <libquadex/extract_quads.h>

#include <libcore/predicates.h>
#include <libcore/topology.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

namespace quadify::quadex {
namespace {

// Integer UV points beyond this magnitude are refused: grid coordinates are stored as int and
// transitions add integer translations, which must not overflow (2^26 grid units is far beyond
// any useful quad density).
constexpr double kMaxUVMagnitude = 67108864.0;  // 2^26 grid units
// Mantissa bits kept for the dyadic UV grid: values and sums with integer translations stay
// exactly representable (53-bit mantissa, 3 bits of headroom for |t| ≤ 4·max|uv|).
constexpr int kDyadicMantissaBits = 50;
constexpr int kMaxDyadicFractionBits = 40;  // finer than any UV noise that matters (2^-40 units)
// Boundary vertices moved off an iso-line move by 2^this dyadic units (see
// unsnap_touching_boundary_vertices): far below any geometric scale, exact in double.
constexpr int kUnsnapDyadicUnitsLog2 = 4;
// A face cycle longer than this is not a cell of the quad layout but a tracing failure.
constexpr int kMaxFaceDegree = 1024;

struct IVec {
  int x = 0, y = 0;
  bool operator==(const IVec&) const = default;
};
IVec operator+(IVec a, IVec b) { return {a.x + b.x, a.y + b.y}; }
IVec operator-(IVec a, IVec b) { return {a.x - b.x, a.y - b.y}; }

// Axis directions by index: 0 = +u, 1 = +v, 2 = −u, 3 = −v. Rotating by r·90° adds r (mod 4);
// the left normal of d is d+1 and its reverse d+2.
constexpr std::array<IVec, 4> kDir = {IVec{1, 0}, IVec{0, 1}, IVec{-1, 0}, IVec{0, -1}};
inline int rot_dir(int d, int r) { return (d + r) & 3; }

IVec rotate(IVec p, int r) {
  switch (r & 3) {
    case 1: return {-p.y, p.x};
    case 2: return {-p.x, -p.y};
    case 3: return {p.y, -p.x};
    default: return p;
  }
}
Eigen::Vector2d rotate(const Eigen::Vector2d& p, int r) {
  switch (r & 3) {
    case 1: return {-p.y(), p.x()};
    case 2: return {-p.x(), -p.y()};
    case 3: return {p.y(), -p.x()};
    default: return p;
  }
}

// x ↦ R_90^r x + t, the transition between two charts.
struct Transform {
  int r = 0;
  IVec t;
  IVec apply(IVec p) const { return rotate(p, r) + t; }
  Eigen::Vector2d apply(const Eigen::Vector2d& p) const {
    return rotate(p, r) + Eigen::Vector2d(t.x, t.y);
  }
  bool is_identity() const { return (r & 3) == 0 && t.x == 0 && t.y == 0; }
};
// (a ∘ b)(x) = a(b(x)).
Transform compose(const Transform& a, const Transform& b) {
  return {(a.r + b.r) & 3, rotate(b.t, a.r) + a.t};
}
Transform inverse(const Transform& a) {
  const int r = (4 - (a.r & 3)) & 3;
  return {r, IVec{0, 0} - rotate(a.t, r)};
}

inline Eigen::Vector2d to_vec(IVec p) { return {p.x, p.y}; }
inline int sign(double a, double b) { return (a > b) - (a < b); }  // sign(a - b), exact

// sign of cross(y - x, kDir[a]): the first-order change of orient2d(x, y, ·) along kDir[a].
int cross_sign(const Eigen::Vector2d& x, const Eigen::Vector2d& y, int a) {
  switch (a) {
    case 0: return sign(x.y(), y.y());
    case 1: return sign(y.x(), x.x());
    case 2: return sign(y.y(), x.y());
    default: return sign(x.x(), y.x());
  }
}

// Sign of orient2d(x, y, P + ε·kDir[a] + ε²·kDir[b]) for infinitesimal ε > 0 (a ⟂ b). Never 0
// for a non-degenerate edge: the symbolic perturbation of every traced point.
int perturbed_orient(const Eigen::Vector2d& x, const Eigen::Vector2d& y, const Eigen::Vector2d& p,
                     int a, int b) {
  if (const int s = core::orient2d(x, y, p)) return s;
  if (const int s = cross_sign(x, y, a)) return s;
  return cross_sign(x, y, b);
}

// Side of vertex v relative to the iso-line through p with direction kDir[d], shifted by ε to
// its left: +1 left, −1 right (a vertex on the unshifted line is right of the shifted one).
int line_side(const Eigen::Vector2d& v, IVec p, int d) {
  int s = 0;
  switch (d) {
    case 0: s = sign(v.y(), p.y); break;
    case 1: s = sign(p.x, v.x()); break;
    case 2: s = sign(p.y, v.y()); break;
    default: s = sign(v.x(), p.x); break;
  }
  return s != 0 ? s : -1;
}

struct Key {
  int elem, x, y;
  bool operator==(const Key&) const = default;
};
struct KeyHash {
  size_t operator()(const Key& k) const {
    uint64_t h = static_cast<uint32_t>(k.elem);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<uint32_t>(k.x);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<uint32_t>(k.y);
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

enum class Where { kOutside, kFace, kEdge, kVertex };
struct Location {
  Where where = Where::kOutside;
  int k = -1;  // kEdge: half-edge 3f+k; kVertex: corner 3f+k
};

struct GridPoint {
  Where where;
  int elem;   // vertex id, owning half-edge, or face
  int face;   // chart in which p is given
  IVec p;
};

struct Slot {  // an outgoing quad half-edge: start point, start face chart, direction in it
  int grid, face, dir;
  IVec p;
};

class Extractor {
 public:
  Extractor(const core::UVMesh& map, const ExtractOptions& options, ExtractResult& result)
      : map_(map), opt_(options), res_(result), nf_(map.mesh.n_faces()) {}

  core::Status run() {
    if (auto s = validate_input(); !s.is_ok()) return s;
    if (auto s = compute_transitions(); !s.is_ok()) return s;
    if (auto s = build_fans_and_snap(); !s.is_ok()) return s;
    if (auto s = check_orientation(); !s.is_ok()) return s;
    if (auto s = check_cone_angles(); !s.is_ok()) return s;
    unsnap_touching_boundary_vertices();  // keeps every triangle positively oriented
    if (auto s = create_grid_points(); !s.is_ok()) return s;
    create_slots();
    if (auto s = trace_all(); !s.is_ok()) return s;
    return build_faces();
  }

 private:
  const Eigen::Vector2d& uv(int f, int k) const { return uv_[3 * f + k]; }

  std::string edge_name(int h) const {
    const int f = h / 3, k = h % 3;
    std::ostringstream os;
    os << "edge (" << map_.mesh.F(f, k) << ", " << map_.mesh.F(f, (k + 1) % 3) << ") of faces " << f;
    if (twin_[h] >= 0) os << " and " << twin_[h] / 3;
    return os.str();
  }

  core::Status validate_input() {
    const auto& mesh = map_.mesh;
    if (!(opt_.max_transition_residual >= 0) || !(opt_.max_cone_offset >= 0) ||
        !(opt_.integer_snap_tolerance >= 0) || !(opt_.integer_snap_tolerance < 0.5) ||
        opt_.max_grid_points < 0)
      return core::Status::invalid_input(
          "extract_quads: options out of range (tolerances must be ≥ 0, integer_snap_tolerance "
          "< 0.5, max_grid_points ≥ 0)");
    if (nf_ == 0) return core::Status::invalid_input("extract_quads: the mesh has no faces");
    if (map_.corner_uv.rows() != 3 * nf_)
      return core::Status::invalid_input("extract_quads: corner_uv has " +
                                         std::to_string(map_.corner_uv.rows()) + " rows, expected 3·#F = " +
                                         std::to_string(3 * nf_));
    for (int f = 0; f < nf_; ++f)
      for (int k = 0; k < 3; ++k) {
        const int v = mesh.F(f, k);
        if (v < 0 || v >= mesh.n_vertices())
          return core::Status::invalid_input("extract_quads: face " + std::to_string(f) +
                                             " has vertex id " + std::to_string(v) + " out of range");
        if (!mesh.V.row(v).allFinite() || !map_.corner_uv.row(3 * f + k).allFinite())
          return core::Status::invalid_input("extract_quads: non-finite position or UV at corner " +
                                             std::to_string(3 * f + k));
        if (mesh.F(f, k) == mesh.F(f, (k + 1) % 3))
          return core::Status::invalid_input("extract_quads: face " + std::to_string(f) +
                                             " repeats a vertex");
      }
    try {
      topo_ = core::build_edge_topology(mesh);
    } catch (const std::invalid_argument& e) {
      return core::Status::invalid_input(std::string("extract_quads: ") + e.what());
    }
    twin_ = topo_.twin;
    const Eigen::Vector2d lo = map_.corner_uv.colwise().minCoeff(), hi = map_.corner_uv.colwise().maxCoeff();
    uv_diag_ = (hi - lo).norm();
    max_abs_uv_ = map_.corner_uv.cwiseAbs().maxCoeff();
    if (!(uv_diag_ > 0)) return core::Status::invalid_input("extract_quads: all UVs coincide");
    if (max_abs_uv_ > kMaxUVMagnitude)
      return core::Status::invalid_input("extract_quads: |uv| = " + std::to_string(max_abs_uv_) +
                                         " exceeds the supported " + std::to_string(kMaxUVMagnitude));
    // Orientation on the raw map first, so a flip is reported as such and not as a bad seam.
    for (int f = 0; f < nf_; ++f) {
      const Eigen::Vector2d a = map_.corner_uv.row(3 * f), b = map_.corner_uv.row(3 * f + 1),
                            c = map_.corner_uv.row(3 * f + 2);
      if (core::orient2d(a, b, c) <= 0) return flip_status(f, a, b, c, "");
    }
    return core::Status::ok();
  }

  core::Status flip_status(int f, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                           const Eigen::Vector2d& c, const std::string& when) const {
    const double area2 = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    std::ostringstream os;
    os << "extract_quads: UV triangle of face " << f << " is "
       << (core::orient2d(a, b, c) < 0 ? "flipped" : "degenerate") << when << " (signed area "
       << 0.5 * area2 << ")";
    return core::Status::invalid_input(os.str());
  }

  // Per interior half-edge h, the transition from the chart of face(h) to that of face(twin h).
  core::Status compute_transitions() {
    trans_.assign(3 * nf_, Transform{});
    const double tol = opt_.max_transition_residual * uv_diag_;
    auto raw = [&](int c) { return Eigen::Vector2d(map_.corner_uv.row(c)); };
    for (int h = 0; h < 3 * nf_; ++h) {
      const int t = twin_[h];
      if (t < 0 || t < h) continue;
      const int f = h / 3, g = t / 3;
      const Eigen::Vector2d a = raw(h), b = raw(3 * f + (h % 3 + 1) % 3);
      const Eigen::Vector2d b2 = raw(t), a2 = raw(3 * g + (t % 3 + 1) % 3);
      int best_r = 0;
      double best_dot = -std::numeric_limits<double>::infinity();
      for (int r = 0; r < 4; ++r) {
        const double dot = rotate(Eigen::Vector2d(b - a), r).dot(b2 - a2);
        if (dot > best_dot) best_dot = dot, best_r = r;
      }
      const Eigen::Vector2d shift =
          0.5 * ((a2 - rotate(a, best_r)) + (b2 - rotate(b, best_r)));
      const Eigen::Vector2d rounded = shift.array().round();
      Transform tr{best_r, IVec{static_cast<int>(rounded.x()), static_cast<int>(rounded.y())}};
      const double residual =
          std::max((tr.apply(a) - a2).norm(), (tr.apply(b) - b2).norm());
      res_.stats.max_transition_residual = std::max(res_.stats.max_transition_residual, residual);
      if (!(residual <= tol)) {
        std::ostringstream os;
        os << "extract_quads: map is not integer-seamless across " << edge_name(h)
           << ": best transition (rotation " << 90 * best_r << "°, translation (" << shift.x() << ", "
           << shift.y() << ")) leaves residual " << residual << " > tolerance " << tol
           << " (max_transition_residual × UV diagonal)";
        return core::Status::invalid_input(os.str());
      }
      trans_[h] = tr;
      trans_[t] = inverse(tr);
      if (!tr.is_identity()) ++res_.stats.n_seam_edges;
    }
    return core::Status::ok();
  }

  // Next corner of the same vertex counter-clockwise (across the edge entering the vertex), or -1.
  int ccw_corner(int c) const { return twin_[3 * (c / 3) + (c % 3 + 2) % 3]; }
  int ccw_halfedge(int c) const { return 3 * (c / 3) + (c % 3 + 2) % 3; }
  int cw_corner(int c) const {
    const int t = twin_[c];
    return t < 0 ? -1 : 3 * (t / 3) + (t % 3 + 1) % 3;
  }

  double snap_coordinate(double x) const {
    const double nearest = std::round(x);
    if (std::abs(x - nearest) <= opt_.integer_snap_tolerance * uv_diag_) return nearest;
    return std::ldexp(std::nearbyint(std::ldexp(x, dyadic_bits_)), -dyadic_bits_);
  }

  // Orders the corners of each vertex counter-clockwise, checks holonomies (cones on integer
  // points, no translational holonomy), snaps the first corner's UV and propagates it to the
  // other corners through the transitions, so that transitions hold exactly afterwards.
  core::Status build_fans_and_snap() {
    const int nv = map_.mesh.n_vertices();
    const double m = std::max(1.0, 4.0 * max_abs_uv_ + 4.0);
    dyadic_bits_ = std::clamp(kDyadicMantissaBits - static_cast<int>(std::ceil(std::log2(m))), 0,
                              kMaxDyadicFractionBits);
    std::vector<int> n_corners(nv, 0);
    for (int c = 0; c < 3 * nf_; ++c) ++n_corners[map_.mesh.F(c / 3, c % 3)];
    fan_start_.assign(nv, -1);
    corner_chart_.assign(3 * nf_, Transform{});
    uv_.assign(3 * nf_, Eigen::Vector2d::Zero());
    const double cone_tol = opt_.max_cone_offset * uv_diag_;
    for (int c0 = 0; c0 < 3 * nf_; ++c0) {
      const int v = map_.mesh.F(c0 / 3, c0 % 3);
      if (fan_start_[v] >= 0) continue;
      // For a boundary vertex, start at the clockwise-most corner.
      int start = c0;
      for (int c = cw_corner(c0); c >= 0 && c != c0; c = cw_corner(c)) start = c;
      fan_start_[v] = start;
      std::vector<int> fan{start};
      Transform acc;
      bool closed = false;
      for (int c = start;;) {
        const int next = ccw_corner(c);
        if (next < 0) break;
        acc = compose(trans_[ccw_halfedge(c)], acc);
        if (next == start) {
          closed = true;
          break;
        }
        if (static_cast<int>(fan.size()) > n_corners[v]) break;
        corner_chart_[next] = acc;
        fan.push_back(next);
        c = next;
      }
      if (static_cast<int>(fan.size()) != n_corners[v])
        return core::Status::invalid_input("extract_quads: vertex " + std::to_string(v) +
                                           " is not manifold (its corners form more than one fan)");
      Eigen::Vector2d p(map_.corner_uv.row(start));
      if (closed && !acc.is_identity()) {
        if ((acc.r & 3) == 0) {
          std::ostringstream os;
          os << "extract_quads: interior vertex " << v << " has a translational holonomy ("
             << acc.t.x << ", " << acc.t.y << "): the seam transitions around it do not close";
          return core::Status::invalid_input(os.str());
        }
        const Eigen::Vector2d q = p.array().round();
        const IVec qi{static_cast<int>(q.x()), static_cast<int>(q.y())};
        if (!((p - q).norm() <= cone_tol) || !(acc.apply(qi) == qi)) {
          std::ostringstream os;
          os << "extract_quads: cone vertex " << v << " (holonomy " << 90 * acc.r
             << "°) is not on an integer point: uv (" << p.x() << ", " << p.y() << "), offset "
             << (p - q).norm() << ", tolerance " << cone_tol << " (max_cone_offset × UV diagonal)";
          return core::Status::invalid_input(os.str());
        }
        p = q;
        ++res_.stats.n_cones;
      } else {
        p = Eigen::Vector2d(snap_coordinate(p.x()), snap_coordinate(p.y()));
      }
      for (int c : fan) uv_[c] = corner_chart_[c].apply(p);
    }
    return core::Status::ok();
  }

  // An interior vertex whose UV angle sum is π/2 or less (cone index 3 or more) would be a quad
  // vertex of valence 1 or 0: no quad mesh has one, and the tracing cannot turn there.
  core::Status check_cone_angles() const {
    std::vector<double> angle(map_.mesh.n_vertices(), 0.0);
    for (int f = 0; f < nf_; ++f)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d a = uv(f, (k + 1) % 3) - uv(f, k), b = uv(f, (k + 2) % 3) - uv(f, k);
        angle[map_.mesh.F(f, k)] += std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
      }
    for (int v = 0; v < map_.mesh.n_vertices(); ++v) {
      const int c0 = fan_start_[v];
      if (c0 < 0 || twin_[c0] < 0) continue;  // unused or boundary vertex (fan from its border)
      if (angle[v] < 0.75 * std::numbers::pi) {
        const int index = static_cast<int>(std::lround(4 - angle[v] / (0.5 * std::numbers::pi)));
        return core::Status::invalid_input(
            "extract_quads: cone vertex " + std::to_string(v) + " has index " + std::to_string(index) +
            " (UV angle " + std::to_string(static_cast<int>(std::lround(angle[v] * 180 / std::numbers::pi))) +
            "°): it would be a quad vertex of valence " + std::to_string(4 - index) + ", which no quad mesh has");
      }
    }
    return core::Status::ok();
  }

  core::Status check_orientation() {
    long long n_points = 0;
    for (int f = 0; f < nf_; ++f) {
      if (core::orient2d(uv(f, 0), uv(f, 1), uv(f, 2)) <= 0)
        return flip_status(f, uv(f, 0), uv(f, 1), uv(f, 2), " after snapping UVs to exact values");
      const Eigen::Vector2d lo = uv(f, 0).cwiseMin(uv(f, 1)).cwiseMin(uv(f, 2));
      const Eigen::Vector2d hi = uv(f, 0).cwiseMax(uv(f, 1)).cwiseMax(uv(f, 2));
      n_points += static_cast<long long>(std::floor(hi.x()) - std::ceil(lo.x()) + 1) *
                  static_cast<long long>(std::floor(hi.y()) - std::ceil(lo.y()) + 1);
    }
    if (n_points > opt_.max_grid_points)
      return core::Status::invalid_input("extract_quads: the map's triangles span " +
                                         std::to_string(n_points) +
                                         " integer points, more than max_grid_points = " +
                                         std::to_string(opt_.max_grid_points));
    return core::Status::ok();
  }

  // Exact location of integer point p relative to the closed UV triangle of face f.
  Location locate(int f, IVec p) const {
    const Eigen::Vector2d q = to_vec(p);
    std::array<int, 3> s;
    for (int k = 0; k < 3; ++k) {
      s[k] = core::orient2d(uv(f, k), uv(f, (k + 1) % 3), q);
      if (s[k] < 0) return {};
    }
    const int n_zero = (s[0] == 0) + (s[1] == 0) + (s[2] == 0);
    if (n_zero == 0) return {Where::kFace, -1};
    if (n_zero == 1) return {Where::kEdge, s[0] == 0 ? 0 : s[1] == 0 ? 1 : 2};
    // Two zeros: p is the common vertex of the two edges, k+1 for edges k and k+1.
    for (int k = 0; k < 3; ++k)
      if (s[k] == 0 && s[(k + 1) % 3] == 0) return {Where::kVertex, (k + 1) % 3};
    return {};  // three zeros: impossible for a positively oriented triangle
  }

  // Is p + ε·kDir[a] + ε²·kDir[b] strictly inside the UV triangle of f?
  bool contains(int f, const Eigen::Vector2d& p, int a, int b) const {
    for (int k = 0; k < 3; ++k)
      if (perturbed_orient(uv(f, k), uv(f, (k + 1) % 3), p, a, b) < 0) return false;
    return true;
  }
  bool contains(int f, IVec p, int a, int b) const { return contains(f, to_vec(p), a, b); }

  // Is p + ε·kDir[a] + ε²·kDir[b] inside some face of the fan of boundary vertex v (p in the
  // fan-start chart, directions too)?
  bool fan_contains(int v, const Eigen::Vector2d& p, int a, int b) const {
    for (int c = fan_start_[v]; c >= 0; c = ccw_corner(c)) {
      const Transform& t = corner_chart_[c];
      if (contains(c / 3, t.apply(p), rot_dir(a, t.r), rot_dir(b, t.r))) return true;
    }
    return false;
  }

  // A boundary vertex exactly on an integer iso-line (one integer coordinate) where the line
  // continues into the interior on one side and along or into the mesh on the other: tracing
  // the line from its two ends with opposite symbolic offsets would disagree about where it
  // touches the boundary and crack the output. Such vertices (typically made by snapping) are
  // moved off the line by a few dyadic units, towards the side where the mesh surrounds them,
  // so that the line crosses the boundary right beside them; a side that flips a triangle is
  // not used.
  void unsnap_touching_boundary_vertices() {
    const double delta = std::ldexp(1.0, -std::max(0, dyadic_bits_ - kUnsnapDyadicUnitsLog2));
    const int nv = map_.mesh.n_vertices();
    for (int v = 0; v < nv; ++v) {
      const int c0 = fan_start_[v];
      if (c0 < 0 || twin_[c0] >= 0) continue;  // unused or interior vertex
      const Eigen::Vector2d p = uv_[c0];
      const bool u_int = p.x() == std::round(p.x()), v_int = p.y() == std::round(p.y());
      if (u_int == v_int) continue;
      const int d = u_int ? 1 : 0;  // direction of the iso-line through p
      auto inside_side = [&](int dir, int side) { return fan_contains(v, p, dir, side); };
      const int left = rot_dir(d, 1), right = rot_dir(d, 3), back = rot_dir(d, 2);
      const bool fwd_strict = inside_side(d, left) && inside_side(d, right);
      const bool back_strict = inside_side(back, left) && inside_side(back, right);
      const bool fwd_any = inside_side(d, left) || inside_side(d, right);
      const bool back_any = inside_side(back, left) || inside_side(back, right);
      if (!(fwd_any && back_any && (fwd_strict || back_strict))) continue;
      // Prefer the side whose half-disk around p lies in the mesh.
      const bool left_full = inside_side(d, left) && inside_side(left, d) && inside_side(back, left);
      std::array<int, 2> sides = left_full ? std::array<int, 2>{left, right} : std::array<int, 2>{right, left};
      for (int side : sides) {
        const Eigen::Vector2d q = p + delta * to_vec(kDir[side]);
        bool flips = false;
        for (int c = c0; c >= 0 && !flips; c = ccw_corner(c)) {
          const int f = c / 3, k = c % 3;
          const Eigen::Vector2d qc = corner_chart_[c].apply(q);
          flips = core::orient2d(k == 0 ? qc : uv(f, 0), k == 1 ? qc : uv(f, 1), k == 2 ? qc : uv(f, 2)) <= 0;
        }
        if (flips) continue;
        for (int c = c0; c >= 0; c = ccw_corner(c)) uv_[c] = corner_chart_[c].apply(q);
        ++res_.stats.n_unsnapped_boundary_vertices;
        break;
      }
    }
  }

  core::Status create_grid_points() {
    for (int f = 0; f < nf_; ++f) {
      const Eigen::Vector2d lo = uv(f, 0).cwiseMin(uv(f, 1)).cwiseMin(uv(f, 2));
      const Eigen::Vector2d hi = uv(f, 0).cwiseMax(uv(f, 1)).cwiseMax(uv(f, 2));
      for (int y = static_cast<int>(std::ceil(lo.y())); y <= static_cast<int>(std::floor(hi.y())); ++y)
        for (int x = static_cast<int>(std::ceil(lo.x())); x <= static_cast<int>(std::floor(hi.x())); ++x) {
          const IVec p{x, y};
          const Location loc = locate(f, p);
          switch (loc.where) {
            case Where::kOutside: break;
            case Where::kFace:
              add_grid_point({Where::kFace, f, f, p}, Key{f, x, y});
              break;
            case Where::kEdge: {
              const int h = 3 * f + loc.k;
              if (twin_[h] < 0 || h < twin_[h]) add_grid_point({Where::kEdge, h, f, p}, Key{nf_ + h, x, y});
              break;
            }
            case Where::kVertex: {
              const int v = map_.mesh.F(f, loc.k);
              if (fan_start_[v] == 3 * f + loc.k) {
                vertex_grid_.emplace(v, static_cast<int>(grid_.size()));
                grid_.push_back({Where::kVertex, v, f, p});
              }
              break;
            }
          }
        }
    }
    return core::Status::ok();
  }

  void add_grid_point(const GridPoint& g, const Key& key) {
    grid_key_.emplace(key, static_cast<int>(grid_.size()));
    grid_.push_back(g);
  }

  // Grid point at integer p of the closed triangle f (with location loc), or -1.
  int find_grid(int f, IVec p, const Location& loc) const {
    switch (loc.where) {
      case Where::kFace: {
        auto it = grid_key_.find(Key{f, p.x, p.y});
        return it == grid_key_.end() ? -1 : it->second;
      }
      case Where::kEdge: {
        int h = 3 * f + loc.k;
        if (twin_[h] >= 0 && twin_[h] < h) {
          p = trans_[h].apply(p);
          h = twin_[h];
        }
        auto it = grid_key_.find(Key{nf_ + h, p.x, p.y});
        return it == grid_key_.end() ? -1 : it->second;
      }
      case Where::kVertex: {
        auto it = vertex_grid_.find(map_.mesh.F(f, loc.k));
        return it == vertex_grid_.end() ? -1 : it->second;
      }
      default: return -1;
    }
  }

  // Charts around a grid point: (face, the point in that face's chart).
  void incident_charts(const GridPoint& g, std::vector<std::pair<int, IVec>>& out) const {
    out.clear();
    if (g.where == Where::kFace) {
      out.push_back({g.face, g.p});
    } else if (g.where == Where::kEdge) {
      out.push_back({g.face, g.p});
      if (twin_[g.elem] >= 0) out.push_back({twin_[g.elem] / 3, trans_[g.elem].apply(g.p)});
    } else {
      const int start = fan_start_[g.elem];
      for (int c = start;;) {
        // corner_chart_ maps the start corner's chart to c's; p is given in the start chart.
        out.push_back({c / 3, corner_chart_[c].apply(g.p)});
        c = ccw_corner(c);
        if (c < 0 || c == start) break;
      }
    }
  }

  // The outgoing quad half-edges ("slots") of every grid point: in each incident face's chart,
  // the directions d with p + ε·d + ε²·left(d) inside the face. Exactly one face qualifies per
  // direction at a regular point; a cone of angle kπ/2 gets k slots; at the boundary, only
  // directions pointing into the mesh (or along it with the mesh on their left) qualify.
  void create_slots() {
    slot_begin_.assign(grid_.size() + 1, 0);
    std::vector<std::pair<int, IVec>> charts;
    for (size_t g = 0; g < grid_.size(); ++g) {
      incident_charts(grid_[g], charts);
      for (const auto& [f, p] : charts)
        for (int d = 0; d < 4; ++d)
          if (contains(f, p, d, rot_dir(d, 1))) slots_.push_back({static_cast<int>(g), f, d, p});
      slot_begin_[g + 1] = static_cast<int>(slots_.size());
    }
  }

  // Walking clockwise around the element of integer point p of face f (location loc), starting
  // with f: the first face containing p + ε·kDir[a] + ε²·kDir[b] and the transform from f's
  // chart to it; {-1, ·} when the walk reaches the boundary first. Clockwise only: around a
  // cone of angle > 2π the same chart direction occurs twice, and the wanted copy is the one
  // less than π/2 clockwise of the start.
  std::pair<int, Transform> locate_cw(int f, IVec p, const Location& loc, int a, int b) const {
    if (contains(f, p, a, b)) return {f, Transform{}};
    if (loc.where == Where::kEdge) {
      const int h = 3 * f + loc.k;
      if (twin_[h] < 0) return {-1, {}};
      const Transform& t = trans_[h];
      const int g = twin_[h] / 3;
      if (contains(g, t.apply(p), rot_dir(a, t.r), rot_dir(b, t.r))) return {g, t};
      return {-1, {}};
    }
    if (loc.where != Where::kVertex) return {-1, {}};
    // Around a cone the walk comes back to f turned by the holonomy: at a cone of index 2 (UV
    // angle π) the quarter turn left of an arriving iso-line lies in f itself, seen once around
    // (octopus with thin-part sizing), so f is tried again after the full turn.
    const int c0 = 3 * f + loc.k;
    Transform acc;
    for (int c = c0;;) {
      const int next = cw_corner(c);
      if (next < 0) break;
      acc = compose(trans_[c], acc);  // crossing the edge leaving the vertex in face(c)
      if (contains(next / 3, acc.apply(p), rot_dir(a, acc.r), rot_dir(b, acc.r))) return {next / 3, acc};
      if (next == c0) break;
      c = next;
    }
    return {-1, {}};
  }

  // Outgoing slot of grid point g with start face `face` and direction `dir`, or -1.
  int find_slot(int g, int face, int dir) const {
    for (int n = slot_begin_[g]; n < slot_begin_[g + 1]; ++n)
      if (slots_[n].face == face && slots_[n].dir == dir) return n;
    return -1;
  }

  // The counter-clockwise-most slot of grid point g starting in face `face` (its slot directions
  // there are consecutive, spanning less than 2π), or -1.
  int ccw_most_slot(int g, int face) const {
    int mask = 0;
    for (int n = slot_begin_[g]; n < slot_begin_[g + 1]; ++n)
      if (slots_[n].face == face) mask |= 1 << slots_[n].dir;
    for (int d = 0; d < 4; ++d)
      if ((mask >> d & 1) && !(mask >> rot_dir(d, 1) & 1)) return find_slot(g, face, d);
    return -1;
  }

  int add_halfedge(int vertex, int face, const Eigen::Vector2d& uv) {
    he_vertex_.push_back(vertex);
    he_face_.push_back(face);
    he_uv_.push_back(uv);
    he_next_.push_back(-1);
    he_to_next_.push_back(Transform{});
    return static_cast<int>(he_vertex_.size()) - 1;
  }

  // An event on a boundary half-edge: the crossing of a (left-perturbed) iso-line
  // {x[axis] = value + σε}, or a grid point exactly on the edge. Events are the boundary
  // vertices of the quad mesh between the triangle-mesh vertices.
  struct BoundaryEvent {
    bool is_line;
    int axis, value, sigma;  // line: coordinate axis (0 = u, 1 = v), integer value, offset sign
    IVec p;                  // point
    int vertex;              // output vertex id
  };

  // Is event x before event y walking along the boundary half-edge h? Exact.
  bool event_before(int h, const BoundaryEvent& x, const BoundaryEvent& y) const {
    const Eigen::Vector2d& a = uv_[h];
    const Eigen::Vector2d& b = uv_[3 * (h / 3) + (h % 3 + 1) % 3];
    const int su = sign(b.x(), a.x()), sv = sign(b.y(), a.y());
    const int s_axis[2] = {su, sv};
    auto coord = [](IVec p, int axis) { return axis == 0 ? p.x : p.y; };
    if (!x.is_line && !y.is_line) {
      const int axis = su != 0 ? 0 : 1;
      return s_axis[axis] * (coord(y.p, axis) - coord(x.p, axis)) > 0;
    }
    if (x.is_line && !y.is_line) {  // line before point ⟺ the point is past the line
      const int diff = coord(y.p, x.axis) - x.value;
      return s_axis[x.axis] * (diff != 0 ? (diff > 0 ? 1 : -1) : -x.sigma) > 0;
    }
    if (!x.is_line && y.is_line) return !event_before(h, y, x);
    if (x.axis == y.axis) {
      const int diff = x.value != y.value ? (x.value < y.value ? -1 : 1) : (x.sigma < y.sigma ? -1 : 1);
      return s_axis[x.axis] * diff < 0;
    }
    // Lines of both families: compare through their common integer point P.
    const BoundaryEvent& lu = x.axis == 0 ? x : y;
    const BoundaryEvent& lv = x.axis == 0 ? y : x;
    int o = core::orient2d(a, b, Eigen::Vector2d(lu.value, lv.value));
    // P on the edge's line: the offsets decide, sign of cross(b - a, (σ_u, σ_v)). The
    // differences are exact on the dyadic UV grid, so the comparison is exact too.
    if (o == 0) o = sign((b.x() - a.x()) * lv.sigma, (b.y() - a.y()) * lu.sigma);
    const bool u_first = su * sv * o > 0;
    return (x.axis == 0) == u_first;
  }

  // Traces the iso-line of every slot to the next grid point (or to the boundary) and links
  // every quad half-edge to the next one of its face (turn left at its end).
  core::Status trace_all() {
    const int n_slots = static_cast<int>(slots_.size());
    for (int s = 0; s < n_slots; ++s) add_halfedge(slots_[s].grid, slots_[s].face, to_vec(slots_[s].p));
    boundary_events_.clear();
    n_out_vertices_ = static_cast<int>(grid_.size());
    const int max_steps = 2 * nf_ + 8;  // a trace never visits a face twice on a valid map
    struct Dangling { int slot, exit_halfedge, event_vertex; Transform acc; };
    std::vector<Dangling> dangling;
    for (int s = 0; s < n_slots; ++s) {
      int f = slots_[s].face, d = slots_[s].dir;
      IVec p = slots_[s].p, q = p + kDir[d];
      Transform acc;
      int exit_halfedge = -1;
      for (int step = 0;; ++step) {
        if (step == max_steps)
          return core::Status::internal("extract_quads: iso-line trace from grid point " +
                                        std::to_string(slots_[s].grid) + " does not terminate");
        if (contains(f, q, rot_dir(d, 2), rot_dir(d, 1))) break;
        int exit = -1;
        for (int k = 0; k < 3 && exit < 0; ++k)
          if (line_side(uv(f, k), p, d) < 0 && line_side(uv(f, (k + 1) % 3), p, d) > 0) exit = k;
        if (exit < 0)
          return core::Status::internal("extract_quads: iso-line trace from grid point " +
                                        std::to_string(slots_[s].grid) + " lost in face " +
                                        std::to_string(f));
        const int h = 3 * f + exit;
        if (twin_[h] < 0) {
          exit_halfedge = h;
          break;
        }
        const Transform& t = trans_[h];
        p = t.apply(p);
        q = t.apply(q);
        d = rot_dir(d, t.r);
        acc = compose(t, acc);
        f = twin_[h] / 3;
      }
      if (exit_halfedge >= 0) {
        // The iso-line leaves the mesh: a new boundary vertex where it crosses the edge.
        const int axis = (d & 1) ? 0 : 1;  // ±u lines are v = const and vice versa
        const int value = axis == 0 ? p.x : p.y;
        const int sigma = (d == 0 || d == 3) ? 1 : -1;  // side of the left offset along the axis
        BoundaryEvent ev{true, axis, value, sigma, IVec{}, n_out_vertices_++};
        boundary_events_[exit_halfedge].push_back(ev);
        const Eigen::Vector2d& a = uv_[exit_halfedge];
        const Eigen::Vector2d& b = uv_[3 * f + (exit_halfedge % 3 + 1) % 3];
        const double t = std::clamp((value - a[axis]) / (b[axis] - a[axis]), 0.0, 1.0);
        const Eigen::Vector2d x = a + t * (b - a);
        extra_uv_.push_back(x);
        const auto& F = map_.mesh.F;
        extra_pos_.push_back((1 - t) * map_.mesh.V.row(F(f, exit_halfedge % 3)).transpose() +
                             t * map_.mesh.V.row(F(f, (exit_halfedge % 3 + 1) % 3)).transpose());
        extra_face_.push_back(f);
        dangling.push_back({s, exit_halfedge, ev.vertex, acc});
        ++res_.stats.n_boundary_crossings;
        continue;
      }
      const Location loc = locate(f, q);
      const int end = find_grid(f, q, loc);
      if (end < 0)
        return core::Status::internal("extract_quads: iso-line from grid point " +
                                      std::to_string(slots_[s].grid) + " ends at an unregistered point");
      // Turn left at the end: direction d+1, starting just beside it (towards the incoming line).
      const auto [g, to_g] = locate_cw(f, q, loc, rot_dir(d, 1), rot_dir(d, 2));
      if (g >= 0) {
        he_next_[s] = find_slot(end, g, rot_dir(d, 1 + to_g.r));
        if (he_next_[s] < 0)
          return core::Status::internal("extract_quads: no outgoing iso-line at grid point " +
                                        std::to_string(end) + " to turn into");
        he_to_next_[s] = compose(to_g, acc);
      } else {
        pending_boundary_.push_back({s, end, f, q, loc, acc});
      }
    }
    // Boundary events of grid points inside boundary edges, then every edge's events in order.
    for (size_t g = 0; g < grid_.size(); ++g)
      if (grid_[g].where == Where::kEdge && twin_[grid_[g].elem] < 0)
        boundary_events_[grid_[g].elem].push_back(
            BoundaryEvent{false, 0, 0, 0, grid_[g].p, static_cast<int>(g)});
    for (auto& [h, events] : boundary_events_) {
      std::sort(events.begin(), events.end(), [&, hh = h](const BoundaryEvent& x, const BoundaryEvent& y) {
        return event_before(hh, x, y);
      });
      for (size_t i = 0; i < events.size(); ++i) event_position_[events[i].vertex] = {h, static_cast<int>(i)};
    }
    // Iso-lines ending on the boundary: their reverse starts there and turns left at the start
    // grid point; the trace itself continues along the boundary.
    for (const Dangling& dg : dangling) {
      const Slot& sl = slots_[dg.slot];
      he_to_next_[dg.slot] = dg.acc;
      he_next_[dg.slot] = boundary_halfedge(dg.event_vertex);
      const Location loc = locate(sl.face, sl.p);
      // No reverse when the iso-line runs along the boundary (outside just right of its start).
      if (locate_cw(sl.face, sl.p, loc, sl.dir, rot_dir(sl.dir, 3)).first < 0) continue;
      const int f_exit = dg.exit_halfedge / 3;
      const int rev = add_halfedge(dg.event_vertex, f_exit, extra_uv_[dg.event_vertex - grid_.size()]);
      reverse_of_vertex_[dg.event_vertex] = rev;
      // Arriving at the start point along −dir; turn left: direction −(dir+1).
      const auto [g, to_g] = locate_cw(sl.face, sl.p, loc, rot_dir(sl.dir, 3), sl.dir);
      const Transform back = inverse(dg.acc);  // exit chart → start chart
      if (g >= 0) {
        he_next_[rev] = find_slot(sl.grid, g, rot_dir(sl.dir, 3 + to_g.r));
        if (he_next_[rev] < 0)
          return core::Status::internal("extract_quads: no outgoing iso-line at grid point " +
                                        std::to_string(sl.grid) + " to turn into");
        he_to_next_[rev] = compose(to_g, back);
      } else {
        pending_boundary_.push_back({rev, sl.grid, sl.face, sl.p, loc, back});
      }
    }
    // Iso-lines arriving at a boundary grid point with no face to their left turn onto the boundary.
    for (const PendingBoundary& pb : pending_boundary_) {
      const Transform to_boundary_chart = cw_most(pb.face, pb.loc).second;
      he_next_[pb.halfedge] = boundary_halfedge(pb.grid);
      he_to_next_[pb.halfedge] = compose(to_boundary_chart, pb.acc);
    }
    // Boundary half-edges (created on demand; creating one may require the next).
    for (size_t i = 0; i < boundary_work_.size(); ++i) {
      if (auto s = link_boundary_halfedge(boundary_work_[i]); !s.is_ok()) return s;
    }
    return core::Status::ok();
  }

  // The clockwise-most face around the element of a point of face f on the boundary, and the
  // transform from f's chart to it.
  std::pair<int, Transform> cw_most(int f, const Location& loc) const {
    if (loc.where != Where::kVertex) return {f, Transform{}};
    Transform acc;
    int c = 3 * f + loc.k;
    for (int next = cw_corner(c); next >= 0 && next != 3 * f + loc.k; next = cw_corner(c)) {
      acc = compose(trans_[c], acc);
      c = next;
    }
    return {c / 3, acc};
  }

  // Quad half-edge along the boundary starting at boundary vertex `vertex` (created on demand).
  int boundary_halfedge(int vertex) {
    if (auto it = boundary_he_.find(vertex); it != boundary_he_.end()) return it->second;
    int face;
    Eigen::Vector2d start_uv;
    if (vertex >= static_cast<int>(grid_.size())) {
      face = event_position_.at(vertex).first / 3;
      start_uv = extra_uv_[vertex - grid_.size()];
    } else if (grid_[vertex].where == Where::kVertex) {
      const int c = fan_start_[grid_[vertex].elem];
      face = c / 3;
      start_uv = uv_[c];
    } else {
      face = grid_[vertex].face;
      start_uv = to_vec(grid_[vertex].p);
    }
    const int h = add_halfedge(vertex, face, start_uv);
    boundary_he_.emplace(vertex, h);
    boundary_work_.push_back(h);
    return h;
  }

  // Walks forward along the boundary from the start of boundary half-edge he to the next
  // boundary vertex, and links he to the half-edge that leaves it with the face on its left.
  core::Status link_boundary_halfedge(int he) {
    const int vertex = he_vertex_[he];
    int h, index;  // current boundary half-edge of the triangle mesh and event index on it
    if (vertex >= static_cast<int>(grid_.size()) || grid_[vertex].where == Where::kEdge) {
      std::tie(h, index) = event_position_.at(vertex);
    } else {
      h = fan_start_[grid_[vertex].elem];
      index = -1;
    }
    Transform acc;  // start chart → chart of face(h)
    for (int step = 0; step <= 3 * nf_; ++step) {
      const auto it = boundary_events_.find(h);
      if (it != boundary_events_.end() && index + 1 < static_cast<int>(it->second.size())) {
        const BoundaryEvent& ev = it->second[index + 1];
        if (ev.is_line) {
          const auto rev = reverse_of_vertex_.find(ev.vertex);
          if (rev == reverse_of_vertex_.end())
            return core::Status::internal("extract_quads: the boundary reaches crossing vertex " +
                                          std::to_string(ev.vertex) + " whose iso-line has no inward half-edge");
          he_next_[he] = rev->second;
          he_to_next_[he] = acc;
        } else {
          const int slot = ccw_most_slot(ev.vertex, h / 3);
          he_next_[he] = slot >= 0 ? slot : boundary_halfedge(ev.vertex);
          he_to_next_[he] = acc;
        }
        return core::Status::ok();
      }
      // Past the last event: the head vertex of h.
      const int c_head = 3 * (h / 3) + (h % 3 + 1) % 3;
      const int v = map_.mesh.F(c_head / 3, c_head % 3);
      if (auto git = vertex_grid_.find(v); git != vertex_grid_.end()) {
        // Clockwise around v from the counter-clockwise-most face: the first outgoing slot.
        Transform around = acc;
        for (int c = c_head; c >= 0; c = cw_corner(c)) {
          const int slot = ccw_most_slot(git->second, c / 3);
          if (slot >= 0) {
            he_next_[he] = slot;
            he_to_next_[he] = around;
            return core::Status::ok();
          }
          if (cw_corner(c) >= 0) around = compose(trans_[c], around);
        }
        he_next_[he] = boundary_halfedge(git->second);
        he_to_next_[he] = around;
        return core::Status::ok();
      }
      // No boundary vertex at v: continue on the boundary half-edge leaving v.
      const int c_next = fan_start_[v];
      acc = compose(inverse(corner_chart_[c_head]), acc);
      h = c_next;
      index = -1;
    }
    return core::Status::internal("extract_quads: boundary walk from vertex " + std::to_string(vertex) +
                                  " does not terminate");
  }

  core::Status build_faces() {
    auto& quads = res_.quads;
    quads = core::PolyMesh{};
    const auto& V = map_.mesh.V;
    quads.V.resize(n_out_vertices_, 3);
    res_.vertex_face.assign(n_out_vertices_, -1);
    for (size_t i = 0; i < extra_face_.size(); ++i) res_.vertex_face[grid_.size() + i] = extra_face_[i];
    for (size_t i = 0; i < grid_.size(); ++i) {
      const GridPoint& g = grid_[i];
      res_.vertex_face[i] = g.face;
      if (g.where == Where::kVertex) {
        quads.V.row(i) = V.row(g.elem);
        ++res_.stats.n_grid_points_on_vertices;
        continue;
      }
      (g.where == Where::kEdge ? res_.stats.n_grid_points_on_edges : res_.stats.n_grid_points_in_faces)++;
      // Barycentric coordinates of p in the UV triangle (positions only: no sign decision).
      const Eigen::Vector2d p = to_vec(g.p), a = uv(g.face, 0), b = uv(g.face, 1), c = uv(g.face, 2);
      auto area = [](const Eigen::Vector2d& x, const Eigen::Vector2d& y, const Eigen::Vector2d& z) {
        return (y - x).x() * (z - x).y() - (y - x).y() * (z - x).x();
      };
      const double total = area(a, b, c);
      const double la = area(p, b, c) / total, lb = area(a, p, c) / total;
      const auto& F = map_.mesh.F;
      quads.V.row(i) = la * V.row(F(g.face, 0)) + lb * V.row(F(g.face, 1)) +
                       (1.0 - la - lb) * V.row(F(g.face, 2));
    }
    for (size_t i = 0; i < extra_pos_.size(); ++i) quads.V.row(grid_.size() + i) = extra_pos_[i];
    const int n_he = static_cast<int>(he_vertex_.size());
    std::vector<char> visited(n_he, 0);
    std::vector<int> cycle;
    std::vector<double> face_uv_rows;
    for (int s0 = 0; s0 < n_he; ++s0) {
      if (visited[s0]) continue;
      cycle.clear();
      bool closed = false;
      for (int s = s0; s >= 0 && !visited[s] && static_cast<int>(cycle.size()) <= kMaxFaceDegree;
           s = he_next_[s]) {
        visited[s] = 1;
        cycle.push_back(s);
        if (he_next_[s] == s0) closed = true;
      }
      if (!closed) {
        ++res_.stats.n_dropped_faces;
        continue;
      }
      std::vector<int> verts, uvs;
      for (int s : cycle) verts.push_back(he_vertex_[s]);
      {
        // A sliver between an iso-line and the boundary can close with two distinct vertices
        // (seen on shark_b): no face; its two edges become one, which keeps the mesh manifold.
        std::vector<int> distinct = verts;
        std::sort(distinct.begin(), distinct.end());
        if (std::unique(distinct.begin(), distinct.end()) - distinct.begin() < 3) {
          ++res_.stats.n_dropped_faces;
          continue;
        }
      }
      Transform to_current;  // chart of the first corner → chart of the current corner
      for (int s : cycle) {
        if (opt_.output_uv) {
          const Eigen::Vector2d p = inverse(to_current).apply(he_uv_[s]);
          uvs.push_back(static_cast<int>(face_uv_rows.size() / 2));
          face_uv_rows.push_back(p.x());
          face_uv_rows.push_back(p.y());
        }
        to_current = compose(he_to_next_[s], to_current);
      }
      quads.add_face(verts, uvs);
      if (verts.size() != 4) ++res_.stats.n_non_quads;
    }
    if (opt_.output_uv) {
      quads.uv.resize(static_cast<int>(face_uv_rows.size() / 2), 2);
      for (size_t i = 0; i < face_uv_rows.size() / 2; ++i)
        quads.uv.row(i) << face_uv_rows[2 * i], face_uv_rows[2 * i + 1];
    }
    res_.stats.n_vertices = quads.n_vertices();
    res_.stats.n_faces = quads.n_faces();
    return core::Status::ok();
  }

  struct PendingBoundary {  // a half-edge ending at a boundary grid point, no face to its left
    int halfedge, grid, face;
    IVec p;
    Location loc;
    Transform acc;  // start chart of the half-edge → chart of `face`
  };

  const core::UVMesh& map_;
  const ExtractOptions& opt_;
  ExtractResult& res_;
  const int nf_;
  core::EdgeTopology topo_;
  std::vector<int> twin_;
  double uv_diag_ = 0, max_abs_uv_ = 0;
  int dyadic_bits_ = 0;
  std::vector<Transform> trans_;         // per half-edge: chart of its face → chart of the twin's
  std::vector<int> fan_start_;           // per vertex: first corner of its CCW fan
  std::vector<Transform> corner_chart_;  // per corner: fan-start chart → this corner's chart
  std::vector<Eigen::Vector2d> uv_;      // per corner, snapped so transitions hold exactly
  std::vector<GridPoint> grid_;
  std::unordered_map<Key, int, KeyHash> grid_key_;  // face / owning-edge points
  std::unordered_map<int, int> vertex_grid_;        // vertex id → grid point
  std::vector<Slot> slots_;                         // outgoing iso-lines = first quad half-edges
  std::vector<int> slot_begin_;                     // per grid point, CSR into slots_
  // Quad half-edges: slots first, then reverses of iso-lines that end on the boundary and
  // half-edges along the boundary. Start vertex, start chart (face) and UV there, next in face.
  std::vector<int> he_vertex_, he_face_, he_next_;
  std::vector<Eigen::Vector2d> he_uv_;
  std::vector<Transform> he_to_next_;  // start chart of a half-edge → start chart of its next
  int n_out_vertices_ = 0;             // grid points, then boundary crossings
  std::vector<Eigen::Vector2d> extra_uv_;  // per boundary crossing: UV in its edge's face chart
  std::vector<Eigen::Vector3d> extra_pos_;
  std::vector<int> extra_face_;  // the face of each boundary crossing
  std::unordered_map<int, std::vector<BoundaryEvent>> boundary_events_;  // boundary half-edge →
  std::unordered_map<int, std::pair<int, int>> event_position_;  // vertex → (half-edge, index)
  std::unordered_map<int, int> reverse_of_vertex_;  // crossing vertex → half-edge leaving inwards
  std::unordered_map<int, int> boundary_he_;        // boundary vertex → boundary half-edge
  std::vector<int> boundary_work_;
  std::vector<PendingBoundary> pending_boundary_;
};

}  // namespace

ExtractResult extract_quads(const core::UVMesh& map, const ExtractOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  ExtractResult result;
  Extractor extractor(map, options, result);
  result.status = extractor.run();
  if (!result.status.is_ok()) result.quads = core::PolyMesh{};
  result.stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace quadify::quadex
