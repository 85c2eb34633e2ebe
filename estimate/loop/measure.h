#pragma once
// `measure`: the displacement field between a global-shutter reference and a rolling-shutter image
// of the same view (docs/FORMATS.md: d(p) = p_ref - p for every rolling-shutter pixel p).
//
// (Interface fixed first so that validate can be written against it; the method is documented in
// measure.cc with the accuracy it was chosen by.)

#include "estimate/loop/measured_point.h"

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct MeasureOptions {
  // Spacing of the sparse measured points handed to the model fit, px.
  int grid_step_px = 16;
  // Pixels that may be measured (docs/FORMATS.md camera.json `mask`): CV_8U of the image's size,
  // non-zero = may be used; empty: every pixel. A masked pixel is never measured, never a point
  // and never bridged by the row model (its field is NaN).
  cv::Mat mask;
  // Compute the frame distortion D of the field (d_px); video pairs have no use for it.
  bool frame_distortion = true;
  // Fill `field` and `confidence` (and so D); off, they stay empty and only the points, noise_px
  // and measured_fraction are computed (the same numbers): video pairs use nothing else.
  bool dense_field = true;
  // Also track sparse corners (estimate/loop/corner_tracks.h) into `tracks`: what the camera-fixed
  // check trusts where the dense flow may be dragged along (dark, nearly textureless regions).
  bool corner_tracks = false;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// The least measurement noise any fit or test assumes, px: identical images measure exactly 0,
// against which every residual would be infinitely significant.
inline constexpr double kMinNoisePx = 1e-3;

// The smallest image side a measurement takes, px: its matching windows need that much around them.
inline constexpr int kMinMeasuredSidePx = 32;

struct DisplacementMeasurement {
  // Both empty without MeasureOptions::dense_field.
  cv::Mat field;       // CV_32FC2 (dx, dy) per rolling-shutter pixel; NaN where unmeasured
  cv::Mat confidence;  // CV_32F, 0..1, 0 where unmeasured (textureless, saturated, inconsistent)
                       // (0.1 in short gaps that the per-row model bridges, see measure.cc)
  std::vector<MeasuredPoint> points;  // independent measurements on the grid, unmeasured left out
  std::vector<MeasuredPoint> tracks;  // with MeasureOptions::corner_tracks: the corner tracks
  // The measurement's own noise: the RMS length of (measured - true) over `points` as estimated
  // from the data, i.e. the rms_px that a perfect model would leave on these points, px.
  double noise_px = 0.0;
  double d_px = 0.0;               // docs/FORMATS.md frame distortion D of `field`, px
  double measured_fraction = 0.0;  // share of pixels with a measurement
};

// ref and image: same size, 8U/16U/32F, grey or RGB (any channel order). Throws
// std::invalid_argument when the sizes differ (images or mask) or an image is empty.
DisplacementMeasurement MeasureDisplacement(const cv::Mat& ref, const cv::Mat& image,
                                            const MeasureOptions& options = {});

// A measured field against a reference field (e.g. a render's truth/NNNN_disp.exr), over the
// pixels where both are finite: RMS and largest length of the difference, px.
struct FieldComparison {
  double rms_px = 0.0;
  double max_px = 0.0;
  size_t pixels = 0;
};
FieldComparison CompareFields(const cv::Mat& measured, const cv::Mat& truth);

// `shutterlab measure`'s report. ground_m_per_px: altitude_m / f (f = (fx + fy) / 2) when a camera
// is known, for D in metres.
struct MeasureReport {
  DisplacementMeasurement measurement;
  std::optional<double> ground_m_per_px;
  std::optional<FieldComparison> truth;  // with --truth
};
// Its JSON: estimate/report/loop_json.h MeasureToJson.
// Table for a person.
std::string MeasureText(const MeasureReport& report);

// Per-row profile CSV: row,measured_columns,mean_dx,mean_dy,left_dx,left_dy,centre_dx,centre_dy,
// right_dx,right_dy (left / centre / right: the mean over the measured pixels of the first, middle
// and last fifth of the columns; empty where a row has none there), px.
std::string RowProfileCsv(const DisplacementMeasurement& measurement);

// Writes DIR/rows.csv, DIR/field.exr (float32 channels dx, dy; NaN where unmeasured),
// DIR/heatmap.png (|d|) and DIR/confidence.png (8-bit, 255 = confidence 1); each file whole or not
// at all. Creates DIR.
void WriteMeasureOutputs(const std::string& dir, const DisplacementMeasurement& measurement);

}  // namespace shutterlab
