// Edge connectivity of a triangle mesh (half-edge convention of mesh.h).
#pragma once

#include <libcore/mesh.h>

#include <utility>
#include <vector>

namespace quadify::core {

// Key of the undirected edge {a, b} (vertex ids ≥ 0), the same for (a, b) and (b, a).
inline long long edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<long long>(a) << 32) | static_cast<unsigned>(b);
}

struct EdgeTopology {
  Eigen::MatrixX2i edge_vertex;  // #E×2, edge_vertex(e,0) < edge_vertex(e,1)
  Eigen::MatrixX3i face_edge;    // #F×3, edge of half-edge 3f+k (from F(f,k) to F(f,(k+1)%3))
  std::vector<int> twin;         // #F·3, opposite half-edge, -1 on a boundary
  std::vector<int> edge_halfedge;  // #E, one half-edge of each edge (the one on a face, if boundary)
  int n_edges() const { return static_cast<int>(edge_vertex.rows()); }
  bool is_boundary_edge(int e) const { return twin[edge_halfedge[e]] < 0; }
};

struct TopologyStats {
  int n_vertices = 0;           // referenced vertices
  int n_edges = 0;
  int n_faces = 0;
  int n_components = 0;         // faces connected through edges
  int n_boundary_loops = 0;
  int euler_characteristic = 0;  // V - E + F over referenced vertices
  int n_nonmanifold_edges = 0;   // edges with more than two incident faces
  int n_nonmanifold_vertices = 0;  // vertices whose incident faces form more than one fan
  bool is_manifold() const { return n_nonmanifold_edges == 0 && n_nonmanifold_vertices == 0; }
  // Genus of a manifold connected oriented mesh: (2 - chi - #boundary loops) / 2, summed over
  // components; -1 when the mesh is not manifold.
  int genus = -1;
};

// Builds edges and twins. Precondition: edge-manifold (≤ 2 faces per edge) and consistently
// oriented; a third face on an edge or an inconsistently oriented pair throws InvalidInput-style
// std::invalid_argument naming the edge.
EdgeTopology build_edge_topology(const TriMesh& mesh);

// Face component ids (#F, 0-based, through shared edges); returns the number of components.
int face_components(const TriMesh& mesh, const EdgeTopology& topo, std::vector<int>* component);

// Sharp edges: interior edges whose dihedral angle (between the two face normals) exceeds
// angle_deg degrees, as EdgeTopology edge ids in increasing order. Degenerate faces make no
// sharp edge (their normal is undefined).
std::vector<int> sharp_edges(const TriMesh& mesh, const EdgeTopology& topo, double angle_deg);

// Which sharp edges are design creases (feature lines to align) rather than curvature that the
// tessellation resolves coarsely (scans, sculpts: thin parts, tips, crevices).
struct CreaseOptions {
  double angle_deg = 40;  // an edge is sharp above this dihedral angle (degrees)
  // A crease separates two locally smooth sides. An edge's side angle is the largest dihedral
  // angle among the other, non-sharp edges of its two faces; a feature chain (sharp edges between
  // vertices where the sharp edges do not simply continue) is a crease chain when the median side
  // angle of its edges is below this (degrees). A connected group of sharp edges made at least
  // half of crease chains is kept whole; elsewhere only the crease chains are kept. 0 keeps every
  // sharp edge (no filtering).
  double max_side_angle_deg = 15;
  // A chain of at least uniform_min_edges edges whose dihedral angles are all at least
  // uniform_min_deg and within uniform_spread_deg of each other is a crease chain too, whatever
  // its sides: a machined edge such as a drilled hole's rim (90° all round) beside a coarsely
  // faceted cylinder. Scan and sculpt creases are not that even (of the 30 benchmark meshes only
  // casting and crank have such chains). uniform_min_deg 0 turns this off.
  double uniform_min_deg = 60;
  double uniform_spread_deg = 5;
  int uniform_min_edges = 4;
  // Connected groups of kept sharp edges with fewer edges than this are dropped (isolated
  // fragments); applies only when max_side_angle_deg > 0.
  int min_group_edges = 6;
  // ... unless the median dihedral angle of the group's edges is at least this (degrees): a short
  // knife edge (a blade's tip) is a crease however few edges it has.
  double keep_small_group_deg = 120;
  // When at least this share of the sharp edges pass the filter, every sharp edge is kept: the
  // mesh is a CAD part whose sharp edges are design edges, and the few the filter would drop are
  // design edges too (short chamfers, the facets of a coarsely tessellated fillet) that the feature
  // benchmark counts. Of the 30 benchmark meshes, the CAD parts have 0.94–1 (casting 0.956,
  // wingnut 0.984, beetle 0.945), teapot 0.84, the scans and sculpts below 0.5. Above 1 = off.
  double keep_all_share = 0.9;
};

// Sharp edges (as sharp_edges) that pass the crease filter of `options`, in increasing order.
std::vector<int> crease_edges(const TriMesh& mesh, const EdgeTopology& topo, const CreaseOptions& options);

// The vertices joined to each vertex by an edge (#V lists, sorted, without duplicates).
std::vector<std::vector<int>> vertex_neighbours(const TriMesh& mesh);

// Topological statistics of any triangle mesh (also non-manifold ones: counts only).
TopologyStats topology_stats(const TriMesh& mesh);

}  // namespace quadify::core
