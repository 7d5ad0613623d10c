// Tests of quantize_seamless: param → quantize → extract on the small meshes of tests/data.
#include <gtest/gtest.h>
#include <libcore/read_mesh.h>
#include <libparam/constrained_layout.h>

#include <Eigen/Geometry>

#include "quantize_test_util.h"
#include "test_util.h"

namespace quadify {
namespace {

// Quad count within this fraction of the target (the scale is set from the UV area; the
// flip-free re-optimization changes the area only slightly).
constexpr double kQuadCountTolerance = 0.10;

core::TriMesh load(const std::string& name) {
  return core::to_trimesh(core::read_mesh(test::data_path(name)));
}

// Asserts every property of a successful pipeline run on `mesh`.
void expect_valid_quads(const std::string& name, const core::TriMesh& mesh, int target,
                        bool check_count) {
  const test::PipelineRun run = test::run_pipeline(mesh, target);
  ASSERT_TRUE(run.param.status.is_ok()) << name << ": " << run.param.status.to_string();
  ASSERT_TRUE(run.quantized.status.is_ok()) << name << ": " << run.quantized.status.to_string();
  const quantize::QuantizeStats& st = run.quantized.stats;
  EXPECT_EQ(st.n_flipped, 0) << name;
  EXPECT_EQ(st.n_rounded, st.n_candidates) << name;
  EXPECT_GT(st.scale, 0) << name;
  EXPECT_EQ(test::integer_seamless_violation(run.quantized.uv), "") << name;
  const core::UVMetrics um = core::compute_uv_metrics(run.quantized.uv);
  EXPECT_EQ(um.n_flipped, 0) << name;
  EXPECT_EQ(um.n_degenerate, 0) << name;
  ASSERT_TRUE(run.quads.status.is_ok()) << name << ": " << run.quads.status.to_string();
  EXPECT_EQ(run.quads.stats.n_non_quads, 0) << name;
  const quadex::QuadMetrics qm = quadex::compute_quad_metrics(run.quads.quads);
  EXPECT_GT(qm.n_faces, 0) << name;
  EXPECT_TRUE(qm.manifold) << name;
  EXPECT_EQ(qm.n_non_quads, 0) << name;
  EXPECT_EQ(qm.euler_characteristic, core::topology_stats(mesh).euler_characteristic) << name;
  if (check_count) {
    EXPECT_NEAR(qm.n_faces, target, kQuadCountTolerance * target)
        << name << ": " << qm.n_faces << " quads for target " << target << ", scale retries "
        << st.n_scale_retries;
  }
}

TEST(QuantizeSeamless, SphereIsIntegerSeamlessAndExtracts) {
  expect_valid_quads("sphere", load("sphere.obj"), 300, true);
}

TEST(QuantizeSeamless, TorusIsIntegerSeamlessAndExtracts) {
  expect_valid_quads("torus", load("torus.obj"), 400, true);
}

TEST(QuantizeSeamless, CubeIsIntegerSeamlessAndExtracts) {
  // Eight cones on 12 triangles: the quad count is dictated by the cone lattice.
  expect_valid_quads("cube", load("cube.obj"), 54, false);
}

TEST(QuantizeSeamless, EdgeLengthSetsTheScale) {
  const core::TriMesh mesh = load("sphere.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok()) << p.status.to_string();
  quantize::QuantizeOptions qo;
  qo.edge_length = 0.2;  // sphere of radius 1: area 4π ≈ 12.6 → about 314 quads
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p, qo);
  ASSERT_TRUE(q.status.is_ok()) << q.status.to_string();
  double area3d = 0;
  for (int f = 0; f < mesh.n_faces(); ++f) {
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)),
                          p2 = mesh.V.row(mesh.F(f, 2));
    area3d += 0.5 * (p1 - p0).cross(p2 - p0).norm();
  }
  const double expected = area3d / (qo.edge_length * qo.edge_length);
  EXPECT_NEAR(q.stats.uv_area, expected, kQuadCountTolerance * expected)
      << "UV area " << q.stats.uv_area << " vs 3D area / h² " << expected << ", scale retries "
      << q.stats.n_scale_retries << ", reverted " << q.stats.n_reverted;
  EXPECT_EQ(test::integer_seamless_violation(q.uv), "");
}

TEST(QuantizeSeamless, RejectsNonSeamlessInput) {
  const core::TriMesh mesh = load("sphere.obj");
  param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  ASSERT_FALSE(p.seams.empty());
  // Break one seam: move one corner of a seam face along its edge.
  p.uv.corner_uv.row(3 * p.seams[0].face_b) += Eigen::RowVector2d(0.01, 0.003);
  const quantize::QuantizeResult q = quantize::quantize_seamless(mesh, p);
  EXPECT_EQ(q.status.code(), core::StatusCode::kInvalidInput) << q.status.to_string();
  EXPECT_NE(q.status.message().find("not seamless"), std::string::npos) << q.status.message();
}

TEST(QuantizeSeamless, RejectsMismatchedSizesAndBadOptions) {
  const core::TriMesh mesh = load("cube.obj");
  param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  quantize::QuantizeOptions bad;
  bad.target_faces = -5;
  EXPECT_EQ(quantize::quantize_seamless(mesh, p, bad).status.code(),
            core::StatusCode::kInvalidInput);
  p.uv.corner_uv.conservativeResize(5, 2);
  EXPECT_EQ(quantize::quantize_seamless(mesh, p).status.code(), core::StatusCode::kInvalidInput);
}

TEST(ConstrainedLayout, CopiesAndAffineRowsOnTheSphere) {
  const core::TriMesh mesh = load("sphere.obj");
  const param::ParamResult p = param::compute_seamless_param(mesh);
  ASSERT_TRUE(p.status.is_ok());
  param::CopyLayout cl;
  ASSERT_TRUE(param::build_copy_layout(mesh, p.uv.corner_uv, p.seams, 1e-6, &cl).is_ok());
  EXPECT_EQ(cl.n_components, 1);
  EXPECT_GE(cl.n_copies(), mesh.n_vertices());
  // Pin a coordinate of one copy to a value, plus a duplicate (dependent) row.
  const int k = cl.n_copies() / 2;
  const double target = cl.x[2 * k] + 0.05;
  param::AffineRow row{{{2 * k, 1.0}}, target};
  const param::ConstrainedLayoutResult r =
      param::solve_constrained_layout(mesh, cl, cl.x, {}, {row, row});
  ASSERT_TRUE(r.status.is_ok()) << r.status.to_string();
  EXPECT_EQ(r.n_flipped, 0);
  ASSERT_EQ(r.independent.size(), 2u);
  EXPECT_EQ(r.independent[0], 1);
  EXPECT_EQ(r.independent[1], 0);
  EXPECT_NEAR(r.x[2 * k], target, 1e-9) << "pinned coordinate";
  // Seams still hold.
  for (const param::CopySeam& s : cl.seams) {
    Eigen::Vector2d ea = r.x.segment<2>(2 * s.a1) - r.x.segment<2>(2 * s.a0);
    for (int i = 0; i < s.matching; ++i) ea = Eigen::Vector2d(-ea.y(), ea.x());
    EXPECT_LT((r.x.segment<2>(2 * s.b1) - r.x.segment<2>(2 * s.b0) - ea).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace quadify
