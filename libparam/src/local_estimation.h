// Local estimation of a matching (paper section 5): lay out a small face patch around the seam
// edge with the floor and with the ceiling of its continuous matching, keep the one with lower
// distortion. Internal to libparam.
#pragma once

#include "cut_layout.h"
#include "distortion_energy.h"
#include "feature_alignment.h"
#include "layout_optimizer.h"

#include <vector>

namespace quadify::param {

struct PatchChoice {
  int matching = 0;                   // chosen integer matching (floor or ceil of the measure)
  double distortion[2] = {0, 0};      // floor, ceil (+inf when the layout failed or flipped)
  int n_faces = 0;
};

// Local estimation of a feature label (paper section 6, "Labeling feature edges"): the patch
// laid out with the edge keeping u constant and keeping v constant.
struct FeatureChoice {
  int label = 0;                    // constant coordinate of the better layout
  double distortion[2] = {0, 0};    // label 0, label 1 (+inf when the layout failed or flipped)
  double tau[2] = {0, 0};           // max distortion τ over the patch of each layout
  double tau_free = 0;              // τ of the patch laid out without the label (the part of
                                    // the distortion that the feature is not to blame for)
  int n_faces = 0;
};

class LocalEstimator {
 public:
  // `features` (may be null) are the feature edges whose labels the choose functions receive;
  // labeled ones inside a patch constrain it.
  LocalEstimator(const core::TriMesh& mesh, const CutMesh& cut, const LayoutDomain& domain,
                 int bfs_levels, const FeatureSet* features = nullptr);
  // Faces within `bfs_levels` vertex rings of seam s (level 1: faces at its two vertices).
  std::vector<int> patch_faces(int seam) const;
  // Chooses the matching of seam s from its measure m. rounded[s'] (INT_MIN = free) are the
  // matchings already fixed, labels[i] the feature labels (empty without features); x the
  // current global layout (flip-free). Thread-safe (const).
  PatchChoice choose(int seam, double measure, const std::vector<int>& rounded,
                     const std::vector<int>& labels, const Eigen::VectorXd& x, Density density,
                     double power) const;
  // Chooses the label of feature i (an index of `features`) likewise.
  FeatureChoice choose_feature(int feature, const std::vector<int>& rounded,
                               const std::vector<int>& labels, const Eigen::VectorXd& x,
                               Density density, double power) const;

 private:
  struct Alternatives {
    double energy[2];
    double tau[2];
    double tau_free;  // +inf unless asked for
    int n_faces;
  };
  // Lays out the patch around mesh edge (v0, v1) twice, with the fixed rows inside it (rounded
  // seams except skip_seam, labeled features except skip_feature) plus alternative[side]; with
  // `free_layout`, a third time with the fixed rows only.
  Alternatives evaluate(int v0, int v1, int skip_seam, int skip_feature,
                        const std::array<std::vector<SparseRow>, 2>& alternative, bool free_layout,
                        double edge_length, const std::vector<int>& rounded,
                        const std::vector<int>& labels, const Eigen::VectorXd& x, Density density,
                        double power) const;
  std::vector<int> patch_faces_around(int v0, int v1) const;

  const core::TriMesh& mesh_;
  const CutMesh& cut_;
  const LayoutDomain& domain_;
  int levels_;
  std::vector<std::vector<int>> vertex_faces_;
  std::vector<int> edge_seam_;  // edge id → seam index or -1
  const FeatureSet* features_;
};

}  // namespace quadify::param
