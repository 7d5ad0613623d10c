// Quality metrics of a polygon (quad) mesh, optionally against a reference triangle mesh.
// Definitions match ../shared/peers/README.md so our figures stand beside the peers'.
#pragma once

#include <libcore/mesh.h>

#include <map>
#include <vector>

namespace quadify::quadex {

struct QuadMetricsOptions {
  // Area samples per side for the Hausdorff/mean distances (plus every vertex).
  int hausdorff_samples = 100'000;
  unsigned seed = 1;  // sampling is deterministic for a given seed
  // Sharp edges of the reference for feature capture: dihedral angle above this (degrees).
  double feature_angle_deg = 40.0;
  // A feature point counts as captured within this distance of a quad edge (× bbox diagonal).
  double feature_capture_tolerance = 1e-3;
  // Measure how quad edges follow the reference's principal curvature directions (needs the
  // curvature estimate of the reference: core::estimate_curvature).
  bool curvature_alignment = true;
};

struct QuadMetrics {
  int n_vertices = 0;
  int n_faces = 0;
  std::map<int, int> faces_by_degree;  // degree → count
  int n_non_quads = 0;
  std::map<int, int> valence_histogram;  // interior vertex valence → count
  int n_irregular = 0;      // interior valence ≠ 4; boundary valence ≠ 3 except corners (valence 2)
  // Faces that visit a vertex more than once (a loop edge, as an iso-line around a handle one
  // quad thick gives, or a pinched polygon): such a mesh is not manifold.
  int n_degenerate = 0;
  bool manifold = false;
  int n_components = 0;
  int n_boundary_loops = 0;
  int euler_characteristic = 0;
  int genus = -1;           // -1 when not manifold or not orientable
  // Quads with a corner of scaled Jacobian ≤ 0, or (with a reference) whose area vector has a
  // negative dot product with the normal of the reference triangle closest to the quad centroid.
  int n_flipped = 0;
  // Scaled Jacobian of the quad corners: minimum over all corners, and mean over quads of each
  // quad's minimum corner (the peers' definition).
  double sj_min = 0, sj_mean = 0;
  // |corner angle - 90°| in degrees over all quad corners, the angle unsigned in [0°, 180°].
  double angle_dev_mean = 0, angle_dev_max = 0;
  double edge_len_cv = 0;   // coefficient of variation of edge lengths
  double edge_len_mean = 0;
  // Against the reference (only when given), fractions of the reference bbox diagonal.
  bool has_reference = false;
  double hausdorff_to_ref = -1;   // max over quad-mesh samples of the distance to the reference
  double hausdorff_from_ref = -1; // max over reference samples of the distance to the quad mesh
  double hausdorff_sym = -1;
  double mean_dist_sym = -1;
  // Feature capture (reference has sharp edges): share of the sharp-edge length within tolerance
  // of a quad edge; -1 when the reference has no sharp edges or is not manifold and consistently
  // oriented. Sharp edges are sampled every 1e-3 × diagonal.
  double feature_capture = -1;
  double feature_hausdorff = -1;  // max distance from sharp-edge samples to the nearest quad edge
  // Alignment with principal curvature directions, in anisotropic regions of the reference (at
  // the reference vertex nearest the quad: the larger curvature magnitude at least twice the
  // smaller and at least 4 / bbox diagonal): mean over those quads' edges of the angle between
  // the edge (in the tangent plane) and the nearest principal direction, in [0°, 45°] (edges at
  // random: 22.5°); -1 when no quad lies in such a region.
  double principal_angle_mean = -1;
  int n_anisotropic_quads = 0;
};

// Precondition: V finite and face ids in range (any PolyMesh from read_mesh satisfies it).
// Distances use CGAL AABB trees; sampling is deterministic (options.seed), queries run in
// parallel with TBB when built with QUADIFY_WITH_TBB.
QuadMetrics compute_quad_metrics(const core::PolyMesh& quads, const core::TriMesh* reference = nullptr,
                                 const QuadMetricsOptions& options = {});

}  // namespace quadify::quadex
