// Running the quadify CLI from a test: exit code and captured stdout/stderr, plus file helpers.
#pragma once

#include "test_util.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace quadify::test {

struct CliRun {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_text(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

// Exit code of a std::system() status: the program's code, or 128 + signal.
inline int exit_code_of(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status); }

// Runs `quadify <args>` with stdout/stderr captured to files of `dir`.
inline CliRun quadify(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  std::string cmd = "'";  // appended piecewise: GCC 12 warns falsely (-Wrestrict) on "'" + string
  cmd.append(cli_path()).append("' ").append(args).append(" >'").append(out.string());
  cmd.append("' 2>'").append(err.string()).append("'");
  CliRun r;
  r.exit_code = exit_code_of(std::system(cmd.c_str()));
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

// `path` in single quotes for a shell command line.
inline std::string shell_quoted(const std::filesystem::path& path) {
  std::string q = "'";
  q.append(path.string()).append("'");
  return q;
}

}  // namespace quadify::test
