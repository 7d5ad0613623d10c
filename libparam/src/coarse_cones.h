// Coarse cones: the matchings of a seamless map rounded on a smoothed copy of the mesh, the layout
// then optimized on the mesh itself (ParamOptions::cone_scale). Internal to libparam.
//
// Why: Alg. 1 places a cone wherever the rounding of the matchings meets a quarter turn of
// integrated curvature, at the scale of the tessellation. On a scan (dragon: 108K triangles,
// about 380 cones) the cones do not depend on the target density, so at a coarse target they
// are far denser than the quad grid and the integer quantization dead-ends (two cones within one
// cell). On a copy smoothed at about a quad edge, curvature details smaller than a quad no longer
// add up to quarter turns in small regions, so fewer cones appear; the matchings (integers on the
// same seams) carry over to the original mesh unchanged, and so do the cone indices, which
// depend on the matchings alone. The smoothed map, flip-free on the copy, is a flip-free
// seamless start for the original triangles: only the distortion energy changes.
#pragma once

#include <libcore/mesh.h>
#include <libcore/status.h>
#include <libparam/seamless_param.h>

namespace quadify::param {

// One implicit step of the cotangent-Laplacian heat flow, (M + t·L) V' = M V with t = scale²
// (M lumped masses, L the cotangent Laplacian with negative weights clamped to zero so that the
// system stays SPD), rescaled about the centroid to the input's surface area. Same faces.
// A copy with a degenerate face (a thin part collapsed to a curve) is blended with the input,
// 10% then 30% of it. Returns kNumericalFailure when the factorization fails, kInvalidInput
// when scale ≤ 0 or even the 30% blend has a degenerate face.
[[nodiscard]] core::Status smooth_for_cones(const core::TriMesh& mesh, double scale,
                                            core::TriMesh* smoothed);

// The map `seamless` (of a mesh with mesh's faces, e.g. smooth_for_cones' copy) re-optimized on
// mesh's own triangles: same seams and matchings, same cones, flip-free (symmetric Dirichlet for
// Energy::kTau, options.energy otherwise), sizing from options.face_size/face_metric. Stats
// are those of `seamless` with τ, flips, SD and seam residual measured on the new map.
[[nodiscard]] ParamResult relayout_on_mesh(const core::TriMesh& mesh, const ParamResult& seamless,
                                           const ParamOptions& options);

}  // namespace quadify::param
