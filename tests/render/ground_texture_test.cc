#include "render/ground_texture.h"

#include "io/image_io.h"
#include "tests/render/render_fixtures.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

GroundTextureOptions Options(int width_px, int height_px, uint64_t seed = 1) {
  GroundTextureOptions options;
  options.width_px = width_px;
  options.height_px = height_px;
  options.seed = seed;
  return options;
}

cv::Mat Grey(const cv::Mat& rgb) {
  cv::Mat grey;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  return grey;
}

// Share of the whole 16x16 blocks whose mean Sobel gradient magnitude (grey levels per pixel, the
// 3x3 Sobel's 1/8 normalisation undone) is below min_gradient: blocks dense optical flow cannot
// track.
double FlatBlockShare(const cv::Mat& grey, double min_gradient) {
  cv::Mat dx, dy, magnitude;
  cv::Sobel(grey, dx, CV_32F, 1, 0, 3, 1.0 / 8.0);
  cv::Sobel(grey, dy, CV_32F, 0, 1, 3, 1.0 / 8.0);
  cv::magnitude(dx, dy, magnitude);
  const int blocks_x = grey.cols / 16, blocks_y = grey.rows / 16;
  int flat = 0;
  for (int by = 0; by < blocks_y; ++by) {
    for (int bx = 0; bx < blocks_x; ++bx) {
      if (cv::mean(magnitude(cv::Rect(bx * 16, by * 16, 16, 16)))[0] < min_gradient) ++flat;
    }
  }
  return static_cast<double>(flat) / (blocks_x * blocks_y);
}

// Straight segments at least min_length_px long that the probabilistic Hough transform finds on
// Canny edges.
int LongSegments(const cv::Mat& grey, double min_length_px) {
  cv::Mat edges;
  cv::Canny(grey, edges, 60, 150);
  std::vector<cv::Vec4i> segments;
  cv::HoughLinesP(edges, segments, 1, CV_PI / 360, 80, min_length_px, 3);
  return static_cast<int>(segments.size());
}

// A flat grey image with sensor-like grain (+-3 levels): no structure to track.
cv::Mat FlatWithGrain(cv::Size size) {
  cv::Mat grain(size, CV_8U);
  cv::randu(grain, 125, 132);
  return grain;
}

TEST(GroundTexture, SameOptionsGiveIdenticalBytes) {
  const cv::Mat a = MakeGroundTexture(Options(640, 480, 7));
  const cv::Mat b = MakeGroundTexture(Options(640, 480, 7));
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
}

TEST(GroundTexture, OtherSeedGivesAnotherScene) {
  const cv::Mat a = MakeGroundTexture(Options(640, 480, 1));
  const cv::Mat b = MakeGroundTexture(Options(640, 480, 2));
  cv::Mat differs;
  cv::compare(Grey(a), Grey(b), differs, cv::CMP_NE);
  EXPECT_GT(cv::countNonZero(differs), 0.9 * a.total());
  EXPECT_GT(cv::norm(a, b, cv::NORM_L1) / (a.total() * 3), 10.0);  // not just other grain
}

TEST(GroundTexture, SizeAndTypeAsAsked) {
  for (const cv::Size size : {cv::Size(333, 217), cv::Size(1, 1), cv::Size(17, 1000)}) {
    const cv::Mat image = MakeGroundTexture(Options(size.width, size.height));
    EXPECT_EQ(image.size(), size);
    EXPECT_EQ(image.type(), CV_8UC3);
  }
}

TEST(GroundTexture, ColoursAreNatural) {
  // Greens, browns and greys in daylight: green leads blue, moderate saturation and brightness
  // (HSV means on OpenCV's 0..255 scales; seeds 1..6 give S 48..71 and V 93..108).
  const cv::Mat image = MakeGroundTexture(Options(800, 600, 3));
  const cv::Scalar rgb = cv::mean(image);
  EXPECT_GT(rgb[1], rgb[2]);
  cv::Mat hsv;
  cv::cvtColor(image, hsv, cv::COLOR_RGB2HSV);
  const cv::Scalar mean = cv::mean(hsv);
  EXPECT_GT(mean[1], 20.0);
  EXPECT_LT(mean[1], 110.0);
  EXPECT_GT(mean[2], 60.0);
  EXPECT_LT(mean[2], 170.0);
}

TEST(GroundTexture, TextureEverywhere) {
  // 2 grey levels per pixel of mean gradient: flat grey with sensor grain (about 1.3) stays below.
  const double min_gradient = 2.0;
  const cv::Size size(1600, 1200);
  EXPECT_EQ(FlatBlockShare(cv::Mat(size, CV_8U, cv::Scalar(128)), min_gradient), 1.0);
  EXPECT_EQ(FlatBlockShare(FlatWithGrain(size), min_gradient), 1.0);
  // At the default 2 cm/px, closer and higher up; the weakest blocks are shadows on lawn or
  // asphalt.
  const std::pair<uint64_t, double> cases[] = {{1, 0.02}, {2, 0.05}, {3, 0.01}};
  for (const auto& [seed, gsd_m] : cases) {
    GroundTextureOptions options = Options(size.width, size.height, seed);
    options.ground_sample_distance_m = gsd_m;
    EXPECT_LT(FlatBlockShare(Grey(MakeGroundTexture(options)), min_gradient), 0.003)
        << "seed " << seed << ", " << gsd_m << " m/px";
  }
}

TEST(GroundTexture, ManyLongStraightEdges) {
  // Road lines, verges, roof edges and field boundaries: long straight segments, which neither a
  // blank image nor smooth random texture has.
  const cv::Size size(1600, 1200);
  const double min_length_px = 100;
  EXPECT_EQ(LongSegments(cv::Mat(size, CV_8U, cv::Scalar(128)), min_length_px), 0);
  cv::Mat noise(size / 2, CV_8U);  // (half size: its dense edges make Hough slow)
  cv::randu(noise, 0, 256);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::normalize(noise, noise, 0, 255, cv::NORM_MINMAX);
  EXPECT_LT(LongSegments(noise, min_length_px), 5);
  for (uint64_t seed : {1, 2, 3}) {
    EXPECT_GE(LongSegments(Grey(MakeGroundTexture(Options(size.width, size.height, seed))),
                           min_length_px),
              20)
        << "seed " << seed;
  }
}

TEST(GroundTexture, DisFlowRecoversAKnownShift) {
  // The property the project needs: dense optical flow tracks the texture to a few hundredths of
  // a pixel.
  const cv::Mat first = Grey(MakeGroundTexture(Options(1024, 768, 5)));
  const cv::Point2d shift(3.25, -1.5);
  const cv::Mat move = (cv::Mat_<double>(2, 3) << 1, 0, shift.x, 0, 1, shift.y);
  cv::Mat second;
  cv::warpAffine(first, second, move, first.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  cv::Mat flow;
  cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM)->calc(first, second, flow);
  std::vector<double> errors;
  const int margin = 32;  // the interior: away from the reflected border
  for (int y = margin; y < flow.rows - margin; ++y) {
    for (int x = margin; x < flow.cols - margin; ++x) {
      const cv::Vec2f f = flow.at<cv::Vec2f>(y, x);
      errors.push_back(std::hypot(f[0] - shift.x, f[1] - shift.y));
    }
  }
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.05);
}

// The message Check() throws for the options, or "" when it accepts them.
std::string CheckMessage(void (*change)(GroundTextureOptions&)) {
  GroundTextureOptions options;
  change(options);
  try {
    options.Check();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "";
}

// The scene file the tests above render take (render_fixtures.h) reads back as written, never
// reoriented: 2560x1440, 8-bit colour.
TEST(GroundTexture, TheTestsSceneFileReadsBackAtItsSize) {
  const cv::Mat scene = ReadImage(test::GroundScenePath(2));
  EXPECT_EQ(scene.cols, 2560);
  EXPECT_EQ(scene.rows, 1440);
  EXPECT_EQ(scene.type(), CV_8UC3);
}

TEST(GroundTexture, CheckRefusesBadOptions) {
  EXPECT_EQ(CheckMessage([](GroundTextureOptions&) {}), "");
  EXPECT_NE(CheckMessage([](GroundTextureOptions& o) { o.width_px = 0; }).find("0x3000"),
            std::string::npos);
  EXPECT_NE(CheckMessage([](GroundTextureOptions& o) { o.height_px = -3; }).find("positive"),
            std::string::npos);
  EXPECT_NE(CheckMessage([](GroundTextureOptions& o) { o.width_px = 100000; }).find("at most"),
            std::string::npos);
  for (double bad_m : {0.0, -0.02, 1.0, static_cast<double>(NAN)}) {
    GroundTextureOptions options;
    options.ground_sample_distance_m = bad_m;
    EXPECT_THROW(options.Check(), std::invalid_argument) << bad_m;
  }
  EXPECT_NE(CheckMessage([](GroundTextureOptions& o) {
              o.ground_sample_distance_m = 0;
            }).find("ground_sample_distance_m"),
            std::string::npos);
  GroundTextureOptions empty;
  empty.width_px = 0;
  EXPECT_THROW(MakeGroundTexture(empty), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
