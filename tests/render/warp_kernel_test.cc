#include "render/warp_kernel.h"

#include "tests/render/render_fixtures.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <random>
#include <sstream>
#include <string>
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

// The kernel's paths this CPU runs, the one-pixel path first, whatever the cap.
std::vector<SamplerPath> EveryPathOnThisCpu() {
  const SamplerPath cap = CapSamplerPath(SamplerPath::kAvx512);
  const SamplerPath widest = WidestSamplerPath();
  CapSamplerPath(cap);
  std::vector<SamplerPath> paths;
  for (const SamplerPath path :
       {SamplerPath::kOnePixel, SamplerPath::kSse41, SamplerPath::kAvx2, SamplerPath::kAvx512}) {
    if (path <= widest) paths.push_back(path);
  }
  return paths;
}

// Samples at (xi, yi) by the one-pixel path into one_pixel, and by every wider path this CPU runs,
// each into a buffer filled afresh with a mark and 64 bytes longer than the row: "" where each
// gives the same bits and writes nothing past the row, else the first path and pixel that does not.
std::string WiderPathsDiffer(const cv::Mat& src, const std::vector<int>& xi,
                             const std::vector<int>& yi, std::vector<uint8_t>* one_pixel) {
  const int n = static_cast<int>(xi.size());
  constexpr uint8_t kMark = 0xA5;
  std::vector<uint8_t> wide;
  one_pixel->resize(3 * n);
  const SamplerPath widest = CapSamplerPath(SamplerPath::kOnePixel);
  SampleRowFixed(src, xi.data(), yi.data(), n, one_pixel->data());
  std::string difference;
  for (const SamplerPath path : EveryPathOnThisCpu()) {
    CapSamplerPath(path);
    wide.assign(3 * n + 64, kMark);
    SampleRowFixed(src, xi.data(), yi.data(), n, wide.data());
    if (!difference.empty()) continue;
    if (std::count(wide.begin() + 3 * n, wide.end(), kMark) != 64) {
      difference = "path " + std::to_string(static_cast<int>(path)) + " wrote past the row";
      continue;
    }
    const auto differ = std::mismatch(one_pixel->begin(), one_pixel->end(), wide.begin());
    if (differ.first == one_pixel->end()) continue;
    const long byte = differ.first - one_pixel->begin();
    std::ostringstream text;
    text << "path " << static_cast<int>(path) << ": pixel " << byte / 3 << " at ("
         << xi[byte / 3] / 128.0 << ", " << yi[byte / 3] / 128.0 << ") channel " << byte % 3
         << " is " << int{wide[byte]} << ", not " << int{(*one_pixel)[byte]};
    difference = text.str();
  }
  CapSamplerPath(widest);
  return difference;
}

// Each RGB path against the one-pixel path and the grey path of each channel, on sources whose
// rows are wide blocks' (157 x 6) and on sources too narrow or too short for any block to fit
// (fewer than 6 columns, 1 row; 6 x 2 and 7 x 3 just fit; 16-pixel blocks need 22 columns): rows
// above the source, at its top edge, inside, near and at its bottom edge (the last row has no row
// below it) and below it.
TEST(WarpKernel, EveryRgbPathGivesTheScalarPathsBits) {
  for (const cv::Size src_size :
       {cv::Size(157, 6), cv::Size(5, 6), cv::Size(157, 1), cv::Size(4, 1), cv::Size(6, 2),
        cv::Size(7, 3), cv::Size(22, 2), cv::Size(21, 3)}) {
    // A block that read outside the source would differ from the one-pixel path, which reads the
    // taps outside as 0, or be reported by AddressSanitizer.
    const cv::Mat src = SmoothTexture(src_size, CV_8UC3, 3, 0.7) + cv::Scalar::all(1);
    std::vector<cv::Mat> channels;
    cv::split(src, channels);
    const float h = static_cast<float>(src_size.height);
    // Lengths of each remainder the 8- and 16-pixel blocks leave; 10 and 18, where an 8-pixel
    // block's wide stores end two pixels before the row does.
    for (const int n : {4001, 4000, 4002, 4005, 4013, 18, 10}) {
      for (const float y0 : {-1.6f, -0.6f, 2.0f / 6 * h, 4.4f / 6 * h, h - 0.4f, h + 0.5f}) {
        std::vector<int> xi, yi;
        NearShiftCoordinates(n, src_size, 11 + static_cast<int>(y0 * 10), &xi, &yi);
        for (int& y : yi) y = y == kInvalidFixed ? y : y - ToFixed(h * 0.5f - y0);
        std::vector<uint8_t> narrow, grey(n);
        EXPECT_EQ(WiderPathsDiffer(src, xi, yi, &narrow), "")
            << src_size << ", y0 = " << y0 << ", n = " << n;
        for (int c = 0; c < 3; ++c) {
          SampleRowFixed(channels[c], xi.data(), yi.data(), n, grey.data());
          for (int u = 0; u < n; ++u) {
            ASSERT_EQ(narrow[3 * u + c], grey[u])
                << src_size << ", pixel " << u << " channel " << c << " y0 " << y0 << " n " << n;
          }
        }
      }
    }
  }
}

// Each RGB path against the one-pixel path along straight lines through the source: scaled along
// x from a squeeze to past the widest span a 16-pixel block takes (its 64 bytes hold taps 0 to 20
// columns from its first pixel's: a scale of 1.25 fits, 1.3 does not everywhere), level or
// sloping across source rows (a row boundary inside a block takes its three-row form), from
// left of the source to right of it; rows of 37 and 38 pixels, whose second 16-pixel block's
// 64-byte store would pass the row's end (a masked store) or just fits; and blocks that start at
// the last column a 64-byte load allows, on the source's last two rows and across its last three.
TEST(WarpKernel, EveryRgbPathGivesTheScalarPathsBitsAlongLines) {
  const cv::Mat src = SmoothTexture(cv::Size(331, 9), CV_8UC3, 3, 0.7) + cv::Scalar::all(1);
  std::vector<int> xi, yi;
  std::vector<uint8_t> one_pixel;
  const auto line = [&](int n, float x0, float scale, float y0, float slope) {
    xi.resize(n);
    yi.resize(n);
    LinearFixedRows(ToFixed(x0), ToFixed(scale), ToFixed(y0), ToFixed(slope), n, xi.data(),
                    yi.data());
    return WiderPathsDiffer(src, xi, yi, &one_pixel);
  };
  for (const int n : {403, 37, 38}) {
    for (const float scale : {0.5f, 1.0f, 1.18f, 1.25f, 1.3f}) {
      for (const float slope : {0.0f, 0.02f, -0.02f, 0.07f}) {
        for (const float x0 : {-5.3f, 0.4f, 17.6f}) {
          EXPECT_EQ(line(n, x0, scale, 4.2f - slope * n / 2, slope), "")
              << "n " << n << ", scale " << scale << ", slope " << slope << ", x0 " << x0;
        }
      }
    }
  }
  // Pixel 64 starts a block at column cols - 22: on rows 7 and 8, the last two; on rows 6 to 8 as
  // its pixels cross from row 6 to row 7 (a slope of 2/128, which the fixed point keeps); and
  // crossing from row 7 to row 8, whose taps below it lie outside (no block may load a row 9).
  const float last_column = static_cast<float>(src.cols - 22) + 0.25f;
  const float slope = 2.0f / 128;
  EXPECT_EQ(line(96, last_column - 64.0f, 1.0f, 7.4f, 0.0f), "") << "the last two rows";
  EXPECT_EQ(line(96, last_column - 64.0f, 1.0f, 6.9f - 64 * slope, slope), "")
      << "the last three rows";
  EXPECT_EQ(line(96, last_column - 64.0f, 1.0f, 7.9f - 64 * slope, slope), "")
      << "from the last row pair to beyond it";
}

// The mask's bits against their definition, pixel by pixel: a source whose every bilinear tap lies
// inside, at and beyond each border, with no source mixed in; every length from 1 to 40 (the
// wide path's blocks of 8 and its tail) and a long row; by every path.
TEST(WarpKernel, MaskBitsMarkThePixelsWhoseTapsAreAllInside) {
  const cv::Size src(23, 5);
  for (const int n : {1, 2, 7, 8, 9, 15, 16, 17, 31, 33, 40, 1001}) {
    for (const float y0 : {-0.6f, 0.0f, 2.0f, 4.0f, 4.2f}) {
      std::vector<int> xi, yi;
      NearShiftCoordinates(n, src, 5 + n, &xi, &yi);
      for (int& y : yi) y = y == kInvalidFixed ? y : y - ToFixed(src.height * 0.5f - y0);
      for (const SamplerPath path : EveryPathOnThisCpu()) {
        const SamplerPath widest = CapSamplerPath(path);
        std::vector<uint8_t> bits((n + 7) / 8, 0xA5);  // to be overwritten, padding included
        InsideMaskBits(xi.data(), yi.data(), n, src.width, src.height, bits.data());
        CapSamplerPath(widest);
        int set = 0;
        for (int k = 0; k < 8 * static_cast<int>(bits.size()); ++k) {
          const bool bit = (bits[k / 8] >> (7 - k % 8)) & 1;
          const bool inside = k < n && xi[k] >= 0 && xi[k] <= ToFixed(src.width - 1.0f) &&
                              yi[k] >= 0 && yi[k] <= ToFixed(src.height - 1.0f);
          ASSERT_EQ(bit, inside) << "path " << static_cast<int>(path) << ", pixel " << k << " of "
                                 << n << ", y0 " << y0;
          set += bit;
        }
        if (n > 100 && y0 == 2.0f) {  // starts inside, runs out below
          EXPECT_GT(set, 0);
          EXPECT_LT(set, n);
        }
      }
    }
  }
}

// Every path's coordinates along two lines are the scalar formula's, bit for bit (AVX-512's fused
// multiply-add would round once): every length up to 40 and a long one, slopes of both signs, far
// from the origin too.
TEST(WarpKernel, LinearRowIsRoundOfAPlusKB) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<float> start(-3e5f, 3e5f), slope(-300.0f, 300.0f);
  std::vector<int> n_values(41);
  for (int n = 0; n <= 40; ++n) n_values[n] = n;
  n_values.push_back(4001);
  for (const int n : n_values) {
    for (int trial = 0; trial < 20; ++trial) {
      const float ax = start(rng), bx = slope(rng), ay = start(rng), by = slope(rng);
      for (const SamplerPath path : EveryPathOnThisCpu()) {
        const SamplerPath widest = CapSamplerPath(path);
        std::vector<int> x_out(n + 1, 12345), y_out(n + 1, 12345);
        LinearFixedRows(ax, bx, ay, by, n, x_out.data(), y_out.data());
        CapSamplerPath(widest);
        for (int k = 0; k < n; ++k) {
          ASSERT_EQ(x_out[k], cvRound(ax + static_cast<float>(k) * bx))
              << "path " << static_cast<int>(path) << ", x, k " << k << " of " << n << ", a " << ax
              << ", b " << bx;
          ASSERT_EQ(y_out[k], cvRound(ay + static_cast<float>(k) * by))
              << "path " << static_cast<int>(path) << ", y, k " << k << " of " << n << ", a " << ay
              << ", b " << by;
        }
        EXPECT_EQ(x_out[n], 12345) << "x written past n = " << n;
        EXPECT_EQ(y_out[n], 12345) << "y written past n = " << n;
      }
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
