#include "estimate/paper/flight.h"

#include "estimate/paper/window_stats.h"
#include "sim/gyro_source.h"
#include "sim/integrate.h"
#include "sim/logs/gyro_io.h"
#include "sim/so3.h"
#include "sim/units.h"
#include "tests/estimate/paper/paper_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kFlightPeriodNs = 1000000;  // 1 kHz, the paper's logging rate
constexpr double kDtS = 1e-3;
// Bias segment: the first second, still (zero rates, so the bias is exactly zero).
constexpr double kStillS = 1.0;
// Angles summed over a few thousand samples carry ~1e-15 rad of rounding; 1e-9 arcsec is far above
// that and far below anything that matters.
constexpr double kAngleTolArcsec = 1e-9;

// A trace at 1 kHz: still for kStillS, then rate(t_s) for motion_s seconds (t_s from motion start).
GyroTrace MakeTrace(double motion_s, const std::function<Eigen::Vector3d(size_t)>& rate_of_index) {
  std::vector<GyroSample> samples;
  const size_t still = static_cast<size_t>(std::llround(kStillS / kDtS));
  const size_t motion = static_cast<size_t>(std::llround(motion_s / kDtS));
  for (size_t i = 0; i < still + motion; ++i) {
    GyroSample s;
    s.t_ns = 2000000000 + static_cast<int64_t>(i) * kFlightPeriodNs;
    s.omega_rad_s = i < still ? Eigen::Vector3d::Zero() : rate_of_index(i - still);
    samples.push_back(s);
  }
  return GyroTrace(std::move(samples));
}

FlightOptions FlightDefaults() {
  FlightOptions options;
  options.bias = {0.0, kStillS};
  return options;
}

double ThresholdRad(double limit_m, double altitude_m = 50.0, double allowance_arcsec = 20.0) {
  return std::atan(limit_m / altitude_m) + allowance_arcsec / kArcsecPerRad;
}

TEST(Flight, ThresholdMatchesPaper) {
  // 5 cm at 50 m is atan(0.001) = 206.26", plus the 20" allowance.
  const auto trace = MakeTrace(1.0, [](size_t) { return Eigen::Vector3d::Zero(); });
  const FlightResult r = Flight(trace, FlightDefaults());
  ASSERT_EQ(r.rows.size(), 4u);
  EXPECT_NEAR(r.rows[0].threshold_arcsec, 226.2648, 1e-4);
  EXPECT_NEAR(r.rows[2].threshold_arcsec, 432.5291, 1e-4);  // atan(0.002) + 20"
  EXPECT_EQ(r.rows[0].flagged, 0u);
}

// Constant rate w on one axis: a 10 ms window at 1 kHz holds exactly 10 samples ([t_k, t_k + W)
// excludes t_k + W), so its range is w * 9 ms. Just above the threshold every window is flagged,
// just below none.
TEST(Flight, ConstantRateFlagsAllOrNothing) {
  const double threshold = ThresholdRad(0.05);
  for (const double factor : {1.0001, 0.9999}) {
    const double rate = threshold / (9 * kDtS) * factor;
    const auto trace = MakeTrace(2.0, [&](size_t) { return Eigen::Vector3d(0, rate, 0); });
    FlightOptions options = FlightDefaults();
    options.limits_m = {0.05};
    options.windows_s = {0.010};
    options.series = true;
    const FlightResult r = Flight(trace, options);
    ASSERT_EQ(r.rows.size(), 1u);
    // 2000 samples after the segment; windows start where t_k + 10 ms <= t_last.
    EXPECT_EQ(r.windows_total, 2000u - 10u);
    const double expected = factor > 1 ? 100.0 : 0.0;
    EXPECT_EQ(r.rows[0].flagged_percent, expected);
    EXPECT_EQ(r.rows[0].flagged_percent_axis[1], expected);
    EXPECT_EQ(r.rows[0].flagged_percent_axis[0], 0.0);
    EXPECT_EQ(r.rows[0].flagged_percent_vector, expected);
    ASSERT_EQ(r.series.t_ns.size(), r.windows_total);
    for (size_t k = 0; k < r.series.t_ns.size(); k += 97) {
      EXPECT_NEAR(r.series.range_arcsec[1][k], rate * 9 * kDtS * kArcsecPerRad, kAngleTolArcsec);
      EXPECT_NEAR(r.series.vector_arcsec[k], rate * 9 * kDtS * kArcsecPerRad, 1e-6);
    }
  }
}

// Isolated one-sample rate spikes on x: the per-axis angle steps by w dt at the spike sample j, so
// exactly the windows holding both j-1 and j see the step: N-1 windows of N samples per spike. The
// SO(3) trapezoid spreads the spike over the intervals (j-1, j) and (j, j+1), half each: N-2
// windows see the whole step and 2 see half of it. With the step between the two thresholds' and
// half of it below both, the counts are exact.
TEST(Flight, SpikesFlagAKnownShare) {
  const double step = 1.2 * ThresholdRad(0.05);  // above the 5 cm threshold, below 10 cm's
  ASSERT_LT(step, ThresholdRad(0.10));
  const size_t spikes = 37;
  const size_t spacing = 53;  // longer than any window
  const auto trace = MakeTrace(2.0, [&](size_t i) {
    const bool spike = i % spacing == 25 && i / spacing < spikes;
    return Eigen::Vector3d(spike ? step / kDtS : 0.0, 0, 0);
  });
  const FlightResult r = Flight(trace, FlightDefaults());
  const size_t total10 = 2000 - 10, total20 = 2000 - 20;
  ASSERT_EQ(r.rows.size(), 4u);  // 5cm x {10, 20} ms, 10cm x {10, 20} ms
  EXPECT_EQ(r.rows[0].windows, total10);
  EXPECT_EQ(r.rows[1].windows, total20);
  EXPECT_EQ(r.rows[0].flagged, spikes * 9);
  EXPECT_EQ(r.rows[1].flagged, spikes * 19);
  EXPECT_DOUBLE_EQ(r.rows[0].flagged_percent, 100.0 * spikes * 9 / total10);
  EXPECT_EQ(r.rows[0].flagged_vector, spikes * 8);
  EXPECT_EQ(r.rows[1].flagged_vector, spikes * 18);
  EXPECT_EQ(r.rows[0].flagged_axis_only, spikes);
  EXPECT_EQ(r.rows[0].flagged_vector_only, 0u);
  EXPECT_EQ(r.rows[2].flagged, 0u);
  EXPECT_EQ(r.rows[3].flagged_vector, 0u);
}

// Rotation at a constant rate about the diagonal: each axis turns by w W'/sqrt(3), the rotation
// angle is w W' (W' = 9 ms): the vector criterion flags where per-axis does not.
TEST(Flight, DiagonalRotationVectorIsSqrt3TimesPerAxis) {
  const double threshold = ThresholdRad(0.05);
  const double rate = 1.2 * threshold / (9 * kDtS);  // vector 1.2x over, per axis 0.69x
  const Eigen::Vector3d axis = Eigen::Vector3d::Ones().normalized();
  const auto trace = MakeTrace(1.0, [&](size_t) -> Eigen::Vector3d { return rate * axis; });
  FlightOptions options = FlightDefaults();
  options.limits_m = {0.05};
  options.windows_s = {0.010};
  options.series = true;
  const FlightResult r = Flight(trace, options);
  EXPECT_EQ(r.rows[0].flagged_percent, 0.0);
  EXPECT_EQ(r.rows[0].flagged_percent_vector, 100.0);
  EXPECT_EQ(r.rows[0].flagged_vector_only, r.windows_total);
  for (size_t k = 0; k < r.series.t_ns.size(); k += 31) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(r.series.vector_arcsec[k] / r.series.range_arcsec[a][k], std::sqrt(3.0), 1e-9);
    }
  }
}

// Rotation about one axis with a varying rate: the two criteria agree (up to the rectangle-vs-
// trapezoid difference of the two integrations, half a rate change times dt per window).
TEST(Flight, SingleAxisMotionCriteriaAgree) {
  const double amplitude = 0.2;  // rad/s, so windows straddle the thresholds
  const auto trace = MakeTrace(3.0, [&](size_t i) {
    return Eigen::Vector3d(0, 0, amplitude * std::sin(2 * kPi * 1.3 * i * kDtS));
  });
  FlightOptions options = FlightDefaults();
  options.series = true;
  const FlightResult r = Flight(trace, options);
  bool some_flagged = false, some_clear = false;
  for (const FlightRow& row : r.rows) {
    EXPECT_NEAR(row.flagged_percent, row.flagged_percent_vector, 1.0);
    some_flagged |= row.flagged > 0;
    some_clear |= row.flagged < row.windows;
  }
  EXPECT_TRUE(some_flagged && some_clear) << "the signal does not exercise the thresholds";
  // Per window, the angle differs by at most |w_end - w_start| dt / 2 <= amplitude * dt.
  for (size_t k = 0; k < r.series.t_ns.size(); ++k) {
    ASSERT_NEAR(r.series.vector_arcsec[k], r.series.range_arcsec[2][k],
                amplitude * kDtS * kArcsecPerRad);
  }
}

// The still second, then motion_samples of smooth random rates: a random walk, large enough to
// straddle both thresholds.
GyroTrace RandomMotionTrace(size_t motion_samples, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> rates(motion_samples);
  for (auto& r : rates) {
    w = 0.98 * w + 0.02 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    r = w + 0.005 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  }
  return MakeTrace(motion_samples * kDtS, [&](size_t i) { return rates[i]; });
}

// The per-axis results of r (FlightResult of trace with options, the samples from first_analysed
// on analysed, bias 0) against their brute-force twin, SlidingRangeBruteForce of
// IntegratePerAxis over WindowEndsByDuration: each row's windows and counts, any axis and per
// axis, and the series of windows_s[0], window by window.
void ExpectPerAxisMatchesBruteForce(const FlightResult& r, const GyroTrace& trace,
                                    const FlightOptions& options, size_t first_analysed) {
  const auto angles = IntegratePerAxis(trace, Eigen::Vector3d::Zero(), first_analysed);
  for (size_t wi = 0; wi < options.windows_s.size(); ++wi) {
    const auto ends = WindowEndsByDuration(angles.t_ns, SecondsToNs(options.windows_s[wi]));
    std::array<std::vector<double>, 3> range;
    for (int a = 0; a < 3; ++a) range[a] = SlidingRangeBruteForce(angles.angle_rad[a], ends);
    for (size_t l = 0; l < options.limits_m.size(); ++l) {
      const double th = ThresholdRad(options.limits_m[l]);
      size_t any = 0;
      std::array<size_t, 3> per_axis{};
      for (size_t k = 0; k < ends.size(); ++k) {
        any += std::max({range[0][k], range[1][k], range[2][k]}) > th;
        for (int a = 0; a < 3; ++a) per_axis[a] += range[a][k] > th;
      }
      const FlightRow& row = r.rows[l * options.windows_s.size() + wi];
      EXPECT_EQ(row.windows, ends.size());
      EXPECT_EQ(row.flagged, any) << "limit " << l << " window " << wi;
      EXPECT_EQ(row.flagged_axis, per_axis) << "limit " << l << " window " << wi;
      EXPECT_GT(any, 0u) << "the motion does not exercise the thresholds";
      EXPECT_LT(any, ends.size()) << "the motion does not exercise the thresholds";
    }
    if (wi == 0 && options.series) {
      ASSERT_EQ(r.series.t_ns,
                std::vector<int64_t>(angles.t_ns.begin(), angles.t_ns.begin() + ends.size()));
      for (int a = 0; a < 3; ++a) {
        for (size_t k = 0; k < ends.size(); ++k)
          ASSERT_EQ(r.series.range_arcsec[a][k], range[a][k] * kArcsecPerRad) << a << " " << k;
      }
    }
  }
}

// Brute-force twin of everything on a random three-axis motion: per-axis counts and series as
// above; vector counts and series against all-pairs AngularDistance of OrientationTrace.
TEST(Flight, MatchesBruteForceOnRandomMotion) {
  const auto trace = RandomMotionTrace(2500, 42);
  FlightOptions options = FlightDefaults();
  options.series = true;
  const FlightResult r = Flight(trace, options);
  ExpectPerAxisMatchesBruteForce(r, trace, options, 1000);

  const auto t_ns = IntegratePerAxis(trace, Eigen::Vector3d::Zero(), 1000).t_ns;
  std::vector<GyroSample> motion(trace.samples().begin() + 1000, trace.samples().end());
  const OrientationTrace orientation{GyroTrace(motion)};
  const auto& q = orientation.world_from_body();
  for (size_t wi = 0; wi < options.windows_s.size(); ++wi) {
    const auto ends = WindowEndsByDuration(t_ns, SecondsToNs(options.windows_s[wi]));
    std::vector<double> vector(ends.size(), 0.0);
    for (size_t k = 0; k < ends.size(); ++k) {
      for (size_t i = k; i < ends[k]; ++i) {
        for (size_t j = i + 1; j < ends[k]; ++j)
          vector[k] = std::max(vector[k], AngularDistance(q[i], q[j]));
      }
    }
    for (size_t l = 0; l < options.limits_m.size(); ++l) {
      const double th = ThresholdRad(options.limits_m[l]);
      size_t vec = 0;
      for (size_t k = 0; k < ends.size(); ++k) vec += vector[k] > th;
      const FlightRow& row = r.rows[l * options.windows_s.size() + wi];
      EXPECT_EQ(row.flagged_vector, vec) << "limit " << l << " window " << wi;
      EXPECT_GT(vec, 0u);
      EXPECT_LT(vec, ends.size());
    }
    if (wi == 0) {
      ASSERT_EQ(r.series.vector_arcsec.size(), ends.size());
      for (size_t k = 0; k < ends.size(); ++k)
        ASSERT_NEAR(r.series.vector_arcsec[k], vector[k] * kArcsecPerRad, 1e-5) << k;
    }
  }
}

// FlightStream fed trace in chunks of random sizes, 1 sample to several analysis chunks (half of
// them under 10 samples), so that every edge of the integration, the window ends and the
// two-at-a-time counts is crossed.
FlightResult StreamInRandomChunks(const GyroTrace& trace, const FlightOptions& options,
                                  uint64_t seed) {
  std::mt19937_64 rng(seed);
  FlightStream stream(options);
  for (size_t i = 0; i < trace.size();) {
    const size_t n = std::min<size_t>(trace.size() - i, 1 + rng() % (rng() % 2 ? 9 : 5000));
    stream.Add(trace.samples().data() + i, n);
    i += n;
  }
  return stream.Finish();
}

// Brute-force twin of the per-axis criterion alone (no orientations: its own integration loop),
// streamed in chunks of any size; its counts equal the vector run's per-axis counts too.
TEST(Flight, PerAxisAloneMatchesBruteForceInChunksOfAnySize) {
  const auto trace = RandomMotionTrace(9000, 11);
  FlightOptions options = FlightDefaults();
  options.vector_criterion = false;
  options.series = true;
  const FlightResult r = StreamInRandomChunks(trace, options, 11);
  ExpectPerAxisMatchesBruteForce(r, trace, options, 1000);
  FlightOptions with_vector = options;
  with_vector.vector_criterion = true;
  with_vector.series = false;
  const FlightResult v = Flight(trace, with_vector);
  for (size_t row = 0; row < r.rows.size(); ++row) {
    EXPECT_EQ(v.rows[row].flagged, r.rows[row].flagged) << "row " << row;
    EXPECT_EQ(v.rows[row].flagged_axis, r.rows[row].flagged_axis) << "row " << row;
  }
}

// The same twin on the clock of the paper's logger (test::IrregularTimes: +-20 % jitter, repeated
// times, 50 ms pauses) from the end of the still second: window ends that move by 0 to 50 samples
// from one window to the next, and windows across a pause shorter than the range kernel's block.
// Run twice, so that the series (of windows_s[0]) checks both durations' ends window by window.
TEST(Flight, PerAxisMatchesBruteForceOnAnIrregularClock) {
  std::vector<GyroSample> samples = RandomMotionTrace(9000, 23).samples();
  const size_t still = 1000;  // kept regular: the bias segment, sample 1000 the first analysed
  const std::vector<int64_t> times = test::IrregularTimes(samples.size() - still, 23);
  for (size_t i = still; i < samples.size(); ++i)
    samples[i].t_ns = samples[still].t_ns + (times[i - still] - times[0]);
  const GyroTrace trace(std::move(samples));
  ASSERT_GT(trace.sampling().duplicate_timestamps, 10u);
  ASSERT_GT(trace.sampling().gap_indices.size(), 5u);
  for (const std::vector<double>& windows_s :
       {std::vector<double>{0.010, 0.020}, std::vector<double>{0.020, 0.010}}) {
    FlightOptions options = FlightDefaults();
    options.windows_s = windows_s;
    options.vector_criterion = false;
    options.series = true;
    SCOPED_TRACE("windows " + std::to_string(windows_s[0]) + " s first");
    ExpectPerAxisMatchesBruteForce(StreamInRandomChunks(trace, options, 23), trace, options, still);
  }
}

TEST(Flight, BadInputIsRejected) {
  const auto trace = MakeTrace(0.5, [](size_t) { return Eigen::Vector3d::Zero(); });
  FlightOptions options = FlightDefaults();
  options.windows_s = {0.6};  // longer than the 0.5 s after the bias segment
  EXPECT_THROW(Flight(trace, options), std::invalid_argument);
  options = FlightDefaults();
  options.bias = {0.0, 0.005};  // 5 samples: too few for a bias
  EXPECT_THROW(Flight(trace, options), std::invalid_argument);
  options = FlightDefaults();
  options.bias = {0.0, 10.0};  // past the end of the trace: no samples after it
  EXPECT_THROW(Flight(trace, options), std::invalid_argument);
  options = FlightDefaults();
  options.altitude_m = 0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = FlightDefaults();
  options.limits_m.clear();
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

TEST(Flight, TableSaysWhichCriterionFlagsMore) {
  const double rate = 1.2 * ThresholdRad(0.05) / (9 * kDtS);
  const Eigen::Vector3d axis = Eigen::Vector3d::Ones().normalized();
  const auto trace = MakeTrace(1.0, [&](size_t) -> Eigen::Vector3d { return rate * axis; });
  const FlightResult r = Flight(trace, FlightDefaults());
  const std::string table = FlightTable(r);
  EXPECT_NE(table.find("NOT on the safe side"), std::string::npos) << table;
}

}  // namespace
}  // namespace shutterlab

namespace shutterlab {
namespace {

// A known bias replaces the segment: every sample is analysed and the bias is taken off exactly,
// so a constant rate equal to the bias flags nothing.
TEST(Flight, KnownBiasAnalysesEverySample) {
  const Eigen::Vector3d bias(0.3, -0.2, 0.1);  // far above any threshold if left in
  std::vector<GyroSample> samples;
  for (int64_t i = 0; i < 1000; ++i) samples.push_back({i * 1000000, bias});
  FlightOptions options;
  options.known_bias_rad_s = bias;
  options.limits_m = {0.05};
  options.windows_s = {0.010};
  const FlightResult r = Flight(GyroTrace(samples), options);
  EXPECT_EQ(r.samples, 1000u);
  EXPECT_EQ(r.windows_total, 1000u - 10u);
  EXPECT_EQ(r.rows[0].flagged, 0u);
  options.known_bias_rad_s = Eigen::Vector3d::Zero();
  EXPECT_EQ(Flight(GyroTrace(samples), options).rows[0].flagged_percent, 100.0);
}

}  // namespace
}  // namespace shutterlab

namespace shutterlab {
namespace {

// At 50 Hz a 10 ms or 20 ms window holds one sample: its range is 0 whatever the motion, so the
// row is refused, not reported as 0 %; a 100 ms window in the same run is analysed.
TEST(Flight, WindowsNotLongerThanTwoSampleIntervalsAreRefused) {
  std::vector<GyroSample> samples;
  for (int k = 0; k < 500; ++k) {  // 10 s at 50 Hz, turning fast about y
    samples.push_back({static_cast<int64_t>(k) * 20'000'000, Eigen::Vector3d(0, 0.5, 0)});
  }
  FlightOptions options;
  options.windows_s = {0.010, 0.040, 0.100};  // 40 ms = exactly two intervals: refused too
  options.known_bias_rad_s = Eigen::Vector3d::Zero();
  const FlightResult r = Flight(GyroTrace(samples), options);
  EXPECT_DOUBLE_EQ(r.sample_interval_s, 0.020);
  ASSERT_EQ(r.rows.size(), 6u);
  for (const FlightRow& row : r.rows) {
    const bool refused = row.window_s < 0.05;
    EXPECT_EQ(row.too_few_samples, refused) << row.window_s;
    if (refused) {
      EXPECT_EQ(row.windows, 0u);
      EXPECT_TRUE(std::isnan(row.flagged_percent));
    } else {
      EXPECT_GT(row.windows, 0u);
      EXPECT_EQ(row.flagged_percent, 100.0);  // 0.5 rad/s over 80 ms is far over both limits
    }
  }
  EXPECT_EQ(r.windows_total, 0u) << "the first window was refused";
  const std::string table = FlightTable(r);
  EXPECT_NE(table.find("too few samples, those rows were not analysed: at 50 Hz a window must be "
                       "longer than 40 ms (2 sample intervals) to measure a range: give flight "
                       "--window 50ms or longer, or log above 200 Hz for 10 ms windows"),
            std::string::npos)
      << table;
  const std::vector<LogWarning>& warnings = r.warnings;
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].kind, "too_few_samples");
  EXPECT_EQ(warnings[0].count, 4u);
  EXPECT_EQ(warnings[0].message.rfind("windows of 10 ms, 40 ms not analysed", 0), 0u)
      << warnings[0].message;
  FlightOptions long_window = options;
  long_window.windows_s = {0.1};
  EXPECT_TRUE(Flight(GyroTrace(samples), long_window).warnings.empty());
}

// The refusal names a window that works, the shortest 1-2-5 step longer than two sample intervals
// (100 Hz: 20 ms is refused, 50 ms named; 30 Hz: 66.7 ms, 100 ms; 8 kHz: 0.25 ms, 0.5 ms; 0.5 Hz:
// 4 s, 5 s), and the rate that the refused window needs (above 2 / window), in plain numbers;
// that window is then analysed.
TEST(Flight, TooFewSamplesNamesAWindowThatIsAnalysedAndTheRateNeeded) {
  struct Case {
    double rate_hz, refused_s, named_s;
    std::string named, needed;
  };
  for (const Case& c : {Case{100.0, 0.020, 0.050, "50ms", "above 100 Hz for 20 ms"},
                        Case{30.0, 0.060, 0.100, "100ms", "above 33.33 Hz for 60 ms"},
                        Case{1000.0, 0.001, 0.005, "5ms", "above 2000 Hz for 1 ms"},
                        Case{8000.0, 0.0002, 0.0005, "0.5ms", "above 10000 Hz for 0.2 ms"},
                        Case{0.5, 1.0, 5.0, "5s", "above 2 Hz for 1000 ms"}}) {
    std::vector<GyroSample> samples;
    const int n = std::max(200, static_cast<int>(20 * c.rate_hz));  // 20 s, 200 samples at least
    for (int k = 0; k < n; ++k)
      samples.push_back(
          {static_cast<int64_t>(std::llround(k * 1e9 / c.rate_hz)), Eigen::Vector3d(0, 0.5, 0)});
    FlightOptions options;
    options.windows_s = {c.refused_s};
    options.known_bias_rad_s = Eigen::Vector3d::Zero();
    const FlightResult r = Flight(GyroTrace(samples), options);
    ASSERT_EQ(r.warnings.size(), 1u) << c.rate_hz;
    const std::string& message = r.warnings[0].message;
    EXPECT_NE(message.find("give flight --window " + c.named + " or longer, or log " + c.needed +
                           " windows"),
              std::string::npos)
        << c.rate_hz << " Hz: " << message;
    EXPECT_EQ(message.find("e+"), std::string::npos) << message;
    options.windows_s = {c.named_s};
    const FlightResult named_window = Flight(GyroTrace(samples), options);
    EXPECT_TRUE(named_window.warnings.empty()) << c.rate_hz << " Hz, " << c.named;
    EXPECT_FALSE(named_window.rows[0].too_few_samples) << c.rate_hz << " Hz, " << c.named;
  }
}

// A bias segment that leaves nothing to analyse says what to change, without an internal tag.
// The closing line compares the criteria on the rows that were analysed only: at 50 Hz a diagonal
// turn that the vector angle flags in 100 ms windows (sqrt(3) x the per-axis range), beside two
// refused 10 ms and 20 ms windows, is "1 of 2 rows", not "1 of 6".
TEST(Flight, CriteriaLineCountsTheAnalysedRowsOnly) {
  std::vector<GyroSample> samples;
  const double rate = 180.0 / kArcsecPerRad / 0.08;  // 180" per axis over a window's 80 ms
  for (int k = 0; k < 500; ++k)
    samples.push_back({static_cast<int64_t>(k) * 20'000'000, Eigen::Vector3d(rate, rate, rate)});
  FlightOptions options;
  options.windows_s = {0.010, 0.020, 0.100};
  options.known_bias_rad_s = Eigen::Vector3d::Zero();
  const std::string table = FlightTable(Flight(GyroTrace(samples), options));
  EXPECT_NE(table.find("criteria: the vector angle flags more in 1 of 2 rows"), std::string::npos)
      << table;
}

TEST(Flight, TooShortTraceSaysWhatToDo) {
  std::vector<GyroSample> samples;
  for (int k = 0; k < 300; ++k)
    samples.push_back({k * int64_t{1'000'000}, Eigen::Vector3d::Zero()});
  FlightOptions options;  // bias 0:5 s, the trace lasts 0.3 s
  try {
    Flight(GyroTrace(samples), options);
    FAIL() << "no samples after the bias segment";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("--auto-bias"), std::string::npos) << message;
    EXPECT_EQ(message.find("check failed"), std::string::npos) << message;
    EXPECT_EQ(message.find(".cc:"), std::string::npos) << message;
  }
}

TEST(Flight, StreamedOnOneThreadOrTwoGivesTheWholeTracesResult) {
  // A gyro.csv read as `flight` reads it (a block at a time, chunks of a few samples so that the
  // analysis' chunk edges fall anywhere) on one thread, and with the reader a chunk ahead on a
  // second thread (ReadAhead), gives exactly Flight's result on the whole trace.
  const GyroTrace trace = RandomMotionTrace(3000, 7);
  test::TempDir dir;
  const std::string path = dir / "gyro.csv";
  WriteGyroCsv(path, trace);
  FlightOptions options = FlightDefaults();
  options.series = true;
  const FlightResult whole = Flight(ReadGyroCsv(path), options);
  for (bool two_threads : {false, true}) {
    for (size_t chunk : {size_t{7}, size_t{4096}}) {
      std::unique_ptr<GyroSource> source = OpenGyroCsv(TextBlocks::OfFile(path, 1000), path, chunk);
      if (two_threads) source = ReadAhead(std::move(source));
      FlightStream stream(options);
      for (GyroChunk c = source->Next(); !c.empty(); c = source->Next()) stream.Add(c.data, c.size);
      const FlightResult got = stream.Finish();
      test::ExpectSameFlightRows(got, whole);
      EXPECT_GT(whole.rows[0].flagged, 0u);
      for (int a = 0; a < 3; ++a)
        EXPECT_EQ(got.series.range_arcsec[a], whole.series.range_arcsec[a]);
      EXPECT_EQ(got.series.vector_arcsec, whole.series.vector_arcsec);
    }
  }
}

}  // namespace
}  // namespace shutterlab
