// Sizing (paper section 7, isotropic): the curvature estimate, size fields from vertex values
// and from curvature, and a seamless map that follows a size field.
#include <libparam/seamless_param.h>
#include <libparam/sizing.h>

#include <libcore/curvature.h>
#include <libcore/predicates.h>
#include <libcore/read_mesh.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <stdexcept>

#include "test_util.h"

namespace quadify::param {
namespace {

core::TriMesh data_mesh(const std::string& name) {
  return core::to_trimesh(core::read_mesh(test::data_path(name)));
}

// tests/data/sphere.obj (unit icosphere) stretched along x: an ellipsoid with semi-axes (a, 1, 1).
core::TriMesh ellipsoid(double a) {
  core::TriMesh m = data_mesh("sphere.obj");
  m.V.col(0) *= a;
  return m;
}

double face_area(const core::TriMesh& m, int f) {
  const Eigen::Vector3d p0 = m.V.row(m.F(f, 0)), p1 = m.V.row(m.F(f, 1)), p2 = m.V.row(m.F(f, 2));
  return 0.5 * (p1 - p0).cross(p2 - p0).norm();
}

TEST(Sizing, JetFittingFindsTheCurvaturesOfSpheresAndEllipsoids) {
  core::TriMesh sphere = data_mesh("sphere.obj");
  sphere.V *= 2.0;  // radius 2: both principal curvatures 1/2 (convex: positive w.r.t. the outward normal)
  const core::VertexCurvature c = core::estimate_curvature(sphere);
  for (int v = 0; v < sphere.n_vertices(); ++v) {
    EXPECT_NEAR(c.k_max[v], 0.5, 0.02) << v;
    EXPECT_NEAR(c.k_min[v], 0.5, 0.02) << v;
  }
  // Ellipsoid (3, 1, 1): at the tip (±3, 0, 0) both curvatures are a/b² = 3; on the equator
  // x = 0 they are 1 (around x) and b/a² = 1/9 (along x), the larger across the long axis.
  const core::TriMesh e = ellipsoid(3);
  const core::VertexCurvature ce = core::estimate_curvature(e);
  int tips = 0, equator = 0;
  for (int v = 0; v < e.n_vertices(); ++v) {
    if (std::abs(e.V(v, 0)) > 2.999) {
      ++tips;
      EXPECT_NEAR(ce.k_max[v], 3, 0.6) << "tip " << v;
    } else if (std::abs(e.V(v, 0)) < 1e-9) {
      ++equator;
      EXPECT_NEAR(ce.k_max[v], 1, 0.1) << "equator " << v;
      EXPECT_NEAR(ce.k_min[v], 1.0 / 9, 0.1) << "equator " << v;
      const Eigen::Vector3d d_min = ce.d_min.row(v);
      EXPECT_GT(std::abs(d_min.x()), 0.95) << "the weak direction runs along the long axis";
    }
  }
  EXPECT_EQ(tips, 2);
  EXPECT_GT(equator, 10);
}

TEST(Sizing, VertexValuesBecomeNormalizedFaceSizes) {
  const core::TriMesh m = data_mesh("sphere.obj");
  std::vector<double> vs(m.n_vertices());
  for (int v = 0; v < m.n_vertices(); ++v) vs[v] = m.V(v, 0) > 0 ? 10.0 : 5.0;  // only ratios matter
  const std::vector<double> fs = face_size_from_vertices(m, vs);
  ASSERT_EQ(fs.size(), static_cast<size_t>(m.n_faces()));
  double area = 0, sized = 0, lo = 1e9, hi = 0;
  for (int f = 0; f < m.n_faces(); ++f) {
    area += face_area(m, f);
    sized += face_area(m, f) / (fs[f] * fs[f]);
    lo = std::min(lo, fs[f]);
    hi = std::max(hi, fs[f]);
  }
  EXPECT_NEAR(sized, area, 1e-9 * area) << "the map keeps the surface's area";
  EXPECT_NEAR(hi / lo, 2.0, 1e-9) << "faces wholly on either side keep the ratio of their values";
  EXPECT_THROW((void)face_size_from_vertices(m, std::vector<double>(3, 1.0)), std::invalid_argument);
  vs[7] = -1;
  EXPECT_THROW((void)face_size_from_vertices(m, vs), std::invalid_argument);
}

TEST(Sizing, AdaptiveSizesAreSmallerWhereTheSurfaceBendsMore) {
  const core::TriMesh e = ellipsoid(3);
  AdaptiveSizingOptions o;
  const std::vector<double> fs = adaptive_face_size(e, o);
  double tip = 0, mid = 0;
  int n_tip = 0, n_mid = 0;
  for (int f = 0; f < e.n_faces(); ++f) {
    const double x = (e.V(e.F(f, 0), 0) + e.V(e.F(f, 1), 0) + e.V(e.F(f, 2), 0)) / 3;
    if (std::abs(x) > 2.5) tip += fs[f], ++n_tip;
    if (std::abs(x) < 0.5) mid += fs[f], ++n_mid;
  }
  ASSERT_GT(n_tip, 0);
  ASSERT_GT(n_mid, 0);
  // Curvature 3 against 1: ideally 1/sqrt(3) = 0.58; the smoothing and the clamp soften it.
  EXPECT_LT(tip / n_tip, 0.8 * mid / n_mid);
  o.max_ratio = 1;
  for (const double s : adaptive_face_size(e, o)) EXPECT_NEAR(s, 1.0, 1e-12) << "ratio 1: uniform";
}

TEST(Sizing, ThinPartSizesShrinkWhereTheRadiusIsBelowAQuadEdge) {
  // Ellipsoid (3, 1, 1): curvatures 1 and 1/9 at the equator (radius 1 / (1 + 1/9) = 0.9), 3 and
  // 3 at the tips (radius 1/6).
  const core::TriMesh e = ellipsoid(3);
  // Quads of edge 0.1 fit everywhere: all ones.
  for (const double s : thin_part_vertex_size(e, 0.1)) EXPECT_EQ(s, 1.0);
  // Quads of edge 0.5: the tips are thinner than a quad, the equator is not.
  ThinPartSizingOptions o;
  const std::vector<double> vs = thin_part_vertex_size(e, 0.5, o);
  int n_tip = 0, n_mid = 0;
  for (int v = 0; v < e.n_vertices(); ++v) {
    EXPECT_GE(vs[v], o.min_ratio - 1e-12) << v;
    EXPECT_LE(vs[v], 1.0) << v;
    if (std::abs(e.V(v, 0)) > 2.9) {
      ++n_tip;
      EXPECT_LT(vs[v], 0.85) << "tip " << v;  // (1/6) / 0.5 = 0.33 at the tip, smoothed over 30 passes
    }
    if (std::abs(e.V(v, 0)) < 0.5) {
      ++n_mid;
      EXPECT_GT(vs[v], 0.99) << "equator " << v;
    }
  }
  EXPECT_GT(n_tip, 0);
  EXPECT_GT(n_mid, 0);
  // A smaller floor is reached with coarser quads; the normalized face sizes keep the count.
  o.min_ratio = 0.5;
  for (const double s : thin_part_vertex_size(e, 5.0, o)) EXPECT_GE(s, 0.5 - 1e-12);
  const std::vector<double> fs = face_size_from_vertices(e, vs);
  double area = 0, sized = 0;
  for (int f = 0; f < e.n_faces(); ++f) {
    area += face_area(e, f);
    sized += face_area(e, f) / (fs[f] * fs[f]);
  }
  EXPECT_NEAR(sized, area, 1e-9 * area);
  EXPECT_THROW((void)thin_part_vertex_size(e, 0.0), std::invalid_argument);
}

// A flat grid of n unit columns and four rows of vertices at y = −1, 0, w, w + 1, two triangles a
// cell; the rows y = 0 and y = w are feature curves bounding a band of width w.
struct Band {
  core::TriMesh mesh;
  std::vector<std::array<int, 2>> lower, upper;  // the feature rows
  int vertex(int row, int column) const { return row * (n + 1) + column; }
  int n = 0;
};

// The upper two rows may rise by `tilt` per unit of x (curves diverging from the lower row).
Band band(int n, double w, double tilt = 0) {
  Band b;
  b.n = n;
  const double y[4] = {-1, 0, w, w + 1};
  b.mesh.V.resize(4 * (n + 1), 3);
  for (int r = 0; r < 4; ++r)
    for (int i = 0; i <= n; ++i) b.mesh.V.row(b.vertex(r, i)) << i, y[r] + (r >= 2 ? tilt * i : 0.0), 0;
  b.mesh.F.resize(6 * n, 3);
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < n; ++i) {
      const int p = b.vertex(r, i), q = b.vertex(r, i + 1);
      const int s = b.vertex(r + 1, i + 1), t = b.vertex(r + 1, i);
      b.mesh.F.row(2 * (r * n + i)) << p, q, s;
      b.mesh.F.row(2 * (r * n + i) + 1) << p, s, t;
    }
  for (int i = 0; i < n; ++i) {
    b.lower.push_back({b.vertex(1, i), b.vertex(1, i + 1)});
    b.upper.push_back({b.vertex(2, i), b.vertex(2, i + 1)});
  }
  return b;
}

TEST(Sizing, NarrowBandsBetweenFeatureCurvesGetQuadsAsLongAsTheyAreWide) {
  FeatureStripSizingOptions o;
  const Band narrow = band(6, 0.4);
  std::vector<std::array<int, 2>> both = narrow.lower;
  both.insert(both.end(), narrow.upper.begin(), narrow.upper.end());
  // Quads of edge 1: the band is 0.4 wide, below half an edge; its vertices get 0.4, the rows one
  // unit away 0.4 + grade.
  const std::vector<double> s = feature_strip_vertex_size(narrow.mesh, both, 1.0, o);
  ASSERT_EQ(static_cast<int>(s.size()), narrow.mesh.n_vertices());
  for (int i = 0; i <= narrow.n; ++i) {
    EXPECT_NEAR(s[narrow.vertex(1, i)], 0.4, 1e-12) << i;
    EXPECT_NEAR(s[narrow.vertex(2, i)], 0.4, 1e-12) << i;
    EXPECT_NEAR(s[narrow.vertex(0, i)], 0.4 + o.grade, 1e-12) << i;
    EXPECT_NEAR(s[narrow.vertex(3, i)], 0.4 + o.grade, 1e-12) << i;
  }
  // Coarser quads: the floor (0.4 wide is a quarter of an edge of 1.6).
  EXPECT_NEAR(feature_strip_vertex_size(narrow.mesh, both, 1.6, o)[narrow.vertex(1, 0)], o.min_ratio, 1e-12);
  // A band wider than half an edge or narrower than a fifth, one curve alone, curves diverging
  // by more than max_turn_deg (26.6°), and curves joined at the band's faces (a feature edge
  // across it) leave the size alone.
  for (const double x : feature_strip_vertex_size(narrow.mesh, both, 0.7, o)) EXPECT_EQ(x, 1.0);
  for (const double x : feature_strip_vertex_size(narrow.mesh, both, 2.5, o)) EXPECT_EQ(x, 1.0);
  const Band diverging = band(1, 0.4, 0.5);
  const std::vector<std::array<int, 2>> diverging_curves = {diverging.lower[0], diverging.upper[0]};
  for (const double x : feature_strip_vertex_size(diverging.mesh, diverging_curves, 1.0, o))
    EXPECT_EQ(x, 1.0);
  FeatureStripSizingOptions wide_turn = o;
  wide_turn.max_turn_deg = 30;
  const std::vector<double> wide = feature_strip_vertex_size(diverging.mesh, diverging_curves, 1.0, wide_turn);
  EXPECT_LT(wide[diverging.vertex(1, 0)], 1.0);
  for (const double x : feature_strip_vertex_size(narrow.mesh, narrow.lower, 1.0, o)) EXPECT_EQ(x, 1.0);
  std::vector<std::array<int, 2>> joined = both;
  for (int i = 0; i <= narrow.n; ++i) joined.push_back({narrow.vertex(1, i), narrow.vertex(2, i)});
  for (int i = 0; i < narrow.n; ++i) joined.push_back({narrow.vertex(1, i), narrow.vertex(2, i + 1)});
  for (const double x : feature_strip_vertex_size(narrow.mesh, joined, 1.0, o)) EXPECT_EQ(x, 1.0);
  EXPECT_THROW((void)feature_strip_vertex_size(narrow.mesh, both, 0.0), std::invalid_argument);
  EXPECT_THROW((void)feature_strip_vertex_size(narrow.mesh, {{0, 1000}}, 1.0), std::invalid_argument);
}

TEST(Sizing, ShortClosedFeatureLoopsGetSmallerQuads) {
  // The link of vertex 0 of the unit icosphere: a closed loop of feature edges around it.
  const core::TriMesh m = data_mesh("sphere.obj");
  std::vector<int> ring;
  for (int f = 0; f < m.n_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (m.F(f, k) == 0) ring.push_back(f);
  std::vector<std::array<int, 2>> loop;
  double length = 0;
  for (const int f : ring) {
    int k = 0;
    while (m.F(f, k) != 0) ++k;
    const int a = m.F(f, (k + 1) % 3), b = m.F(f, (k + 2) % 3);
    loop.push_back({a, b});
    length += (m.V.row(a) - m.V.row(b)).norm();
  }
  ASSERT_GE(loop.size(), 5u);
  FeatureLoopSizingOptions o;
  // Quads of edge C / 6: the loop wants 12 around, it gets 6 → half the edge along it.
  const double edge = length / 6;
  const std::vector<double> s = feature_loop_vertex_size(m, loop, edge, o);
  ASSERT_EQ(static_cast<int>(s.size()), m.n_vertices());
  for (const auto& [a, b] : loop) EXPECT_NEAR(s[a], 0.5, 1e-12) << "loop vertex " << a;
  // Growing back by `grade` per target edge of distance: the centre is within one mesh edge.
  const double centre_distance = (m.V.row(0) - m.V.row(loop[0][0])).norm();
  EXPECT_GT(s[0], 0.5);
  EXPECT_LE(s[0], 0.5 + o.grade * centre_distance / edge + 1e-12);
  int far = -1;
  for (int v = 0; v < m.n_vertices(); ++v) {
    EXPECT_GE(s[v], 0.5 - 1e-12) << v;
    EXPECT_LE(s[v], 1.0) << v;
    if (m.V.row(v).dot(m.V.row(0)) < -0.9) far = v;
  }
  ASSERT_GE(far, 0);
  EXPECT_EQ(s[far], 1.0) << "the antipode is far from the loop";
  // The floor, with coarse quads.
  for (const double x : feature_loop_vertex_size(m, loop, 100 * length, o)) EXPECT_GE(x, o.min_ratio - 1e-12);
  EXPECT_NEAR(feature_loop_vertex_size(m, loop, 100 * length, o)[loop[0][0]], o.min_ratio, 1e-12);
  // A loop already 12 quad edges around, and an open curve, leave the size alone.
  for (const double x : feature_loop_vertex_size(m, loop, length / 12, o)) EXPECT_EQ(x, 1.0);
  const std::vector<std::array<int, 2>> open(loop.begin() + 1, loop.end());
  for (const double x : feature_loop_vertex_size(m, open, edge, o)) EXPECT_EQ(x, 1.0);
  EXPECT_THROW((void)feature_loop_vertex_size(m, loop, 0.0), std::invalid_argument);
  EXPECT_THROW((void)feature_loop_vertex_size(m, {{0, m.n_vertices()}}, edge), std::invalid_argument);
}

TEST(Sizing, AnisotropicMetricIsLongerAlongTheDirectionOfLesserCurvature) {
  const core::TriMesh e = ellipsoid(3);
  const std::vector<Eigen::Matrix3d> metric = adaptive_face_metric(e);
  ASSERT_EQ(metric.size(), static_cast<size_t>(e.n_faces()));
  double area = 0;
  for (int f = 0; f < e.n_faces(); ++f) area += face_area(e, f);
  EXPECT_NEAR(sized_area(e, {}, metric), area, 1e-9 * area) << "normalized: the map keeps the area";
  // Around the middle (curvature 1 around, 1/9 along x) the metric shrinks x less: edges along x
  // ask to be longer (|M·x̂| small) than edges around (|M·ŷ| or |M·ẑ|, whichever is tangent).
  int n = 0;
  for (int f = 0; f < e.n_faces(); ++f) {
    const Eigen::Vector3d p0 = e.V.row(e.F(f, 0)), p1 = e.V.row(e.F(f, 1)), p2 = e.V.row(e.F(f, 2));
    const Eigen::Vector3d c = (p0 + p1 + p2) / 3;
    if (std::abs(c.x()) > 0.3) continue;
    const Eigen::Vector3d around = Eigen::Vector3d(0, -c.z(), c.y()).normalized();
    EXPECT_GT((metric[f] * around).norm(), 1.5 * (metric[f] * Eigen::Vector3d::UnitX()).norm()) << f;
    ++n;
  }
  EXPECT_GT(n, 10);
  // The parametrization takes it like a size field: flip-free and seamless.
  ParamOptions o;
  o.energy = Energy::kSymmetricDirichlet;
  o.face_metric = metric;
  const ParamResult r = compute_seamless_param(e, o);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_flipped, 0);
  o.face_metric.assign(e.n_faces(), Eigen::Matrix3d::Zero());
  EXPECT_EQ(compute_seamless_param(e, o).status.code(), core::StatusCode::kInvalidInput)
      << "a metric that flattens the faces is bad input";
}

// A seamless map with a size field: flip-free and seamless as always, and where faces ask for
// twice the edge length their UV triangles are half as large (a quad there covers 4× the area).
TEST(Sizing, SeamlessMapFollowsTheSizeField) {
  const core::TriMesh m = data_mesh("sphere.obj");
  ParamOptions o;
  o.energy = Energy::kSymmetricDirichlet;
  std::vector<double> vs(m.n_vertices());
  for (int v = 0; v < m.n_vertices(); ++v) vs[v] = m.V(v, 2) > 0 ? 2.0 : 1.0;
  o.face_size = face_size_from_vertices(m, vs);
  const ParamResult r = compute_seamless_param(m, o);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_flipped, 0);
  EXPECT_LT(r.stats.seam_residual, 1e-9);
  double uv_top = 0, uv_bottom = 0, a_top = 0, a_bottom = 0;
  for (int f = 0; f < m.n_faces(); ++f) {
    const Eigen::Vector2d a = r.uv.corner_uv.row(3 * f), b = r.uv.corner_uv.row(3 * f + 1),
                          c = r.uv.corner_uv.row(3 * f + 2);
    const double uv_area = 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
    const double z = (m.V(m.F(f, 0), 2) + m.V(m.F(f, 1), 2) + m.V(m.F(f, 2), 2)) / 3;
    if (z > 0.3) uv_top += uv_area, a_top += face_area(m, f);
    if (z < -0.3) uv_bottom += uv_area, a_bottom += face_area(m, f);
  }
  const double ratio = (uv_top / a_top) / (uv_bottom / a_bottom);
  EXPECT_NEAR(ratio, 0.25, 0.08) << "UV area per surface area: 1/size²";
  o.face_size.assign(3, 1.0);
  EXPECT_EQ(compute_seamless_param(m, o).status.code(), core::StatusCode::kInvalidInput);
}

// Area-weighted mean angle (degrees) between the UV image of each face's direction and the
// nearest UV axis, measured on the result's corner UVs (not the library's own bookkeeping).
double mean_direction_angle(const core::TriMesh& m, const ParamResult& r,
                            const std::vector<Eigen::Vector3d>& dir) {
  double sum = 0, weight = 0;
  for (int f = 0; f < m.n_faces(); ++f) {
    if (dir[f].squaredNorm() == 0) continue;
    const Eigen::Vector3d p0 = m.V.row(m.F(f, 0));
    const Eigen::Vector3d e1 = m.V.row(m.F(f, 1)).transpose() - p0, e2 = m.V.row(m.F(f, 2)).transpose() - p0;
    Eigen::Matrix2d g;
    g << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
    const Eigen::Vector2d ab = g.inverse() * Eigen::Vector2d(e1.dot(dir[f]), e2.dot(dir[f]));
    const Eigen::Vector2d u0 = r.uv.corner_uv.row(3 * f), u1 = r.uv.corner_uv.row(3 * f + 1),
                          u2 = r.uv.corner_uv.row(3 * f + 2);
    const Eigen::Vector2d img = ab.x() * (u1 - u0) + ab.y() * (u2 - u0);
    const double t = std::atan2(std::min(std::abs(img.x()), std::abs(img.y())),
                                std::max(std::abs(img.x()), std::abs(img.y())));
    sum += face_area(m, f) * t * 180 / M_PI;
    weight += face_area(m, f);
  }
  return sum / weight;
}

// Ellipsoid (3, 1, 1): anisotropic around the middle (curvatures 1 around, 1/9 along the axis),
// isotropic at the tips; a sphere has no prominent directions.
TEST(Sizing, PrincipalDirectionsWhereTheyAreProminent) {
  const core::TriMesh e = ellipsoid(3);
  const std::vector<Eigen::Vector3d> dir = principal_face_directions(e);
  ASSERT_EQ(static_cast<int>(dir.size()), e.n_faces());
  int middle = 0, tips = 0;
  for (int f = 0; f < e.n_faces(); ++f) {
    const double x = (e.V(e.F(f, 0), 0) + e.V(e.F(f, 1), 0) + e.V(e.F(f, 2), 0)) / 3;
    if (std::abs(x) < 1.5) {
      ASSERT_GT(dir[f].norm(), 0.99) << "face " << f << " at x = " << x;
      EXPECT_LT(std::abs(dir[f].x()), 0.2) << "the larger curvature runs around the axis";
      ++middle;
    } else if (std::abs(x) > 2.8) {
      EXPECT_EQ(dir[f].norm(), 0) << "isotropic tip, face " << f;
      ++tips;
    }
  }
  EXPECT_GT(middle, 100);
  EXPECT_GT(tips, 4);
  for (const Eigen::Vector3d& d : principal_face_directions(data_mesh("sphere.obj")))
    EXPECT_EQ(d.norm(), 0);
}

// Direction alignment (paper 6.1): the map sends the principal directions of the ellipsoid onto
// the UV axes, flip-free and seamless; without it they lie at random angles.
TEST(Sizing, SeamlessMapFollowsThePrincipalDirections) {
  const core::TriMesh e = ellipsoid(3);
  const std::vector<Eigen::Vector3d> dir = principal_face_directions(e);
  ParamOptions o;
  const ParamResult plain = compute_seamless_param(e, o);
  ASSERT_TRUE(plain.status.is_ok()) << plain.status.to_string();
  o.face_direction = dir;
  o.direction_weight = 3;
  const ParamResult r = compute_seamless_param(e, o);
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.stats.n_flipped, 0);
  EXPECT_LT(r.stats.seam_residual, 1e-9);
  int n_dir = 0;
  for (const Eigen::Vector3d& d : dir) n_dir += d.norm() > 0;
  EXPECT_EQ(r.stats.n_direction_faces, n_dir);
  const double aligned = mean_direction_angle(e, r, dir), unaligned = mean_direction_angle(e, plain, dir);
  EXPECT_LT(aligned, 4) << "unaligned: " << unaligned;
  EXPECT_GT(unaligned, 12);
  EXPECT_NEAR(r.stats.direction_angle, aligned, 0.5) << "the reported angle is the measured one";
  EXPECT_LT(r.stats.tau, 2) << "alignment costs some distortion, not a blow-up";
  o.face_direction.assign(2, Eigen::Vector3d::UnitX());
  EXPECT_EQ(compute_seamless_param(e, o).status.code(), core::StatusCode::kInvalidInput);
}

}  // namespace
}  // namespace quadify::param
