// validate --out DIR (estimate/report/validate_report.h WriteValidationPlots): the residual
// pictures are drawn and written in parallel; the files and their order must not depend on the
// thread count.

#include "estimate/report/validate_report.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>

#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// A video result of 8 pairs of 160x120 with residuals on a 16 px grid, some points left out.
ValidationResult SmallVideoResult() {
  ValidationResult result;
  result.video = true;
  result.dataset = "small";
  result.declared.camera.width = 160;
  result.declared.camera.height = 120;
  std::mt19937_64 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.1f);
  for (int k = 1; k <= 8; ++k) {
    FrameValidation f;
    f.frame = k;
    f.previous = k - 1;
    f.before.rms_px = 0.1 + 0.01 * k;
    f.after.rms_px = f.translation_after.rms_px = 0.05;
    for (int v = 8; v < 120; v += 16) {
      for (int u = 8; u < 160; u += 16) {
        PointResidual r;
        r.u = u;
        r.v = v;
        r.before_dx = noise(rng) * k;
        r.before_dy = noise(rng);
        r.after_dx = r.translation_dx = noise(rng);
        r.after_dy = r.translation_dy = noise(rng);
        if ((u + v + k) % 7 == 0) r.status = PointStatus::kMoving;
        f.residuals.push_back(r);
      }
    }
    f.points = f.residuals.size();
    result.frames.push_back(std::move(f));
  }
  return result;
}

TEST(WriteValidationPlots, TheSameFilesWhateverTheThreadCount) {
  const ValidationResult result = SmallVideoResult();
  const int threads = cv::getNumThreads();
  test::TempDir dir;
  cv::setNumThreads(1);
  const std::vector<std::string> one = WriteValidationPlots(dir / "one", result);
  cv::setNumThreads(4);
  const std::vector<std::string> four = WriteValidationPlots(dir / "four", result);
  cv::setNumThreads(threads);
  ASSERT_EQ(one.size(), four.size());
  size_t pictures = 0;
  for (size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(fs::path(one[i]).filename(), fs::path(four[i]).filename()) << i;
    EXPECT_EQ(ReadFileToString(one[i]), ReadFileToString(four[i])) << one[i];
    pictures += one[i].find("_residual.png") != std::string::npos;
  }
  EXPECT_EQ(pictures, result.frames.size());
  EXPECT_EQ(fs::path(one.front()).filename(), "0001_residual.png");
}

}  // namespace
}  // namespace shutterlab
