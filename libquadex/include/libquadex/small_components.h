// Components too small for the quad grid. A component of the input smaller than a few quads (a
// tiny part, a fin left by the repair of a non-manifold edge) comes out of the extraction as a
// handful of faces that are not quads, or as quads with a repeated vertex (a tetrahedron smaller
// than a quad: four "quads" on six vertices, one of them [a b c b]). Such a component is
// replaced by its own triangles, each split into three quads (its corners, edge midpoints and
// centroid): a pure-quad, manifold mesh that lies on the input exactly.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>

#include <vector>

namespace quadify::quadex {

struct SmallComponentOptions {
  // A component is replaced when its extracted faces include a non-quad or a face with a repeated
  // vertex, or it has none, and it has at most this many extracted faces and at most
  // max_triangles input triangles.
  int max_faces = 16;
  int max_triangles = 64;
  // Faces of the map whose components are replaced whatever their size (the faces a caller left
  // out of the extraction, e.g. QuantizeStats::faces_with_unresolved_cones).
  std::vector<int> replace_faces;
};

struct SmallComponentStats {
  int n_replaced = 0;       // components replaced by split triangles
  int n_faces_removed = 0;  // extracted faces they had
  int n_quads_added = 0;    // quads that replace them (three per triangle)
};

struct SmallComponentResult {
  core::Status status;
  core::PolyMesh quads;  // the input quads with the small components replaced
  SmallComponentStats stats;
};

// quads: the extraction of `map` (extract_quads), vertex_face its per-vertex input face
// (ExtractResult::vertex_face). Components are those of map.mesh (faces joined through edges).
// Unchanged when no component is replaced; else the kept faces keep their order, their vertices
// are numbered in order of first use (unreferenced ones are dropped), and the new quads come last. When quads carries UVs, the new quads get map.corner_uv interpolated.
// Returns kInvalidInput when the sizes do not match.
[[nodiscard]] SmallComponentResult split_small_components(const core::UVMesh& map, const core::PolyMesh& quads,
                                                          const std::vector<int>& vertex_face,
                                                          const SmallComponentOptions& options = {});

}  // namespace quadify::quadex
