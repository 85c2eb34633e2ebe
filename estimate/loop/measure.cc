// `measure`: dense optical flow from the rolling-shutter image to the reference, a validity mask,
// and a robust per-row-band polynomial model on top (see measure.h).
//
// Method (chosen by accuracy against the exact truth field of rendered pairs; see the numbers at
// the end of this comment):
//  1. Both images become one grey channel (the plain mean of the channels: any channel order), in
//     0..1 of the type's full scale.
//  2. cv::DISOpticalFlow (ULTRAFAST preset) down to the finest scale, forward (image -> ref)
//     and backward (ref -> image); the forward flow at p is d(p) = p_ref - p directly.
//  3. A pixel is measured when: it and its match are not saturated / black (renderer's border), the
//     smaller eigenvalue of the structure tensor is large enough (texture in both directions), and
//     the forward-backward round trip closes within kMaxRoundTripPx.
//  4. The field along a row is a ratio of linear functions of u (a per-row homography); on top of
//     the raw flow, every row v gets a local polynomial fitted to rows v-h..v+h: cubic in u times
//     quadratic in (w - v), by IRLS with Tukey weights (scale from the MAD of the residuals). The
//     row's model (w = v) is the field. This assumes only that the field is smooth along a row and
//     slowly varying over a few dozen rows; it does not assume the rig or motion model.
//  5. The field is written at measured pixels and in short gaps (<= kMaxGapPx) between measured
//     pixels of the same row; never beyond them (no extrapolation), never at saturated pixels.
//  6. `points`: the raw flow on the grid at measured pixels (DIS patches are 8 px, so points 16 px
//     apart are close to independent); noise_px is the RMS of (point - row model) over them,
//     corrected for the model's degrees of freedom.
//
// Accuracy, RMS of |flow - truth| over the measured pixels, px, on rendered 1280x960 pairs of both
// real scenes (tests/estimate/loop/measure_test.cc, fx 1100, 30 ms readout, D = 1.8 .. 24.4 px),
// one core; raw flow alone unless "+ model":
//   DIS ULTRAFAST finest scale 0 + row model (chosen)       0.0012 .. 0.0055   0.85 s / frame (both
//                                                                               directions + model)
//   DIS MEDIUM finest 0 (variational refinement) + model    0.0019 .. 0.0042   2.75 s
//   DIS ULTRAFAST / FAST / MEDIUM finest 0, raw             0.008-0.083 / 0.007-0.032 / 0.007-0.027
//                                                            (0.36 / 0.87 / 1.15 s one direction)
//   DIS FAST / MEDIUM finest 1, raw                          0.052-0.090 / 0.051-0.077
//   DIS finest 2 (the presets' default), raw                 0.07-0.60
//   Farneback (pyr 0.5, 4 levels, win 15), raw               0.017-1.96 (fails on large D)
//   pyramidal LK 21x21 on the 16 px grid, fb-checked, raw    0.007-0.067   (0.2 s, sparse only)
// So the row model, not the flow preset, sets the accuracy; the rest buys nothing but time.
// A quintic or sixth-degree model in u instead of the cubic: no better (max errors grow at the row
// ends). Renders with an undeclared effect (the canopy scene, D 1.6 .. 27 px): velocity [6,4,1] m/s
// 0.002-0.006 px, bottom_to_top 0.001-0.007 px, lens distortion k1 -0.15 k2 0.05 0.011-0.013 px
// (there the raw flow itself is 2-4x noisier than on the undistorted renders, whatever the degree).

#include "estimate/loop/measure.h"

#include "estimate/loop/corner_tracks.h"
#include "io/image_io.h"
#include "render/pictures.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

namespace shutterlab {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Grey levels (of 255) at or beyond which a pixel counts as black / saturated.
constexpr double kDarkLevel = 1.5 / 255.0;
constexpr double kBrightLevel = 253.5 / 255.0;
// Black / saturated pixels corrupt the flow of every patch that overlaps them: grow the mask.
constexpr int kBadGrowPx = 6;
// Texture: the smallest structure-tensor eigenvalue, as an equivalent gradient (grey fraction
// per px) that the weaker direction must reach (about 0.4 grey levels per px on 8 bits).
constexpr double kMinGradient = 0.4 / 255.0;
constexpr int kTensorBlockPx = 9;
// Forward-backward: the round trip p -> p + f(p) -> back must close within this, px.
constexpr float kMaxRoundTripPx = 0.3f;
// Row bands: rows v-h..v+h.
constexpr int kBandHalfRows = 20;
// Short gaps between measured pixels of a row that the row model may bridge, px.
constexpr int kMaxGapPx = 24;
constexpr int kIrlsIterations = 3;
// DIS's patch stride (ULTRAFAST's): the grid points cycle through its phases (GridPoints).
constexpr int kPatchStridePx = 4;
constexpr double kTukeyC = 4.685;

// Grey 0..1 (mean of the channels over the type's full scale).
cv::Mat GreyUnit(const cv::Mat& image) {
  double full_scale = 1.0;
  if (image.depth() == CV_8U) full_scale = 255.0;
  if (image.depth() == CV_16U) full_scale = 65535.0;
  if (image.depth() == CV_32F) {
    // Float images are 0..1 by convention; one whose values reach beyond is taken as 0..255.
    double lo, hi;
    cv::minMaxLoc(image.reshape(1), &lo, &hi);
    full_scale = hi <= 1.0 ? 1.0 : (hi <= 255.0 ? 255.0 : hi);
  }
  const int cn = image.channels();
  cv::Mat grey;
  if (cn == 1) {
    image.convertTo(grey, CV_32F, 1.0 / full_scale);
  } else {
    cv::Mat as_float;
    image.convertTo(as_float, CV_32F, 1.0 / full_scale);
    cv::transform(as_float, grey, cv::Mat(1, cn, CV_32F, cv::Scalar(1.0 / cn)));
  }
  return grey;
}

// 255 for a black or saturated pixel, grown by kBadGrowPx.
cv::Mat BadMask(const cv::Mat& grey) {
  cv::Mat dark, bright, bad;
  cv::compare(grey, kDarkLevel, dark, cv::CMP_LE);
  cv::compare(grey, kBrightLevel, bright, cv::CMP_GE);
  cv::bitwise_or(dark, bright, bad);
  cv::dilate(bad, bad,
             cv::getStructuringElement(cv::MORPH_RECT, {2 * kBadGrowPx + 1, 2 * kBadGrowPx + 1}));
  return bad;
}

// Equivalent gradient of the weaker direction of the structure tensor, grey fraction per px.
// cornerMinEigenVal on a float image scales the Sobel derivative by 1 / (4 * block), so a ramp of
// slope g gives lambda = 4 g^2 (summed over the block without normalisation: block^2 (2 g /
// block)^2).
cv::Mat WeakGradient(const cv::Mat& grey) {
  cv::Mat lambda;
  cv::cornerMinEigenVal(grey, lambda, kTensorBlockPx, 3);
  cv::Mat g;
  cv::sqrt(cv::max(lambda, 0.0) / 4.0, g);
  return g;
}

// Bilinear sample of a CV_32FC2 field at (x, y); false outside the image.
bool SampleField(const cv::Mat& field, float x, float y, cv::Vec2f* out) {
  if (!(x >= 0 && y >= 0 && x <= field.cols - 1 && y <= field.rows - 1)) return false;
  const int x0 = std::min(static_cast<int>(x), field.cols - 2);
  const int y0 = std::min(static_cast<int>(y), field.rows - 2);
  const float ax = x - x0, ay = y - y0;
  const cv::Vec2f* r0 = field.ptr<cv::Vec2f>(y0) + x0;
  const cv::Vec2f* r1 = field.ptr<cv::Vec2f>(y0 + 1) + x0;
  *out = (1 - ay) * ((1 - ax) * r0[0] + ax * r0[1]) + ay * ((1 - ax) * r1[0] + ax * r1[1]);
  return true;
}

// Per-row-band robust polynomial model of a displacement field (step 4 of the header).
class RowBandModel {
 public:
  static constexpr int kU = 4;        // 1, u, u^2, u^3
  static constexpr int kV = 3;        // 1, dv, dv^2
  static constexpr int kP = kU * kV;  // parameters per component per band

  RowBandModel(int width, int height) : width_(width), height_(height) {
    coeff_.assign(height, {});
    valid_.assign(height, false);
  }

  // Normalised column: u in [-1, 1] keeps the normal equations well conditioned.
  double Un(double u) const { return (2.0 * u - (width_ - 1)) / (width_ - 1); }

  // Fits to the flow at the pixels with weight > 0 (weights: CV_32F). Robust by IRLS.
  void Fit(const cv::Mat& flow, const cv::Mat& weight) {
    cv::Mat w = weight.clone();
    // Each measured pixel's residual length against its own row model, px (one evaluation of the
    // model per pixel and iteration serves both the scale and the weights).
    std::vector<double> length(static_cast<size_t>(width_) * height_);
    std::vector<float> residuals;
    residuals.reserve(static_cast<size_t>(width_) * height_ / 4);
    for (int it = 0; it <= kIrlsIterations; ++it) {
      FitWeighted(flow, w);
      if (it == kIrlsIterations) break;
      // Residuals against each pixel's own row model; a global robust scale.
      residuals.clear();
      for (int v = 0; v < height_; ++v) {
        if (!valid_[v]) continue;
        const float* wr = weight.ptr<float>(v);
        const cv::Vec2f* fr = flow.ptr<cv::Vec2f>(v);
        double* lr = length.data() + static_cast<size_t>(v) * width_;
        for (int u = 0; u < width_; ++u) {
          if (wr[u] <= 0) continue;
          lr[u] = cv::norm(fr[u] - Eval(u, v));
          residuals.push_back(static_cast<float>(lr[u]));
        }
      }
      if (residuals.empty()) return;
      // |r| of a 2D Gaussian is Rayleigh: median = sigma * sqrt(2 ln 2).
      const double sigma = std::max(1e-3, UpperMedian(residuals) / std::sqrt(2.0 * std::log(2.0)));
      scale_px_ = sigma;
      const double c = kTukeyC * sigma;
      for (int v = 0; v < height_; ++v) {
        const float* wr = weight.ptr<float>(v);
        float* out = w.ptr<float>(v);
        const double* lr = length.data() + static_cast<size_t>(v) * width_;
        for (int u = 0; u < width_; ++u) {
          if (wr[u] <= 0 || !valid_[v]) {
            out[u] = 0;
            continue;
          }
          const double r = lr[u] / c;
          out[u] = r >= 1 ? 0.0f : static_cast<float>(wr[u] * (1 - r * r) * (1 - r * r));
        }
      }
    }
    robust_weight_ = w;
  }

  bool RowValid(int v) const { return valid_[v]; }
  cv::Vec2f Eval(double u, int v) const {
    const double x = Un(u);
    const auto& c = coeff_[v];
    double dx = 0.0, dy = 0.0;  // Horner
    for (int k = kU - 1; k >= 0; --k) {
      dx = dx * x + c[k];
      dy = dy * x + c[kU + k];
    }
    return {static_cast<float>(dx), static_cast<float>(dy)};
  }
  // Final IRLS weights (input weight times Tukey weight).
  const cv::Mat& robust_weight() const { return robust_weight_; }
  double scale_px() const { return scale_px_; }

 private:
  void FitWeighted(const cv::Mat& flow, const cv::Mat& weight) {
    // Per-row moments: S_k = sum w u^k (k = 0..6), T_k = sum w u^k dx, Y_k = sum w u^k dy.
    struct RowMoments {
      std::array<double, 2 * kU - 1> s{};
      std::array<double, kU> tx{}, ty{};
      double count = 0;
      double u_min = 1e9, u_max = -1e9;
    };
    std::vector<RowMoments> rows(height_);
    for (int v = 0; v < height_; ++v) {
      RowMoments& m = rows[v];
      const float* wr = weight.ptr<float>(v);
      const cv::Vec2f* fr = flow.ptr<cv::Vec2f>(v);
      for (int u = 0; u < width_; ++u) {
        const double w = wr[u];
        if (w <= 0) continue;
        const double x = Un(u);
        double p = w;
        for (int k = 0; k < 2 * kU - 1; ++k) {
          m.s[k] += p;
          if (k < kU) {
            m.tx[k] += p * fr[u][0];
            m.ty[k] += p * fr[u][1];
          }
          p *= x;
        }
        m.count += 1;
        m.u_min = std::min(m.u_min, x);
        m.u_max = std::max(m.u_max, x);
      }
    }
    for (int v = 0; v < height_; ++v) {
      Eigen::Matrix<double, kP, kP> a = Eigen::Matrix<double, kP, kP>::Zero();
      Eigen::Matrix<double, kP, 2> b = Eigen::Matrix<double, kP, 2>::Zero();
      double count = 0, u_min = 1e9, u_max = -1e9;
      int rows_used = 0;
      for (int w = std::max(0, v - kBandHalfRows); w <= std::min(height_ - 1, v + kBandHalfRows);
           ++w) {
        const RowMoments& m = rows[w];
        if (m.count == 0) continue;
        ++rows_used;
        count += m.count;
        u_min = std::min(u_min, m.u_min);
        u_max = std::max(u_max, m.u_max);
        const double t = static_cast<double>(w - v) / kBandHalfRows;
        const double psi[kV] = {1.0, t, t * t};
        for (int i = 0; i < kV; ++i) {
          for (int j = 0; j < kV; ++j) {
            const double pij = psi[i] * psi[j];
            for (int k = 0; k < kU; ++k) {
              for (int l = 0; l < kU; ++l) a(i * kU + k, j * kU + l) += pij * m.s[k + l];
            }
          }
          for (int k = 0; k < kU; ++k) {
            b(i * kU + k, 0) += psi[i] * m.tx[k];
            b(i * kU + k, 1) += psi[i] * m.ty[k];
          }
        }
      }
      // Enough pixels, rows and columns for 12 parameters per component.
      valid_[v] = count >= 4 * kP && rows_used >= kV + 2 && u_max - u_min > 0.1;
      if (!valid_[v]) continue;
      // A tiny ridge keeps narrow supports solvable; its bias is far below the noise.
      a.diagonal().array() += 1e-9 * a.diagonal().maxCoeff();
      const Eigen::Matrix<double, kP, 2> x = a.ldlt().solve(b);
      for (int k = 0; k < kU; ++k) {
        coeff_[v][k] = x(k, 0);
        coeff_[v][kU + k] = x(k, 1);
      }
    }
  }

  int width_, height_;
  std::vector<std::array<double, 2 * kU>> coeff_;  // the row's own (dv = 0) coefficients
  std::vector<bool> valid_;
  cv::Mat robust_weight_;
  double scale_px_ = 0.0;
};

// Throws unless both images are usable and of one size.
void CheckImages(const cv::Mat& ref, const cv::Mat& image) {
  SHUTTERLAB_CHECK(!ref.empty() && !image.empty()) << "empty image";
  SHUTTERLAB_CHECK(ref.size() == image.size())
      << "image sizes differ: reference " << ref.cols << "x" << ref.rows << ", image " << image.cols
      << "x" << image.rows;
  for (const cv::Mat* m : {&ref, &image}) {
    SHUTTERLAB_CHECK(m->depth() == CV_8U || m->depth() == CV_16U || m->depth() == CV_32F)
        << "images must be 8-bit, 16-bit or float";
    SHUTTERLAB_CHECK(m->channels() == 1 || m->channels() == 3 || m->channels() == 4)
        << "images must have 1, 3 or 4 channels";
  }
  SHUTTERLAB_CHECK(ref.cols >= kMinMeasuredSidePx && ref.rows >= kMinMeasuredSidePx)
      << "images must be at least " << kMinMeasuredSidePx << "x" << kMinMeasuredSidePx
      << " pixels (got " << ref.cols << "x" << ref.rows << ")";
}

void CheckMask(const cv::Mat& mask, const cv::Mat& image) {
  if (mask.empty()) return;
  SHUTTERLAB_CHECK(mask.type() == CV_8UC1) << "the mask must be one 8-bit channel";
  SHUTTERLAB_CHECK(mask.size() == image.size())
      << "the mask is " << mask.cols << "x" << mask.rows << ", the images " << image.cols << "x"
      << image.rows;
}

// The dense flow image -> reference (*forward) and back (*backward) of the grey images.
void DenseFlow(const cv::Mat& grey_ref, const cv::Mat& grey_img, cv::Mat* forward,
               cv::Mat* backward) {
  cv::Mat ref8, img8;
  grey_ref.convertTo(ref8, CV_8U, 255.0);
  grey_img.convertTo(img8, CV_8U, 255.0);

  // ULTRAFAST (no variational refinement) at full resolution: as accurate after the row model as
  // the slower presets (header), at a third of the time.
  cv::Ptr<cv::DISOpticalFlow> dis =
      cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_ULTRAFAST);
  dis->setFinestScale(0);
  dis->setPatchStride(kPatchStridePx);
  dis->calc(img8, ref8, *forward);
  // The backward flow only checks the round trip to kMaxRoundTripPx: half resolution (finest
  // scale 1, a quarter of the patches) is accurate far below that, at a third of the time.
  dis->setFinestScale(1);
  dis->calc(ref8, img8, *backward);
}

// Validity and a first confidence per pixel (*weight, CV_32F), and the masked pixels (mask 0), the
// black / saturated ones and those whose match is (*never_fill, CV_8U 255): never filled, not even
// in short gaps.
void FirstWeights(const cv::Mat& grey_ref, const cv::Mat& grey_img, const cv::Mat& forward,
                  const cv::Mat& backward, const cv::Mat& mask, cv::Mat* weight,
                  cv::Mat* never_fill) {
  const int width = grey_img.cols, height = grey_img.rows;
  const cv::Mat bad_img = BadMask(grey_img), bad_ref = BadMask(grey_ref);
  const cv::Mat gradient = WeakGradient(grey_img);
  *weight = cv::Mat(height, width, CV_32F, cv::Scalar(0));
  *never_fill = cv::Mat(height, width, CV_8U, cv::Scalar(0));
  for (int v = 0; v < height; ++v) {
    const cv::Vec2f* fw = forward.ptr<cv::Vec2f>(v);
    const uchar* bi = bad_img.ptr<uchar>(v);
    const float* g = gradient.ptr<float>(v);
    float* wr = weight->ptr<float>(v);
    uchar* sat = never_fill->ptr<uchar>(v);
    const uchar* use = mask.empty() ? nullptr : mask.ptr<uchar>(v);
    for (int u = 0; u < width; ++u) {
      if (use != nullptr && use[u] == 0) {
        sat[u] = 255;
        continue;
      }
      if (!std::isfinite(fw[u][0]) || !std::isfinite(fw[u][1])) continue;
      const float qx = u + fw[u][0], qy = v + fw[u][1];
      const int qu = static_cast<int>(std::lround(qx)), qv = static_cast<int>(std::lround(qy));
      const bool inside = qu >= 0 && qv >= 0 && qu < width && qv < height;
      if (bi[u] || !inside || bad_ref.at<uchar>(qv, qu)) {
        sat[u] = 255;
        continue;
      }
      if (g[u] < kMinGradient) continue;
      cv::Vec2f back;
      if (!SampleField(backward, qx, qy, &back)) continue;
      const cv::Vec2f loop = fw[u] + back;
      if (loop.dot(loop) > kMaxRoundTripPx * kMaxRoundTripPx) continue;
      wr[u] = static_cast<float>(std::min(1.0, g[u] / (4 * kMinGradient)));
    }
  }
}

// The model's field and confidence wherever measured (and across short gaps), when `write`;
// result->measured_fraction always.
void FillField(const RowBandModel& model, const cv::Mat& weight, const cv::Mat& robust,
               const cv::Mat& never_fill, bool write, DisplacementMeasurement* result) {
  const int width = weight.cols, height = weight.rows;
  if (write) {
    result->field.create(height, width, CV_32FC2);
    result->field.setTo(cv::Scalar(kNaN, kNaN));
    result->confidence = cv::Mat(height, width, CV_32F, cv::Scalar(0));
  }
  size_t measured = 0;
  for (int v = 0; v < height; ++v) {
    if (!model.RowValid(v)) continue;
    const float* wr = weight.ptr<float>(v);
    const float* rw = robust.ptr<float>(v);
    const uchar* sat = never_fill.ptr<uchar>(v);
    cv::Vec2f* out = write ? result->field.ptr<cv::Vec2f>(v) : nullptr;
    float* conf = write ? result->confidence.ptr<float>(v) : nullptr;
    int last = -1;  // last measured column
    for (int u = 0; u < width; ++u) {
      if (wr[u] <= 0) continue;
      // Bridge a short gap since the last measured pixel (confidence 0.1), skipping black and
      // saturated pixels.
      if (last >= 0 && u - last > 1 && u - last <= kMaxGapPx) {
        for (int g = last + 1; g < u; ++g) {
          if (sat[g]) continue;
          if (write) {
            out[g] = model.Eval(g, v);
            conf[g] = 0.1f;
          }
          ++measured;
        }
      }
      if (write) {
        out[u] = model.Eval(u, v);
        conf[u] = std::max(0.1f, rw[u]);
      }
      ++measured;
      last = u;
    }
  }
  result->measured_fraction = static_cast<double>(measured) / (static_cast<double>(width) * height);
}

// Points: the raw flow on the grid where measured and consistent with the robust model; and the
// noise of the flow about the model (result->points, result->noise_px).
//
// DIS estimates the flow on patches kPatchStridePx apart and blends them; its small bias depends on
// where a pixel lies among the patches. A grid whose step is a multiple of the stride (16 and 4)
// samples every point at the same place among them, and that bias then adds up over the whole
// image instead of averaging out: on a rendered 640x480 clip, a 1 % underestimate of the rotation
// about the optical axis and a time offset 0.11-0.14 ms (10 standard errors) off the truth. So the
// grid point of row j and column k is moved by (j mod stride, k mod stride) px: the points sample
// every place among the patches alike (the same clip: 0.002-0.007 ms, within one standard error).
void GridPoints(const RowBandModel& model, const cv::Mat& forward, const cv::Mat& weight,
                const cv::Mat& robust, int step, DisplacementMeasurement* result) {
  const int width = weight.cols, height = weight.rows;
  double sum_sq = 0.0;
  for (int j = 0; step / 2 + j * step < height; ++j) {
    for (int k = 0; step / 2 + k * step < width; ++k) {
      const int v = step / 2 + j * step + k % kPatchStridePx;
      const int u = step / 2 + k * step + j % kPatchStridePx;
      if (v >= height || u >= width || !model.RowValid(v)) continue;
      if (weight.at<float>(v, u) <= 0 || robust.at<float>(v, u) <= 0) continue;
      const cv::Vec2f d = forward.at<cv::Vec2f>(v, u);
      const cv::Vec2f r = d - model.Eval(u, v);
      sum_sq += r.dot(r);
      result->points.push_back({static_cast<double>(u), static_cast<double>(v), d[0], d[1],
                                static_cast<double>(robust.at<float>(v, u))});
    }
  }
  if (!result->points.empty()) {
    // Degrees of freedom: each band's 2 x 12 parameters are shared by (2h + 1) * width pixels, of
    // which a point is one; the share of a fitted model in one point's residual is that ratio.
    const double band_pixels =
        (2.0 * kBandHalfRows + 1) * width * std::max(0.05, result->measured_fraction);
    const double leverage = std::min(0.5, RowBandModel::kP / band_pixels);
    result->noise_px = std::sqrt(sum_sq / result->points.size() / (1.0 - leverage));
  }
}

}  // namespace

void MeasureOptions::Check() const {
  SHUTTERLAB_CHECK(grid_step_px >= 4 && grid_step_px <= 1024)
      << "grid_step_px must be 4..1024, got " << grid_step_px;
}

DisplacementMeasurement MeasureDisplacement(const cv::Mat& ref, const cv::Mat& image,
                                            const MeasureOptions& options) {
  options.Check();
  CheckImages(ref, image);
  CheckMask(options.mask, image);
  const int width = image.cols, height = image.rows;
  const cv::Mat grey_ref = GreyUnit(ref), grey_img = GreyUnit(image);
  cv::Mat forward, backward;
  DenseFlow(grey_ref, grey_img, &forward, &backward);
  cv::Mat weight, never_fill;
  FirstWeights(grey_ref, grey_img, forward, backward, options.mask, &weight, &never_fill);

  RowBandModel model(width, height);
  model.Fit(forward, weight);
  const cv::Mat& robust = model.robust_weight().empty() ? weight : model.robust_weight();

  DisplacementMeasurement result;
  FillField(model, weight, robust, never_fill, options.dense_field, &result);
  GridPoints(model, forward, weight, robust, options.grid_step_px, &result);
  if (options.dense_field && options.frame_distortion) {
    result.d_px = FrameDistortionPx(result.field);
  }
  if (options.corner_tracks)
    result.tracks = TrackCorners(grey_ref, grey_img, forward, options.mask);
  return result;
}

FieldComparison CompareFields(const cv::Mat& measured, const cv::Mat& truth) {
  SHUTTERLAB_CHECK(measured.type() == CV_32FC2 && truth.type() == CV_32FC2)
      << "displacement fields must be CV_32FC2";
  SHUTTERLAB_CHECK(measured.size() == truth.size()) << "displacement fields differ in size";
  FieldComparison c;
  double sum_sq = 0.0;
  for (int v = 0; v < measured.rows; ++v) {
    const cv::Vec2f* m = measured.ptr<cv::Vec2f>(v);
    const cv::Vec2f* t = truth.ptr<cv::Vec2f>(v);
    for (int u = 0; u < measured.cols; ++u) {
      const cv::Vec2f e = m[u] - t[u];
      const double sq = e.dot(e);
      if (!std::isfinite(sq)) continue;
      sum_sq += sq;
      c.max_px = std::max(c.max_px, std::sqrt(sq));
      ++c.pixels;
    }
  }
  c.rms_px = c.pixels ? std::sqrt(sum_sq / c.pixels) : 0.0;
  return c;
}

std::string MeasureText(const MeasureReport& report) {
  const DisplacementMeasurement& m = report.measurement;
  char line[256];
  std::string text;
  std::snprintf(line, sizeof(line), "frame distortion D  %.3f px", m.d_px);
  text += line;
  if (report.ground_m_per_px) {
    std::snprintf(line, sizeof(line), " = %.4f m on the ground", m.d_px * *report.ground_m_per_px);
    text += line;
  }
  std::snprintf(line, sizeof(line),
                "\nmeasurement noise   %.4f px (over %zu grid points)\n"
                "measured            %.1f %% of pixels\n",
                m.noise_px, m.points.size(), 100.0 * m.measured_fraction);
  text += line;
  if (report.truth) {
    std::snprintf(line, sizeof(line),
                  "against the truth   rms %.4f px, max %.4f px over %zu pixels\n",
                  report.truth->rms_px, report.truth->max_px, report.truth->pixels);
    text += line;
  }
  return text;
}

std::string RowProfileCsv(const DisplacementMeasurement& measurement) {
  const cv::Mat& field = measurement.field;
  const int width = field.cols;
  std::string csv =
      "row,measured_columns,mean_dx,mean_dy,left_dx,left_dy,centre_dx,centre_dy,"
      "right_dx,right_dy\n";
  // Mean of the finite entries of row v in columns [u0, u1); false when there are none.
  auto mean = [&](int v, int u0, int u1, cv::Vec2d* out, int* count) {
    cv::Vec2d sum(0, 0);
    int n = 0;
    const cv::Vec2f* row = field.ptr<cv::Vec2f>(v);
    for (int u = u0; u < u1; ++u) {
      if (!std::isfinite(row[u][0])) continue;
      sum += cv::Vec2d(row[u][0], row[u][1]);
      ++n;
    }
    if (count) *count = n;
    if (n) *out = sum / n;
    return n > 0;
  };
  auto append_pair = [&csv](bool ok, const cv::Vec2d& d) {
    csv += ',';
    if (ok) AppendDouble(d[0], &csv);
    csv += ',';
    if (ok) AppendDouble(d[1], &csv);
  };
  for (int v = 0; v < field.rows; ++v) {
    cv::Vec2d all, left, centre, right;
    int count = 0;
    const bool any = mean(v, 0, width, &all, &count);
    csv += std::to_string(v) + ',' + std::to_string(count);
    append_pair(any, all);
    append_pair(mean(v, 0, width / 5, &left, nullptr), left);
    append_pair(mean(v, 2 * width / 5, 3 * width / 5, &centre, nullptr), centre);
    append_pair(mean(v, 4 * width / 5, width, &right, nullptr), right);
    csv += '\n';
  }
  return csv;
}

void WriteMeasureOutputs(const std::string& dir, const DisplacementMeasurement& measurement) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(IoMessage(dir, 0, "cannot create folder: " + ec.message()));
  WriteFileAtomically(dir + "/rows.csv", RowProfileCsv(measurement));
  WriteImage(dir + "/field.exr", measurement.field, {"dx", "dy"});
  WriteImage(dir + "/heatmap.png", DisplacementHeatmap(measurement.field));
  cv::Mat confidence8;
  measurement.confidence.convertTo(confidence8, CV_8U, 255.0);
  WriteImage(dir + "/confidence.png", confidence8);
}

}  // namespace shutterlab
