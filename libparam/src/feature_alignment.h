// Feature alignment (paper section 6): which half-edges carry the alignment rows, how far a
// feature edge is from an axis (Def. 6.1), the optimal initial rotation (Alg. 4), and the wedge
// check that keeps two features at a vertex from being labeled into one direction. Internal to
// libparam.
#pragma once

#include "cut_layout.h"

#include <libcore/mesh.h>

#include <Eigen/Core>

#include <functional>
#include <numbers>
#include <vector>

namespace quadify::param {

// Label of a feature edge: the UV coordinate it keeps constant (0: u, 1: v), or one of these.
constexpr int kUnlabeled = -1;
constexpr int kDisabled = 2;

struct FeatureSet {
  std::vector<int> halfedge;      // per feature: the half-edge 3f+k whose copies carry its row
  std::vector<int> edge_feature;  // per EdgeTopology edge: feature index or -1
  int size() const { return static_cast<int>(halfedge.size()); }
};

// Features of the edges `edges` (EdgeTopology ids of cut.topo; duplicates ignored), each on the
// half-edge stored in cut.topo.edge_halfedge.
FeatureSet make_feature_set(const CutMesh& cut, const std::vector<int>& edges);

// Angle of the feature's edge vector (x: 2·#copies) to the u axis, in quarter turns, (−2, 2].
double feature_measure(const CutMesh& cut, const Eigen::VectorXd& x, int halfedge);

// The label nearest to a measure: an even number of quarter turns runs along u (v constant).
inline int nearest_label(double measure) {
  const long n = std::lround(measure);
  return (n % 2 == 0) ? 1 : 0;
}

// Turn (radians) that brings an edge of measure q (quarter turns) onto the nearest direction
// of label l's axis.
double label_turn(double q, int label);

// A smooth feature curve: features that continue each other on the surface (their angle at the
// shared vertex within max_bend of 180°, each the other's only such partner at that vertex), in
// order along the curve; joints[k] is the vertex shared by features[k] and features[k + 1]
// (and, on a closed curve, joints.back() the one shared by the last and the first).
struct FeatureCurve {
  std::vector<int> features;
  std::vector<int> joints;
  bool closed = false;
};
// The smooth curves of two features or more (max_bend in radians), in order of first feature.
// With corner_length > 0, a curve that turns by corner_turn (radians) or more within an arc of
// corner_length (a rounded corner at the scale of the quads) is split there, at the joint whose
// turn within corner_length / 4 is largest (the middle of the rounding).
std::vector<FeatureCurve> smooth_feature_curves(const core::TriMesh& mesh, const FeatureSet& fs,
                                                double max_bend, double corner_length = 0,
                                                double corner_turn = std::numbers::pi / 3);

// The straight runs of the open curves of `curves` from their ends at acute corners: an end
// where another feature leaves at an angle in [min_angle, max_angle) (radians, on the surface) to
// the curve's end edge. A run is the curve's edges from that end while their direction stays
// within max_bend of the end edge's (on the surface; a curve bending into a rounded rim further on
// keeps its rim out), two edges at least; a curve acute at both ends gives the part from the start
// of one run to the end of the other. In the order of `curves`.
std::vector<FeatureCurve> curves_at_acute_corners(const core::TriMesh& mesh, const FeatureSet& fs,
                                                  const std::vector<FeatureCurve>& curves,
                                                  double min_angle, double max_angle,
                                                  double max_bend);

// Turn (radians, counter-clockwise positive) of each feature of a curve from the direction of its
// first feature, followed along the curve in the layout x (corner angles summed around each
// joint, so seams in between do not matter); the first is 0. NaN after a joint on a boundary
// whose fan does not join the two features.
std::vector<double> curve_turns(const core::TriMesh& mesh, const CutMesh& cut, const Eigen::VectorXd& x,
                                const FeatureSet& fs, const FeatureCurve& curve);

// One batch of whole-curve labels (ParamOptions::feature_curve_labels). Each curve with unlabeled
// features is to become one straight iso-line: its target direction, followed along the curve
// (curve_turns), is the axis its labeled features already have (the one of most labeled
// length), else the axis direction that turns its unlabeled features least at most. A feature
// whose turn to it stays below max_turn is handled by the curve (else it is labeled on its own):
// its label is the one of that axis in its chart, and it is taken when take(|turn to that axis|
// in quarter turns) holds.
struct CurveLabels {
  std::vector<int> label;     // per feature: the curve's label if taken, else kUnlabeled
  std::vector<char> handled;  // per feature: handled by its curve (taken now or later)
  std::vector<int> taken;     // features taken in this batch, increasing
};
CurveLabels label_curves(const core::TriMesh& mesh, const CutMesh& cut, const Eigen::VectorXd& x,
                         const FeatureSet& fs, const std::vector<FeatureCurve>& curves,
                         const std::vector<int>& label, double max_turn,
                         const std::function<bool(double)>& take);

// The alignment row x_b[c] − x_a[c] = 0 of a half-edge a→b keeping coordinate c constant.
SparseRow feature_row(const CutMesh& cut, int halfedge, int constant_coord);

// Alg. 4: the angle (radians) of the mean of the largest of four k-means groups of the features'
// unit edge vectors (length-weighted; deterministic start from the 4-fold circular mean).
double feature_rotation_angle(const CutMesh& cut, const Eigen::VectorXd& x, const FeatureSet& fs);

// Wedge check around every vertex touched by a feature of `is_new`: going around the vertex
// through its faces in the layout x, each labeled feature edge (label 0/1, old or new) will turn
// by its rounding δ to its axis; two consecutive ones whose target directions are less than
// 45° apart would close the faces between them (both along one direction). One feature of each
// such pair (a new one, the one farther from its axis) is first given its other axis, if that
// turns it by at most 0.6 of a quarter turn and the two do not continue each other straight;
// if it still conflicts, it is disabled; until no pair remains.
// A pair whose wedge would open or close by more than max_ratio (its target angle, a multiple of
// 90°, against its angle on the surface) is a conflict too: it would cost a distortion of about
// that ratio. A wedge bounded by a boundary edge (where an open mesh needs its corners) uses
// max_boundary_ratio instead.
struct WedgeResolution {
  std::vector<int> relabeled;  // new features to give the other axis (increasing)
  std::vector<int> disabled;   // new features to disable (increasing)
};
WedgeResolution resolve_wedge_conflicts(const core::TriMesh& mesh, const CutMesh& cut,
                                        const Eigen::VectorXd& x, const FeatureSet& fs,
                                        const std::vector<int>& label,
                                        const std::vector<char>& is_new, double max_ratio,
                                        double max_boundary_ratio);

}  // namespace quadify::param
