// `quadify compare` end to end on tiny folders: real figures for a quad cube over the triangle
// cube, missing and unreadable outputs reported (not fatal), seconds from reports and peer tables,
// and bad input rejected with exit 2 and no output.
#include "cli_run.h"
#include "compare_fixture.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using quadify::test::data_path;
using quadify::test::make_temp_dir;

namespace {

using quadify::test::CliRun;
using quadify::test::quadify;
using quadify::test::shell_quoted;
using quadify::test::slurp;
using quadify::test::write_text;

// compare.csv as rows of column → cell (no quoted cells in these fixtures except errors).
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& path) {
  std::istringstream in(slurp(path));
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  auto split = [](const std::string& s) {
    std::vector<std::string> cells;
    std::string cell;
    bool in_quotes = false;
    for (char c : s) {
      if (c == '"') in_quotes = !in_quotes;
      else if (c == ',' && !in_quotes) cells.push_back(std::exchange(cell, {}));
      else cell += c;
    }
    cells.push_back(cell);
    return cells;
  };
  if (std::getline(in, line)) header = split(line);
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line);
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

const std::map<std::string, std::string>* find_row(const std::vector<std::map<std::string, std::string>>& rows,
                                                    const std::string& model, const std::string& tool) {
  for (const auto& row : rows)
    if (row.at("model") == model && row.at("tool") == tool) return &row;
  return nullptr;
}

class CompareTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (quadify::test::cli_path().empty()) GTEST_SKIP() << "quadify CLI not built";
    dir_ = make_temp_dir("compare");
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST_F(CompareTest, QuadCubeOverCubeMissingAndBrokenOutputs) {
  const quadify::test::CompareFixture fx = quadify::test::make_compare_fixture(dir_);
  const CliRun r = quadify(fx.command_line, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("compare cube"), std::string::npos) << "progress per model on stderr:\n" << r.err;

  const auto rows = read_csv(fx.out_dir / "compare.csv");
  ASSERT_EQ(rows.size(), 6u) << "2 models × 3 tools:\n" << slurp(fx.out_dir / "compare.csv");
  const auto* exact = find_row(rows, "cube", "exact");
  ASSERT_NE(exact, nullptr);
  EXPECT_EQ(exact->at("status"), "ok");
  EXPECT_EQ(exact->at("faces"), "6");
  EXPECT_EQ(exact->at("quads"), "6");
  EXPECT_EQ(exact->at("non_quads"), "0");
  EXPECT_EQ(exact->at("irregular_vertices"), "8") << "a cube's corners have valence 3";
  EXPECT_EQ(exact->at("valence_histogram"), "3:8");
  EXPECT_EQ(exact->at("flipped_quads"), "0");
  EXPECT_NEAR(std::stod(exact->at("feature_capture")), 1.0, 1e-9);
  EXPECT_LT(std::stod(exact->at("hausdorff_sym")), 1e-9);
  EXPECT_NEAR(std::stod(exact->at("sj_min")), 1.0, 1e-9);
  EXPECT_NEAR(std::stod(exact->at("seconds")), 2.0, 1e-9) << "remesh report: stages without 'measure'";

  const auto* grown = find_row(rows, "cube", "grown");
  ASSERT_NE(grown, nullptr);
  EXPECT_EQ(grown->at("status"), "ok");
  EXPECT_LT(std::stod(grown->at("feature_capture")), 0.01) << "edges moved by 1% of the side";
  EXPECT_GT(std::stod(grown->at("hausdorff_sym")), 0.004);
  EXPECT_NEAR(std::stod(grown->at("seconds")), 3.5, 1e-9) << "from the peers' results.tsv";

  const auto* broken = find_row(rows, "cube", "broken");
  ASSERT_NE(broken, nullptr);
  EXPECT_EQ(broken->at("status").rfind("error: ", 0), 0u) << broken->at("status");
  EXPECT_NE(broken->at("status").find("cube.obj"), std::string::npos) << broken->at("status");
  EXPECT_EQ(find_row(rows, "tet", "exact")->at("status"), "missing");
  EXPECT_EQ(find_row(rows, "tet", "grown")->at("status"), "missing (failed rc=124)");

  const auto j = nlohmann::json::parse(slurp(fx.out_dir / "compare.json"));
  EXPECT_EQ(j["command"], "compare");
  ASSERT_EQ(j["rows"].size(), 6u);
  const auto& first = j["rows"][0];  // models sorted by name, tools in command-line order
  EXPECT_EQ(first["model"], "cube");
  EXPECT_EQ(first["tool"], "exact");
  EXPECT_EQ(first["flipped_quads"], 0);
  EXPECT_EQ(first["valence_histogram"]["3"], 8);
  EXPECT_NEAR(first["feature_capture"].get<double>(), 1.0, 1e-9);
  EXPECT_LT(first["feature_hausdorff"].get<double>(), 1e-9);
  EXPECT_EQ(j["models"][0]["sharp_edges"], 12) << "the cube's 12 edges are sharp; its diagonals are not";

  const std::string md = slurp(fx.out_dir / "compare.md");
  EXPECT_NE(md.find("| cube | exact | ok |"), std::string::npos) << md;
  EXPECT_NE(md.find("**1.000**"), std::string::npos) << "best feature capture in bold:\n" << md;
  EXPECT_NE(md.find("| tet | exact | missing |"), std::string::npos) << md;
  const std::string page = slurp(fx.out_dir / "index.html");
  EXPECT_NE(page.find("img/cube__exact.svg"), std::string::npos);
  const std::string svg = slurp(fx.out_dir / "img" / "cube__exact.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("#ff1f1f"), std::string::npos) << "sharp edges drawn";
  EXPECT_TRUE(fs::exists(fx.out_dir / "img" / "cube__input.svg"));
  EXPECT_FALSE(fs::exists(fx.out_dir / "img" / "tet__exact.svg")) << "no picture of a missing output";
}

// The same run twice gives the same files (parallel over models and tools, deterministic).
TEST_F(CompareTest, OutputIsDeterministic) {
  const quadify::test::CompareFixture fx = quadify::test::make_compare_fixture(dir_);
  ASSERT_EQ(quadify(fx.command_line + " --threads 1", dir_).exit_code, 0);
  const std::string csv1 = slurp(fx.out_dir / "compare.csv"), json1 = slurp(fx.out_dir / "compare.json"),
                    svg1 = slurp(fx.out_dir / "img" / "cube__exact.svg");
  ASSERT_EQ(quadify(fx.command_line, dir_).exit_code, 0);
  EXPECT_EQ(csv1, slurp(fx.out_dir / "compare.csv"));
  EXPECT_EQ(json1, slurp(fx.out_dir / "compare.json"));
  EXPECT_EQ(svg1, slurp(fx.out_dir / "img" / "cube__exact.svg"));
}

// quadify's own output, with the seconds of its report.
TEST_F(CompareTest, MeasuresRemeshOutputWithReportSeconds) {
  fs::create_directories(dir_ / "in");
  fs::create_directories(dir_ / "quadify");
  fs::copy_file(data_path("torus.obj"), dir_ / "in" / "torus.obj");
  const CliRun remesh = quadify(shell_quoted(data_path("torus.obj")) + " -o " + shell_quoted(dir_ / "quadify" / "torus.obj") +
                                    " --target-faces 300 --no-measure -q --json " + shell_quoted(dir_ / "quadify" / "torus.json"),
                                dir_);
  ASSERT_EQ(remesh.exit_code, 0) << remesh.err;
  const CliRun r = quadify("compare -q --samples 5000 --inputs " + shell_quoted(dir_ / "in") + " --outputs quadify=" +
                               shell_quoted(dir_ / "quadify") + " -o " + shell_quoted(dir_ / "cmp"),
                           dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << "--quiet:\n" << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "cmp" / "compare.json"));
  const auto& row = j["rows"][0];
  ASSERT_EQ(row["status"], "ok") << row.dump();
  EXPECT_EQ(row["non_quads"], 0);
  EXPECT_EQ(row["flipped_quads"], 0);
  EXPECT_NEAR(row["faces"].get<int>(), 300, 60);
  EXPECT_LT(row["hausdorff_sym"].get<double>(), 0.05);
  EXPECT_TRUE(row["feature_capture"].is_null()) << "a torus has no sharp edges";
  EXPECT_GT(row["seconds"].get<double>(), 0.0);
  EXPECT_NE(row["seconds_source"].get<std::string>().find("torus.json"), std::string::npos);
}

TEST_F(CompareTest, HelpExplainsEveryOption) {
  const CliRun r = quadify("compare --help", dir_);
  EXPECT_EQ(r.exit_code, 0);
  for (const char* word : {"--inputs", "--outputs", "NAME=DIR", "--output", "--only", "--samples", "--feature-angle"})
    EXPECT_NE(r.out.find(word), std::string::npos) << "help lacks " << word << ":\n" << r.out;
}

TEST_F(CompareTest, OnlySelectsModels) {
  const quadify::test::CompareFixture fx = quadify::test::make_compare_fixture(dir_);
  const CliRun r = quadify(fx.command_line + " --only tet", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = read_csv(fx.out_dir / "compare.csv");
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& row : rows) EXPECT_EQ(row.at("model"), "tet");
}

// Each bad input: exit 2, one line naming the culprit, and no output folder.
TEST_F(CompareTest, BadInputIsExit2WithoutOutput) {
  const quadify::test::CompareFixture fx = quadify::test::make_compare_fixture(dir_);
  fs::create_directories(dir_ / "empty");
  const std::string out = " -o " + shell_quoted(dir_ / "never");
  const std::string tool = " --outputs exact=" + shell_quoted(fx.tool_dirs[0]);
  const struct {
    std::string args, culprit;
  } cases[] = {
      {"--inputs " + shell_quoted(dir_ / "nope") + tool + out, "nope"},
      {"--inputs " + shell_quoted(dir_ / "empty") + tool + out, "no meshes"},
      {"--inputs " + shell_quoted(fx.inputs) + " --outputs " + shell_quoted(fx.tool_dirs[0]) + out, "NAME=DIR"},
      {"--inputs " + shell_quoted(fx.inputs) + " --outputs =x" + out, "NAME=DIR"},
      {"--inputs " + shell_quoted(fx.inputs) + " --outputs x=" + shell_quoted(dir_ / "no_tool") + out, "no_tool"},
      {"--inputs " + shell_quoted(fx.inputs) + tool + tool + out, "twice"},
      {"--inputs " + shell_quoted(fx.inputs) + " --outputs " + shell_quoted("a/b=" + fx.tool_dirs[0].string()) + out,
       "NAME may hold"},
      {"--inputs " + shell_quoted(fx.inputs) + tool + " --only cube,nosuch" + out, "nosuch"},
  };
  for (const auto& c : cases) {
    const CliRun r = quadify("compare " + c.args, dir_);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.culprit), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one error line expected:\n" << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "never")) << c.args;
  }
}

}  // namespace
