#include "render/warp_kernel.h"

#include "tests/render/render_fixtures.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <random>
#include <vector>

namespace shutterlab {
namespace {

using test::SmoothTexture;

// Coordinates of a map close to a shift (the wide blocks' case), with what makes a block fall back
// mixed in: a row boundary inside a block, a stretch, a mirrored run, the source's borders and
// beyond, and pixels with no source.
void NearShiftCoordinates(int n, cv::Size src, uint64_t seed, std::vector<int>* xi,
                          std::vector<int>* yi) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
  std::uniform_int_distribution<int> kind(0, 19);
  xi->resize(n);
  yi->resize(n);
  float x = -3.0f, y = static_cast<float>(src.height) * 0.5f;
  for (int u = 0; u < n; ++u) {
    switch (kind(rng)) {
      case 0:  // stretch
        x += 2.7f;
        break;
      case 1:  // mirrored step
        x -= 1.0f;
        break;
      case 2:  // next source row
        y += 1.0f;
        break;
      default:
        x += 1.0f + 0.01f * jitter(rng);
        y += 0.002f;
    }
    if (x > src.width + 3) x = -3.0f;
    const bool no_source = u % 97 == 5;
    (*xi)[u] = no_source ? kInvalidFixed : ToFixed(x + 0.1f * jitter(rng));
    (*yi)[u] = ToFixed(y + 0.1f * jitter(rng));
  }
}

// Each RGB path against the one-pixel path and the grey path of each channel, on sources whose
// rows are wide blocks' (157 x 6) and on sources too narrow or too short for any block to fit
// (fewer than 6 columns, 1 row; 6 x 2 and 7 x 3 just fit): rows above the source, at its top edge,
// inside, near and at its bottom edge (the last row has no row below it) and below it.
TEST(WarpKernel, EveryRgbPathGivesTheScalarPathsBits) {
  for (const cv::Size src_size : {cv::Size(157, 6), cv::Size(5, 6), cv::Size(157, 1),
                                  cv::Size(4, 1), cv::Size(6, 2), cv::Size(7, 3)}) {
    // A block that read outside the source would differ from the one-pixel path, which reads the
    // taps outside as 0, or be reported by AddressSanitizer.
    const cv::Mat src = SmoothTexture(src_size, CV_8UC3, 3, 0.7) + cv::Scalar::all(1);
    std::vector<cv::Mat> channels;
    cv::split(src, channels);
    const float h = static_cast<float>(src_size.height);
    // Lengths of each remainder the 8-pixel blocks leave, and 10 and 18, where a block's wide
    // stores end two pixels before the row does.
    for (const int n : {4001, 4000, 4002, 4005, 18, 10}) {
      for (const float y0 : {-1.6f, -0.6f, 2.0f / 6 * h, 4.4f / 6 * h, h - 0.4f, h + 0.5f}) {
        std::vector<int> xi, yi;
        NearShiftCoordinates(n, src_size, 11 + static_cast<int>(y0 * 10), &xi, &yi);
        for (int& y : yi) y = y == kInvalidFixed ? y : y - ToFixed(h * 0.5f - y0);
        std::vector<uint8_t> wide(3 * n), narrow(3 * n), grey(n);
        const bool previous = SetWideSampler(true);
        SampleRowFixed(src, xi.data(), yi.data(), n, wide.data());
        SetWideSampler(false);
        SampleRowFixed(src, xi.data(), yi.data(), n, narrow.data());
        SetWideSampler(previous);
        EXPECT_EQ(wide, narrow) << src_size << ", y0 = " << y0 << ", n = " << n;
        for (int c = 0; c < 3; ++c) {
          SampleRowFixed(channels[c], xi.data(), yi.data(), n, grey.data());
          for (int u = 0; u < n; ++u) {
            ASSERT_EQ(wide[3 * u + c], grey[u])
                << src_size << ", pixel " << u << " channel " << c << " y0 " << y0 << " n " << n;
          }
        }
      }
    }
  }
}

// The mask's bits against their definition, pixel by pixel: a source whose every bilinear tap lies
// inside, at and beyond each border, with no source mixed in; every length from 1 to 40 (the
// wide path's blocks of 8 and its tail) and a long row.
TEST(WarpKernel, MaskBitsMarkThePixelsWhoseTapsAreAllInside) {
  const cv::Size src(23, 5);
  for (const int n : {1, 2, 7, 8, 9, 15, 16, 17, 31, 33, 40, 1001}) {
    for (const float y0 : {-0.6f, 0.0f, 2.0f, 4.0f, 4.2f}) {
      std::vector<int> xi, yi;
      NearShiftCoordinates(n, src, 5 + n, &xi, &yi);
      for (int& y : yi) y = y == kInvalidFixed ? y : y - ToFixed(src.height * 0.5f - y0);
      std::vector<uint8_t> bits((n + 7) / 8, 0xA5);  // to be overwritten, padding included
      InsideMaskBits(xi.data(), yi.data(), n, src.width, src.height, bits.data());
      int set = 0;
      for (int k = 0; k < 8 * static_cast<int>(bits.size()); ++k) {
        const bool bit = (bits[k / 8] >> (7 - k % 8)) & 1;
        const bool inside = k < n && xi[k] >= 0 && xi[k] <= ToFixed(src.width - 1.0f) &&
                            yi[k] >= 0 && yi[k] <= ToFixed(src.height - 1.0f);
        ASSERT_EQ(bit, inside) << "pixel " << k << " of " << n << ", y0 " << y0;
        set += bit;
      }
      if (n > 100 && y0 == 2.0f) {  // starts inside, runs out below
        EXPECT_GT(set, 0);
        EXPECT_LT(set, n);
      }
    }
  }
}

// The wide path's coordinates along two lines are the scalar formula's, bit for bit: every length
// up to 40 and a long one, slopes of both signs, far from the origin too.
TEST(WarpKernel, LinearRowIsRoundOfAPlusKB) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<float> start(-3e5f, 3e5f), slope(-300.0f, 300.0f);
  std::vector<int> n_values(41);
  for (int n = 0; n <= 40; ++n) n_values[n] = n;
  n_values.push_back(4001);
  for (const int n : n_values) {
    for (int trial = 0; trial < 20; ++trial) {
      const float ax = start(rng), bx = slope(rng), ay = start(rng), by = slope(rng);
      std::vector<int> x_out(n + 1, 12345), y_out(n + 1, 12345);
      LinearFixedRows(ax, bx, ay, by, n, x_out.data(), y_out.data());
      for (int k = 0; k < n; ++k) {
        ASSERT_EQ(x_out[k], cvRound(ax + static_cast<float>(k) * bx))
            << "x, k " << k << " of " << n << ", a " << ax << ", b " << bx;
        ASSERT_EQ(y_out[k], cvRound(ay + static_cast<float>(k) * by))
            << "y, k " << k << " of " << n << ", a " << ay << ", b " << by;
      }
      EXPECT_EQ(x_out[n], 12345) << "x written past n = " << n;
      EXPECT_EQ(y_out[n], 12345) << "y written past n = " << n;
    }
  }
}

TEST(WarpKernel, SamplesAtPixelCentresAreThePixels) {
  const cv::Mat src = SmoothTexture(cv::Size(40, 8), CV_8UC3, 5, 1.0);
  std::vector<int> xi(40), yi(40);
  for (int u = 0; u < 40; ++u) {
    xi[u] = ToFixed(static_cast<float>(u));
    yi[u] = ToFixed(3.0f);
  }
  cv::Mat out(1, 40, CV_8UC3);
  SampleRowFixed(src, xi.data(), yi.data(), 40, out.ptr());
  EXPECT_EQ(cv::norm(out, src.row(3), cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace shutterlab
