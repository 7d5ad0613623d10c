// Metrics of a parametrization (a triangle mesh with per-corner UVs), independent of how the map
// was made: distortion (paper eq. 3), flips, seams with matchings and residuals, cones and the
// Gauss–Bonnet check. Used by `quadify check` on any UV OBJ, and by the tests of every stage.
#pragma once

#include <libcore/mesh.h>

#include <vector>

namespace quadify::core {

struct UVMetricsOptions {
  // A triangle whose UV area is below this, relative to (UV bbox diagonal)², counts as degenerate.
  double degenerate_uv_area = 1e-14;
  // Corners of two faces at a shared vertex are "the same UV" (no seam) when they differ by less
  // than this, relative to the UV bbox diagonal. Exact equality (0) for maps written by quadify.
  double seam_detect_tolerance = 1e-12;
  // A cone index (in quarter turns) closer than this to an integer counts as integer.
  double integer_tolerance = 1e-6;
};

struct SeamEdge {
  int edge = -1;          // edge id of EdgeTopology
  int matching = 0;       // r ∈ {0,1,2,3}: e' ≈ R_90^r e across the seam
  double angle = 0;       // measured rotation in quarter turns, before rounding (may be non-integer)
  double residual = 0;    // |e' - R^r e| / |e|
};

struct Cone {
  int vertex = -1;
  double angle_sum = 0;   // UV angle sum around the vertex (radians)
  // Interior: index k = 4 - angle_sum / (π/2), so k = +1 at a valence-3-like cone, -1 at a 5-like.
  double index = 0;
  bool on_boundary = false;
};

struct UVMetrics {
  int n_faces = 0;
  int n_flipped = 0;       // UV orientation opposite to the majority of the component (exact test)
  int n_degenerate = 0;    // zero (or below tolerance) UV area
  // Per triangle singular values of the Jacobian 3D → UV, #F×2 (σ1 ≥ σ2; σ2 < 0 when flipped).
  Eigen::MatrixX2d singular_values;
  double sigma1_max = 0, sigma2_min = 0;
  double tau = 0;          // sqrt(σ1max / σ2min) (paper eq. 3); +inf if any flipped/degenerate
  // Symmetric Dirichlet energy per triangle, σ1² + σ1⁻² + σ2² + σ2⁻² (4 at an isometry),
  // area-weighted mean and max; +inf if flipped/degenerate. Scale-normalised: the UVs are first
  // scaled so that the total UV area equals the 3D area.
  double sd_mean = 0, sd_max = 0;
  double conformal_mean = 0, conformal_max = 0;  // σ1/σ2 (1 = conformal)
  double area_mean = 0, area_max = 0;            // max(σ1σ2, 1/(σ1σ2)) after the same scaling
  // Seams: edges whose two faces disagree on the UVs of the shared vertices.
  std::vector<SeamEdge> seams;
  int n_seam_edges = 0;
  double seam_residual_max = 0;   // max over seam edges of the relative residual
  double seam_residual_abs = 0;   // max absolute residual |e' - R^r e| in UV units
  bool matchings_integer = true;  // every seam angle within integer_tolerance of an integer
  // Cones: interior vertices with a non-zero index (|index| > integer_tolerance).
  std::vector<Cone> cones;
  int n_cones = 0;
  bool cone_indices_integer = true;
  // Gauss–Bonnet: Σ_interior (2π − Θ_v) + Σ_boundary (π − Θ_v) = 2π χ. Error in radians.
  int euler_characteristic = 0;
  double gauss_bonnet_error = 0;
  int n_boundary_vertices = 0;
  double uv_bbox_diagonal = 0;
};

// Precondition: mesh manifold and consistently oriented, corner_uv (#F·3)×2 finite. Throws
// std::invalid_argument (naming the edge, or the sizes) when the mesh is not edge-manifold or not
// consistently oriented (see build_edge_topology) or corner_uv has the wrong size. O(#F).
// Corner angles are signed by the exact face orientation, so each flipped triangle adds 2π to
// gauss_bonnet_error.
UVMetrics compute_uv_metrics(const UVMesh& uv_mesh, const UVMetricsOptions& options = {});

}  // namespace quadify::core
