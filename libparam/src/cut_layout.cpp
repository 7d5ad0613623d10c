#include "cut_layout.h"

#include <cmath>
#include <numbers>
#include <numeric>

#include <Eigen/Geometry>

namespace quadify::param {
namespace {

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

}  // namespace

Eigen::Matrix2d sized_rest_frame(const core::TriMesh& mesh, int f, double scale,
                                 const std::vector<double>& face_size,
                                 const std::vector<Eigen::Matrix3d>& face_metric, double* area) {
  const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0));
  Eigen::Vector3d e1 = Eigen::Vector3d(mesh.V.row(mesh.F(f, 1))) - p0;
  Eigen::Vector3d e2 = Eigen::Vector3d(mesh.V.row(mesh.F(f, 2))) - p0;
  if (!face_metric.empty()) {
    e1 = face_metric[f] * e1;
    e2 = face_metric[f] * e2;
  }
  const double s = face_size.empty() ? scale : scale / face_size[f];
  e1 *= s;
  e2 *= s;
  const double l1 = e1.norm();
  const double cr = e1.cross(e2).norm();
  Eigen::Matrix2d dm;
  dm << l1, e1.dot(e2) / l1, 0.0, cr / l1;
  if (area) *area = 0.5 * cr;
  return dm;
}

CutMesh cut_along_dual_tree(const core::TriMesh& mesh, int seed_face,
                            const std::vector<double>& face_size,
                            const std::vector<Eigen::Matrix3d>& face_metric) {
  CutMesh cut;
  const int nf = mesh.n_faces();
  cut.topo = core::build_edge_topology(mesh);
  const auto& twin = cut.topo.twin;

  // BFS over faces through interior edges; the tree edges are the discovery edges.
  cut.tree_parent_halfedge.assign(nf, -1);
  std::vector<char> visited(nf, 0);
  std::vector<char> is_tree_halfedge(3 * nf, 0);
  cut.face_order.reserve(nf);
  cut.face_order.push_back(seed_face);
  visited[seed_face] = 1;
  for (size_t head = 0; head < cut.face_order.size(); ++head) {
    const int f = cut.face_order[head];
    for (int k = 0; k < 3; ++k) {
      const int t = twin[3 * f + k];
      if (t < 0 || visited[t / 3]) continue;
      visited[t / 3] = 1;
      cut.tree_parent_halfedge[t / 3] = 3 * f + k;
      is_tree_halfedge[3 * f + k] = is_tree_halfedge[t] = 1;
      cut.face_order.push_back(t / 3);
    }
  }

  // Corners merged across tree edges: half-edge 3g+k (F(g,k)→F(g,k+1)) and its twin 3f+j
  // (F(f,j)→F(f,j+1)) share F(g,k) = F(f,j+1) and F(g,k+1) = F(f,j).
  std::vector<int> parent(3 * nf);
  std::iota(parent.begin(), parent.end(), 0);
  auto unite = [&](int a, int b) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  for (int g = 0; g < nf; ++g) {
    const int hp = cut.tree_parent_halfedge[g];
    if (hp < 0) continue;
    const int hg = twin[hp];
    const int f = hp / 3, j = hp % 3, k = hg % 3;
    unite(3 * g + k, 3 * f + (j + 1) % 3);
    unite(3 * g + (k + 1) % 3, 3 * f + j);
  }
  cut.corner_copy.assign(3 * nf, -1);
  std::vector<int> root_copy_id(3 * nf, -1);
  for (int f : cut.face_order) {
    for (int k = 0; k < 3; ++k) {
      const int r = find_root(parent, 3 * f + k);
      if (root_copy_id[r] < 0) {
        root_copy_id[r] = static_cast<int>(cut.copy_vertex.size());
        cut.copy_vertex.push_back(mesh.F(f, k));
      }
      cut.corner_copy[3 * f + k] = root_copy_id[r];
    }
  }
  cut.root_copy = cut.corner_copy[3 * seed_face];

  for (int e = 0; e < cut.topo.n_edges(); ++e) {
    const int h = cut.topo.edge_halfedge[e];
    if (twin[h] < 0 || is_tree_halfedge[h]) continue;
    cut.seams.push_back({h, twin[h], e});
  }

  cut.rest.resize(nf);
  cut.area.resize(nf);
  for (int f = 0; f < nf; ++f) cut.rest[f] = sized_rest_frame(mesh, f, 1.0, face_size, face_metric, &cut.area[f]);
  cut.sized = !face_size.empty() || !face_metric.empty();
  return cut;
}

Eigen::MatrixX2d isometric_unfold(const core::TriMesh& mesh, const CutMesh& cut) {
  (void)mesh;
  Eigen::MatrixX2d x = Eigen::MatrixX2d::Zero(cut.n_copies(), 2);
  const auto& cc = cut.corner_copy;
  for (int f : cut.face_order) {
    const Eigen::Matrix2d& dm = cut.rest[f];
    const std::array<Eigen::Vector2d, 3> q = {Eigen::Vector2d::Zero(), Eigen::Vector2d(dm.col(0)),
                                              Eigen::Vector2d(dm.col(1))};
    const int hp = cut.tree_parent_halfedge[f];
    if (hp < 0) {
      for (int k = 0; k < 3; ++k) x.row(cc[3 * f + k]) = q[k].transpose();
      continue;
    }
    // Rigid motion (similarity with a size field) mapping the rest edge k→k+1 onto the placed
    // shared edge.
    const int k = cut.topo.twin[hp] % 3, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    const Eigen::Vector2d xa = x.row(cc[3 * f + k]).transpose();
    const Eigen::Vector2d xb = x.row(cc[3 * f + k1]).transpose();
    const Eigen::Vector2d a = q[k1] - q[k], b = xb - xa;
    const double inv = cut.sized ? 1.0 / a.squaredNorm() : 1.0 / (a.norm() * b.norm());
    const double c = a.dot(b) * inv, s = cross2(a, b) * inv;
    const Eigen::Vector2d d = q[k2] - q[k];
    x.row(cc[3 * f + k2]) = (xa + Eigen::Vector2d(c * d.x() - s * d.y(), s * d.x() + c * d.y()))
                                .transpose();
  }
  return x;
}

SeamEnds seam_ends(const CutMesh& cut, int seam) {
  const CutSeam& s = cut.seams[seam];
  const int fa = s.he_a / 3, ka = s.he_a % 3, fb = s.he_b / 3, kb = s.he_b % 3;
  return {cut.corner_copy[3 * fa + ka], cut.corner_copy[3 * fa + (ka + 1) % 3],
          cut.corner_copy[3 * fb + (kb + 1) % 3], cut.corner_copy[3 * fb + kb]};
}

double seam_length(const CutMesh& cut, int seam) {
  const int f = cut.seams[seam].he_a / 3, k = cut.seams[seam].he_a % 3;
  const Eigen::Matrix2d& dm = cut.rest[f];
  const std::array<Eigen::Vector2d, 3> q = {Eigen::Vector2d::Zero(), Eigen::Vector2d(dm.col(0)),
                                            Eigen::Vector2d(dm.col(1))};
  return (q[(k + 1) % 3] - q[k]).norm();
}

std::vector<double> measure_matchings(const CutMesh& cut, const Eigen::MatrixX2d& x) {
  std::vector<double> m(cut.seams.size());
  for (size_t i = 0; i < cut.seams.size(); ++i) {
    const SeamEnds c = seam_ends(cut, static_cast<int>(i));
    const Eigen::Vector2d ea = (x.row(c.a1) - x.row(c.a0)).transpose();
    const Eigen::Vector2d eb = (x.row(c.b1) - x.row(c.b0)).transpose();
    m[i] = std::atan2(cross2(ea, eb), ea.dot(eb)) / (0.5 * std::numbers::pi);
  }
  return m;
}

SparseRow make_row(std::vector<std::pair<int, double>> terms) {
  std::sort(terms.begin(), terms.end());
  SparseRow row;
  for (const auto& [var, coef] : terms) {
    if (!row.entries.empty() && row.entries.back().first == var)
      row.entries.back().second += coef;
    else
      row.entries.push_back({var, coef});
  }
  std::erase_if(row.entries, [](const auto& p) { return p.second == 0.0; });
  return row;
}

std::array<SparseRow, 2> seam_constraint_rows(const CutMesh& cut, int seam, int matching) {
  const SeamEnds c = seam_ends(cut, seam);
  const int r = ((matching % 4) + 4) % 4;
  std::array<SparseRow, 2> rows;
  for (int d = 0; d < 2; ++d)
    rows[d] = make_row({{2 * c.b1 + d, 1.0},
                        {2 * c.b0 + d, -1.0},
                        {2 * c.a1 + kRotationSource[r][d], -kRotationSign[r][d]},
                        {2 * c.a0 + kRotationSource[r][d], kRotationSign[r][d]}});
  return rows;
}

}  // namespace quadify::param
