#pragma once
// The source paper's flight analysis (its Table 4): the share of sliding time windows in which the
// camera rotated enough for the rolling shutter to smear the image by more than a ground limit.
//
// Definitions (docs/FORMATS.md `flight`): bias b = per-axis mean rate over the bias segment;
// per-axis angles angle_k = sum over i <= k of (w_i - b)(t_i - t_{i-1}) over the samples after the
// segment (sim/integrate.h IntegratePerAxis); a window of duration W starts at every sample and
// holds the samples with t in [t_k, t_k + W); windows that run past the last sample are left out. A
// window is flagged when the range (max - min) of any axis's angle exceeds
//   threshold = atan(limit_m / altitude_m) + noise allowance.
// The vector criterion flags a window when the rotation angle between any two orientations in it
// (SO(3) trapezoid integration of the same bias-corrected rates) exceeds the same threshold.

#include "estimate/paper/plot_summary.h"
#include "sim/bias.h"
#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

struct FlightOptions {
  double altitude_m = 50.0;                     // camera height above flat ground
  std::vector<double> limits_m{0.05, 0.10};     // acceptable smear on the ground
  std::vector<double> windows_s{0.010, 0.020};  // rolling-shutter readout durations to test
  double noise_allowance_arcsec = 20.0;         // the paper's allowance for the gyro's own noise
  BiasSegment bias;                             // default 0:5 s, as in the paper
  // When set, this bias (rad/s, gyro axes) is used instead of the segment's mean, and every sample
  // is analysed: flight-controller logs are calibrated at arming and rarely hold a still stretch.
  std::optional<Eigen::Vector3d> known_bias_rad_s;
  bool vector_criterion = true;  // also flag by the SO(3) angle (costs ~2x)
  bool series = false;           // fill FlightResult::series for windows_s[0]
  // Fill FlightResult::summary for windows_s[0]: what a plot draws of the series, in bounded
  // memory; its flagged intervals per limit are kept up to this many (0: no cap).
  bool summary = false;
  size_t summary_max_intervals = 4000;
  // The series' exact per-window vector angle too (O(samples x window samples): slow at kHz rates;
  // the per-axis ranges cost nothing extra).
  bool series_vector = true;
  // Called now and then with the fraction done (0..1); may be empty.
  std::function<void(double)> progress;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// A window must be longer than this many sample intervals to hold a range: one no longer than two
// intervals holds one or two samples, and its range says nothing about the motion in it.
inline constexpr double kMinWindowSampleIntervals = 2.0;

// One (limit, window) cell of the paper's Table 4.
struct FlightRow {
  double limit_m = 0;
  double window_s = 0;
  double threshold_arcsec = 0;
  // The window is not longer than kMinWindowSampleIntervals sample intervals: not analysed, its
  // counts are 0 and its shares NaN ("too few samples" in the table and the JSON).
  bool too_few_samples = false;
  size_t windows = 0;                    // windows of this duration
  size_t flagged = 0;                    // per-axis criterion: any axis over the threshold
  std::array<size_t, 3> flagged_axis{};  // that axis over the threshold
  size_t flagged_vector = 0;             // vector criterion (0 when not computed)
  size_t flagged_vector_only = 0;        // vector flags, per-axis does not
  size_t flagged_axis_only = 0;          // per-axis flags, vector does not
  double flagged_percent = 0;
  std::array<double, 3> flagged_percent_axis{};
  double flagged_percent_vector = 0;
};

// Per-window values for plotting, for the windows of windows_s[0] (arcsec).
struct FlightSeries {
  double window_s = 0;
  std::vector<int64_t> t_ns;  // window start, gyro clock
  std::array<std::vector<double>, 3> range_arcsec;
  std::vector<double> vector_arcsec;  // largest pairwise rotation angle; empty without
                                      // the vector criterion or series_vector
};

// What a plot draws of the windows of windows_s[0] (FlightOptions::summary), in memory that does
// not grow with the trace: the series' flagged intervals and a fine histogram of its ranges.
struct FlightWindowSummary {
  double window_s = 0;
  size_t windows = 0;  // 0 when the windows were not analysed (too few samples)
  // Per limit (FlightOptions::limits_m order): FlaggedIntervalsS(series, the limit's threshold),
  // the same intervals, until there are more than summary_max_intervals of them; then the shortest
  // gaps are filled (IntervalUnion::filled_gap says up to which length).
  std::vector<IntervalUnion> flagged;
  // Per axis: the series' ranges, arcsec (range_arcsec), within 0.1 % of their value.
  std::array<LogBinHistogram, 3> range_arcsec;
};

struct FlightResult {
  double altitude_m = 0;
  double noise_allowance_arcsec = 0;
  BiasEstimate bias;
  size_t samples = 0;            // samples analysed (those after the bias segment)
  double sample_interval_s = 0;  // median interval of the analysed samples
  size_t windows_total = 0;      // windows of windows_s[0] (each row has its own count)
  bool vector_criterion = false;
  std::vector<FlightRow> rows;  // limit-major: for each limit, each window (Table 4 order)
  FlightSeries series;
  std::optional<FlightWindowSummary> summary;  // with FlightOptions::summary
  // A too_few_samples warning (docs/FORMATS.md "Warnings") naming the rows the sampling rate could
  // not answer and the shortest window it allows; empty when every row was analysed. Commands add
  // it to the log's warnings.
  std::vector<LogWarning> warnings;
};

// Runs the analysis. Windows too short for the sampling rate are marked
// (FlightRow::too_few_samples), not analysed. Throws std::invalid_argument, saying what to change,
// when the bias segment leaves fewer than 2 samples, or a window is longer than the trace after the
// bias segment (none fits).
FlightResult Flight(const GyroTrace& trace, const FlightOptions& options);

// The same analysis on a trace that arrives in chunks (a log read a block at a time), in memory
// O(bias segment + chunk + longest window) whatever the trace's length; the results are
// bit-identical to Flight's on the whole trace. The windows are swept as soon as they are complete;
// which ones the rate is too low for is known, and said, at Finish.
class FlightStream {
 public:
  // Throws std::invalid_argument for bad options (FlightOptions::Check); progress is not called.
  explicit FlightStream(const FlightOptions& options);
  ~FlightStream();
  FlightStream(const FlightStream&) = delete;
  FlightStream& operator=(const FlightStream&) = delete;
  // The next samples (time order, finite: as a GyroTrace holds them).
  void Add(const GyroSample* samples, size_t count);
  // After the last Add; throws as Flight does.
  FlightResult Finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The person-readable table in the paper's Table 4 layout, with a closing line saying which
// criterion flags more on this data.
std::string FlightTable(const FlightResult& result);
// CSV "t,range_x,range_y,range_z,vector" (seconds, arcsec; vector empty when not computed), written
// whole or not at all.
void WriteFlightSeriesCsv(const std::string& path, const FlightSeries& series);

// The windows of a series that the per-axis criterion flags (any axis's range above
// threshold_arcsec), as time intervals in seconds on the gyro clock: window k covers
// [t_k, t_k + window_s]; overlapping or touching windows are merged, so the intervals are disjoint
// and ascending.
std::vector<std::pair<double, double>> FlaggedIntervalsS(const FlightSeries& series,
                                                         double threshold_arcsec);

}  // namespace shutterlab
