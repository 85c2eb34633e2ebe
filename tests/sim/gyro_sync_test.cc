// Two gyros on two clocks with a known offset, clock rate, mounting, bias and noise, sampled at
// different rates: SyncGyros finds them, within one sample interval of the faster stream and
// within its standard errors; it refuses still or repetitive motion.

#include "sim/gyro_sync.h"

#include "sim/gyro_trace.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// A smooth, broadband motion: per axis 12 sines of random frequency (0.1-6 Hz), phase and
// amplitude (rad/s).
struct Motion {
  std::vector<Eigen::Vector3d> amplitude, frequency, phase;
  explicit Motion(uint64_t seed, double scale = 0.4) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> f(0.1, 6.0), ph(0, 2 * M_PI), amp(0.2, 1.0);
    for (int k = 0; k < 12; ++k) {
      amplitude.push_back(scale * Eigen::Vector3d(amp(rng), amp(rng), amp(rng)) / 3.0);
      frequency.push_back(Eigen::Vector3d(f(rng), f(rng), f(rng)));
      phase.push_back(Eigen::Vector3d(ph(rng), ph(rng), ph(rng)));
    }
  }
  Eigen::Vector3d operator()(double t_s) const {
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < amplitude.size(); ++k) {
      for (int i = 0; i < 3; ++i)
        w[i] += amplitude[k][i] * std::sin(2 * M_PI * frequency[k][i] * t_s + phase[k][i]);
    }
    return w;
  }
};

struct Truth {
  double offset_s = 3.2718;  // t_b = t_a + offset + rate (t_a - t_mid)
  double rate = 0.0;
  double t_mid_s = 0.0;
  Eigen::Matrix3d b_from_a =
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
      Eigen::AngleAxisd(0.05, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  Eigen::Vector3d b_bias{0.01, -0.02, 0.005};
};

// A stream of `motion` sampled every interval_s from t0_s of its own clock for duration_s;
// b_of: b's clock (the truth's mapping and mounting), else a's.
GyroTrace Stream(const std::function<Eigen::Vector3d(double)>& motion, double t0_s,
                 double interval_s, double duration_s, double noise, const Truth* b_of,
                 uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, noise);
  std::vector<GyroSample> samples;
  for (double u = t0_s; u < t0_s + duration_s; u += interval_s) {
    Eigen::Vector3d w;
    if (b_of) {  // the a-time of this b sample: u = t + offset + rate (t - t_mid)
      const double t = (u - b_of->offset_s + b_of->rate * b_of->t_mid_s) / (1 + b_of->rate);
      w = b_of->b_from_a * motion(t) + b_of->b_bias;
    } else {
      w = motion(u);
    }
    samples.push_back({SecondsToNs(u), w + Eigen::Vector3d(n(rng), n(rng), n(rng))});
  }
  return GyroTrace(std::move(samples));
}

double AngleDeg(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle() * 180.0 / M_PI; }

TEST(GyroSync, FindsTheOffsetAndTheMountingWithinASampleOfTheFasterStream) {
  const Motion motion(1);
  Truth truth;
  const GyroTrace a = Stream(motion, 10.0, 1e-3, 40.0, 0.005, nullptr, 11);      // 1 kHz
  const GyroTrace b = Stream(motion, 14.0, 1.0 / 400, 40.0, 0.005, &truth, 12);  // 400 Hz
  const GyroSync sync = SyncGyros(a, b);
  EXPECT_LT(std::abs(sync.offset_s - truth.offset_s), 0.1e-3) << sync.offset_s;
  EXPECT_LT(std::abs(sync.offset_s - truth.offset_s), 3 * sync.offset_stderr_s)
      << sync.offset_s << " +- " << sync.offset_stderr_s;
  EXPECT_FALSE(sync.rate_ppm) << "40 s overlap: no rate";
  EXPECT_TRUE(sync.mounting_fitted);
  EXPECT_LT(AngleDeg(sync.a_from_b * truth.b_from_a), 0.5);
  EXPECT_GT(sync.peak_correlation, 0.9);
  EXPECT_DOUBLE_EQ(sync.faster_interval_s, 1e-3);
  EXPECT_NEAR(sync.residual_rms_rad_s, 0.005 * std::sqrt(1 + 1.0), 0.002);  // both sensors' noise
  // The same the other way round: b's clock = a's - offset.
  const GyroSync back = SyncGyros(b, a);
  EXPECT_LT(std::abs(back.offset_s + truth.offset_s), 0.1e-3) << back.offset_s;
}

TEST(GyroSync, FitsTheClockRateOverALongOverlap) {
  const Motion motion(2);
  Truth truth;
  truth.rate = 80e-6;  // b's clock runs 80 ppm fast
  truth.t_mid_s = 80.0;
  const GyroTrace a = Stream(motion, 20.0, 1.0 / 500, 120.0, 0.004, nullptr, 21);
  const GyroTrace b = Stream(motion, 23.0, 1.0 / 200, 125.0, 0.004, &truth, 22);
  const GyroSync sync = SyncGyros(a, b);
  ASSERT_TRUE(sync.rate_ppm);
  EXPECT_LT(std::abs(*sync.rate_ppm - 80.0), 3 * *sync.rate_stderr_ppm)
      << *sync.rate_ppm << " +- " << *sync.rate_stderr_ppm;
  EXPECT_LT(std::abs(*sync.rate_ppm - 80.0), 5.0);
  // The offset at the fit's own reference time.
  const double true_offset = truth.offset_s + truth.rate * (sync.reference_a_s - truth.t_mid_s);
  EXPECT_LT(std::abs(sync.offset_s - true_offset), 3 * sync.offset_stderr_s)
      << sync.offset_s << " +- " << sync.offset_stderr_s << " against " << true_offset;
}

// The standard error holds: over 20 seeded pairs (800 and 250 Hz, 25 s) the truth lies within 2 of
// them in most (19 of 20 when written, errors 0.2-30 us against standard errors of 12-16 us).
TEST(GyroSync, TheStandardErrorCoversTheTruth) {
  int within = 0;
  std::string report;
  for (int seed = 0; seed < 20; ++seed) {
    const Motion motion(100 + seed);
    Truth truth;
    truth.offset_s = -1.5 + 0.137 * seed;
    const GyroTrace a = Stream(motion, 0.0, 1.0 / 800, 25.0, 0.006, nullptr, 200 + seed);
    const GyroTrace b = Stream(motion, 2.0, 1.0 / 250, 25.0, 0.006, &truth, 300 + seed);
    const GyroSync sync = SyncGyros(a, b);
    within += std::abs(sync.offset_s - truth.offset_s) < 2 * sync.offset_stderr_s;
    // Each well under the faster stream's 1.25 ms interval: sub-sample.
    EXPECT_LT(std::abs(sync.offset_s - truth.offset_s), 0.1e-3) << seed;
    report += std::to_string(1e6 * (sync.offset_s - truth.offset_s)) + " +- " +
              std::to_string(1e6 * sync.offset_stderr_s) + " us\n";
  }
  EXPECT_GE(within, 16) << within << " of 20 within 2 standard errors:\n" << report;
  std::printf("%d of 20 within 2 standard errors; error +- standard error:\n%s", within,
              report.c_str());
}

TEST(GyroSync, RefusesStillOrRepetitiveMotion) {
  const auto still = [](double) { return Eigen::Vector3d::Zero(); };
  Truth truth;
  const GyroTrace a = Stream(still, 0.0, 1e-3, 30.0, 0.005, nullptr, 1);
  const GyroTrace b = Stream(still, 0.0, 1e-3, 30.0, 0.005, &truth, 2);
  try {
    SyncGyros(a, b);
    FAIL() << "aligned noise";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("too weak or too repetitive"), std::string::npos)
        << e.what();
  }
  // One steady swing: every period looks the same.
  const auto swing = [](double t) { return Eigen::Vector3d(0.5 * std::sin(2 * M_PI * t), 0, 0); };
  const GyroTrace sa = Stream(swing, 0.0, 1e-3, 30.0, 0.002, nullptr, 3);
  const GyroTrace sb = Stream(swing, 0.0, 1e-3, 30.0, 0.002, &truth, 4);
  EXPECT_THROW(SyncGyros(sa, sb), std::invalid_argument);
  // Too short to overlap: refused naming the overlap.
  const GyroTrace tiny = Stream(swing, 0.0, 1e-3, 0.05, 0.002, nullptr, 5);
  EXPECT_THROW(SyncGyros(tiny, sb), std::invalid_argument);
}

// What cannot be aligned is said, never answered: a rate that never changes (its correlations are
// rounding's), and traces too short for any lag but the peak's to be searched (with nothing to
// compare, the peak's uniqueness is untested) unless the caller bounds the offset.
TEST(GyroSync, RefusesAConstantRateAndTracesTooShortToTellLagsApart) {
  const auto expect_refusal = [](const GyroTrace& a, const GyroTrace& b, const std::string& words) {
    try {
      const GyroSync sync = SyncGyros(a, b);
      ADD_FAILURE() << "aligned at " << sync.offset_s << " s";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  const auto constant = [](double) { return Eigen::Vector3d(0.001, 0.0, 0.0); };
  const GyroTrace steady = Stream(constant, 0.0, 1e-3, 20.0, 0.0, nullptr, 1);
  expect_refusal(steady, steady, "the rate magnitude of A never changes");
  const auto still = [](double) { return Eigen::Vector3d::Zero(); };
  expect_refusal(Stream(still, 0.0, 1e-3, 20.0, 0.0, nullptr, 1), steady,
                 "the rate magnitude of A never changes");

  // 0.6 s of broadband motion against itself 40 ms later: refused, then found once bounded.
  const Motion motion(7);
  Truth truth;
  truth.offset_s = 0.04;
  truth.b_from_a.setIdentity();
  truth.b_bias.setZero();
  const GyroTrace a = Stream(motion, 0.0, 1e-3, 0.6, 0.0, nullptr, 2);
  const GyroTrace b = Stream(motion, 0.0, 1e-3, 0.6, 0.0, &truth, 3);
  expect_refusal(a, b, "too short to tell their offset");
  // A bound that still leaves offsets 0.5 s from the peak proves nothing either.
  GyroSyncOptions loose;
  loose.max_offset_s = 10.0;
  loose.bound_option = "--max-offset";
  try {
    SyncGyros(a, b, loose);
    ADD_FAILURE() << "aligned under a 10 s bound";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("say so (--max-offset 0.25s)"), std::string::npos)
        << e.what();
  }
  GyroSyncOptions bounded;
  bounded.max_offset_s = 0.2;
  const GyroSync sync = SyncGyros(a, b, bounded);
  EXPECT_NEAR(sync.offset_s, truth.offset_s, 1e-3);
}

// Brute-force twin: each sample the plain mean of the samples within half the window of it.
TEST(BoxAverage, EachSampleIsTheMeanOfItsWindow) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<GyroSample> samples;
  int64_t t_ns = 0;
  for (int i = 0; i < 500; ++i) {
    t_ns += 1'000'000 + static_cast<int64_t>(200'000 * noise(rng));  // about 1 kHz, jittered
    samples.push_back({t_ns, Eigen::Vector3d(noise(rng), noise(rng), std::sin(i * 0.05))});
  }
  const GyroTrace trace(samples);
  const double window_s = 0.0333;
  const GyroTrace averaged = BoxAverage(trace, window_s);
  ASSERT_EQ(averaged.size(), trace.size());
  const int64_t half_ns = SecondsToNs(0.5 * window_s);
  for (size_t i = 0; i < trace.size(); ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int n = 0;
    for (const GyroSample& s : samples) {
      if (std::llabs(s.t_ns - samples[i].t_ns) <= half_ns) sum += s.omega_rad_s, ++n;
    }
    EXPECT_EQ(averaged[i].t_ns, samples[i].t_ns);
    EXPECT_LT((averaged[i].omega_rad_s - sum / n).norm(), 1e-12) << i;
  }
}

}  // namespace
}  // namespace shutterlab
