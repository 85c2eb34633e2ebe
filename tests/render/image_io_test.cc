#include "render/image_io.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

TEST(ImageIo, LosslessFormatsRoundTripExactly) {
  test::TempDir dir;
  for (const char* extension : {".png", ".tif"}) {
    for (int type : {CV_8UC1, CV_8UC3, CV_16UC1, CV_16UC3}) {
      const cv::Mat image = test::SmoothTexture(cv::Size(37, 23), type, 9, 0.5);
      const std::string path = dir / ("image_" + std::to_string(type) + extension);
      WriteImage(path, image);
      const cv::Mat back = ReadImage(path);
      ASSERT_EQ(back.type(), type) << path;
      EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0.0) << path;
    }
  }
}

TEST(ImageIo, ChannelOrderIsTheFilesRgb) {
  // A pure red pixel written as channel 0 comes back as channel 0 (no BGR swap anywhere).
  test::TempDir dir;
  cv::Mat image(2, 2, CV_8UC3, cv::Scalar(255, 0, 0));
  WriteImage(dir / "red.png", image);
  const cv::Mat back = ReadImage(dir / "red.png");
  EXPECT_EQ(back.at<cv::Vec3b>(1, 1), cv::Vec3b(255, 0, 0));
}

TEST(ImageIo, JpegRoundTripsClosely) {
  test::TempDir dir;
  const cv::Mat image = test::SmoothTexture(cv::Size(64, 48), CV_8UC3, 9, 3.0);
  WriteImage(dir / "image.jpg", image);
  const cv::Mat back = ReadImage(dir / "image.jpg");
  ASSERT_EQ(back.type(), CV_8UC3);
  // Quality 95 on a smooth texture: a few levels at most.
  EXPECT_LT(cv::norm(back, image, cv::NORM_L1) / image.total() / 3, 3.0);
}

TEST(ImageIo, ExrKeepsFloatsAndChannelNames) {
  test::TempDir dir;
  cv::Mat field(5, 7, CV_32FC2);
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 7; ++u)
      field.at<cv::Vec2f>(v, u) = cv::Vec2f(0.1f * u - 1e-3f * v, -3.25f * v + 1e-7f);
  }
  field.at<cv::Vec2f>(2, 3) = cv::Vec2f(NAN, NAN);
  WriteImage(dir / "disp.exr", field, {"dx", "dy"});
  std::vector<std::string> names;
  const cv::Mat back = ReadFloatImage(dir / "disp.exr", &names);
  ASSERT_EQ(back.type(), CV_32FC2);
  EXPECT_EQ(names, (std::vector<std::string>{"dx", "dy"}));
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 7; ++u) {
      const cv::Vec2f a = field.at<cv::Vec2f>(v, u), b = back.at<cv::Vec2f>(v, u);
      if (v == 2 && u == 3) {
        EXPECT_TRUE(std::isnan(b[0]) && std::isnan(b[1]));
      } else {
        EXPECT_EQ(a, b);  // float32 stays float32 bit for bit
      }
    }
  }
}

TEST(ImageIo, ReadsRealJpegWithoutReorienting) {
  const cv::Mat scene = ReadImage(test::GroundScenePath(2));
  EXPECT_EQ(scene.cols, 2560);
  EXPECT_EQ(scene.rows, 1440);
  EXPECT_EQ(scene.type(), CV_8UC3);
}

TEST(ImageIo, BadFilesThrowIoErrorNamingThePath) {
  test::TempDir dir;
  WriteFileAtomically(dir / "garbage.png", "this is not a png");
  for (const std::string& path : {dir / "missing.png", dir / "garbage.png"}) {
    try {
      ReadImage(path);
      ADD_FAILURE() << "read " << path;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  // Writing into a missing folder fails cleanly and leaves nothing behind.
  EXPECT_THROW(WriteImage(dir / "no/such/folder/out.png", cv::Mat(2, 2, CV_8UC1, cv::Scalar(1))),
               IoError);
  EXPECT_THROW(WriteImage(dir / "out.unknownext", cv::Mat(2, 2, CV_8UC1, cv::Scalar(1))), IoError);
  size_t files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path()))
    ++files;
  EXPECT_EQ(files, 1u) << "only garbage.png may remain";
}

}  // namespace
}  // namespace shutterlab
