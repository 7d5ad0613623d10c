// Helpers shared by the test suites: test-data paths, the optional benchmark folder, loaders.
#pragma once

#include <cstdlib>
#include <stdlib.h>
#include <filesystem>
#include <string>

namespace quadify::test {

// A file of tests/data.
inline std::filesystem::path data_path(const std::string& name) {
  return std::filesystem::path(QUADIFY_TEST_DATA_DIR) / name;
}

// ../shared/meshes (or $QUADIFY_SHARED_MESHES), empty when absent: tests over it GTEST_SKIP().
inline std::filesystem::path shared_meshes_dir() {
  if (const char* env = std::getenv("QUADIFY_SHARED_MESHES"); env && *env) return env;
  std::filesystem::path dir(QUADIFY_SHARED_MESHES_DIR);
  std::error_code ec;
  return std::filesystem::is_directory(dir, ec) ? dir : std::filesystem::path();
}

// The quadify CLI built alongside the tests (empty when tools are not built).
inline std::string cli_path() { return QUADIFY_CLI_PATH; }

// A fresh empty temporary directory for one test.
inline std::filesystem::path make_temp_dir(const std::string& tag) {
  std::string pattern = (std::filesystem::temp_directory_path() / ("quadify_" + tag + "_XXXXXX")).string();
  if (!::mkdtemp(pattern.data())) return {};
  return pattern;
}

}  // namespace quadify::test
