#include "local_estimation.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <limits>

namespace quadify::param {
namespace {

// Newton iterations of a patch layout (patches are small and start near their optimum).
constexpr int kPatchIterations = 20;
constexpr double kPatchTolerance = 1e-6;
// Two patch distortions closer than this (relative) are a tie: the patch solves stop at
// kPatchTolerance, so smaller differences are round-off (e.g. a patch that turns freely).
constexpr double kTieTolerance = 10 * kPatchTolerance;

// 0 or 1: the alternative with clearly lower distortion; -1: a tie (both failed, or equal
// within `tolerance`, relative).
int lower_distortion(double d0, double d1, double tolerance) {
  if (!(d0 < d1) && !(d1 < d0)) return -1;
  if (std::isfinite(d0) && std::isfinite(d1) &&
      std::abs(d0 - d1) <= tolerance * std::max(std::abs(d0), std::abs(d1)))
    return -1;
  return d0 < d1 ? 0 : 1;
}

}  // namespace

LocalEstimator::LocalEstimator(const core::TriMesh& mesh, const CutMesh& cut,
                               const LayoutDomain& domain, int bfs_levels,
                               const FeatureSet* features)
    : mesh_(mesh), cut_(cut), domain_(domain), levels_(bfs_levels), features_(features) {
  vertex_faces_.resize(mesh.n_vertices());
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) vertex_faces_[mesh.F(f, k)].push_back(f);
  edge_seam_.assign(cut.topo.n_edges(), -1);
  for (size_t s = 0; s < cut.seams.size(); ++s) edge_seam_[cut.seams[s].edge] = static_cast<int>(s);
}

std::vector<int> LocalEstimator::patch_faces(int seam) const {
  const int fa = cut_.seams[seam].he_a / 3, ka = cut_.seams[seam].he_a % 3;
  return patch_faces_around(mesh_.F(fa, ka), mesh_.F(fa, (ka + 1) % 3));
}

std::vector<int> LocalEstimator::patch_faces_around(int v0, int v1) const {
  std::vector<char> in_face(mesh_.n_faces(), 0), in_vertex(mesh_.n_vertices(), 0);
  std::vector<int> faces, frontier = {v0, v1};
  for (int v : frontier) in_vertex[v] = 1;
  for (int level = 0; level < levels_; ++level) {
    std::vector<int> next;
    for (int v : frontier)
      for (int f : vertex_faces_[v]) {
        if (in_face[f]) continue;
        in_face[f] = 1;
        faces.push_back(f);
        for (int k = 0; k < 3; ++k)
          if (!in_vertex[mesh_.F(f, k)]) {
            in_vertex[mesh_.F(f, k)] = 1;
            next.push_back(mesh_.F(f, k));
          }
      }
    frontier.swap(next);
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

LocalEstimator::Alternatives LocalEstimator::evaluate(
    int v0, int v1, int skip_seam, int skip_feature,
    const std::array<std::vector<SparseRow>, 2>& alternative, bool free_layout, double edge_length,
    const std::vector<int>& rounded, const std::vector<int>& labels, const Eigen::VectorXd& x,
    Density density, double power) const {
  Alternatives out{};
  const std::vector<int> faces = patch_faces_around(v0, v1);
  out.n_faces = static_cast<int>(faces.size());
  // Local copies (global copy → local id, in increasing global order so pivots stay "newest").
  std::vector<int> copies;
  for (int f : faces)
    for (int k = 0; k < 3; ++k) copies.push_back(cut_.corner_copy[3 * f + k]);
  std::sort(copies.begin(), copies.end());
  copies.erase(std::unique(copies.begin(), copies.end()), copies.end());
  auto local = [&](int global_copy) {
    return static_cast<int>(std::lower_bound(copies.begin(), copies.end(), global_copy) -
                            copies.begin());
  };
  LayoutDomain dom;
  dom.n_copies = static_cast<int>(copies.size());
  std::vector<char> face_in(mesh_.n_faces(), 0);
  double area = 0;
  for (int f : faces) {
    face_in[f] = 1;
    const auto& fc = domain_.face_copies[f];
    dom.face_copies.push_back({local(fc[0]), local(fc[1]), local(fc[2])});
    dom.rest_inverse.push_back(domain_.rest_inverse[f]);
    dom.area.push_back(domain_.area[f]);
    area += domain_.area[f];
  }
  Eigen::VectorXd x0(2 * dom.n_copies);
  for (int i = 0; i < dom.n_copies; ++i) x0.segment<2>(2 * i) = x.segment<2>(2 * copies[i]);
  auto to_local = [&](SparseRow row) {
    for (auto& e : row.entries) e.first = 2 * local(e.first / 2) + e.first % 2;
    std::sort(row.entries.begin(), row.entries.end());
    return row;
  };
  std::vector<char> gauge(2 * dom.n_copies, 0);
  gauge[0] = gauge[1] = 1;
  ConstraintEliminator base(2 * dom.n_copies, gauge);
  std::vector<char> seen_seam(cut_.seams.size(), 0), seen_feature;
  if (features_) seen_feature.assign(features_->size(), 0);
  for (int f : faces)
    for (int k = 0; k < 3; ++k) {
      const int e = cut_.topo.face_edge(f, k);
      const int s = edge_seam_[e];
      if (s >= 0 && s != skip_seam && !seen_seam[s] && rounded[s] != INT_MIN) {
        seen_seam[s] = 1;
        const CutSeam& cs = cut_.seams[s];
        if (face_in[cs.he_a / 3] && face_in[cs.he_b / 3])
          for (const auto& row : seam_constraint_rows(cut_, s, rounded[s]))
            base.add_row(to_local(row));
      }
      const int i = features_ ? features_->edge_feature[e] : -1;
      if (i >= 0 && i != skip_feature && !seen_feature[i] && (labels[i] == 0 || labels[i] == 1) &&
          face_in[features_->halfedge[i] / 3]) {
        seen_feature[i] = 1;
        base.add_row(to_local(feature_row(cut_, features_->halfedge[i], labels[i])));
      }
    }
  const Reduction base_red = base.reduction(x0);
  // Optimizes the patch from xs in `red`; its energy and τ (+inf when it failed or flipped).
  auto lay_out = [&](const Reduction& red, const Eigen::VectorXd& xs, double* value, double* tau) {
    *value = *tau = std::numeric_limits<double>::infinity();
    Eigen::VectorXd y = red.restrict(xs);
    OptimizeSettings st;
    st.density = density;
    st.power = power;
    st.max_iterations = kPatchIterations;
    st.relative_tolerance = kPatchTolerance;
    const OptimizeReport rep = optimize_layout(dom, red, st, &y);
    if (!rep.status.is_ok()) return;
    *value = rep.energy;
    *tau = max_isometric_distortion(dom, red.expand(y));
  };
  for (int side = 0; side < 2; ++side) {
    ConstraintEliminator elim = base;
    std::vector<SparseRow> rows;
    for (const auto& row : alternative[side]) {
      rows.push_back(to_local(row));
      elim.add_row(rows.back());
    }
    Eigen::VectorXd xs = x0;
    TransitionReport tr =
        move_into_constraints(dom, base_red, elim, rows, area / (edge_length * edge_length), &xs);
    out.energy[side] = out.tau[side] = std::numeric_limits<double>::infinity();
    if (tr.status.is_ok()) lay_out(tr.reduction, xs, &out.energy[side], &out.tau[side]);
  }
  out.tau_free = std::numeric_limits<double>::infinity();
  if (free_layout) {
    double value;
    lay_out(base_red, x0, &value, &out.tau_free);
  }
  return out;
}

PatchChoice LocalEstimator::choose(int seam, double measure, const std::vector<int>& rounded,
                                   const std::vector<int>& labels, const Eigen::VectorXd& x,
                                   Density density, double power) const {
  PatchChoice choice;
  const int lo = static_cast<int>(std::floor(measure));
  std::array<std::vector<SparseRow>, 2> alt;
  for (int side = 0; side < 2; ++side)
    for (const auto& row : seam_constraint_rows(cut_, seam, lo + side)) alt[side].push_back(row);
  const int fa = cut_.seams[seam].he_a / 3, ka = cut_.seams[seam].he_a % 3;
  const Alternatives a = evaluate(mesh_.F(fa, ka), mesh_.F(fa, (ka + 1) % 3), seam, -1, alt,
                                  false, seam_length(cut_, seam), rounded, labels, x, density, power);
  choice.n_faces = a.n_faces;
  choice.distortion[0] = a.energy[0];
  choice.distortion[1] = a.energy[1];
  // Lower distortion wins; ties (both failed, or exactly equal) go to the nearest rounding.
  // Matchings keep exact ties: kTieTolerance here changed 16 of the 21 benchmark maps both ways
  // (elk's Hausdorff over 1%; README, "Ties in local estimation").
  const int better = lower_distortion(choice.distortion[0], choice.distortion[1], 0);
  choice.matching = better < 0 ? static_cast<int>(std::lround(measure)) : lo + better;
  return choice;
}

FeatureChoice LocalEstimator::choose_feature(int feature, const std::vector<int>& rounded,
                                             const std::vector<int>& labels,
                                             const Eigen::VectorXd& x, Density density,
                                             double power) const {
  FeatureChoice choice;
  const int h = features_->halfedge[feature];
  std::array<std::vector<SparseRow>, 2> alt;
  for (int c = 0; c < 2; ++c) alt[c].push_back(feature_row(cut_, h, c));
  const int v0 = mesh_.F(h / 3, h % 3), v1 = mesh_.F(h / 3, (h % 3 + 1) % 3);
  const double len = (mesh_.V.row(v1) - mesh_.V.row(v0)).norm();
  const Alternatives a =
      evaluate(v0, v1, -1, feature, alt, true, len, rounded, labels, x, density, power);
  choice.n_faces = a.n_faces;
  choice.tau_free = a.tau_free;
  for (int c = 0; c < 2; ++c) {
    choice.distortion[c] = a.energy[c];
    choice.tau[c] = a.tau[c];
  }
  // A patch that only this edge's row holds can turn freely: both labels then cost the same
  // (up to round-off), and the edge takes its nearest axis, the smaller turn.
  const int better = lower_distortion(choice.distortion[0], choice.distortion[1], kTieTolerance);
  choice.label = better < 0 ? nearest_label(feature_measure(cut_, x, h)) : better;
  return choice;
}

}  // namespace quadify::param
