#pragma once
// The source paper's static-noise analysis (its Tables 1-2): sliding-window sigma and range of the
// per-axis integrated angle of a still gyro, plus the Allan deviation of the same samples.

#include "estimate/paper/allan.h"
#include "sim/bias.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <cstddef>
#include <string>

namespace shutterlab {

struct NoiseOptions {
  int window_samples = 120;  // N: consecutive samples per window (the paper: 120 at ~3 kHz = 40 ms)
  // When above 0, the window is this long instead: N = round(window_s x the trace's rate).
  double window_s = 0.0;
  BiasSegment bias;        // seconds after the first sample; default 0:5 (docs/FORMATS.md)
  bool zero_bias = false;  // the rates are bias-free (calibrated): no segment, every sample
  int allan_points_per_decade = 10;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Statistics of one axis over all windows, arcsec.
struct AxisNoise {
  double sigma_mean_arcsec = 0.0;  // mean over windows of the window's population std
  double sigma_max_arcsec = 0.0;
  double sigma_rms_arcsec = 0.0;  // sqrt(mean of sigma^2): has an exact expectation for white noise
  double range_mean_arcsec = 0.0;  // mean over windows of max - min
  double range_max_arcsec = 0.0;
};

struct NoiseResult {
  int window_samples = 0;
  size_t windows = 0;           // windows per axis: samples_analysed - window_samples + 1
  size_t samples_analysed = 0;  // samples after the bias segment's end
  double rate_hz = 0.0;         // the trace's median sample rate
  BiasEstimate bias;  // per-axis mean over the bias segment, subtracted before integrating
  AxisNoise axes[3];  // x, y, z (gyro axes)
  AllanResult allan;  // over the same samples
};

// docs/FORMATS.md "Analysis outputs" / noise: bias = per-axis mean rate over the bias segment; the
// per-axis angles (sim/integrate.h IntegratePerAxis) of the samples after the segment's end;
// sliding windows of window_samples consecutive samples, step one sample. Throws
// std::invalid_argument when the bias segment is too short or the window is longer than the samples
// after it. Its JSON is written at the edge (estimate/report/analysis_json.h NoiseToJson).
NoiseResult AnalyzeNoise(const GyroTrace& trace, const NoiseOptions& options);

// A table for a person in the paper's layout: one row per axis; sigma mean/max, range mean/max
// (arcsec); then ARW and bias instability from the Allan deviation.
std::string NoiseTable(const NoiseResult& result);

// Two sensors and their fusion (sim/sensor_pair.h): per axis the window sigma mean and the white
// noise (ARW) of each and of the fused trace, and the fused gain over each: sigma of the sensor /
// sigma of the fused trace (about sqrt(2) for two equal independent sensors).
struct NoisePairGain {
  double sigma_vs_first[3] = {0, 0, 0}, sigma_vs_second[3] = {0, 0, 0};
  double arw_vs_first[3] = {0, 0, 0}, arw_vs_second[3] = {0, 0, 0};  // 0 without Allan deviations
};
NoisePairGain FusedNoiseGain(const NoiseResult& first, const NoiseResult& second,
                             const NoiseResult& fused);
std::string NoisePairTable(const NoiseResult& first, const NoiseResult& second,
                           const NoiseResult& fused);

}  // namespace shutterlab
