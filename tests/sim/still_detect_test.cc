#include "sim/still_detect.h"

#include "sim/units.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// The brief's requirement for a recovered still segment's ends.
constexpr double kEdgeTolS = 0.050;

struct Synth {
  double rate_hz = 1000.0;
  double duration_s = 12.0;
  Eigen::Vector3d bias_rad_s = Eigen::Vector3d(0.012, -0.02, 0.004);
  double noise_rad_s = 0.002;  // white noise per sample and axis
  double lowpass_alpha =
      1.0;                   // 1: white; < 1: first-order low pass (correlated noise, like a DLPF)
  double count_rad_s = 0.0;  // > 0: quantise to this step (raw counts)
  uint64_t seed = 1;
};

// motion(t_s) is the true body rate; the gyro reads motion + bias + noise.
GyroTrace Make(const Synth& o, const std::function<Eigen::Vector3d(double)>& motion) {
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int64_t period_ns = std::llround(1e9 / o.rate_hz);
  const size_t n = static_cast<size_t>(o.duration_s * o.rate_hz);
  std::vector<GyroSample> samples;
  Eigen::Vector3d filtered = Eigen::Vector3d::Zero();
  // Scale the driving noise so that the filtered noise keeps the std noise_rad_s.
  const double drive = o.noise_rad_s * std::sqrt((2 - o.lowpass_alpha) / o.lowpass_alpha);
  for (size_t k = 0; k < n; ++k) {
    const int64_t t_ns = 1000000000LL + static_cast<int64_t>(k) * period_ns;
    const double t_s = static_cast<double>(k) * period_ns * 1e-9;
    const Eigen::Vector3d white(normal(rng), normal(rng), normal(rng));
    filtered += o.lowpass_alpha * (drive * white - filtered);
    Eigen::Vector3d w = motion(t_s) + o.bias_rad_s + filtered;
    if (o.count_rad_s > 0) w = (w / o.count_rad_s).array().round().matrix() * o.count_rad_s;
    samples.push_back({t_ns, w});
  }
  return GyroTrace(std::move(samples));
}

// Hand-held style motion outside [still_begin, still_end): sinusoids that start at zero rate at
// the still segment's end (the hardest onset to see) and a step into stillness at its start.
std::function<Eigen::Vector3d(double)> MotionOutside(double still_begin, double still_end) {
  return [=](double t) -> Eigen::Vector3d {
    if (t >= still_begin && t < still_end) return Eigen::Vector3d::Zero();
    const double u = t - still_end;
    return Eigen::Vector3d(0.3 * std::sin(2 * kPi * 0.7 * u), 0.2 * std::sin(2 * kPi * 1.3 * u),
                           0.1 + 0.05 * std::sin(2 * kPi * 0.4 * u));
  };
}

void ExpectSegment(const StillSegment& s, double begin_s, double end_s) {
  EXPECT_NEAR(s.segment.begin_s, begin_s, kEdgeTolS);
  EXPECT_NEAR(s.segment.end_s, end_s, kEdgeTolS);
}

TEST(StillDetect, FindsTheStillSegmentWithinFiftyMilliseconds) {
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    Synth o;
    o.seed = seed;
    const GyroTrace trace = Make(o, MotionOutside(2.0, 6.0));
    const StillSegment s = DetectStillSegment(trace);
    ExpectSegment(s, 2.0, 6.0);
    // The reference mean is the bias, to the noise of a 2 s mean (sigma / sqrt(2000) ~ 4.5e-5).
    EXPECT_LE((s.quiet_mean_rad_s - o.bias_rad_s).cwiseAbs().maxCoeff(), 2.5e-4) << seed;
  }
}

// The sums are kept in a ring of a power of two slots, at least every window's span + 1: at spans
// next to a power of two (windows of 127 and 128 samples, stretches of 1023 and 1024), a ring one
// slot short would read a window's first prefix where its last was written.
TEST(StillDetect, SpansNextToAPowerOfTwoFindTheSegment) {
  const Synth o;
  const GyroTrace trace = Make(o, MotionOutside(2.0, 6.0));
  for (const int window : {127, 128}) {
    StillDetectOptions options;
    options.window_s = window * 1e-3;
    options.min_duration_s = (window == 127 ? 1023 : 1024) * 1e-3;
    const StillSegment s = DetectStillSegment(trace, options);
    EXPECT_EQ(s.window_samples, static_cast<size_t>(window));
    ExpectSegment(s, 2.0, 6.0);
  }
}

TEST(StillDetect, StillAtTheStartAsInThePaper) {
  Synth o;
  o.duration_s = 10.0;
  const GyroTrace trace = Make(o, MotionOutside(0.0, 5.0));
  const StillSegment s = DetectStillSegment(trace);
  ExpectSegment(s, 0.0, 5.0);
  EXPECT_EQ(s.first_sample, 0u);
}

TEST(StillDetect, StillAtTheEndRunsToTheLastSample) {
  Synth o;
  o.duration_s = 8.0;
  const GyroTrace trace = Make(o, MotionOutside(5.0, 100.0));
  ExpectSegment(DetectStillSegment(trace), 5.0, 8.0);
}

TEST(StillDetect, CorrelatedAndQuantisedNoise) {
  // A 41 Hz-like low pass at 1 kHz (alpha 0.2) and MPU-9250 counts at +-250 deg/s.
  Synth o;
  o.lowpass_alpha = 0.2;
  o.count_rad_s = kRadPerDeg / 131.0;
  o.noise_rad_s = 0.0015;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    o.seed = seed;
    ExpectSegment(DetectStillSegment(Make(o, MotionOutside(3.0, 7.5))), 3.0, 7.5);
  }
}

TEST(StillDetect, SmallSlowMotionIsNotStill) {
  // A 0.02 rad/s drift (ten times the noise, far below the motion above) breaks the still segment.
  Synth o;
  const GyroTrace trace = Make(o, [](double t) -> Eigen::Vector3d {
    if (t < 2.0) return Eigen::Vector3d(0.5, 0, 0);
    if (t >= 4.0 && t < 4.5) return Eigen::Vector3d(0, 0, 0.02);
    if (t >= 9.0) return Eigen::Vector3d(0, -0.5, 0);
    return Eigen::Vector3d::Zero();
  });
  // Still runs: 2-4 s and 4.5-9 s; the longest is the second.
  ExpectSegment(DetectStillSegment(trace), 4.5, 9.0);
}

TEST(StillDetect, LongestOrFirst) {
  Synth o;
  o.duration_s = 16.0;
  const GyroTrace trace = Make(o, [](double t) -> Eigen::Vector3d {
    const bool still = (t >= 1.0 && t < 3.5) || (t >= 6.0 && t < 11.0);
    return still ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0.2 * std::sin(3 * t) + 0.3, 0.1, 0);
  });
  ExpectSegment(DetectStillSegment(trace), 6.0, 11.0);
  StillDetectOptions first;
  first.first = true;
  ExpectSegment(DetectStillSegment(trace, first), 1.0, 3.5);
  // With a 3 s minimum the first run is too short, and the second qualifies.
  first.min_duration_s = 3.0;
  ExpectSegment(DetectStillSegment(trace, first), 6.0, 11.0);
}

TEST(StillDetect, NoiseFreeTrace) {
  Synth o;
  o.noise_rad_s = 0.0;
  o.duration_s = 6.0;
  ExpectSegment(DetectStillSegment(Make(o, MotionOutside(1.0, 4.0))), 1.0, 4.0);
}

TEST(StillDetect, RejectsTracesWithoutStillness) {
  Synth o;
  o.duration_s = 6.0;
  const GyroTrace moving = Make(o, [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.3 * std::sin(2 * kPi * 0.9 * t), 0.2 * std::cos(2 * kPi * 1.7 * t),
                           0.1 * t);
  });
  EXPECT_THROW(DetectStillSegment(moving), std::invalid_argument);
  // Shorter than the window / than the minimum duration.
  Synth short_trace;
  short_trace.duration_s = 0.05;
  EXPECT_THROW(DetectStillSegment(Make(short_trace, MotionOutside(0, 1))), std::invalid_argument);
  short_trace.duration_s = 1.5;
  EXPECT_THROW(DetectStillSegment(Make(short_trace, MotionOutside(0, 1))), std::invalid_argument);
  StillDetectOptions bad;
  bad.window_s = -1;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = {};
  bad.min_duration_s = 0.01;  // shorter than the window
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

TEST(StillDetect, SegmentFeedsEstimateBias) {
  Synth o;
  const GyroTrace trace = Make(o, MotionOutside(2.0, 6.0));
  const StillSegment s = DetectStillSegment(trace);
  const BiasEstimate bias = EstimateBias(trace, s.segment);
  EXPECT_EQ(bias.samples, s.end_sample - s.first_sample);
  // Four seconds of 0.002 rad/s noise: the mean is within 5 standard errors (~1.6e-4) of the bias.
  EXPECT_LE((bias.bias_rad_s - o.bias_rad_s).cwiseAbs().maxCoeff(), 1.6e-4);
}

// A trace held whole and the same trace streamed in chunks of any size give the same segment, to
// the bit, and the same refusals.
// Samples stamped in threes with one time, every 1 ms (a median interval of 0): the windows are
// sized by the samples' rate (3 kHz), and the still stretch is found, held whole and streamed
// alike (it was refused: "still detection needs increasing timestamps").
TEST(StillDetect, BurstStampedSamplesHaveTheirStillSegment) {
  Synth o;
  o.rate_hz = 3000.0;
  o.duration_s = 10.0;
  const GyroTrace regular = Make(o, MotionOutside(2.0, 6.0));
  std::vector<GyroSample> samples = regular.samples();
  for (size_t k = 0; k < samples.size(); ++k)
    samples[k].t_ns = samples[k - k % 3].t_ns;  // the first of each three's time
  const GyroTrace bursts(std::move(samples));
  ASSERT_EQ(bursts.sampling().median_interval_ns, 0);
  const StillSegment whole = DetectStillSegment(bursts);
  ExpectSegment(whole, 2.0, 6.0);
  const StillSegment streamed = DetectStillSegment([&bursts]() -> std::unique_ptr<GyroSource> {
    return std::make_unique<TraceSource>(bursts, 1000);
  });
  EXPECT_EQ(streamed.segment.begin_s, whole.segment.begin_s);
  EXPECT_EQ(streamed.segment.end_s, whole.segment.end_s);
}

TEST(StillDetectStreamed, EqualsTheWholeTraceAtAwkwardChunkSizes) {
  Synth o;
  o.duration_s = 16.0;
  o.lowpass_alpha = 0.3;
  const GyroTrace longest = Make(o, [](double t) -> Eigen::Vector3d {
    const bool still = (t >= 1.0 && t < 3.5) || (t >= 6.0 && t < 11.0);
    return still ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0.2 * std::sin(3 * t) + 0.3, 0.1, 0);
  });
  Synth at_end;
  at_end.duration_s = 9.0;
  at_end.count_rad_s = 0.001;
  const GyroTrace still_at_end = Make(at_end, MotionOutside(5.0, 100.0));
  StillDetectOptions first;
  first.first = true;
  struct Case {
    const GyroTrace* trace;
    StillDetectOptions options;
  };
  for (const Case& c : {Case{&longest, {}}, Case{&longest, first}, Case{&still_at_end, {}}}) {
    const StillSegment whole = DetectStillSegment(*c.trace, c.options);
    for (const size_t chunk : {size_t{1}, size_t{7}, size_t{999}, size_t{1} << 16}) {
      const StillSegment streamed = DetectStillSegment(
          [&] { return std::make_unique<TraceSource>(*c.trace, chunk); }, c.options);
      EXPECT_EQ(streamed.first_sample, whole.first_sample) << chunk;
      EXPECT_EQ(streamed.end_sample, whole.end_sample) << chunk;
      EXPECT_EQ(streamed.window_samples, whole.window_samples) << chunk;
      EXPECT_EQ(streamed.segment.begin_s, whole.segment.begin_s) << chunk;
      EXPECT_EQ(streamed.segment.end_s, whole.segment.end_s) << chunk;
      EXPECT_EQ(streamed.quiet_mean_rad_s, whole.quiet_mean_rad_s) << chunk;
    }
  }
  // Refusals say the same.
  const GyroTrace moving = Make(at_end, [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.3 * std::sin(2 * kPi * 0.9 * t), 0.2, 0.1 * t);
  });
  std::string whole_error, streamed_error;
  try {
    DetectStillSegment(moving);
  } catch (const std::invalid_argument& e) {
    whole_error = e.what();
  }
  try {
    DetectStillSegment([&] { return std::make_unique<TraceSource>(moving, 13); });
  } catch (const std::invalid_argument& e) {
    streamed_error = e.what();
  }
  EXPECT_FALSE(whole_error.empty());
  EXPECT_EQ(streamed_error, whole_error);
}

}  // namespace
}  // namespace shutterlab
