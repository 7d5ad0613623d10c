#include "coarse_cones.h"

#include <libcore/predicates.h>
#include <libcore/sparse_solver.h>
#include <libcore/uv_metrics.h>
#include <libparam/constrained_layout.h>

#include "distortion_energy.h"

#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include <cmath>
#include <string>
#include <vector>

namespace quadify::param {
namespace {

// A smoothed face whose area is below this fraction of the mean face area counts as collapsed:
// the parametrization of such a copy is ill-conditioned, so the coarse cones are not tried.
constexpr double kMinSmoothedAreaRatio = 1e-8;
// Fractions of the input blended into a smoothed copy that has a collapsed face, tried in turn.
constexpr double kInputBlend[] = {0, 0.1, 0.3};
// build_copy_layout's seam tolerance (× UV bbox diagonal) for the smoothed map carried over:
// compute_seamless_param guarantees ParamOptions::seam_tol × the copy's bbox diagonal, and the
// re-optimization imposes the seam rows exactly again.
constexpr double kCarriedSeamTolerance = 1e-7;
// Newton iterations of the re-optimization on the original triangles: it starts from the
// smoothed copy's layout, further from its optimum than a batch of Alg. 1 starts from its own.
constexpr int kRelayoutNewtonIters = 200;
constexpr double kRelayoutTolerance = 1e-8;

double face_area(const Eigen::MatrixX3d& V, const Eigen::MatrixX3i& F, int f) {
  const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace

core::Status smooth_for_cones(const core::TriMesh& mesh, double scale, core::TriMesh* smoothed) {
  if (!(scale > 0) || !std::isfinite(scale))
    return core::Status::invalid_input("smooth_for_cones: scale must be positive");
  const int nv = mesh.n_vertices(), nf = mesh.n_faces();
  std::vector<Eigen::Triplet<double>> w_entries;
  w_entries.reserve(6 * static_cast<size_t>(nf));
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(nv);
  double total_area = 0;
  for (int f = 0; f < nf; ++f) {
    const double area = face_area(mesh.V, mesh.F, f);
    total_area += area;
    for (int k = 0; k < 3; ++k) {
      const int i = mesh.F(f, k), j = mesh.F(f, (k + 1) % 3), o = mesh.F(f, (k + 2) % 3);
      mass[i] += area / 3;
      // Half the cotangent of the angle at o, opposite edge (i, j).
      const Eigen::Vector3d a = mesh.V.row(i) - mesh.V.row(o), b = mesh.V.row(j) - mesh.V.row(o);
      const double cross = a.cross(b).norm();
      if (!(cross > 0)) continue;
      const double half_cot = 0.5 * a.dot(b) / cross;
      w_entries.emplace_back(i, j, half_cot);
      w_entries.emplace_back(j, i, half_cot);
    }
  }
  Eigen::SparseMatrix<double> W(nv, nv);
  W.setFromTriplets(w_entries.begin(), w_entries.end());
  // A = M + t·(D − W) with clamped weights: L = D − W stays positive semi-definite whatever the
  // triangles' angles, so A is SPD.
  const double t = scale * scale;
  std::vector<Eigen::Triplet<double>> a_entries;
  a_entries.reserve(W.nonZeros() + nv);
  for (int v = 0; v < nv; ++v) a_entries.emplace_back(v, v, mass[v]);
  for (int col = 0; col < W.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(W, col); it; ++it) {
      const double w = std::max(0.0, it.value());
      a_entries.emplace_back(it.row(), it.col(), -t * w);
      a_entries.emplace_back(it.row(), it.row(), t * w);
    }
  Eigen::SparseMatrix<double> A(nv, nv);
  A.setFromTriplets(a_entries.begin(), a_entries.end());
  core::SparseSolver solver;
  if (core::Status s = solver.factorize(A); !s.is_ok()) return s;
  const Eigen::MatrixXd rhs = mass.asDiagonal() * mesh.V;
  Eigen::MatrixX3d V = solver.solve(rhs);
  if (!V.allFinite()) return core::Status::numerical_failure("smooth_for_cones: non-finite solution");
  // The flow shrinks the surface; restore its area (the map's scale, not its cones, depends on it).
  double new_area = 0;
  for (int f = 0; f < nf; ++f) new_area += face_area(V, mesh.F, f);
  if (!(new_area > 0)) return core::Status::invalid_input("smooth_for_cones: the smoothed surface has no area");
  const Eigen::RowVector3d centroid = V.colwise().mean();
  V = ((V.rowwise() - centroid) * std::sqrt(total_area / new_area)).rowwise() + centroid;
  const double min_area = kMinSmoothedAreaRatio * total_area / std::max(nf, 1);
  auto collapsed_face = [&](const Eigen::MatrixX3d& W) {
    for (int f = 0; f < nf; ++f)
      if (!(face_area(W, mesh.F, f) > min_area) ||
          core::collinear3d(W.row(mesh.F(f, 0)), W.row(mesh.F(f, 1)), W.row(mesh.F(f, 2))))
        return f;
    return -1;
  };
  // A thin part that the flow collapses to a curve (dragon at 1.4 quad edges) keeps a little of
  // its own shape: the copy is blended with the input, as little as makes every face proper.
  int f_collapsed = -1;
  for (const double keep : kInputBlend) {
    const Eigen::MatrixX3d W = (1 - keep) * V + keep * mesh.V;
    f_collapsed = collapsed_face(W);
    if (f_collapsed < 0) {
      smoothed->V = W;
      smoothed->F = mesh.F;
      return core::Status::ok();
    }
  }
  return core::Status::invalid_input("smooth_for_cones: face " + std::to_string(f_collapsed) +
                                     " collapses at this scale");
}

ParamResult relayout_on_mesh(const core::TriMesh& mesh, const ParamResult& seamless,
                             const ParamOptions& options) {
  ParamResult out;
  out.uv.mesh = mesh;
  out.seams = seamless.seams;
  out.cones = seamless.cones;
  out.stats = seamless.stats;
  CopyLayout copies;
  out.status = build_copy_layout(mesh, seamless.uv.corner_uv, seamless.seams, kCarriedSeamTolerance, &copies);
  if (!out.status.is_ok()) return out;
  ConstrainedLayoutOptions lo;
  lo.energy = options.energy == Energy::kTau ? Energy::kSymmetricDirichlet : options.energy;
  lo.face_size = options.face_size;
  lo.face_metric = options.face_metric;
  lo.max_newton_iters = kRelayoutNewtonIters;
  lo.relative_tolerance = kRelayoutTolerance;
  // τ's L^p continuation after the symmetric Dirichlet solve (as in compute_seamless_param).
  if (options.energy == Energy::kTau) lo.tau_powers.assign(std::begin(kTauPowers), std::end(kTauPowers));
  const ConstrainedLayoutResult r = solve_constrained_layout(mesh, copies, copies.x, {}, {}, lo);
  out.stats.total_iterations += r.iterations;
  if (!r.status.is_ok()) {
    out.status = core::Status::not_converged(r.status.message() + " (smoothed map: tau " +
                                                   std::to_string(seamless.stats.tau) + ", " +
                                                   std::to_string(r.n_flipped) + " flipped)");
    return out;
  }
  out.uv.corner_uv.resize(3 * mesh.n_faces(), 2);
  for (int c = 0; c < 3 * mesh.n_faces(); ++c)
    out.uv.corner_uv.row(c) = r.x.segment<2>(2 * copies.corner_copy[c]).transpose();
  const core::UVMetrics m = core::compute_uv_metrics(out.uv);
  out.stats.tau = m.tau;
  out.stats.n_flipped = m.n_flipped;
  out.stats.sd_max = m.sd_max;
  out.stats.seam_residual = m.seam_residual_abs;
  // solve_constrained_layout reports remaining flips as a failure; this is the exact recount.
  if (m.n_flipped > 0)
    out.status = core::Status::not_converged("the carried-over layout keeps " +
                                             std::to_string(m.n_flipped) + " flipped faces");
  return out;
}

}  // namespace quadify::param
