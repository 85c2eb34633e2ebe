#pragma once
// Small image fixtures shared by the io tests and the tests above them.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <random>

namespace shutterlab::test {

// A smooth random texture (blurred noise, fixed seed): band-limited, so bilinear sampling is
// accurate.
inline cv::Mat SmoothTexture(cv::Size size, int type, uint64_t seed = 7,
                             double blur_sigma_px = 2.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  const int cn = CV_MAT_CN(type);
  cv::Mat noise(size, CV_32FC(cn));
  for (int v = 0; v < size.height; ++v) {
    float* row = noise.ptr<float>(v);
    for (int i = 0; i < size.width * cn; ++i) row[i] = uniform(rng);
  }
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), blur_sigma_px);
  cv::normalize(noise, noise, 0.0, 1.0, cv::NORM_MINMAX);
  const double scale = CV_MAT_DEPTH(type) == CV_8U    ? 255.0
                       : CV_MAT_DEPTH(type) == CV_16U ? 65535.0
                                                      : 1.0;
  cv::Mat out;
  noise.convertTo(out, type, scale);
  return out;
}

}  // namespace shutterlab::test
