// Per-triangle distortion densities ψ(J) of the 2×2 Jacobian J (UV w.r.t. the isometric rest
// frame of the 3D triangle), with gradient and Hessian in vec(J) = (J00, J01, J10, J11).
// Internal to libparam.
#pragma once

#include <libparam/seamless_param.h>

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

// Exponents of the L^p continuation of the symmetric Dirichlet energy for Energy::kTau. Going on
// to 64 after 16 lowered τ by 5–10% (spot 1.525 → 1.405, casting 1.536 → 1.466, elk 1.564 →
// 1.460, dilo 1.956 → 1.791) for about 25% more Newton iterations; 128 and 256 gained < 2% more.
inline constexpr double kTauPowers[] = {2, 4, 8, 16, 32, 64};
// Newton iterations per continuation stage: each stage only needs to move the maximum, and
// the stages follow each other closely.
inline constexpr int kTauStageIterations = 15;
// Newton-decrement stop of the intermediate stages: each only hands its layout to the next
// exponent; the last stage converges to its caller's final tolerance.
inline constexpr double kTauStageTolerance = 1e-5;

// The density and exponent that optimize a user-facing Energy: kTau is optimized as symmetric
// Dirichlet (its L^p continuation is run separately), kLinfArap as L^8 ARAP.
struct EnergyDensity {
  Density density = Density::kSymmetricDirichlet;
  double power = 1;
};
inline EnergyDensity energy_density(Energy energy) {
  constexpr double kLinfArapPower = 8;
  switch (energy) {
    case Energy::kArap: return {Density::kArap, 1};
    case Energy::kLinfArap: return {Density::kPowerArap, kLinfArapPower};
    case Energy::kConformal: return {Density::kMips, 1};
    default: return {Density::kSymmetricDirichlet, 1};
  }
}

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

// The derivatives of area·ψ(X·Dm⁻¹) over the face's edge vectors X = [x_1 − x_0, x_2 − x_0]
// (local variable 2j + d: coordinate d of edge j), from ev's derivatives over vec(J) (index 2d+r).
inline void edge_vector_derivatives(const Eigen::Matrix2d& rest_inverse, double area,
                                    const DensityEval& ev, Eigen::Vector4d* g,
                                    Eigen::Matrix4d* h) {
  Eigen::Matrix4d B = Eigen::Matrix4d::Zero();
  for (int j = 0; j < 2; ++j)
    for (int d = 0; d < 2; ++d)
      for (int r = 0; r < 2; ++r) B(2 * d + r, 2 * j + d) = rest_inverse(j, r);
  *g = area * B.transpose() * ev.gradient;
  *h = area * B.transpose() * ev.hessian * B;
}

}  // namespace quadify::param
