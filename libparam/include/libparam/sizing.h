// Sizing fields for the parametrization (paper section 7, isotropic scaling): per-face target
// edge lengths, from the surface's curvature or from per-vertex values given by the user, and the
// principal curvature estimate they rest on. Feed the result to param::ParamOptions::face_size
// and quantize::QuantizeOptions::face_size. Curvatures come from core::estimate_curvature.
#pragma once

#include <libcore/mesh.h>

#include <Eigen/Core>

#include <array>
#include <vector>

namespace quadify::param {

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

// Thin-part sizing: where the surface curves around a radius smaller than the quad edge (a
// tentacle, a finger, a horn's tip), a grid of that edge cannot wrap it, and the cones its tip
// needs have no grid points to sit on (octopus at 5,000 quads). The relative edge length there is
// the local radius r = 1 / |κ1 + κ2| (a tube's radius from its mean curvature; a saddle, where a
// tentacle leaves the body, is not thin) over the quad edge, times max_edge_over_radius: a tube
// of radius r gets about 2π / max_edge_over_radius quads around.
struct ThinPartSizingOptions {
  // Quad edge over the local radius of curvature where that would be smaller than the target
  // edge: 1 gives a tube about six quads around.
  double max_edge_over_radius = 1;
  // Smallest relative edge length (elsewhere 1).
  double min_ratio = 0.25;
  // Passes of averaging log sizes with the neighbours' (as adaptive_face_size).
  int smoothing_passes = 30;
};

// Per-vertex relative edge lengths in [min_ratio, 1] for quads of edge `edge_length` (model
// units): 1 wherever the surface is not thinner than that (pass them to face_size_from_vertices,
// which normalizes them so the quad count of a target stays). All ones when the surface has no
// such part.
[[nodiscard]] std::vector<double> thin_part_vertex_size(const core::TriMesh& mesh, double edge_length,
                                                        const ThinPartSizingOptions& options = {});

// Feature-loop sizing: a closed feature curve (a hole's rim, a boss's edge) only n quad edges
// around is cut off by their chords, by R·(1 − cos(π/n)) for a circle of radius R: casting at
// 5,000 quads has holes of radius 1.2 quad edges rimmed by 6–8 chords that miss the crease by up
// to 1% of the diagonal. A closed loop of length C shorter than min_loop_edges target edges gets
// quads of relative edge length C / (min_loop_edges · edge_length) (at least min_ratio) along
// it, growing back to 1 by `grade` per target edge of distance along the mesh edges.
struct FeatureLoopSizingOptions {
  // Quad edges wanted around a closed feature curve.
  double min_loop_edges = 12;
  // Smallest relative edge length (elsewhere 1).
  double min_ratio = 0.3;
  // Growth of the relative length per target edge of distance from the loop.
  double grade = 0.25;
};

// Per-vertex relative edge lengths in [min_ratio, 1] for quads of edge `edge_length` (model units)
// around the closed loops of `feature_edges` (vertex pairs, as param::ParamOptions::feature_edges):
// 1 wherever no loop is that short (pass them to face_size_from_vertices). Throws
// std::invalid_argument on invalid options or an edge with a vertex out of range.
[[nodiscard]] std::vector<double> feature_loop_vertex_size(
    const core::TriMesh& mesh, const std::vector<std::array<int, 2>>& feature_edges,
    double edge_length, const FeatureLoopSizingOptions& options = {});

// Feature-strip sizing: two feature curves that run closer than a quad edge apart (a narrow
// chamfer or fillet band between two creases, wingnut's 0.03-wide bands at quads of 0.11) can
// both be iso-lines only if the band becomes a row of quads, stretched several times across
// where the quads are of the target size; the rounding then often cannot reach the next integer
// line flip-free and releases one of them (lost in the quads). A face with a feature edge whose
// opposite vertex lies on another feature curve (not joined to that edge's ends by a feature
// edge) running within max_turn_deg of parallel to it, at a distance w of min_width_edges to
// max_width_edges target edges, gets quads of relative edge length w / edge_length (at least
// min_ratio) at its vertices, growing back to 1 by `grade` per target edge of distance along the
// mesh edges. Narrower bands (beetle's, 0.06 of a quad) are left alone: quads a third of the
// target would still be stretched across them, and at 5,000 quads sizing them cost beetle
// capture 0.973 → 0.950; so are wedges between diverging creases (fandisk's 22° corner: 0.986 →
// 0.979).
struct FeatureStripSizingOptions {
  // Bands of widths in [min_width_edges, max_width_edges) target edges are sized.
  double min_width_edges = 0.2;
  double max_width_edges = 0.5;
  // The other curve's edges at the opposite vertex: at least one within this angle of parallel
  // to the face's feature edge (degrees).
  double max_turn_deg = 15;
  // Smallest relative edge length (elsewhere 1).
  double min_ratio = 0.3;
  // Growth of the relative length per target edge of distance from the band.
  double grade = 0.25;
};

// Per-vertex relative edge lengths in [min_ratio, 1] for quads of edge `edge_length` (model units)
// along the narrow bands between `feature_edges` (vertex pairs, as param::ParamOptions::
// feature_edges): 1 wherever there is none (pass them to face_size_from_vertices). Throws
// std::invalid_argument on invalid options or an edge with a vertex out of range.
[[nodiscard]] std::vector<double> feature_strip_vertex_size(
    const core::TriMesh& mesh, const std::vector<std::array<int, 2>>& feature_edges,
    double edge_length, const FeatureStripSizingOptions& options = {});

// Curvature-adaptive anisotropic sizing: per face a metric (param::ParamOptions::face_metric)
// asking for edge length ∝ 1/sqrt(|κ|) along each principal direction (longer quads along the
// direction in which the surface bends less, e.g. along a cylinder's axis), each length clamped
// to max_ratio around the median-curvature length, smoothed like adaptive_face_size (log
// lengths, and the directions through their outer products), and normalized so that the sized
// area equals the surface area.
[[nodiscard]] std::vector<Eigen::Matrix3d> adaptive_face_metric(
    const core::TriMesh& mesh, const AdaptiveSizingOptions& options = {});

// Where principal curvature directions are prominent (paper section 6.1: "in places where they
// were prominent").
struct PrincipalDirectionOptions {
  // A vertex is anisotropic when its larger principal curvature magnitude is at least min_ratio
  // times the smaller one and at least min_curvature / (bounding-box diagonal): the same regions
  // as the quad metrics' principal-direction measure (quadex::QuadMetrics::principal_angle_mean).
  double min_ratio = 2;
  double min_curvature = 4;
  // Passes of averaging the directions (as outer products, sign-free) over vertex neighbours.
  int smoothing_passes = 4;
};

// Per face the direction of larger principal curvature magnitude (a unit tangent vector; the
// other direction is the cross's other arm) where all three vertices are anisotropic and the
// smoothed directions agree, zero elsewhere: the input of ParamOptions::face_direction.
[[nodiscard]] std::vector<Eigen::Vector3d> principal_face_directions(
    const core::TriMesh& mesh, const PrincipalDirectionOptions& options = {});

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
