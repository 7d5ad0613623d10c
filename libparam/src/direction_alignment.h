// Soft alignment of the map with a direction per face (paper section 6.1, principal curvature
// directions). Internal to libparam.
#pragma once

#include "cut_layout.h"
#include "layout_optimizer.h"

#include <libcore/mesh.h>

#include <Eigen/Core>

#include <vector>

namespace quadify::param {

// The faces that carry a direction, each direction written in the face's edge basis: d = α·(p1−p0)
// + β·(p2−p0), scaled so that its image in the rest frame (Dm·(α, β)) has unit length. The image of
// d in the map is then X·(α, β), X = [uv1−uv0, uv2−uv0], linear in the layout.
struct DirectionField {
  std::vector<int> face;
  std::vector<Eigen::Vector2d> coef;
  std::vector<double> area;  // rest area of the face
  int size() const { return static_cast<int>(face.size()); }
};

// direction: #F 3D vectors (zero: no direction); the tangential part is taken.
DirectionField make_direction_field(const core::TriMesh& mesh, const LayoutDomain& domain,
                                    const std::vector<Eigen::Vector3d>& direction);

// One penalty row per face: sqrt(area)·(the component of the direction's image across the UV axis
// it is nearest to in the layout x), so that w·Σ row² = w·Σ area·|J d|²·sin²(angle to the cross).
// The choice of axis is the face's label, re-taken from the current layout at every call.
std::vector<SparseRow> direction_rows(const LayoutDomain& domain, const DirectionField& field,
                                      const Eigen::VectorXd& x);

// The rotation angle that brings the area-weighted four-fold mean of the directions' images onto
// the axes (the directions' counterpart of Alg. 4).
double direction_rotation_angle(const LayoutDomain& domain, const DirectionField& field,
                                const Eigen::VectorXd& x);

// Area-weighted mean angle (degrees, in [0°, 45°]) between the directions' images and the nearest
// UV axis.
double direction_angle_mean(const LayoutDomain& domain, const DirectionField& field,
                            const Eigen::VectorXd& x);

}  // namespace quadify::param
