#include "render_svg.h"

#include <libcore/topology.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <unordered_map>

namespace quadify::cli {
using core::edge_key;
namespace {

constexpr double kAzimuthDeg = 30;    // turn about the vertical, from the face-on view
constexpr double kElevationDeg = 25;  // tilt, looking down on the model
constexpr double kFill = 0.92;        // share of the picture the bbox projection may fill
constexpr double kAmbient = 0.35;     // Lambert: ambient + (1 - ambient)·max(0, n·l)
// A highlighted point counts as visible when no surface lies nearer than this (× bbox diagonal)
// in front of it: a remesher may cut a crease by about its Hausdorff distance (~1%).
constexpr double kDepthTolerance = 0.015;
constexpr double kHighlightStep = 0.75;  // pixels between visibility samples of a highlighted edge

// #rrggbb of an RGB colour in [0, 1].
std::string hex_colour(const Eigen::Vector3d& rgb) {
  char text[8];
  auto channel = [](double x) { return static_cast<int>(std::lround(std::clamp(x, 0.0, 1.0) * 255)); };
  std::snprintf(text, sizeof text, "#%02x%02x%02x", channel(rgb.x()), channel(rgb.y()), channel(rgb.z()));
  return text;
}

void append_point(std::string* out, char command, double x, double y) {
  char text[48];
  std::snprintf(text, sizeof text, "%c%.1f %.1f", command, x, y);
  out->append(text);
}

struct Projected {
  Eigen::MatrixX3d screen;  // #V×3: pixel x (right), pixel y (down), depth in pixels (nearer larger)
};

Projected project(const Eigen::MatrixX3d& V, const Camera& camera) {
  Projected p;
  p.screen.resize(V.rows(), 3);
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::Vector3d d = V.row(v).transpose() - camera.center;
    p.screen(v, 0) = 0.5 * camera.width + camera.scale * d.dot(camera.right);
    p.screen(v, 1) = 0.5 * camera.height - camera.scale * d.dot(camera.up);
    p.screen(v, 2) = camera.scale * d.dot(camera.toward);
  }
  return p;
}

// Nearest depth per pixel of the fan-triangulated faces (-inf where no face covers the pixel).
class DepthBuffer {
 public:
  DepthBuffer(int width, int height)
      : width_(width), height_(height),
        depth_(static_cast<size_t>(width) * height, -std::numeric_limits<double>::infinity()) {}

  void add_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (area == 0) return;  // no pixel centre lies strictly inside a zero-area triangle
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(width_ - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(height_ - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double wa = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
        const double wb = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
        const double wc = 1 - wa - wb;
        if (wa < 0 || wb < 0 || wc < 0) continue;
        double& d = depth_[static_cast<size_t>(y) * width_ + x];
        d = std::max(d, wa * a.z() + wb * b.z() + wc * c.z());
      }
  }

  // Farthest surface depth among the 3×3 pixels around (x, y): a point at a silhouette or crease
  // is visible when any neighbouring pixel does not hide it.
  double lenient_depth(double x, double y) const {
    const int cx = static_cast<int>(std::floor(x)), cy = static_cast<int>(std::floor(y));
    double d = std::numeric_limits<double>::infinity();
    for (int j = cy - 1; j <= cy + 1; ++j)
      for (int i = cx - 1; i <= cx + 1; ++i) {
        if (i < 0 || j < 0 || i >= width_ || j >= height_) return -std::numeric_limits<double>::infinity();
        d = std::min(d, depth_[static_cast<size_t>(j) * width_ + i]);
      }
    return d;
  }

 private:
  int width_, height_;
  std::vector<double> depth_;
};

}  // namespace

Camera camera_for_bbox(const Eigen::MatrixX3d& V, int width, int height) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  if (V.rows() == 0) return camera;
  const Eigen::Vector3d lo = V.colwise().minCoeff().transpose(), hi = V.colwise().maxCoeff().transpose();
  const Eigen::Vector3d extent = hi - lo;
  camera.center = 0.5 * (lo + hi);
  camera.diagonal = extent.norm();
  std::array<int, 3> axis{0, 1, 2};  // by decreasing extent, ties by axis id (deterministic)
  std::stable_sort(axis.begin(), axis.end(), [&](int a, int b) { return extent[a] > extent[b]; });
  const Eigen::Vector3d right0 = Eigen::Vector3d::Unit(axis[0]), up0 = Eigen::Vector3d::Unit(axis[1]);
  const Eigen::Vector3d toward0 = right0.cross(up0);
  const double azimuth = kAzimuthDeg * std::numbers::pi / 180, elevation = kElevationDeg * std::numbers::pi / 180;
  const Eigen::Vector3d right = std::cos(azimuth) * right0 - std::sin(azimuth) * toward0;
  const Eigen::Vector3d toward1 = std::sin(azimuth) * right0 + std::cos(azimuth) * toward0;
  camera.right = right;
  camera.toward = std::cos(elevation) * toward1 + std::sin(elevation) * up0;
  camera.up = camera.toward.cross(camera.right);

  double x_extent = 0, y_extent = 0;
  for (int corner = 0; corner < 8; ++corner) {
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) p[k] = (corner >> k) & 1 ? hi[k] : lo[k];
    const Eigen::Vector3d d = p - camera.center;
    x_extent = std::max(x_extent, 2 * std::abs(d.dot(camera.right)));
    y_extent = std::max(y_extent, 2 * std::abs(d.dot(camera.up)));
  }
  const double sx = x_extent > 0 ? width / x_extent : 1, sy = y_extent > 0 ? height / y_extent : 1;
  camera.scale = kFill * std::min(sx, sy);
  return camera;
}

std::vector<std::array<Eigen::Vector3d, 2>> sharp_edges(const core::TriMesh& mesh, double angle_deg) {
  struct EdgeFaces {
    int count = 0;
    int face[2] = {-1, -1};
    bool forward[2] = {false, false};  // the face runs the edge from its smaller vertex id
  };
  std::unordered_map<long long, EdgeFaces> edges;
  std::vector<long long> order;  // first-seen order, so the output does not depend on hashing
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      if (a == b) continue;
      auto [it, inserted] = edges.try_emplace(edge_key(a, b));
      if (inserted) order.push_back(it->first);
      EdgeFaces& e = it->second;
      if (e.count < 2) {
        e.face[e.count] = f;
        e.forward[e.count] = a < b;
      }
      ++e.count;
    }
  auto normal = [&](int f) {
    const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)), c = mesh.V.row(mesh.F(f, 2));
    return Eigen::Vector3d((b - a).cross(c - a));
  };
  const double cos_threshold = std::cos(angle_deg * std::numbers::pi / 180);
  std::vector<std::array<Eigen::Vector3d, 2>> sharp;
  for (long long key : order) {
    const EdgeFaces& e = edges.at(key);
    if (e.count != 2) continue;
    const Eigen::Vector3d n0 = normal(e.face[0]);
    // Consistently oriented neighbours run the edge in opposite directions.
    const Eigen::Vector3d n1 = e.forward[0] != e.forward[1] ? normal(e.face[1]) : Eigen::Vector3d(-normal(e.face[1]));
    const double len = n0.norm() * n1.norm();
    if (!(len > 0) || n0.dot(n1) / len >= cos_threshold) continue;
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffff);
    sharp.push_back({mesh.V.row(a).transpose(), mesh.V.row(b).transpose()});
  }
  return sharp;
}

std::string render_svg(const core::PolyMesh& mesh, const Camera& camera, const SvgStyle& style) {
  const Projected projected = project(mesh.V, camera);
  const Eigen::MatrixX3d& s = projected.screen;

  std::unordered_map<long long, int> edge_uses;
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < mesh.degree(f); ++k) ++edge_uses[edge_key(mesh.vertex(f, k), mesh.vertex(f, (k + 1) % mesh.degree(f)))];
  const bool closed = mesh.n_faces() > 0 &&
                      std::all_of(edge_uses.begin(), edge_uses.end(), [](const auto& e) { return e.second == 2; });

  const Eigen::Vector3d light =
      (-0.3 * camera.right + 0.4 * camera.up + 0.87 * camera.toward).normalized();  // upper left, front
  const Eigen::Vector3d kQuadColour(0.80, 0.84, 0.90), kPolygonColour(0.96, 0.84, 0.42),
      kBackColour(0.62, 0.50, 0.44);

  struct DrawnFace {
    int face;
    double depth;
    std::string fill, stroke;
  };
  std::vector<DrawnFace> drawn;
  std::vector<double> edge_px;
  DepthBuffer depth(camera.width, camera.height);
  for (int f = 0; f < mesh.n_faces(); ++f) {
    const int n = mesh.degree(f);
    if (n < 3) continue;
    // Area vector (Newell): well defined for non-planar quads; relative to corner 0 for precision.
    const Eigen::Vector3d p0 = mesh.V.row(mesh.vertex(f, 0));
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    double face_depth = 0;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d p = mesh.V.row(mesh.vertex(f, k)), q = mesh.V.row(mesh.vertex(f, (k + 1) % n));
      normal += (p - p0).cross(q - p0);
      face_depth += s(mesh.vertex(f, k), 2) / n;
    }
    const double area2 = normal.norm();
    if (!(area2 > 0)) continue;
    normal /= area2;
    const bool front = normal.dot(camera.toward) > 0;
    for (int k = 1; k + 1 < n; ++k)
      depth.add_triangle(s.row(mesh.vertex(f, 0)), s.row(mesh.vertex(f, k)), s.row(mesh.vertex(f, k + 1)));
    if (!front && closed) continue;
    const Eigen::Vector3d lit_normal = front ? normal : Eigen::Vector3d(-normal);
    const double intensity = kAmbient + (1 - kAmbient) * std::max(0.0, lit_normal.dot(light));
    const Eigen::Vector3d& base = !front ? kBackColour : n == 4 || !style.tint_non_quads ? kQuadColour : kPolygonColour;
    const Eigen::Vector3d fill = intensity * base;
    // Wireframe darker than a lit face, lighter than a face in shadow: visible on both.
    const Eigen::Vector3d stroke =
        fill.mean() > 0.45 ? Eigen::Vector3d(0.45 * fill) : Eigen::Vector3d(fill.array() + 0.3);
    drawn.push_back({f, face_depth, hex_colour(fill), hex_colour(style.wireframe ? stroke : fill)});
    for (int k = 0; k < n; ++k)
      edge_px.push_back((s.row(mesh.vertex(f, k)) - s.row(mesh.vertex(f, (k + 1) % n))).head<2>().norm());
  }
  std::stable_sort(drawn.begin(), drawn.end(), [](const DrawnFace& a, const DrawnFace& b) { return a.depth < b.depth; });

  double median_edge = 0;
  if (!edge_px.empty()) {
    std::nth_element(edge_px.begin(), edge_px.begin() + edge_px.size() / 2, edge_px.end());
    median_edge = edge_px[edge_px.size() / 2];
  }
  // Thin, faint lines when quads are a few pixels wide, so the shading still shows the shape.
  const double stroke_width = std::clamp(0.09 * median_edge, 0.12, 0.9);
  const double stroke_opacity = std::clamp(0.15 + median_edge / 10, 0.25, 0.85);

  std::string svg;
  svg.reserve(64 * drawn.size() + 1024);
  char text[256];
  std::snprintf(text, sizeof text,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\">\n"
                "<rect width=\"100%%\" height=\"100%%\" fill=\"#f6f7f9\"/>\n",
                camera.width, camera.height, camera.width, camera.height);
  svg += text;
  if (style.wireframe) {
    std::snprintf(text, sizeof text, "<g stroke-width=\"%.2f\" stroke-opacity=\"%.2f\" stroke-linejoin=\"round\">\n",
                  stroke_width, stroke_opacity);
    svg += text;
  } else {
    svg += "<g stroke-width=\"0.6\" stroke-linejoin=\"round\">\n";  // stroke = fill hides seams
  }
  for (const DrawnFace& d : drawn) {
    svg += "<path d=\"";
    for (int k = 0; k < mesh.degree(d.face); ++k) {
      const int v = mesh.vertex(d.face, k);
      append_point(&svg, k == 0 ? 'M' : 'L', s(v, 0), s(v, 1));
    }
    svg.append("Z\" fill=\"").append(d.fill).append("\" stroke=\"").append(d.stroke).append("\"/>\n");
  }
  svg += "</g>\n";

  if (!style.highlight.empty()) {
    const double tolerance = kDepthTolerance * camera.diagonal * camera.scale;
    std::string path;
    for (const auto& [a, b] : style.highlight) {
      auto to_screen = [&](const Eigen::Vector3d& p) {
        const Eigen::Vector3d d = p - camera.center;
        return Eigen::Vector3d(0.5 * camera.width + camera.scale * d.dot(camera.right),
                               0.5 * camera.height - camera.scale * d.dot(camera.up), camera.scale * d.dot(camera.toward));
      };
      const Eigen::Vector3d pa = to_screen(a), pb = to_screen(b);
      const int n = std::max(1, static_cast<int>(std::ceil((pb - pa).head<2>().norm() / kHighlightStep)));
      int run_start = -1;  // first visible sample of the current run
      for (int i = 0; i <= n + 1; ++i) {
        bool visible = false;
        if (i <= n) {
          const Eigen::Vector3d p = pa + (pb - pa) * (static_cast<double>(i) / n);
          visible = p.z() + tolerance >= depth.lenient_depth(p.x(), p.y());
        }
        if (visible && run_start < 0) run_start = i;
        if (!visible && run_start >= 0) {
          const Eigen::Vector3d p0 = pa + (pb - pa) * (static_cast<double>(run_start) / n);
          const Eigen::Vector3d p1 = pa + (pb - pa) * (static_cast<double>(i - 1) / n);
          append_point(&path, 'M', p0.x(), p0.y());
          append_point(&path, 'L', p1.x(), p1.y());
          run_start = -1;
        }
      }
    }
    if (!path.empty())
      svg += "<path fill=\"none\" stroke=\"#ff1f1f\" stroke-width=\"1.2\" stroke-linecap=\"round\" d=\"" + path +
             "\"/>\n";
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace quadify::cli
