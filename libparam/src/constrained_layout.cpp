#include <libcore/topology.h>
#include <libparam/constrained_layout.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>

#include "constraint_elimination.h"
#include "cut_layout.h"
#include "layout_optimizer.h"

namespace quadify::param {
namespace {

// Dimensionless penalty weights (× area / Σ edge²) of the optional long homotopy.
constexpr double kHomotopyWeights[] = {1e0, 1e2, 1e4, 1e6};
// Newton stop of the homotopy stages (fraction of the energy): run the iterations out.
constexpr double kHomotopyTolerance = 1e-12;
// Exponent of the L^p ARAP density for Energy::kLinfArap (as in compute_seamless_param).
constexpr double kLinfArapPower = 8;

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Entry (d, j) of R_90^r.
double rotation_entry(int r, int d, int j) {
  const Eigen::Vector2d col =
      rotate_quarter(j == 0 ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1), r);
  return col[d];
}

// Sums duplicate variables and drops zero coefficients.
SparseRow compress(const std::map<int, double>& acc) {
  SparseRow row;
  for (const auto& [v, a] : acc)
    if (a != 0) row.entries.push_back({v, a});
  return row;
}

}  // namespace

core::Status build_copy_layout(const core::TriMesh& mesh, const Eigen::MatrixX2d& corner_uv,
                               const std::vector<SeamMatching>& seams, double seam_tol,
                               CopyLayout* out) {
  const int nf = mesh.n_faces();
  if (corner_uv.rows() != 3 * nf)
    return core::Status::invalid_input("corner_uv has " + std::to_string(corner_uv.rows()) +
                                       " rows, expected 3·#F = " + std::to_string(3 * nf));
  if (!corner_uv.allFinite()) return core::Status::invalid_input("corner_uv is not finite");
  core::EdgeTopology topo;
  try {
    topo = core::build_edge_topology(mesh);
  } catch (const std::invalid_argument& e) {
    return core::Status::invalid_input(e.what());
  }
  // Seam list → matching per edge.
  std::vector<int> edge_matching(topo.n_edges(), -1);
  for (const SeamMatching& s : seams) {
    int he = -1;
    if (s.face_a >= 0 && s.face_a < nf)
      for (int k = 0; k < 3; ++k)
        if (mesh.F(s.face_a, k) == s.edge_vertex0 &&
            mesh.F(s.face_a, (k + 1) % 3) == s.edge_vertex1)
          he = 3 * s.face_a + k;
    if (he < 0 || topo.twin[he] < 0 || topo.twin[he] / 3 != s.face_b)
      return core::Status::invalid_input("seam (" + std::to_string(s.edge_vertex0) + ", " +
                                         std::to_string(s.edge_vertex1) + ") of faces " +
                                         std::to_string(s.face_a) + "/" + std::to_string(s.face_b) +
                                         " is not an interior edge of the mesh");
    // Store the matching in the orientation of edge_halfedge.
    const int e = topo.face_edge(he / 3, he % 3);
    edge_matching[e] = topo.edge_halfedge[e] == he ? ((s.matching % 4) + 4) % 4
                                                   : ((4 - s.matching % 4) % 4 + 4) % 4;
  }
  // Merge corners across edges without a seam.
  std::vector<int> parent(3 * nf);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> is_seam(topo.n_edges(), 0);
  for (int e = 0; e < topo.n_edges(); ++e) {
    const int he = topo.edge_halfedge[e], tw = topo.twin[he];
    if (tw < 0) continue;
    const int fa = he / 3, ka = he % 3, fb = tw / 3, kb = tw % 3;
    const int ca0 = 3 * fa + ka, ca1 = 3 * fa + (ka + 1) % 3;
    const int cb1 = 3 * fb + kb, cb0 = 3 * fb + (kb + 1) % 3;
    const bool agree =
        corner_uv.row(ca0) == corner_uv.row(cb0) && corner_uv.row(ca1) == corner_uv.row(cb1);
    if (edge_matching[e] > 0 || (edge_matching[e] == 0 && !agree)) {
      is_seam[e] = 1;
      continue;
    }
    if (!agree)
      return core::Status::invalid_input(
          "edge (" + std::to_string(mesh.F(fa, ka)) + ", " +
          std::to_string(mesh.F(fa, (ka + 1) % 3)) + ") between faces " + std::to_string(fa) +
          " and " + std::to_string(fb) +
          " has different UVs on its sides but is not a listed seam");
    parent[find_root(parent, ca0)] = find_root(parent, cb0);
    parent[find_root(parent, ca1)] = find_root(parent, cb1);
  }
  CopyLayout cl;
  cl.corner_copy.assign(3 * nf, -1);
  std::vector<int> root_copy(3 * nf, -1);
  for (int c = 0; c < 3 * nf; ++c) {
    const int r = find_root(parent, c);
    if (root_copy[r] < 0) {
      root_copy[r] = cl.n_copies();
      cl.copy_vertex.push_back(mesh.F(c / 3, c % 3));
    }
    cl.corner_copy[c] = root_copy[r];
  }
  std::vector<int> face_comp;
  cl.n_components = core::face_components(mesh, topo, &face_comp);
  cl.copy_component.assign(cl.n_copies(), -1);
  cl.x.resize(2 * cl.n_copies());
  for (int c = 0; c < 3 * nf; ++c) {
    const int k = cl.corner_copy[c];
    cl.copy_component[k] = face_comp[c / 3];
    cl.x.segment<2>(2 * k) = corner_uv.row(c).transpose();
  }
  // Seams with their residuals.
  Eigen::Vector2d lo = corner_uv.colwise().minCoeff(), hi = corner_uv.colwise().maxCoeff();
  const double tol = seam_tol * std::max((hi - lo).norm(), 1e-300);
  for (int e = 0; e < topo.n_edges(); ++e) {
    if (!is_seam[e]) continue;
    const int he = topo.edge_halfedge[e], tw = topo.twin[he];
    const int fa = he / 3, ka = he % 3, fb = tw / 3, kb = tw % 3;
    CopySeam s;
    s.face_a = fa;
    s.face_b = fb;
    s.a0 = cl.corner_copy[3 * fa + ka];
    s.a1 = cl.corner_copy[3 * fa + (ka + 1) % 3];
    s.b1 = cl.corner_copy[3 * fb + kb];
    s.b0 = cl.corner_copy[3 * fb + (kb + 1) % 3];
    s.matching = std::max(0, edge_matching[e]);
    const Eigen::Vector2d ea = cl.x.segment<2>(2 * s.a1) - cl.x.segment<2>(2 * s.a0);
    const Eigen::Vector2d eb = cl.x.segment<2>(2 * s.b1) - cl.x.segment<2>(2 * s.b0);
    const double residual = (eb - rotate_quarter(ea, s.matching)).norm();
    if (!(residual <= tol))
      return core::Status::invalid_input(
          "seam edge (" + std::to_string(mesh.F(fa, ka)) + ", " +
          std::to_string(mesh.F(fa, (ka + 1) % 3)) + ") between faces " + std::to_string(fa) +
          " and " + std::to_string(fb) + " violates its matching " + std::to_string(s.matching) +
          ": residual " + std::to_string(residual) + " > " + std::to_string(tol));
    cl.seams.push_back(s);
  }
  *out = std::move(cl);
  return core::Status::ok();
}

ConstrainedLayoutResult solve_constrained_layout(const core::TriMesh& mesh,
                                                 const CopyLayout& copies,
                                                 const Eigen::VectorXd& x0,
                                                 const std::vector<AffineRow>& old_rows,
                                                 const std::vector<AffineRow>& new_rows,
                                                 const ConstrainedLayoutOptions& options) {
  ConstrainedLayoutResult res;
  const int nf = mesh.n_faces();
  const int n = copies.n_copies();
  const int n_seams = static_cast<int>(copies.seams.size());
  const int n_ext = 2 * n + 2 * n_seams;
  if (static_cast<int>(copies.corner_copy.size()) != 3 * nf ||
      (x0.size() != 2 * n && x0.size() != n_ext) || !(options.rest_scale > 0) ||
      (!options.gauge_copies.empty() &&
       static_cast<int>(options.gauge_copies.size()) != copies.n_components)) {
    res.status = core::Status::invalid_input("solve_constrained_layout: sizes do not match");
    return res;
  }
  // Internal variables: [one, 0 | translations (2 per seam) | copies (2 each)]. The eliminator
  // pivots on the highest-index unit coefficient, so copies become dependent on the
  // translations: x_b0 = R^r x_a0 + t, and integer rows on translations stay unimodular.
  const int kOne = 0, t_base = 2, x_base = 2 + 2 * n_seams;
  const int n_vars = x_base + 2 * n;
  auto internal = [&](int e) { return e < 2 * n ? x_base + e : t_base + (e - 2 * n); };
  auto homogenize = [&](const AffineRow& row) {
    std::map<int, double> acc;
    for (const auto& [v, a] : row.entries) acc[internal(v)] += a;
    if (row.rhs != 0) acc[kOne] -= row.rhs;
    return compress(acc);
  };
  for (const auto* rows : {&old_rows, &new_rows})
    for (const AffineRow& row : *rows)
      for (const auto& [v, a] : row.entries)
        if (v < 0 || v >= n_ext) {
          res.status = core::Status::invalid_input("solve_constrained_layout: variable " +
                                                   std::to_string(v) + " out of range");
          return res;
        }
  // The domain: faces over the internal copies, rest frames of the 3D triangles × rest_scale.
  LayoutDomain domain;
  domain.n_copies = n_vars / 2;
  domain.face_copies.resize(nf);
  domain.rest_inverse.resize(nf);
  domain.area.resize(nf);
  double total_area = 0, edge_len = 0;
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k)
      domain.face_copies[f][k] = x_base / 2 + copies.corner_copy[3 * f + k];
    const Eigen::Vector3d p0 = mesh.V.row(mesh.F(f, 0)), p1 = mesh.V.row(mesh.F(f, 1)),
                          p2 = mesh.V.row(mesh.F(f, 2));
    const Eigen::Vector3d e1 = (p1 - p0) * options.rest_scale, e2 = (p2 - p0) * options.rest_scale;
    const double l1 = e1.norm();
    Eigen::Matrix2d dm;
    dm << l1, e1.dot(e2) / l1, 0, e1.cross(e2).norm() / l1;
    domain.rest_inverse[f] = dm.inverse();
    domain.area[f] = 0.5 * e1.cross(e2).norm();
    total_area += domain.area[f];
    edge_len += l1;
  }
  edge_len /= std::max(nf, 1);

  std::vector<char> never_pivot(n_vars, 0);
  never_pivot[kOne] = never_pivot[kOne + 1] = 1;
  std::vector<char> gauge_set(copies.n_components, 0);
  auto fix_copy = [&](int k) {
    never_pivot[x_base + 2 * k] = never_pivot[x_base + 2 * k + 1] = 1;
    gauge_set[copies.copy_component[k]] = 1;
  };
  for (int comp = 0; comp < copies.n_components; ++comp) {
    const int g = options.gauge_copies.empty() ? -1 : options.gauge_copies[comp];
    if (g >= 0 && g < n && copies.copy_component[g] == comp) fix_copy(g);
  }
  for (int k = 0; k < n; ++k)
    if (copies.copy_component[k] >= 0 && !gauge_set[copies.copy_component[k]]) fix_copy(k);

  // Seam rows: x_b0 − R^r x_a0 − t = 0 and x_b1 − R^r x_a1 − t = 0.
  ConstraintEliminator elim(n_vars, never_pivot);
  for (int si = 0; si < n_seams; ++si) {
    const CopySeam& s = copies.seams[si];
    for (const auto& [a, b] : {std::pair{s.a0, s.b0}, std::pair{s.a1, s.b1}})
      for (int d = 0; d < 2; ++d) {
        std::map<int, double> acc;
        acc[x_base + 2 * b + d] += 1;
        for (int j = 0; j < 2; ++j)
          if (const double r = rotation_entry(s.matching, d, j); r != 0)
            acc[x_base + 2 * a + j] -= r;
        acc[t_base + 2 * si + d] -= 1;
        elim.add_row(compress(acc));
      }
  }
  for (const AffineRow& row : old_rows) elim.add_row(homogenize(row));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n_vars);
  x[kOne] = 1;
  x.segment(x_base, 2 * n) = x0.head(2 * n);
  for (int si = 0; si < n_seams; ++si) {
    const CopySeam& s = copies.seams[si];
    x.segment<2>(t_base + 2 * si) = x.segment<2>(x_base + 2 * s.b0) -
                                    rotate_quarter(x.segment<2>(x_base + 2 * s.a0), s.matching);
  }
  const Reduction old_red = elim.reduction(x);
  x = old_red.expand(old_red.restrict(x));

  std::vector<SparseRow> added;
  res.independent.assign(new_rows.size(), 0);
  for (size_t i = 0; i < new_rows.size(); ++i) {
    SparseRow row = homogenize(new_rows[i]);
    if (elim.add_row(row)) {
      res.independent[i] = 1;
      added.push_back(std::move(row));
    }
  }
  int n_never_pivot = 0;
  for (char c : never_pivot) n_never_pivot += c;
  Reduction red;
  if (options.reduce_only) {
    red = elim.reduction(x);
  } else if (n_vars - n_never_pivot - elim.rank() == 0) {
    // No freedom left (e.g. every vertex pinned): the layout is the constant part. Handled here
    // because the projection would factor an empty matrix.
    red = elim.reduction(x);
    x = red.c;
  } else if (!added.empty()) {
    // Penalty unit: area / Σ (length scale)², one UV edge per pair of new rows.
    const double weight_unit =
        total_area /
        std::max(1e-300, 0.5 * static_cast<double>(added.size()) * edge_len * edge_len);
    // Optional long homotopy inside the old space before the transition: large moves (cones
    // pulled apart onto distinct grid points) need more Newton steps than its stages take.
    if (options.homotopy_iterations > 0) {
      Eigen::VectorXd y = old_red.restrict(x);
      for (const double w : kHomotopyWeights) {
        OptimizeSettings st;
        st.max_iterations = options.homotopy_iterations;
        st.relative_tolerance = kHomotopyTolerance;
        st.penalty_rows = &added;
        st.penalty_weight = w * weight_unit;
        const OptimizeReport r = optimize_layout(domain, old_red, st, &y);
        res.iterations += r.iterations;
        if (!r.status.is_ok()) break;
        x = old_red.expand(y);
      }
    }
    TransitionReport tr = move_into_constraints(domain, old_red, elim, added, weight_unit, &x);
    res.iterations += tr.iterations;
    red = std::move(tr.reduction);
    res.status = tr.status;
  } else {
    red = old_red;
  }
  res.n_flipped = options.reduce_only ? 0 : count_flipped(domain, x);
  if (!options.reduce_only && res.n_flipped == 0 && res.status.is_ok()) {
    OptimizeSettings st;
    switch (options.energy) {
      case Energy::kArap:
        st.density = Density::kArap;
        break;
      case Energy::kLinfArap:
        st.density = Density::kPowerArap;
        st.power = kLinfArapPower;
        break;
      case Energy::kConformal:
        st.density = Density::kMips;
        break;
      default:
        st.density = Density::kSymmetricDirichlet;
    }
    st.max_iterations = options.max_newton_iters;
    st.relative_tolerance = options.relative_tolerance;
    Eigen::VectorXd y = red.restrict(x);
    const OptimizeReport rep = optimize_layout(domain, red, st, &y);
    res.iterations += rep.iterations;
    if (rep.status.is_ok()) {
      const Eigen::VectorXd xn = red.expand(y);
      if (count_flipped(domain, xn) == 0) x = xn;
    }
    res.n_flipped = count_flipped(domain, x);
  }
  if (res.status.is_ok() && res.n_flipped > 0)
    res.status = core::Status::not_converged(std::to_string(res.n_flipped) +
                                             " flipped faces in the constrained layout");
  // Back to the external order [copies | translations].
  std::vector<int> ext_of(n_vars, -1);
  for (int e = 0; e < n_ext; ++e) ext_of[internal(e)] = e;
  res.x.resize(n_ext);
  for (int e = 0; e < n_ext; ++e) res.x[e] = x[internal(e)];
  Eigen::SparseMatrix<double, Eigen::RowMajor> P(n_ext, red.n_free());
  std::vector<Eigen::Triplet<double>> trip;
  res.reduction.c.resize(n_ext);
  for (int e = 0; e < n_ext; ++e) {
    res.reduction.c[e] = red.c[internal(e)];
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(red.P, internal(e)); it;
         ++it)
      trip.emplace_back(e, static_cast<int>(it.col()), it.value());
  }
  P.setFromTriplets(trip.begin(), trip.end());
  res.reduction.P = std::move(P);
  for (int v : red.free_vars) res.reduction.free_vars.push_back(ext_of[v]);
  return res;
}

}  // namespace quadify::param
