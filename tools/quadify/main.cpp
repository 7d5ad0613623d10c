// quadify: triangle mesh → quad mesh. Subcommands: remesh (the default), info, check, param, compare. Exit codes: 0 ok, 2 bad input, 1 internal failure.
#include "commands.h"

#include <libcore/atomic_file.h>
#include <libcore/status.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>
#include <map>
#include <new>

#ifdef QUADIFY_WITH_TBB
#include <tbb/global_control.h>
#endif
#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace {

constexpr const char* kFooter = R"(Typical use:
  quadify bunny.stl -o bunny_quads.obj --target-faces 5000   remesh (OBJ, glTF or GLB out)
  quadify info scan.ply                                      what the file holds, what repair does
  quadify check result.obj --reference bunny.stl             quality of any quad mesh or UV map
  quadify compare --inputs in --outputs a=A --outputs b=B -o cmp   tools A, B side by side on in/*

Exit codes:
  0  success
  2  bad input: the file cannot be read or used, or the options are invalid (one line on stderr
     names the file and the problem; no output file is written)
  1  internal failure (a bug or an exhausted resource); no partial output is left behind

Run `quadify <command> --help` for the options of a command.)";

// Large blocks (sparse factors, Hessians, the transposes CHOLMOD makes per factorization: tens of
// MB at 100K triangles, allocated and freed hundreds of times) are kept in the heap for reuse
// instead of being mapped and unmapped each time by glibc's default; every fresh mapping costs
// page faults on all its pages. feline (100K triangles, 2 cores): 0.85–1.4 M minor page faults →
// 0.31 M, quantization 17–36 s → 15.4–18.7 s, the whole run 60–84 s → 54–64 s, peak memory
// 1.05 → 1.27 GB (README: "Heap reuse and one transpose per factorization"). Process-wide, so set here (the libraries keep no global state).
void keep_large_blocks_in_heap() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  using namespace quadify;
  keep_large_blocks_in_heap();
  CLI::App app{"quadify " QUADIFY_VERSION " — quad remeshing by direct seamless parametrization"};
  app.footer(kFooter);
  app.set_version_flag("--version", "quadify " QUADIFY_VERSION);
  app.require_subcommand(1);
  app.fallthrough();  // common options may follow the subcommand

  cli::CommonOptions common;
  app.add_option("--json", common.json_path,
                 "Write a JSON report (inputs, repairs, metrics, per-stage seconds) to this file")
      ->type_name("FILE");
  app.add_option("--threads", common.threads, "Worker threads (0 = all cores); results do not depend on it")
      ->check(CLI::Range(0, 1024))
      ->type_name("N");
  app.add_flag("-q,--quiet", common.quiet, "No progress messages on stderr");

  std::map<CLI::App*, cli::CommandRunner> runners;
  auto add = [&](const char* name, const char* description, auto registrar) {
    CLI::App* sub = app.add_subcommand(name, description);
    runners[sub] = registrar(*sub);
  };
  add("info", "Mesh statistics and what repair would do to the input", cli::register_info);
  add("check",
      "Metrics of a parametrization (triangle OBJ with vt) or of a quad mesh, made by any tool",
      cli::register_check);
  add("param", "Seamless parametrization (Levi 2021) written as a UV OBJ", cli::register_param);
  add("remesh", "Triangle mesh to quad mesh (the default: `quadify IN -o OUT` means `quadify remesh IN -o OUT`)",
      cli::register_remesh);
  add("compare",
      "Feature benchmark: several tools' quad meshes of a folder of inputs, measured and pictured side by side",
      cli::register_compare);

  // `quadify IN -o OUT` is `quadify remesh IN -o OUT`: insert the subcommand when none is named.
  std::vector<std::string> args(argv + 1, argv + argc);
  // The subcommand is the first word that is neither an option nor the value of a global option
  // taking one (so an input or output path that happens to be called `info` stays a path).
  bool names_subcommand = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--json" || a == "--threads") {
      ++i;
      continue;
    }
    if (a.empty() || a[0] == '-') continue;
    names_subcommand = a == "info" || a == "check" || a == "param" || a == "remesh" || a == "compare";
    break;
  }
  const bool only_global = std::all_of(args.begin(), args.end(), [](const std::string& a) {
    return a == "-h" || a == "--help" || a == "--version";
  });
  if (!names_subcommand && !only_global) args.insert(args.begin(), "remesh");
  std::reverse(args.begin(), args.end());  // CLI11 takes the arguments reversed

  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help/version or the error
    return code == 0 ? cli::kExitOk : cli::kExitBadInput;
  }

#ifdef QUADIFY_WITH_TBB
  std::unique_ptr<tbb::global_control> thread_limit;
  if (common.threads > 0)
    thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                         static_cast<size_t>(common.threads));
#endif

  try {
    if (!common.json_path.empty()) core::check_can_write(common.json_path);
    for (auto& [sub, run] : runners)
      if (sub->parsed()) return run(common);
    return cli::kExitBadInput;
  } catch (const cli::CliError& e) {
    std::fprintf(stderr, "quadify: %s\n", e.message.c_str());
    return e.exit_code;
  } catch (const core::InputError& e) {
    std::fprintf(stderr, "quadify: %s\n", e.what());
    return cli::kExitBadInput;
  } catch (const core::OutputError& e) {
    std::fprintf(stderr, "quadify: %s\n", e.what());
    return cli::kExitInternal;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "quadify: out of memory\n");
    return cli::kExitInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "quadify: internal error: %s\n", e.what());
    return cli::kExitInternal;
  }
}
