// Principal curvatures of a triangle mesh, estimated at its vertices.
#pragma once

#include <libcore/mesh.h>

#include <Eigen/Core>

namespace quadify::core {

// Principal curvatures and directions at the vertices of a mesh.
struct VertexCurvature {
  // #V, k_max ≥ k_min, signed so that a convex surface (bending away from the outward,
  // area-weighted vertex normal) has positive curvatures: 1/r on a sphere of radius r.
  Eigen::VectorXd k_max, k_min;
  Eigen::MatrixX3d d_max, d_min;  // #V×3, unit principal directions (tangent), zero where unknown
};

// Fits a degree-2 jet (osculating quadric, CGAL's Monge_via_jet_fitting) to each vertex and its
// neighbours up to `rings` edge rings (more rings where fewer than 12 points: boundaries, low
// valences). Jet fitting is a least-squares fit over a neighbourhood, so one noisy vertex or a
// thin triangle does not dominate it as it does discrete (cotangent, angle-defect) estimates;
// the 2-ring balances that against smearing sharp variation. Parallel over vertices (TBB) and
// deterministic. Isolated vertices get zeros.
[[nodiscard]] VertexCurvature estimate_curvature(const core::TriMesh& mesh, int rings = 2);

}  // namespace quadify::core
