// Exact geometric predicates (CGAL Epick filtered predicates behind a small interface, so that
// CGAL stays out of widely included headers). Every sign decision in quadify goes through here.
#pragma once

#include <Eigen/Core>

namespace quadify::core {

// Sign of the orientation of (a, b, c) in the plane: +1 counter-clockwise, -1 clockwise,
// 0 collinear. Exact for any finite doubles.
int orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

// Sign of the orientation of (a, b, c, d) in space: sign of det[b-a, c-a, d-a] (CGAL::POSITIVE
// convention): +1 if d lies on the side from which (a, b, c) appear counter-clockwise, -1 on the
// other side, 0 coplanar.
int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d);

// True when the three points are exactly collinear in space.
bool collinear3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace quadify::core
