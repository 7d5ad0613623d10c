#include "distortion_energy.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>

namespace quadify::param {
namespace {

using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;

// vec(J) = (a, b, c, d) for J = [[a, b], [c, d]].
Vec4 vec(const Eigen::Matrix2d& J) { return {J(0, 0), J(0, 1), J(1, 0), J(1, 1)}; }

// det J = ad − bc: gradient (d, −c, −b, a) and constant Hessian.
Vec4 det_gradient(const Vec4& w) { return {w[3], -w[2], -w[1], w[0]}; }
Mat4 det_hessian() {
  Mat4 h = Mat4::Zero();
  h(0, 3) = h(3, 0) = 1;
  h(1, 2) = h(2, 1) = -1;
  return h;
}

DensityEval symmetric_dirichlet(const Vec4& w, bool derivatives) {
  DensityEval r;
  const double det = w[0] * w[3] - w[1] * w[2];
  if (!(det > 0)) {
    r.finite = false;
    r.value = std::numeric_limits<double>::infinity();
    return r;
  }
  const double s = w.squaredNorm();
  const double q = 1 + 1 / (det * det);
  r.value = s * q;
  if (!derivatives) return r;
  const Vec4 gs = 2 * w;
  const Vec4 gd = det_gradient(w);
  const Vec4 gq = -2 / (det * det * det) * gd;
  r.gradient = q * gs + s * gq;
  const Mat4 hq = 6 / (det * det * det * det) * gd * gd.transpose() -
                  2 / (det * det * det) * det_hessian();
  r.hessian = 2 * q * Mat4::Identity() + gs * gq.transpose() + gq * gs.transpose() + s * hq;
  return r;
}

DensityEval arap(const Vec4& w, bool derivatives) {
  // Σ(σi − 1)² = |J|² − 2(σ1 + σ2) + 2 with σ1 + σ2 = |(a + d, c − b)| (signed σ2).
  DensityEval r;
  const Eigen::Vector2d v(w[0] + w[3], w[2] - w[1]);
  const double nv = v.norm();
  r.value = w.squaredNorm() - 2 * nv + 2;
  if (!derivatives) return r;
  Eigen::Matrix<double, 2, 4> L;
  L << 1, 0, 0, 1, 0, -1, 1, 0;
  r.gradient = 2 * w;
  r.hessian = 2 * Mat4::Identity();
  // The norm is not differentiable at v = 0 (a collapsed triangle); use the subgradient 0.
  constexpr double kTinyNorm = 1e-300;
  if (nv > kTinyNorm) {
    r.gradient -= 2 * L.transpose() * v / nv;
    const Eigen::Matrix2d hn = (Eigen::Matrix2d::Identity() - v * v.transpose() / (nv * nv)) / nv;
    r.hessian -= 2 * L.transpose() * hn * L;
  }
  return r;
}

DensityEval mips(const Vec4& w, bool derivatives) {
  DensityEval r;
  const double det = w[0] * w[3] - w[1] * w[2];
  if (!(det > 0)) {
    r.finite = false;
    r.value = std::numeric_limits<double>::infinity();
    return r;
  }
  const double s = w.squaredNorm();
  r.value = s / det;
  if (!derivatives) return r;
  const Vec4 gs = 2 * w;
  const Vec4 gd = det_gradient(w);
  r.gradient = gs / det - s * gd / (det * det);
  r.hessian = 2 * Mat4::Identity() / det - (gs * gd.transpose() + gd * gs.transpose()) / (det * det) +
              2 * s * gd * gd.transpose() / (det * det * det) - s * det_hessian() / (det * det);
  return r;
}

// φ(ψ) = ((ψ + offset)/scale)^e composed with a density.
DensityEval power(DensityEval base, double offset, double scale, double e, bool derivatives) {
  if (!base.finite) return base;
  const double u = std::max((base.value + offset) / scale, 0.0);
  DensityEval r;
  r.value = std::pow(u, e);
  if (!derivatives) return r;
  const double d1 = e * std::pow(u, e - 1) / scale;
  const double d2 = e * (e - 1) * std::pow(u, e - 2) / (scale * scale);
  r.gradient = d1 * base.gradient;
  r.hessian = d1 * base.hessian + (u > 0 ? d2 : 0.0) * base.gradient * base.gradient.transpose();
  return r;
}

// The PSD-projected Hessian over vec(J) of an isotropic density ψ(σ1, σ2) of the symmetric
// Dirichlet family, from its analytic eigensystem (Smith, de Goes, Kim 2019, "Analytic
// eigensystems for isotropic distortion energies", 2D case): with J = U diag(σ1, σ2) Vᵀ
// (det J > 0), the twist U·[[0,−1],[1,0]]·Vᵀ/√2 has eigenvalue (ψ1 + ψ2)/(σ1 + σ2), the flip
// U·[[0,1],[1,0]]·Vᵀ/√2 has (ψ1 − ψ2)/(σ1 − σ2), and the scalings U·e_i e_iᵀ·Vᵀ span a 2×2 block
// [[ψ11, ψ12], [ψ12, ψ22]]. The four directions come from J's conformal part E = (a + d)/2,
// H = (c − b)/2 and its anticonformal part F = (a − d)/2, G = (c + b)/2 without an SVD:
// σ1,2 = |(E, H)| ± |(F, G)|. Symmetric Dirichlet ψ = Σ σi² + σi⁻²; with `power` > 0 it is
// composed with (ψ/4)^power (Density::kPowerSD). A tenth of the cost of a 4×4 eigensolver.
Mat4 projected_sd_hessian(const Vec4& w, double power) {
  const double E = 0.5 * (w[0] + w[3]), H = 0.5 * (w[2] - w[1]);
  const double F = 0.5 * (w[0] - w[3]), G = 0.5 * (w[2] + w[1]);
  const double Q = std::hypot(E, H), R = std::hypot(F, G);
  const double s1 = Q + R, s2 = Q - R;
  const double i1 = 1 / (s1 * s1 * s1), i2 = 1 / (s2 * s2 * s2);
  // Symmetric Dirichlet's derivatives over the singular values.
  double p1 = 2 * s1 - 2 * i1, p2 = 2 * s2 - 2 * i2;
  double p11 = 2 + 6 * i1 / s1, p22 = 2 + 6 * i2 / s2, p12 = 0;
  double twist = 2 - 2 * (i1 + i2) / (s1 + s2);
  double flip = 2 + 2 * (s1 * s1 + s1 * s2 + s2 * s2) * i1 * i2;
  if (power > 0) {
    const double u = std::max((s1 * s1 + s2 * s2 + 1 / (s1 * s1) + 1 / (s2 * s2)) / 4, 0.0);
    const double d1 = power * std::pow(u, power - 1) / 4;
    const double d2 = u > 0 ? power * (power - 1) * std::pow(u, power - 2) / 16 : 0.0;
    p11 = d1 * p11 + d2 * p1 * p1;
    p22 = d1 * p22 + d2 * p2 * p2;
    p12 = d2 * p1 * p2;
    twist *= d1;
    flip *= d1;
    p1 *= d1;
    p2 *= d1;
  }
  // Orthonormal directions (Frobenius) over vec(J) = (a, b, c, d): rotation-like n+ and
  // reflection-like n− (U·Vᵀ and U·diag(1, −1)·Vᵀ, over √2), twist t and flip l.
  const double rq = Q > 0 ? 1 / (Q * std::sqrt(2.0)) : 0, rr = R > 0 ? 1 / (R * std::sqrt(2.0)) : 0;
  const double r2 = 1 / std::sqrt(2.0);
  const Vec4 n_plus = Q > 0 ? Vec4(Vec4(E, -H, H, E) * rq) : Vec4(Vec4(1, 0, 0, 1) * r2);
  const Vec4 n_minus = R > 0 ? Vec4(Vec4(F, G, G, -F) * rr) : Vec4(Vec4(1, 0, 0, -1) * r2);
  const Vec4 t = Q > 0 ? Vec4(Vec4(-H, -E, E, -H) * rq) : Vec4(Vec4(0, -1, 1, 0) * r2);
  const Vec4 l = R > 0 ? Vec4(Vec4(-G, F, F, G) * rr) : Vec4(Vec4(0, 1, 1, 0) * r2);
  const Vec4 d1v = (n_plus + n_minus) * r2, d2v = (n_plus - n_minus) * r2;
  Mat4 h = std::max(twist, 0.0) * t * t.transpose() + std::max(flip, 0.0) * l * l.transpose();
  // The 2×2 scaling block, projected in closed form.
  const double mean = 0.5 * (p11 + p22), half = 0.5 * (p11 - p22);
  const double rad = std::hypot(half, p12);
  const double mu1 = mean + rad, mu2 = mean - rad;
  // Eigenvector of mu1: (cos θ, sin θ) with tan 2θ = 2·p12/(p11 − p22).
  const double theta = 0.5 * std::atan2(p12, half);
  const Vec4 e1 = std::cos(theta) * d1v + std::sin(theta) * d2v;
  const Vec4 e2 = -std::sin(theta) * d1v + std::cos(theta) * d2v;
  h += std::max(mu1, 0.0) * e1 * e1.transpose() + std::max(mu2, 0.0) * e2 * e2.transpose();
  return h;
}

}  // namespace

DensityEval evaluate_density(Density kind, double p, const Eigen::Matrix2d& J, bool derivatives,
                             bool project_psd) {
  const Vec4 w = vec(J);
  DensityEval r;
  // Symmetric Dirichlet and its powers: value and gradient as below, the projected Hessian from
  // the analytic eigensystem.
  if (derivatives && project_psd && (kind == Density::kSymmetricDirichlet || kind == Density::kPowerSD)) {
    r = kind == Density::kSymmetricDirichlet ? symmetric_dirichlet(w, true)
                                             : power(symmetric_dirichlet(w, true), 0.0, 4.0, p, true);
    if (r.finite) r.hessian = projected_sd_hessian(w, kind == Density::kPowerSD ? p : 0.0);
    return r;
  }
  switch (kind) {
    case Density::kSymmetricDirichlet: r = symmetric_dirichlet(w, derivatives); break;
    case Density::kPowerSD: r = power(symmetric_dirichlet(w, derivatives), 0.0, 4.0, p, derivatives); break;
    case Density::kArap: r = arap(w, derivatives); break;
    case Density::kPowerArap: r = power(arap(w, derivatives), 1.0, 1.0, 0.5 * p, derivatives); break;
    case Density::kMips: r = mips(w, derivatives); break;
  }
  // A Cholesky factorization succeeds exactly on positive definite Hessians, which the
  // projection leaves as they are, at a fraction of the eigensolver's cost.
  if (derivatives && project_psd && r.finite && Eigen::LLT<Mat4>(r.hessian).info() != Eigen::Success) {
    Eigen::SelfAdjointEigenSolver<Mat4> es(r.hessian);
    Vec4 ev = es.eigenvalues();
    if (ev.minCoeff() < 0) {
      ev = ev.cwiseMax(0.0);
      r.hessian = es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
    }
  }
  return r;
}

}  // namespace quadify::param
