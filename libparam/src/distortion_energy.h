// Per-triangle distortion densities ψ(J) of the 2×2 Jacobian J (UV w.r.t. the isometric rest
// frame of the 3D triangle), with gradient and Hessian in vec(J) = (J00, J01, J10, J11).
// Internal to libparam.
#pragma once

#include <Eigen/Core>

namespace quadify::param {

enum class Density {
  kSymmetricDirichlet,  // |J|² + |J⁻¹|²  (4 at an isometry; +inf when det J ≤ 0)
  kPowerSD,             // (SD/4)^p       (L^p continuation towards the max distortion)
  kArap,                // |J − R(J)|² = Σ(σi − 1)² with signed σ2
  kPowerArap,           // (1 + ARAP)^(p/2) (L^p ARAP; the offset keeps the Hessian regular
                        // at an isometry)
  kMips,                // |J|²/det J = σ1/σ2 + σ2/σ1 (+inf when det J ≤ 0)
};

inline bool is_barrier(Density d) {
  return d == Density::kSymmetricDirichlet || d == Density::kPowerSD || d == Density::kMips;
}

struct DensityEval {
  double value = 0;
  Eigen::Vector4d gradient = Eigen::Vector4d::Zero();
  Eigen::Matrix4d hessian = Eigen::Matrix4d::Zero();
  bool finite = true;  // false when J is outside the barrier's domain
};

// ψ(J) and, when `derivatives`, its gradient and Hessian. `project_psd` clamps the Hessian's
// negative eigenvalues to zero (for Newton). `p` is the exponent of the power densities.
DensityEval evaluate_density(Density kind, double p, const Eigen::Matrix2d& J, bool derivatives,
                             bool project_psd);

}  // namespace quadify::param
