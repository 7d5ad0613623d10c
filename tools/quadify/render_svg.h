// Pictures of meshes for `quadify compare`: a fixed orthographic camera from a bounding box, the
// surface Lambert-shaded and sorted back to front (painter's algorithm), the polygon wireframe and
// sharp reference edges, hidden parts removed with a small depth buffer, written as SVG.
#pragma once

#include <libcore/mesh.h>

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace quadify::cli {

// An orthographic view: screen x = (p - center)·right, screen y = (p - center)·up, and
// (p - center)·toward is the depth, larger nearer the viewer. `scale` is pixels per model unit.
struct Camera {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d right = Eigen::Vector3d::UnitX(), up = Eigen::Vector3d::UnitY(),
                  toward = Eigen::Vector3d::UnitZ();
  double scale = 1;
  int width = 480, height = 360;  // picture size, pixels
  double diagonal = 1;            // bbox diagonal of the framed mesh, model units
};

// A camera that frames the bounding box of V in a width×height picture, the same for any mesh
// framed from the same V: it looks at the box's largest side (down its shortest axis, the longest
// axis horizontal), turned 30° about the vertical and tilted 25° down for a three-quarter view.
Camera camera_for_bbox(const Eigen::MatrixX3d& V, int width, int height);

// Edges of `mesh` whose dihedral angle exceeds angle_deg (faces adjacent by a shared edge, in
// either orientation), as segments in model units. Non-manifold edges are skipped.
std::vector<std::array<Eigen::Vector3d, 2>> sharp_edges(const core::TriMesh& mesh, double angle_deg);

struct SvgStyle {
  bool wireframe = true;       // stroke the polygon edges
  bool tint_non_quads = true;  // faces of degree ≠ 4 in a warning colour
  // Shown on top of the surface where not hidden by it (depth test, see render_svg).
  std::vector<std::array<Eigen::Vector3d, 2>> highlight;
};

// The SVG document of `mesh` seen by `camera`. Faces turned away from the camera are culled when
// the mesh is closed (every edge shared by two faces), and drawn in a warning colour otherwise. Wireframe width and opacity follow the projected edge length, so dense
// meshes still read as surfaces.
std::string render_svg(const core::PolyMesh& mesh, const Camera& camera, const SvgStyle& style);

}  // namespace quadify::cli
