// The compare page as a browser shows it: headless Chromium screenshots index.html, and the picture
// must hold shaded surfaces and red sharp edges; a blank page must fail the same check.
// Registered only when Chromium is found (QUADIFY_HAVE_CHROMIUM, tests/CMakeLists.txt).
#include "cli_run.h"
#include "compare_fixture.h"

#include <gtest/gtest.h>

#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>

namespace fs = std::filesystem;
using quadify::test::make_temp_dir;

namespace {

using quadify::test::exit_code_of;
using quadify::test::quadify;
using quadify::test::shell_quoted;
using quadify::test::write_text;

constexpr int kWidth = 1200, kHeight = 900;
constexpr int kBrowserTimeoutSeconds = 120;  // a cold Chromium start on a busy 2-core machine

struct Screenshot {
  int width = 0, height = 0;
  double luminance_stddev = 0;  // over all pixels, 0..255
  long red_pixels = 0;          // the sharp-edge colour
  long shaded_pixels = 0;       // the bluish grey of the quad surface, at any light level
};

// Screenshot of `page` by headless Chromium, decoded; width 0 when none was written.
Screenshot screenshot(const fs::path& page, const fs::path& dir) {
  const fs::path png = dir / (page.stem().string() + ".png");
  std::string cmd = "timeout " + std::to_string(kBrowserTimeoutSeconds) + " " + shell_quoted(QUADIFY_CHROMIUM);
  cmd += " --headless --no-sandbox --disable-gpu --hide-scrollbars --user-data-dir=" + shell_quoted(dir / "profile");
  cmd += " --screenshot=" + shell_quoted(png) + " --window-size=" + std::to_string(kWidth) + "," + std::to_string(kHeight);
  cmd += " " + shell_quoted("file://" + fs::absolute(page).string()) + " >" + shell_quoted(dir / "chromium.log") + " 2>&1";
  Screenshot s;
  if (exit_code_of(std::system(cmd.c_str())) != 0 || !fs::exists(png)) return s;
  int channels = 0;
  std::unique_ptr<unsigned char, decltype(&stbi_image_free)> pixels(
      stbi_load(png.string().c_str(), &s.width, &s.height, &channels, 3), &stbi_image_free);
  if (!pixels) return Screenshot{};
  const long n = static_cast<long>(s.width) * s.height;
  double sum = 0, sum2 = 0;
  for (long i = 0; i < n; ++i) {
    const int r = pixels.get()[3 * i], g = pixels.get()[3 * i + 1], b = pixels.get()[3 * i + 2];
    const double y = 0.299 * r + 0.587 * g + 0.114 * b;
    sum += y;
    sum2 += y * y;
    if (r > 200 && g < 90 && b < 90) ++s.red_pixels;
    if (b > r + 8 && b > 60 && b < 235 && std::abs(g - r) < 30) ++s.shaded_pixels;
  }
  s.luminance_stddev = std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
  return s;
}

// Not blank: the page shows pictures (enough contrast, red feature lines, shaded surface).
::testing::AssertionResult shows_pictures(const Screenshot& s) {
  if (s.width != kWidth || s.height != kHeight)
    return ::testing::AssertionFailure() << "screenshot " << s.width << "x" << s.height << ", expected " << kWidth
                                         << "x" << kHeight;
  if (s.luminance_stddev < 10 || s.red_pixels < 200 || s.shaded_pixels < 5000)
    return ::testing::AssertionFailure() << "blank-looking page: luminance stddev " << s.luminance_stddev << ", "
                                         << s.red_pixels << " red and " << s.shaded_pixels << " shaded pixels";
  return ::testing::AssertionSuccess();
}

class CompareScreenshotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (quadify::test::cli_path().empty()) GTEST_SKIP() << "quadify CLI not built";
    dir_ = make_temp_dir("compare_shot");
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST_F(CompareScreenshotTest, IndexHtmlShowsShadedMeshesWithSharpEdges) {
  const quadify::test::CompareFixture fx = quadify::test::make_compare_fixture(dir_);
  const auto r = quadify(fx.command_line + " -q", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Screenshot s = screenshot(fx.out_dir / "index.html", dir_);
  ASSERT_GT(s.width, 0) << "no screenshot; see " << (dir_ / "chromium.log");
  EXPECT_TRUE(shows_pictures(s));
}

// The check itself: a white page fails it.
TEST_F(CompareScreenshotTest, BlankPageFailsTheCheck) {
  write_text(dir_ / "blank.html", "<!DOCTYPE html><html><body style=\"background:#fff\"></body></html>\n");
  const Screenshot s = screenshot(dir_ / "blank.html", dir_);
  ASSERT_EQ(s.width, kWidth) << "no screenshot; see " << (dir_ / "chromium.log");
  EXPECT_FALSE(shows_pictures(s));
  EXPECT_LT(s.luminance_stddev, 1.0);
}

}  // namespace
