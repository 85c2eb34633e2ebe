// Pictures for people: the whole-factor shrink that draws a photo's overview tile.

#include "render/pictures.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

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

}  // namespace
}  // namespace shutterlab
