// A tiny benchmark for `quadify compare`: inputs cube + tet (tests/data), and three tools —
// "exact" (the cube as 6 quads, with a quadify report giving 2 s), "grown" (the quad cube scaled
// by 1.02 about its centre, seconds in the peers' results.tsv, which lists tet as failed) and
// "broken" (an unreadable cube.obj). No tool has a tet.
#pragma once

#include "cli_run.h"

#include <filesystem>
#include <string>
#include <vector>

namespace quadify::test {

struct CompareFixture {
  std::filesystem::path inputs, out_dir;
  std::vector<std::filesystem::path> tool_dirs;  // exact, grown, broken
  std::string command_line;                      // `compare ...` over all of it, into out_dir
};

// The unit cube [0,1]³ as 6 quads, outward, scaled by `scale` about its centre.
inline std::string quad_cube_obj(double scale) {
  std::string obj;
  for (int v = 0; v < 8; ++v) {
    const int x = (v == 1 || v == 2 || v == 5 || v == 6), y = (v == 2 || v == 3 || v == 6 || v == 7), z = v >= 4;
    auto c = [&](int i) { return std::to_string(0.5 + (i - 0.5) * scale); };
    obj += "v " + c(x) + " " + c(y) + " " + c(z) + "\n";
  }
  return obj + "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
}

inline CompareFixture make_compare_fixture(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  CompareFixture fx;
  fx.inputs = dir / "inputs";
  fx.out_dir = dir / "out";
  fx.tool_dirs = {dir / "ours" / "exact", dir / "peers" / "grown", dir / "peers" / "broken"};
  fs::create_directories(fx.inputs);
  for (const fs::path& d : fx.tool_dirs) fs::create_directories(d);
  fs::copy_file(data_path("cube.obj"), fx.inputs / "cube.obj");
  fs::copy_file(data_path("tet.obj"), fx.inputs / "tet.obj");
  write_text(fx.tool_dirs[0] / "cube.obj", quad_cube_obj(1.0));
  write_text(fx.tool_dirs[0] / "cube.json",
             R"({"command": "remesh", "timings": {"param": 1.5, "quantize": 0.5, "measure": 9.0}})");
  write_text(fx.tool_dirs[1] / "cube.obj", quad_cube_obj(1.02));
  write_text(dir / "peers" / "results.tsv",
             "mesh\tpeer\tstatus\twall_s\tfaces\n"
             "cube\tgrown\tok\t3.5\t6\n"
             "tet\tgrown\tfailed rc=124\t240\t\n"
             "cube\tother\tok\t99\t6\n");
  write_text(fx.tool_dirs[2] / "cube.obj", "v 0 0 0\nf 1 2 3\n");  // vertex ids out of range
  fx.command_line = "compare --samples 2000 --inputs " + shell_quoted(fx.inputs) + " --outputs exact=" +
                    shell_quoted(fx.tool_dirs[0]) + " --outputs grown=" + shell_quoted(fx.tool_dirs[1]) +
                    " --outputs broken=" + shell_quoted(fx.tool_dirs[2]) + " -o " + shell_quoted(fx.out_dir);
  return fx;
}

}  // namespace quadify::test
