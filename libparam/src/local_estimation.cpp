#include "local_estimation.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

namespace quadify::param {
namespace {

// Newton iterations of a patch layout (patches are small and start near their optimum).
constexpr int kPatchIterations = 20;
constexpr double kPatchTolerance = 1e-6;

}  // namespace

LocalEstimator::LocalEstimator(const core::TriMesh& mesh, const CutMesh& cut,
                               const LayoutDomain& domain, int bfs_levels)
    : mesh_(mesh), cut_(cut), domain_(domain), levels_(bfs_levels) {
  vertex_faces_.resize(mesh.n_vertices());
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) vertex_faces_[mesh.F(f, k)].push_back(f);
  edge_seam_.assign(cut.topo.n_edges(), -1);
  for (size_t s = 0; s < cut.seams.size(); ++s) edge_seam_[cut.seams[s].edge] = static_cast<int>(s);
}

std::vector<int> LocalEstimator::patch_faces(int seam) const {
  const int fa = cut_.seams[seam].he_a / 3, ka = cut_.seams[seam].he_a % 3;
  std::vector<char> in_face(mesh_.n_faces(), 0), in_vertex(mesh_.n_vertices(), 0);
  std::vector<int> faces, frontier = {mesh_.F(fa, ka), mesh_.F(fa, (ka + 1) % 3)};
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

PatchChoice LocalEstimator::choose(int seam, double measure, const std::vector<int>& rounded,
                                   const Eigen::VectorXd& x, Density density, double power) const {
  PatchChoice choice;
  const std::vector<int> faces = patch_faces(seam);
  choice.n_faces = static_cast<int>(faces.size());
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
  auto local_rows = [&](int s, int r) {
    auto rows = seam_constraint_rows(cut_, s, r);
    for (auto& row : rows)
      for (auto& e : row.entries) e.first = 2 * local(e.first / 2) + e.first % 2;
    return rows;
  };
  std::vector<char> gauge(2 * dom.n_copies, 0);
  gauge[0] = gauge[1] = 1;
  ConstraintEliminator base(2 * dom.n_copies, gauge);
  std::vector<char> seen_seam(cut_.seams.size(), 0);
  for (int f : faces)
    for (int k = 0; k < 3; ++k) {
      const int s = edge_seam_[cut_.topo.face_edge(f, k)];
      if (s < 0 || s == seam || seen_seam[s] || rounded[s] == INT_MIN) continue;
      seen_seam[s] = 1;
      const CutSeam& cs = cut_.seams[s];
      if (!face_in[cs.he_a / 3] || !face_in[cs.he_b / 3]) continue;
      for (const auto& row : local_rows(s, rounded[s])) base.add_row(row);
    }
  const Reduction base_red = base.reduction(x0);
  const int lo = static_cast<int>(std::floor(measure));
  for (int side = 0; side < 2; ++side) {
    ConstraintEliminator elim = base;
    std::vector<SparseRow> rows;
    for (const auto& row : local_rows(seam, lo + side)) {
      elim.add_row(row);
      rows.push_back(row);
    }
    Eigen::VectorXd xs = x0;
    const double edge_sq = seam_length(cut_, seam) * seam_length(cut_, seam);
    TransitionReport tr = move_into_constraints(dom, base_red, elim, rows, area / edge_sq, &xs);
    double value = std::numeric_limits<double>::infinity();
    if (tr.status.is_ok()) {
      Eigen::VectorXd y = tr.reduction.restrict(xs);
      OptimizeSettings st;
      st.density = density;
      st.power = power;
      st.max_iterations = kPatchIterations;
      st.relative_tolerance = kPatchTolerance;
      const OptimizeReport rep = optimize_layout(dom, tr.reduction, st, &y);
      if (rep.status.is_ok()) value = rep.energy;
    }
    choice.distortion[side] = value;
  }
  // Lower distortion wins; ties (both failed, or equal) go to the nearest rounding.
  const int nearest = static_cast<int>(std::lround(measure));
  if (choice.distortion[0] < choice.distortion[1])
    choice.matching = lo;
  else if (choice.distortion[1] < choice.distortion[0])
    choice.matching = lo + 1;
  else
    choice.matching = nearest;
  return choice;
}

}  // namespace quadify::param
