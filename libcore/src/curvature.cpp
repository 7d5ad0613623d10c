#include <libcore/curvature.h>
#include <libcore/topology.h>

#define CGAL_EIGEN3_ENABLED 1
#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Simple_cartesian.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

#ifdef QUADIFY_WITH_TBB
#include <tbb/parallel_for.h>
#endif

namespace quadify::core {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using JetFitting = CGAL::Monge_via_jet_fitting<Kernel>;

constexpr int kMinJetPoints = 12;  // a degree-2 jet has 6 coefficients: twice that, for stability
constexpr int kMaxRings = 4;

template <class Body>
void for_each_index(int n, const Body& body) {
#ifdef QUADIFY_WITH_TBB
  tbb::parallel_for(0, n, [&](int i) { body(i); });
#else
  for (int i = 0; i < n; ++i) body(i);
#endif
}

}  // namespace

VertexCurvature estimate_curvature(const TriMesh& mesh, int rings) {
  const int nv = mesh.n_vertices();
  VertexCurvature out;
  out.k_max = Eigen::VectorXd::Zero(nv);
  out.k_min = Eigen::VectorXd::Zero(nv);
  out.d_max = Eigen::MatrixX3d::Zero(nv, 3);
  out.d_min = Eigen::MatrixX3d::Zero(nv, 3);
  const std::vector<std::vector<int>> nb = vertex_neighbours(mesh);
  Eigen::MatrixX3d normal = Eigen::MatrixX3d::Zero(nv, 3);
  for (int f = 0; f < mesh.n_faces(); ++f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)),
                          p2 = mesh.V.row(mesh.F(f, 2));
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);  // area-weighted
    for (int k = 0; k < 3; ++k) normal.row(mesh.F(f, k)) += n.transpose();
  }
  for_each_index(nv, [&](int v) {
    if (nb[v].empty()) return;
    // Rings around v, breadth first, until enough points.
    std::vector<int> points = {v}, frontier = {v};
    std::vector<int> seen = {v};
    for (int ring = 0; ring < kMaxRings && (ring < rings || static_cast<int>(points.size()) < kMinJetPoints);
         ++ring) {
      std::vector<int> next;
      for (const int u : frontier)
        for (const int w : nb[u])
          if (std::find(seen.begin(), seen.end(), w) == seen.end()) {
            seen.push_back(w);
            next.push_back(w);
          }
      if (next.empty()) break;
      points.insert(points.end(), next.begin(), next.end());
      frontier.swap(next);
    }
    if (static_cast<int>(points.size()) < 6) return;
    std::vector<Kernel::Point_3> pts;
    pts.reserve(points.size());
    for (const int u : points) pts.emplace_back(mesh.V(u, 0), mesh.V(u, 1), mesh.V(u, 2));
    JetFitting fit;
    JetFitting::Monge_form form;
    try {
      form = fit(pts.begin(), pts.end(), 2, 2);
    } catch (...) {
      return;  // degenerate neighbourhood (collinear points): no estimate
    }
    const Eigen::Vector3d n = normal.row(v);
    if (n.squaredNorm() > 0) form.comply_wrt_given_normal(Kernel::Vector_3(n.x(), n.y(), n.z()));
    // CGAL's Monge form: z = ½(k1·x² + k2·y²) + … along the outward normal, k1 ≥ k2, so a convex
    // surface has negative curvatures. Ours: convex positive, k_max ≥ k_min.
    const double k1 = form.principal_curvatures(0), k2 = form.principal_curvatures(1);
    if (!std::isfinite(k1) || !std::isfinite(k2)) return;
    const auto d1 = form.maximal_principal_direction(), d2 = form.minimal_principal_direction();
    out.k_max[v] = -k2;
    out.k_min[v] = -k1;
    out.d_max.row(v) << d2.x(), d2.y(), d2.z();
    out.d_min.row(v) << d1.x(), d1.y(), d1.z();
  });
  return out;
}

}  // namespace quadify::core
