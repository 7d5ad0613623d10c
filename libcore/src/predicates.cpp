#include <libcore/predicates.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace quadify::core {
namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
}

int orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return static_cast<int>(CGAL::orientation(Kernel::Point_2(a.x(), a.y()), Kernel::Point_2(b.x(), b.y()),
                                            Kernel::Point_2(c.x(), c.y())));
}

int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d) {
  auto p = [](const Eigen::Vector3d& x) { return Kernel::Point_3(x.x(), x.y(), x.z()); };
  return static_cast<int>(CGAL::orientation(p(a), p(b), p(c), p(d)));
}

bool collinear3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  auto p = [](const Eigen::Vector3d& x) { return Kernel::Point_3(x.x(), x.y(), x.z()); };
  return CGAL::collinear(p(a), p(b), p(c));
}

}  // namespace quadify::core
