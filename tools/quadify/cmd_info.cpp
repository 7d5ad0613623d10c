// quadify info IN: what the file holds, what repair does to it, and the repaired topology.
#include "commands.h"

#include <libcore/topology.h>

#include <Eigen/Core>

#include <cstdio>
#include <memory>

namespace quadify::cli {
namespace {

struct EdgeLengths {
  double min = 0, mean = 0, max = 0;
};

EdgeLengths edge_lengths(const core::TriMesh& mesh) {
  EdgeLengths out;
  if (mesh.n_faces() == 0) return out;
  out.min = std::numeric_limits<double>::infinity();
  double sum = 0;
  for (int f = 0; f < mesh.n_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const double l = (mesh.V.row(mesh.F(f, k)) - mesh.V.row(mesh.F(f, (k + 1) % 3))).norm();
      out.min = std::min(out.min, l);
      out.max = std::max(out.max, l);
      sum += l;
    }
  out.mean = sum / (3.0 * mesh.n_faces());
  return out;
}

int run_info(const std::string& input, const CommonOptions& common) {
  Progress progress(common.quiet);
  const LoadedMesh loaded = load_and_repair(input, progress);
  progress.begin("topology");
  const core::TopologyStats raw_stats = core::topology_stats(core::to_trimesh(loaded.raw));
  const core::TopologyStats stats = core::topology_stats(loaded.repaired.mesh);
  const EdgeLengths lengths = edge_lengths(loaded.repaired.mesh);
  // The sharp edges the remesher would align at its defaults (--feature-angle 40, the crease filter).
  const core::EdgeTopology topo = core::build_edge_topology(loaded.repaired.mesh);
  const core::CreaseOptions crease;
  const size_t n_sharp = core::sharp_edges(loaded.repaired.mesh, topo, crease.angle_deg).size();
  const size_t n_creases = core::crease_edges(loaded.repaired.mesh, topo, crease).size();
  progress.end();

  const core::RepairReport& r = loaded.repaired.report;
  std::printf("%s: %d vertices, %d faces as read (%d non-manifold edges, %d non-manifold vertices)\n",
              input.c_str(), loaded.raw.n_vertices(), loaded.raw.n_faces(), raw_stats.n_nonmanifold_edges,
              raw_stats.n_nonmanifold_vertices);
  std::printf("repair: %d polygons triangulated, %d invalid faces, %d vertices welded, %d degenerate faces, "
              "%d caps, %d folds flipped, %d fin faces, %d duplicate faces, %d unreferenced vertices, %d faces reoriented, %d non-manifold edges and "
              "%d vertices split\n",
              r.polygons_triangulated, r.invalid_faces_removed, r.welded_vertices, r.degenerate_faces_removed,
              r.caps_removed, r.folds_flipped, r.fin_faces_removed, r.duplicate_faces_removed, r.unreferenced_vertices_removed, r.faces_reoriented,
              r.nonmanifold_edges_split, r.nonmanifold_vertices_split);
  std::printf("repaired: %d vertices, %d triangles, %d components, %d boundary loops, chi %d, genus %s\n",
              stats.n_vertices, stats.n_faces, stats.n_components, stats.n_boundary_loops,
              stats.euler_characteristic, stats.genus >= 0 ? std::to_string(stats.genus).c_str() : "undefined");
  std::printf("size: bbox diagonal %.6g, edge length min %.4g mean %.4g max %.4g\n",
              core::bbox_diagonal(loaded.repaired.mesh.V), lengths.min, lengths.mean, lengths.max);
  std::printf("features: %zu sharp edges (dihedral angle above %g degrees), %zu of them creases: what the "
              "remesher aligns at its defaults, less curves too short for the quad size%s\n",
              n_sharp, crease.angle_deg, n_creases,
              n_creases == n_sharp ? "" : " (the others are scattered or faceted: see --feature-side-angle)");

  nlohmann::json report;
  report["command"] = "info";
  report["status"] = "ok";
  report["input"] = input_json(input, loaded.raw);
  report["input"]["topology"] = to_json(raw_stats);
  report["repair"] = to_json(r);
  report["mesh"] = to_json(stats);
  report["mesh"]["edge_length"] = {{"min", lengths.min}, {"mean", lengths.mean}, {"max", lengths.max}};
  report["mesh"]["sharp_edges"] = n_sharp;
  report["mesh"]["crease_edges"] = n_creases;
  report["timings"] = progress.timings();
  write_report(common, report);
  return kExitOk;
}

}  // namespace

CommandRunner register_info(CLI::App& app) {
  auto input = std::make_shared<std::string>();
  app.add_option("input", *input, "Triangle or polygon mesh (OBJ, OFF, PLY, STL, glTF, GLB)")
      ->required()
      ->type_name("IN");
  return [input](const CommonOptions& common) { return run_info(*input, common); };
}

}  // namespace quadify::cli
