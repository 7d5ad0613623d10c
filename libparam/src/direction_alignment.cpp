#include "direction_alignment.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace quadify::param {
namespace {

Eigen::Vector2d image(const LayoutDomain& domain, const DirectionField& field, int i,
                      const Eigen::VectorXd& x) {
  const auto& fc = domain.face_copies[field.face[i]];
  const Eigen::Vector2d p0 = x.segment<2>(2 * fc[0]);
  return field.coef[i].x() * (x.segment<2>(2 * fc[1]) - p0) +
         field.coef[i].y() * (x.segment<2>(2 * fc[2]) - p0);
}

}  // namespace

DirectionField make_direction_field(const core::TriMesh& mesh, const LayoutDomain& domain,
                                    const std::vector<Eigen::Vector3d>& direction) {
  DirectionField field;
  if (direction.empty()) return field;
  for (int f = 0; f < mesh.n_faces(); ++f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0));
    const Eigen::Vector3d e1 = mesh.V.row(mesh.F(f, 1)).transpose() - p0;
    const Eigen::Vector3d e2 = mesh.V.row(mesh.F(f, 2)).transpose() - p0;
    const Eigen::Vector3d& d = direction[f];
    if (!(d.squaredNorm() > 0)) continue;
    // Least squares in the face plane: [e1 e2]·(α, β) = d (the normal part of d drops out).
    Eigen::Matrix2d gram;
    gram << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
    const double det = gram.determinant();
    if (!(std::abs(det) > 1e-30 * gram(0, 0) * gram(1, 1))) continue;
    const Eigen::Vector2d ab = gram.inverse() * Eigen::Vector2d(e1.dot(d), e2.dot(d));
    const Eigen::Vector2d rest_image = domain.rest_inverse[f].inverse() * ab;
    const double len = rest_image.norm();
    if (!(len > 0) || !ab.allFinite()) continue;
    field.face.push_back(f);
    field.coef.push_back(ab / len);
    field.area.push_back(domain.area[f]);
  }
  return field;
}

std::vector<SparseRow> direction_rows(const LayoutDomain& domain, const DirectionField& field,
                                      const Eigen::VectorXd& x) {
  std::vector<SparseRow> rows;
  rows.reserve(field.face.size());
  for (int i = 0; i < field.size(); ++i) {
    const Eigen::Vector2d img = image(domain, field, i, x);
    // Nearest axis u (|u| ≥ |v|): penalize the v component, and the other way round.
    const int k = std::abs(img.x()) >= std::abs(img.y()) ? 1 : 0;
    const auto& fc = domain.face_copies[field.face[i]];
    const double s = std::sqrt(field.area[i]);
    const double a = field.coef[i].x(), b = field.coef[i].y();
    rows.push_back(make_row({{2 * fc[1] + k, s * a}, {2 * fc[2] + k, s * b}, {2 * fc[0] + k, -s * (a + b)}}));
  }
  return rows;
}

double direction_rotation_angle(const LayoutDomain& domain, const DirectionField& field,
                                const Eigen::VectorXd& x) {
  Eigen::Vector2d fourfold = Eigen::Vector2d::Zero();
  for (int i = 0; i < field.size(); ++i) {
    const Eigen::Vector2d img = image(domain, field, i, x);
    if (!(img.squaredNorm() > 0)) continue;
    const double a = 4 * std::atan2(img.y(), img.x());
    fourfold += field.area[i] * Eigen::Vector2d(std::cos(a), std::sin(a));
  }
  if (!(fourfold.squaredNorm() > 0)) return 0;
  return std::atan2(fourfold.y(), fourfold.x()) / 4;
}

double direction_angle_mean(const LayoutDomain& domain, const DirectionField& field,
                            const Eigen::VectorXd& x) {
  double sum = 0, weight = 0;
  for (int i = 0; i < field.size(); ++i) {
    const Eigen::Vector2d img = image(domain, field, i, x);
    const double t = std::atan2(std::min(std::abs(img.x()), std::abs(img.y())),
                                std::max(std::abs(img.x()), std::abs(img.y())));
    sum += field.area[i] * t;
    weight += field.area[i];
  }
  return weight > 0 ? sum / weight * 180 / std::numbers::pi : 0;
}

}  // namespace quadify::param
