// Corner measures of a quad shared by the quad metrics and the quad relaxation. Internal to
// libquadex.
#pragma once

#include <libcore/mesh.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>

namespace quadify::quadex {

// Quad f's corners p_k, its area vector Σ_k (p_{k+1} − p_k) × (p_{k−1} − p_k), and each corner's
// scaled Jacobian: that corner's cross product against the unit area vector over the product of
// its two edge lengths (1 = right angle, ≤ 0 = reflex or flipped; 0 where an edge has zero length
// or the area vector vanishes).
struct QuadCorners {
  std::array<Eigen::Vector3d, 4> p;
  Eigen::Vector3d area_vector = Eigen::Vector3d::Zero();
  std::array<double, 4> scaled_jacobian{};
  double min_scaled_jacobian() const {
    return std::min(std::min(scaled_jacobian[0], scaled_jacobian[1]),
                    std::min(scaled_jacobian[2], scaled_jacobian[3]));
  }
  Eigen::Vector3d centroid() const { return (p[0] + p[1] + p[2] + p[3]) / 4.0; }
  // Cosine between the area vector and a surface normal (any length; 0 when either vanishes).
  // The quad faces away from the surface when it is negative: the flip test of the metrics and
  // the relaxation, with the normal of the surface triangle closest to centroid().
  double facing_cosine(const Eigen::Vector3d& surface_normal) const {
    const double denom = surface_normal.norm() * area_vector.norm();
    return denom > 0 ? area_vector.dot(surface_normal) / denom : 0.0;
  }
};

inline QuadCorners quad_corners(const core::PolyMesh& quads, int f) {
  QuadCorners q;
  for (int k = 0; k < 4; ++k) q.p[k] = quads.V.row(quads.vertex(f, k)).transpose();
  std::array<Eigen::Vector3d, 4> cross;
  for (int k = 0; k < 4; ++k) {
    cross[k] = (q.p[(k + 1) % 4] - q.p[k]).cross(q.p[(k + 3) % 4] - q.p[k]);
    q.area_vector += cross[k];
  }
  const double area_norm = q.area_vector.norm();
  const Eigen::Vector3d n =
      area_norm > 0 ? Eigen::Vector3d(q.area_vector / area_norm) : Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) {
    const double lengths = (q.p[(k + 1) % 4] - q.p[k]).norm() * (q.p[(k + 3) % 4] - q.p[k]).norm();
    q.scaled_jacobian[k] = lengths > 0 ? cross[k].dot(n) / lengths : 0.0;
  }
  return q;
}

}  // namespace quadify::quadex
