#include "distortion_energy.h"

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

}  // namespace

DensityEval evaluate_density(Density kind, double p, const Eigen::Matrix2d& J, bool derivatives,
                             bool project_psd) {
  const Vec4 w = vec(J);
  DensityEval r;
  switch (kind) {
    case Density::kSymmetricDirichlet: r = symmetric_dirichlet(w, derivatives); break;
    case Density::kPowerSD: r = power(symmetric_dirichlet(w, derivatives), 0.0, 4.0, p, derivatives); break;
    case Density::kArap: r = arap(w, derivatives); break;
    case Density::kPowerArap: r = power(arap(w, derivatives), 1.0, 1.0, 0.5 * p, derivatives); break;
    case Density::kMips: r = mips(w, derivatives); break;
  }
  if (derivatives && project_psd && r.finite) {
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
