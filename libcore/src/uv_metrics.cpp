#include <libcore/predicates.h>
#include <libcore/topology.h>
#include <libcore/uv_metrics.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace quadify::core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kQuarterTurn = std::numbers::pi / 2;

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Singular values of a 2×2 matrix in closed form: with E=(a+d)/2, F=(a-d)/2, G=(c+b)/2,
// H=(c-b)/2, Q=|(E,H)|, R=|(F,G)|, the singular values are Q+R and |Q-R|.
Eigen::Vector2d singular_values_2x2(const Eigen::Matrix2d& J) {
  const double e = 0.5 * (J(0, 0) + J(1, 1)), f = 0.5 * (J(0, 0) - J(1, 1));
  const double g = 0.5 * (J(1, 0) + J(0, 1)), h = 0.5 * (J(1, 0) - J(0, 1));
  const double q = std::hypot(e, h), r = std::hypot(f, g);
  return {q + r, std::abs(q - r)};
}

// Jacobian of the linear map from the triangle (p0,p1,p2), in an orthonormal frame of its plane,
// to the UV triangle (u0,u1,u2). Returns false when the 3D triangle is degenerate.
bool triangle_jacobian(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                       const Eigen::Vector2d& u0, const Eigen::Vector2d& u1, const Eigen::Vector2d& u2,
                       Eigen::Matrix2d* J, double* area3d) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = p2 - p0;
  const Eigen::Vector3d n = d1.cross(d2);
  *area3d = 0.5 * n.norm();
  const double l1 = d1.norm();
  if (!(l1 > 0) || !(*area3d > 0)) return false;
  const Eigen::Vector3d x_axis = d1 / l1;
  const Eigen::Vector3d y_axis = n.cross(d1).normalized();
  Eigen::Matrix2d X;  // columns: local coordinates of d1, d2
  X << l1, d2.dot(x_axis), 0, d2.dot(y_axis);
  Eigen::Matrix2d U;
  U.col(0) = u1 - u0;
  U.col(1) = u2 - u0;
  *J = U * X.inverse();
  return true;
}

}  // namespace

UVMetrics compute_uv_metrics(const UVMesh& uv_mesh, const UVMetricsOptions& options) {
  const TriMesh& mesh = uv_mesh.mesh;
  const Eigen::MatrixX2d& uv = uv_mesh.corner_uv;
  const int nf = mesh.n_faces(), nv = mesh.n_vertices();
  if (uv.rows() != 3 * nf || uv.cols() != 2)
    throw std::invalid_argument("compute_uv_metrics: corner_uv is " + std::to_string(uv.rows()) + "x" +
                                std::to_string(uv.cols()) + ", expected (3*" + std::to_string(nf) + ")x2");
  UVMetrics m;
  m.n_faces = nf;
  m.singular_values.setZero(nf, 2);
  if (nf == 0) return m;

  if (uv.rows() > 0) {
    const Eigen::Vector2d lo = uv.colwise().minCoeff(), hi = uv.colwise().maxCoeff();
    m.uv_bbox_diagonal = (hi - lo).norm();
  }
  const double diag = m.uv_bbox_diagonal;
  const double degenerate_area = options.degenerate_uv_area * diag * diag;
  const double seam_tol = options.seam_detect_tolerance * diag;
  auto corner_uv = [&](int c) -> Eigen::Vector2d { return uv.row(c).transpose(); };

  const EdgeTopology topo = build_edge_topology(mesh);
  std::vector<int> component;
  const int n_components = face_components(mesh, topo, &component);

  // Majority orientation per component: sign of the total signed UV area (a map may be mirrored).
  std::vector<double> signed_uv_area(nf);
  std::vector<double> component_area(n_components, 0.0);
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector2d u0 = corner_uv(3 * f), u1 = corner_uv(3 * f + 1), u2 = corner_uv(3 * f + 2);
    signed_uv_area[f] = 0.5 * cross2(u1 - u0, u2 - u0);
    component_area[component[f]] += signed_uv_area[f];
  }
  std::vector<int> majority(n_components);
  for (int c = 0; c < n_components; ++c) majority[c] = component_area[c] < 0 ? -1 : 1;

  // Per-face orientation relative to the majority: +1 fine, -1 flipped, 0 degenerate.
  std::vector<int> face_sign(nf);
  std::vector<double> area3d(nf, 0.0);
  std::vector<Eigen::Matrix2d> jacobian(nf, Eigen::Matrix2d::Zero());
  double total_area3d = 0, total_area_uv = 0;
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector2d u0 = corner_uv(3 * f), u1 = corner_uv(3 * f + 1), u2 = corner_uv(3 * f + 2);
    const int orient = orient2d(u0, u1, u2);
    const bool valid3d = triangle_jacobian(mesh.V.row(mesh.F(f, 0)).transpose(),
                                           mesh.V.row(mesh.F(f, 1)).transpose(),
                                           mesh.V.row(mesh.F(f, 2)).transpose(), u0, u1, u2,
                                           &jacobian[f], &area3d[f]);
    if (orient == 0 || std::abs(signed_uv_area[f]) < degenerate_area || !valid3d) {
      face_sign[f] = 0;
      ++m.n_degenerate;
    } else if (orient != majority[component[f]]) {
      face_sign[f] = -1;
      ++m.n_flipped;
    } else {
      face_sign[f] = 1;
    }
    total_area3d += area3d[f];
    total_area_uv += std::abs(signed_uv_area[f]);
  }

  // Distortion (paper eq. 3). Singular values are of the map as given; the energies use the UVs
  // scaled so that the total UV area equals the 3D area.
  const double scale = total_area_uv > 0 ? std::sqrt(total_area3d / total_area_uv) : 0.0;
  m.sigma1_max = 0;
  m.sigma2_min = kInf;
  double sd_sum = 0, conf_sum = 0, area_sum = 0;
  for (int f = 0; f < nf; ++f) {
    Eigen::Vector2d s = singular_values_2x2(jacobian[f]);
    if (face_sign[f] == 0) s.y() = 0;
    if (face_sign[f] < 0) s.y() = -s.y();
    m.singular_values.row(f) = s.transpose();
    m.sigma1_max = std::max(m.sigma1_max, s.x());
    m.sigma2_min = std::min(m.sigma2_min, s.y());
    double sd = kInf, conf = kInf, area = kInf;
    if (face_sign[f] > 0 && s.y() > 0) {
      const double s1 = scale * s.x(), s2 = scale * s.y();
      sd = s1 * s1 + 1 / (s1 * s1) + s2 * s2 + 1 / (s2 * s2);
      conf = s1 / s2;
      area = std::max(s1 * s2, 1 / (s1 * s2));
    }
    m.sd_max = std::max(m.sd_max, sd);
    m.conformal_max = std::max(m.conformal_max, conf);
    m.area_max = std::max(m.area_max, area);
    sd_sum += area3d[f] * sd;
    conf_sum += area3d[f] * conf;
    area_sum += area3d[f] * area;
  }
  const bool any_bad = m.n_flipped > 0 || m.n_degenerate > 0;
  m.tau = any_bad || !(m.sigma2_min > 0) ? kInf : std::sqrt(m.sigma1_max / m.sigma2_min);
  if (total_area3d > 0) {
    m.sd_mean = any_bad ? kInf : sd_sum / total_area3d;
    m.conformal_mean = any_bad ? kInf : conf_sum / total_area3d;
    m.area_mean = any_bad ? kInf : area_sum / total_area3d;
  }

  // Seams: interior edges whose two faces disagree on a shared vertex's UV.
  for (int e = 0; e < topo.n_edges(); ++e) {
    const int h = topo.edge_halfedge[e];
    const int t = topo.twin[h];
    if (t < 0) continue;
    const int ha = h, hb = 3 * (h / 3) + (h % 3 + 1) % 3;  // corners of a and b in face A
    const int tb = t, ta = 3 * (t / 3) + (t % 3 + 1) % 3;  // twin runs b → a in face B
    const Eigen::Vector2d a_in_A = corner_uv(ha), b_in_A = corner_uv(hb);
    const Eigen::Vector2d a_in_B = corner_uv(ta), b_in_B = corner_uv(tb);
    if ((a_in_A - a_in_B).norm() <= seam_tol && (b_in_A - b_in_B).norm() <= seam_tol) continue;
    const Eigen::Vector2d ev = b_in_A - a_in_A, ev_twin = b_in_B - a_in_B;
    SeamEdge seam;
    seam.edge = e;
    seam.angle = std::atan2(cross2(ev, ev_twin), ev.dot(ev_twin)) / kQuarterTurn;
    const double rounded = std::round(seam.angle);
    seam.matching = ((static_cast<int>(rounded) % 4) + 4) % 4;
    Eigen::Vector2d rotated = ev;
    for (int i = 0; i < seam.matching; ++i) rotated = Eigen::Vector2d(-rotated.y(), rotated.x());
    const double abs_residual = (ev_twin - rotated).norm();
    const double len = ev.norm();
    seam.residual = len > 0 ? abs_residual / len : (abs_residual > 0 ? kInf : 0.0);
    if (std::abs(seam.angle - rounded) >= options.integer_tolerance) m.matchings_integer = false;
    m.seam_residual_max = std::max(m.seam_residual_max, seam.residual);
    m.seam_residual_abs = std::max(m.seam_residual_abs, abs_residual);
    m.seams.push_back(seam);
  }
  m.n_seam_edges = static_cast<int>(m.seams.size());

  // Cones: UV angle sums. Corner angles are signed by the face orientation relative to the
  // majority, so a flipped triangle contributes −π in total (each flip adds 2π to the
  // Gauss–Bonnet error); the sign comes from the exact predicate, the magnitude from atan2.
  std::vector<double> angle_sum(nv, 0.0);
  std::vector<char> used(nv, 0), on_boundary(nv, 0);
  for (int f = 0; f < nf; ++f) {
    const int sign = face_sign[f] == 0 ? 0 : (face_sign[f] > 0 ? 1 : -1);
    for (int k = 0; k < 3; ++k) {
      const int c = 3 * f + k;
      const Eigen::Vector2d u = corner_uv(c);
      const Eigen::Vector2d to_next = corner_uv(3 * f + (k + 1) % 3) - u;
      const Eigen::Vector2d to_prev = corner_uv(3 * f + (k + 2) % 3) - u;
      const double cross = sign == 0 ? 0.0 : sign * std::abs(cross2(to_next, to_prev));
      const int v = mesh.F(f, k);
      angle_sum[v] += std::atan2(cross, to_next.dot(to_prev));
      used[v] = 1;
      if (topo.twin[c] < 0) on_boundary[v] = on_boundary[mesh.F(f, (k + 1) % 3)] = 1;
    }
  }
  int n_used = 0;
  double curvature_sum = 0;
  for (int v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    ++n_used;
    if (on_boundary[v]) {
      ++m.n_boundary_vertices;
      curvature_sum += std::numbers::pi - angle_sum[v];
      continue;
    }
    curvature_sum += 2 * std::numbers::pi - angle_sum[v];
    const double index = 4 - angle_sum[v] / kQuarterTurn;
    if (std::abs(index - std::round(index)) >= options.integer_tolerance) m.cone_indices_integer = false;
    if (std::abs(index) > options.integer_tolerance) m.cones.push_back({v, angle_sum[v], index, false});
  }
  m.n_cones = static_cast<int>(m.cones.size());
  m.euler_characteristic = n_used - topo.n_edges() + nf;
  m.gauss_bonnet_error = std::abs(curvature_sum - 2 * std::numbers::pi * m.euler_characteristic);
  return m;
}

}  // namespace quadify::core
