#include "seam_basis.h"

#include <libcore/status.h>

#include <algorithm>
#include <climits>

namespace quadify::param {
namespace {

// Pivot priorities: copies first, then the translation each closed vertex is solved for, and
// the translations meant to stay free last.
constexpr int kCopyPriority = 3, kTreeTranslationPriority = 2, kFreeTranslationPriority = 1;

int quarter_turns(int matching) { return ((matching % 4) + 4) % 4; }

// Rows x_b − R^r x_a − t = 0 of one end (copies a, b of one vertex; a == b at a leaf of the cut).
std::array<SparseRow, 2> end_rows(const CutMesh& cut, int seam, int r, int a, int b) {
  std::array<SparseRow, 2> rows;
  for (int d = 0; d < 2; ++d)
    rows[d] = make_row({{2 * b + d, 1.0},
                        {2 * a + kRotationSource[r][d], -kRotationSign[r][d]},
                        {seam_translation_var(cut, seam, d), -1.0}});
  return rows;
}

}  // namespace

std::array<SparseRow, 4> seam_translation_rows(const CutMesh& cut, int seam, int matching) {
  const SeamEnds c = seam_ends(cut, seam);
  const int r = quarter_turns(matching);
  const auto r0 = end_rows(cut, seam, r, c.a0, c.b0);
  const auto r1 = end_rows(cut, seam, r, c.a1, c.b1);
  return {r0[0], r0[1], r1[0], r1[1]};
}

ConstraintEliminator eliminate_seams(const CutMesh& cut, const std::vector<int>& matching,
                                     SeamBasisInfo* info) {
  const int n_copies = cut.n_copies();
  const int n_seams = static_cast<int>(cut.seams.size());
  const int n_vars = n_seam_basis_vars(cut);
  int nv = 0;
  for (int v : cut.copy_vertex) nv = std::max(nv, v + 1);
  auto constrained = [&](int s) { return matching[s] != INT_MIN; };

  // Seam ends at each vertex: (seam, end), end 0 at v0, 1 at v1.
  std::vector<std::vector<std::pair<int, int>>> ends(nv);
  std::vector<char> open(nv, 0);  // a seam still free, or a boundary: no closing row
  for (int s = 0; s < n_seams; ++s) {
    const SeamEnds c = seam_ends(cut, s);
    const int v0 = cut.copy_vertex[c.a0], v1 = cut.copy_vertex[c.a1];
    ends[v0].push_back({s, 0});
    ends[v1].push_back({s, 1});
    if (!constrained(s)) open[v0] = open[v1] = 1;
  }
  for (int e = 0; e < cut.topo.n_edges(); ++e)
    if (cut.topo.is_boundary_edge(e))
      open[cut.topo.edge_vertex(e, 0)] = open[cut.topo.edge_vertex(e, 1)] = 1;

  // Rotation around each closed vertex: walk the cycle of its copies, x_b = R^r x_a + t.
  std::vector<char> cone(nv, 0);
  SeamBasisInfo stats;
  for (int v = 0; v < nv; ++v) {
    if (open[v] || ends[v].empty()) continue;
    ++stats.n_closed_vertices;
    struct Link {
      int a, b, r;
    };
    std::vector<Link> links;
    for (const auto& [s, end] : ends[v]) {
      const SeamEnds c = seam_ends(cut, s);
      links.push_back(end == 0 ? Link{c.a0, c.b0, quarter_turns(matching[s])}
                               : Link{c.a1, c.b1, quarter_turns(matching[s])});
    }
    std::vector<char> used(links.size(), 0);
    int cur = links[0].a, turns = 0;
    bool closed_cycle = true;
    for (size_t step = 0; step < links.size(); ++step) {
      size_t i = 0;
      while (i < links.size() && (used[i] || (links[i].a != cur && links[i].b != cur))) ++i;
      if (i == links.size()) {
        closed_cycle = false;
        break;
      }
      used[i] = 1;
      if (links[i].a == cur) {
        turns += links[i].r;
        cur = links[i].b;
      } else {
        turns -= links[i].r;
        cur = links[i].a;
      }
    }
    // Not a single cycle cannot happen on a manifold cut; treated like a cone (its rows then
    // pivot on copies or on any translation, which stays correct, only less local).
    cone[v] = !closed_cycle || cur != links[0].a || quarter_turns(turns) != 0;
    stats.n_cones += cone[v];
  }

  // BFS along the constrained seams from the vertices without a translation row to solve for
  // (open vertices and cones); what it does not reach starts from its lowest vertex.
  std::vector<int> depth(nv, -1), parent_seam(nv, -1), order;
  order.reserve(nv);
  auto run = [&](size_t head) {
    for (; head < order.size(); ++head) {
      const int u = order[head];
      for (const auto& [s, end] : ends[u]) {
        if (!constrained(s)) continue;
        const SeamEnds c = seam_ends(cut, s);
        const int w = cut.copy_vertex[end == 0 ? c.a1 : c.a0];
        if (depth[w] >= 0) continue;
        depth[w] = depth[u] + 1;
        parent_seam[w] = s;
        order.push_back(w);
      }
    }
  };
  for (int v = 0; v < nv; ++v)
    if (open[v] || cone[v] || ends[v].empty()) {
      depth[v] = 0;
      order.push_back(v);
    }
  run(0);
  for (int v = 0; v < nv; ++v)
    if (depth[v] < 0) {
      depth[v] = 0;
      order.push_back(v);
      run(order.size() - 1);
    }

  // Gauge: the root copy unless its vertex is a cone (whose copy is solved for).
  int gauge = cut.root_copy;
  if (cone[cut.copy_vertex[gauge]])
    for (int k = 0; k < n_copies; ++k)
      if (!cone[cut.copy_vertex[k]]) {
        gauge = k;
        break;
      }
  std::vector<char> never_pivot(n_vars, 0);
  never_pivot[2 * gauge] = never_pivot[2 * gauge + 1] = 1;
  std::vector<int> priority(n_vars, kCopyPriority);
  std::vector<char> tree_seam(n_seams, 0);
  for (int v = 0; v < nv; ++v)
    if (parent_seam[v] >= 0 && !open[v] && !cone[v]) tree_seam[parent_seam[v]] = 1;
  for (int s = 0; s < n_seams; ++s)
    for (int d = 0; d < 2; ++d) {
      const int t = seam_translation_var(cut, s, d);
      priority[t] = tree_seam[s] ? kTreeTranslationPriority : kFreeTranslationPriority;
      if (!constrained(s)) never_pivot[t] = 1;
      else if (!tree_seam[s] && d == 0) ++stats.n_free_translations;
    }

  // Rows vertex by vertex, farthest from the BFS sources first: a vertex's closing row then meets
  // its tree translation still free and its children's already solved.
  std::vector<int> by_depth = order;
  std::stable_sort(by_depth.begin(), by_depth.end(),
                   [&](int a, int b) { return depth[a] > depth[b]; });
  ConstraintEliminator elim(n_vars, std::move(never_pivot), std::move(priority));
  for (int v : by_depth)
    for (const auto& [s, end] : ends[v]) {
      if (!constrained(s)) continue;
      const SeamEnds c = seam_ends(cut, s);
      const int r = quarter_turns(matching[s]);
      for (const SparseRow& row :
           end == 0 ? end_rows(cut, s, r, c.a0, c.b0) : end_rows(cut, s, r, c.a1, c.b1))
        elim.add_row(row);
    }
  stats.gauge_copy = gauge;
  if (info) *info = stats;
  return elim;
}

}  // namespace quadify::param
