// Sizing fields for the parametrization (paper section 7, isotropic scaling): per-face target
// edge lengths, from the surface's curvature or from per-vertex values given by the user, and the
// principal curvature estimate they rest on. Feed the result to param::ParamOptions::face_size
// and quantize::QuantizeOptions::face_size.
#pragma once

#include <libcore/mesh.h>

#include <Eigen/Core>

#include <vector>

namespace quadify::param {

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

struct AdaptiveSizingOptions {
  // Largest over smallest quad edge length (before smoothing); 1 = uniform.
  double max_ratio = 4;
  // Passes of averaging the log size of each vertex with its neighbours' (a graded field: quad
  // sizes change over several quads, not from one to the next).
  int smoothing_passes = 8;
};

// Curvature-adaptive isotropic sizing: a quad edge of length ℓ on a surface of curvature κ leaves
// a chordal error of about ℓ²κ/8, so ℓ ∝ 1/sqrt(κ) spreads the error evenly; κ is the larger
// principal curvature magnitude. Sizes are relative to the area-weighted median curvature,
// clamped to max_ratio, smoothed, and normalized like face_size_from_vertices.
[[nodiscard]] std::vector<double> adaptive_face_size(const core::TriMesh& mesh,
                                                     const AdaptiveSizingOptions& options = {});

// Curvature-adaptive anisotropic sizing: per face a metric (param::ParamOptions::face_metric)
// asking for edge length ∝ 1/sqrt(|κ|) along each principal direction (longer quads along the
// direction in which the surface bends less, e.g. along a cylinder's axis), each length clamped
// to max_ratio around the median-curvature length, smoothed like adaptive_face_size (log
// lengths, and the directions through their outer products), and normalized so that the sized
// area equals the surface area.
[[nodiscard]] std::vector<Eigen::Matrix3d> adaptive_face_metric(
    const core::TriMesh& mesh, const AdaptiveSizingOptions& options = {});

// Per-vertex relative edge lengths (#V positive values) → per-face sizes: the geometric mean of
// the face's corners, normalized so that Σ area/size² = Σ area (the map's area, and so the quad
// count of a target, is unchanged). Throws std::invalid_argument on a wrong count or a value that
// is not finite and positive.
[[nodiscard]] std::vector<double> face_size_from_vertices(const core::TriMesh& mesh,
                                                          const std::vector<double>& vertex_size);

// The area of the mesh's target shapes: Σ over faces of the area of the triangle mapped by
// face_metric[f] and scaled by 1/face_size[f] (either may be empty); the surface area if both are.
[[nodiscard]] double sized_area(const core::TriMesh& mesh, const std::vector<double>& face_size,
                                const std::vector<Eigen::Matrix3d>& face_metric);

}  // namespace quadify::param
