// Pictures for people: the whole-factor shrink that draws a photo's overview tile, and the
// displacement heatmap at every size a camera may have.

#include "render/pictures.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <limits>

namespace shutterlab {
namespace {

TEST(ShrinkByWholeFactor, EachPixelIsTheMeanOfItsBlock) {
  // 10 x 7, one channel of u + 10 v and another of its square: k = 3 keeps 3 x 2 pixels (the
  // 10th column and the 7th row left out), each the rounded mean of its 3 x 3 block.
  cv::Mat image(7, 10, CV_8UC2);
  for (int v = 0; v < image.rows; ++v) {
    for (int u = 0; u < image.cols; ++u) {
      const int value = u + 10 * v;
      image.at<cv::Vec2b>(v, u) = cv::Vec2b(value, value * value % 251);
    }
  }
  const cv::Mat small = ShrinkByWholeFactor(image, 3);
  ASSERT_EQ(small.size(), cv::Size(3, 2));
  ASSERT_EQ(small.type(), image.type());
  for (int v = 0; v < small.rows; ++v) {
    for (int u = 0; u < small.cols; ++u) {
      for (int c = 0; c < 2; ++c) {
        double sum = 0.0;
        for (int dv = 0; dv < 3; ++dv) {
          for (int du = 0; du < 3; ++du) sum += image.at<cv::Vec2b>(3 * v + dv, 3 * u + du)[c];
        }
        EXPECT_NEAR(small.at<cv::Vec2b>(v, u)[c], sum / 9.0, 0.5 + 1e-9)
            << "pixel " << u << "," << v << " channel " << c;
      }
    }
  }
  // 3 columns are not enough for 4: the image itself.
  const cv::Mat same = ShrinkByWholeFactor(image, 6);
  EXPECT_EQ(same.data, image.data);
  // Never fewer than one row: a strip 2 rows high shrinks by 2 at most.
  EXPECT_EQ(ShrinkByWholeFactor(cv::Mat(2, 100, CV_8UC3, cv::Scalar::all(7)), 10).size(),
            cv::Size(50, 1));
}

TEST(DisplacementHeatmap, DrawsTheFieldAndItsScaleBarAtAnySize) {
  // Fields from one pixel to a frame, as tall as a scale bar's labels need and far shorter: each
  // drawn at the top left, |d| rising to the right from 0 (viridis: the largest yellow, 0
  // purple), a pixel without a value black, the bar to its right.
  for (const cv::Size size :
       {cv::Size(1, 1), cv::Size(8, 8), cv::Size(64, 2), cv::Size(2, 64), cv::Size(320, 240)}) {
    cv::Mat field(size, CV_32FC2);
    for (int v = 0; v < size.height; ++v) {
      for (int u = 0; u < size.width; ++u)
        field.at<cv::Vec2f>(v, u) = cv::Vec2f(0.0f, size.width == 1 ? 1.0f : static_cast<float>(u));
    }
    const bool has_hole = size.area() > 2;
    if (has_hole) {
      field.at<cv::Vec2f>(size.height - 1, 0)[0] = std::numeric_limits<float>::quiet_NaN();
    }
    const cv::Mat picture = DisplacementHeatmap(field);
    ASSERT_EQ(picture.type(), CV_8UC3) << size;
    EXPECT_GE(picture.rows, size.height) << size;
    EXPECT_GT(picture.cols, size.width + 12) << size;  // the bar's strip, 12 px wide at least
    const cv::Vec3b largest = picture.at<cv::Vec3b>(0, size.width - 1);  // R, G, B
    EXPECT_GT(largest[0], 200) << size;
    EXPECT_GT(largest[1], 200) << size;
    EXPECT_LT(largest[2], 100) << size;
    if (size.width > 1) {
      const cv::Vec3b smallest = picture.at<cv::Vec3b>(0, 0);
      EXPECT_LT(smallest[1], 100) << size;
      EXPECT_GT(smallest[2], smallest[1]) << size;
    }
    if (has_hole) EXPECT_EQ(picture.at<cv::Vec3b>(size.height - 1, 0), cv::Vec3b(0, 0, 0)) << size;
  }
}

}  // namespace
}  // namespace shutterlab
