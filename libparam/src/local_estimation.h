// Local estimation of a matching (paper section 5): lay out a small face patch around the seam
// edge with the floor and with the ceiling of its continuous matching, keep the one with lower
// distortion. Internal to libparam.
#pragma once

#include "cut_layout.h"
#include "distortion_energy.h"
#include "layout_optimizer.h"

#include <vector>

namespace quadify::param {

struct PatchChoice {
  int matching = 0;                   // chosen integer matching (floor or ceil of the measure)
  double distortion[2] = {0, 0};      // floor, ceil (+inf when the layout failed or flipped)
  int n_faces = 0;
};

class LocalEstimator {
 public:
  LocalEstimator(const core::TriMesh& mesh, const CutMesh& cut, const LayoutDomain& domain,
                 int bfs_levels);
  // Faces within `bfs_levels` vertex rings of seam s (level 1: faces at its two vertices).
  std::vector<int> patch_faces(int seam) const;
  // Chooses the matching of seam s from its measure m. rounded[s'] (INT_MIN = free) are the
  // matchings already fixed; x the current global layout (flip-free). Thread-safe (const).
  PatchChoice choose(int seam, double measure, const std::vector<int>& rounded,
                     const Eigen::VectorXd& x, Density density, double power) const;

 private:
  const core::TriMesh& mesh_;
  const CutMesh& cut_;
  const LayoutDomain& domain_;
  int levels_;
  std::vector<std::vector<int>> vertex_faces_;
  std::vector<int> edge_seam_;  // edge id → seam index or -1
};

}  // namespace quadify::param
