// Shared checks of the quantize tests: the full pipeline param → quantize → extract and an exact,
// independent verification of Def. 3.2 (integer-seamless) of the paper.
#pragma once

#include <libcore/mesh.h>
#include <libcore/topology.h>
#include <libcore/uv_metrics.h>
#include <libparam/seamless_param.h>
#include <libquadex/extract_quads.h>
#include <libquadex/quad_metrics.h>
#include <libquadex/relax_quads.h>
#include <libquantize/quantize.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <string>

namespace quadify::test {

// Exact check of Def. 3.2 without the quantizer's own bookkeeping: across every interior edge
// some rotation R^r maps the edge vector of one side exactly onto the other, the translation is an
// exact integer pair and the same at both endpoints; every cone's corners sit on integer points.
// Returns an empty string when it holds, else a description of the first violation.
inline std::string integer_seamless_violation(const core::UVMesh& map) {
  const core::TriMesh& mesh = map.mesh;
  const core::EdgeTopology topo = core::build_edge_topology(mesh);
  auto uv = [&](int c) { return Eigen::Vector2d(map.corner_uv.row(c).transpose()); };
  auto rot = [](const Eigen::Vector2d& e, int r) -> Eigen::Vector2d {
    switch (r) {
      case 0:
        return e;
      case 1:
        return {-e.y(), e.x()};
      case 2:
        return -e;
      default:
        return {e.y(), -e.x()};
    }
  };
  auto integer = [](const Eigen::Vector2d& p) {
    return p.x() == std::round(p.x()) && p.y() == std::round(p.y());
  };
  for (int e = 0; e < topo.n_edges(); ++e) {
    const int he = topo.edge_halfedge[e], tw = topo.twin[he];
    if (tw < 0) continue;
    const int fa = he / 3, ka = he % 3, fb = tw / 3, kb = tw % 3;
    const Eigen::Vector2d a0 = uv(3 * fa + ka), a1 = uv(3 * fa + (ka + 1) % 3);
    const Eigen::Vector2d b1 = uv(3 * fb + kb), b0 = uv(3 * fb + (kb + 1) % 3);
    int found = -1;
    for (int r = 0; r < 4 && found < 0; ++r)
      if (b1 - b0 == rot(a1 - a0, r)) found = r;
    if (found < 0) return "edge " + std::to_string(e) + ": no exact rotation";
    const Eigen::Vector2d t0 = b0 - rot(a0, found), t1 = b1 - rot(a1, found);
    if (t0 != t1 || !integer(t0))
      return "edge " + std::to_string(e) + ": translation (" + std::to_string(t0.x()) + ", " +
             std::to_string(t0.y()) + ") not an exact integer";
  }
  const core::UVMetrics m = core::compute_uv_metrics(map);
  for (const core::Cone& cone : m.cones)
    for (int c = 0; c < 3 * mesh.n_faces(); ++c)
      if (mesh.F(c / 3, c % 3) == cone.vertex && !integer(uv(c)))
        return "cone vertex " + std::to_string(cone.vertex) + " at non-integer UV (" +
               std::to_string(uv(c).x()) + ", " + std::to_string(uv(c).y()) + ")";
  return "";
}

struct PipelineRun {
  param::ParamResult param;
  quantize::QuantizeResult quantized;
  quadex::ExtractResult quads;
  double seconds_param = 0, seconds_quantize = 0, seconds_extract = 0;
};

inline PipelineRun run_pipeline(const core::TriMesh& mesh, int target_faces) {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  PipelineRun run;
  auto t = Clock::now();
  quantize::QuantizeOptions qo;
  qo.target_faces = target_faces;
  param::ParamOptions po;
  po.energy = param::Energy::kSymmetricDirichlet;
  po.cone_pair_distance = quantize::recommended_cone_pair_distance(mesh, qo);
  po.cone_pair_max_hops = quantize::kRecommendedConePairHops;
  po.cone_split_distance = quantize::target_edge_length(mesh, qo);
  run.param = param::compute_seamless_param(mesh, po);
  run.seconds_param = since(t);
  if (!run.param.status.is_ok()) return run;
  t = Clock::now();
  run.quantized = quantize::quantize_seamless(mesh, run.param, qo);
  run.seconds_quantize = since(t);
  if (!run.quantized.status.is_ok()) return run;
  t = Clock::now();
  run.quads = quadex::extract_quads(run.quantized.uv);
  // As the CLI does: relax the vertices of badly shaped quads on the input surface.
  if (run.quads.status.is_ok()) {
    quadex::RelaxResult relaxed = quadex::relax_bad_quads(run.quads.quads, mesh);
    if (relaxed.status.is_ok()) run.quads.quads = std::move(relaxed.quads);
  }
  run.seconds_extract = since(t);
  return run;
}

}  // namespace quadify::test
