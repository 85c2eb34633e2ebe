#include "estimate/paper/accuracy.h"

#include "sim/so3.h"
#include "sim/units.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kPeriodNs = 333'333;  // 3 kHz
constexpr double kDt = kPeriodNs * 1e-9;
// Per-sample rate noise of an MPU-9250 at 3 kHz (the paper's ~1.1" sigma over 120-sample windows).
constexpr double kSigmaRadS = 0.0036;

// A total-station session: still 5.5 s (bias segment 0:5 s inside it), then turns of turn_deg
// about a fixed unit axis (sensor frame), each a sin^2 rate pulse of kPulseSamples samples,
// separated by still_s; still_s after the last turn, then end. Pulses start on a sample and last an
// integer number of samples, so the rectangle and trapezoid sums over a pulse are exactly the turn
// angle (sum of sin^2(pi j / M) over j = 0..M-1 is M/2): the ground truth is exact.
struct Session {
  std::vector<double> turn_deg;  // one entry per turn (a pulse)
  std::vector<double> still_s;   // still time after each pulse
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double sigma_rad_s = 0.0;
  Eigen::Vector3d bias_rad_s = Eigen::Vector3d(0.01, -0.02, 0.004);
  uint64_t seed = 1;
};
constexpr size_t kPulseSamples = 750;  // 0.25 s

GyroTrace MakeSession(const Session& session) {
  std::mt19937_64 rng(session.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3d> rate(static_cast<size_t>(5.5 / kDt), Eigen::Vector3d::Zero());
  const double pulse_s = kPulseSamples * kDt;
  for (size_t i = 0; i < session.turn_deg.size(); ++i) {
    const double peak = 2.0 * session.turn_deg[i] * kRadPerDeg / pulse_s;  // mean of sin^2 is 1/2
    for (size_t j = 0; j < kPulseSamples; ++j) {
      const double s = std::sin(M_PI * static_cast<double>(j) / kPulseSamples);
      rate.push_back(session.axis * (peak * s * s));
    }
    rate.resize(rate.size() + static_cast<size_t>(session.still_s[i] / kDt),
                Eigen::Vector3d::Zero());
  }
  std::vector<GyroSample> samples(rate.size());
  for (size_t k = 0; k < rate.size(); ++k) {
    samples[k].t_ns = 2'000'000'000 + static_cast<int64_t>(k) * kPeriodNs;
    samples[k].omega_rad_s = rate[k] + session.bias_rad_s;
    if (session.sigma_rad_s > 0) {
      for (int a = 0; a < 3; ++a) samples[k].omega_rad_s[a] += session.sigma_rad_s * unit(rng);
    }
  }
  return GyroTrace(std::move(samples));
}

Session Turns(int n, double turn_deg, const Eigen::Vector3d& axis, double sigma_rad_s) {
  Session s;
  s.turn_deg.assign(n, turn_deg);
  s.still_s.assign(n, 1.5);
  s.axis = axis.normalized();
  s.sigma_rad_s = sigma_rad_s;
  return s;
}

// A total station's vertical axis seen by a sensor mounted 5 degrees off level (azimuth 30 deg).
Eigen::Vector3d TiltedAxis(double tilt_deg) {
  const double t = tilt_deg * kRadPerDeg, az = 30.0 * kRadPerDeg;
  return Eigen::Vector3d(std::sin(t) * std::cos(az), std::sin(t) * std::sin(az), std::cos(t));
}

AccuracyOptions Options() {
  AccuracyOptions options;
  options.reference_deg = 1.0;
  return options;
}

TEST(AnalyzeAccuracy, NoiselessTurnsAreFoundAndMeasuredExactly) {
  const Eigen::Vector3d axis = TiltedAxis(5.0);
  const AccuracyResult r = AnalyzeAccuracy(MakeSession(Turns(4, 1.0, axis, 0.0)), Options());
  ASSERT_EQ(r.rotations.size(), 4u);
  EXPECT_TRUE(r.skipped_t_s.empty());
  for (size_t i = 0; i < 4; ++i) {
    const DetectedRotation& rot = r.rotations[i];
    // Turn i starts at 5.5 + i * (0.25 + 1.5) s; smoothing (+-5 ms) starts the detection a bit
    // early.
    const double start_s = 5.5 + i * (kPulseSamples * kDt + 1.5);
    EXPECT_NEAR(rot.t_start_s, start_s, 0.01);
    EXPECT_NEAR(rot.t_end_s, start_s + 0.25, 0.01);
    constexpr double kZyxTol = 0.5;  // arcsec (the brief); ZYX composition error here is ~0.1"
    EXPECT_NEAR(rot.theta_arcsec, 3600.0, kZyxTol);
    EXPECT_NEAR(rot.difference_arcsec, rot.theta_arcsec - 3600.0, 1e-9);
    constexpr double kExact = 1e-6;  // arcsec: fixed-axis turns integrate exactly, rounding only
    EXPECT_NEAR(rot.theta_vector_arcsec, 3600.0, kExact);
    EXPECT_NEAR(rot.theta_so3_arcsec, 3600.0, kExact);
    // The per-axis angle moved by exactly turn * axis.
    const Eigen::Vector3d d = rot.after_arcsec - rot.before_arcsec;
    EXPECT_LT((d - 3600.0 * axis).norm(), kExact);
  }
  EXPECT_NEAR(r.difference_mean_arcsec, r.rotations[0].difference_arcsec, 1e-9);
}

TEST(AnalyzeAccuracy, PerAxisAnglesAreExactButTheZyxCompositionIsNot) {
  // About a fixed axis n the per-axis angles are exactly phi n (the rotation vector) and the SO(3)
  // angle is phi. R = Rz(phi n_z) Ry(phi n_y) Rx(phi n_x) is not Exp(phi n): by BCH its angle is
  // phi - phi^2 n_x n_y n_z / 2 + O(phi^3), 6" short of 1 deg for n = (1,1,1)/sqrt(3).
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 1, 1).normalized();
  const double phi = 1.0 * kRadPerDeg;
  const AccuracyResult r = AnalyzeAccuracy(MakeSession(Turns(2, 1.0, axis, 0.0)), Options());
  ASSERT_EQ(r.rotations.size(), 2u);
  const double bch_arcsec = (phi - 0.5 * phi * phi * axis.prod()) * kArcsecPerRad;
  for (const DetectedRotation& rot : r.rotations) {
    EXPECT_NEAR(rot.theta_so3_arcsec, 3600.0, 1e-6);
    EXPECT_NEAR(rot.theta_vector_arcsec, 3600.0, 1e-6);
    EXPECT_LT(rot.theta_arcsec, 3600.0 - 5.0);  // a visible error of the paper's method ...
    constexpr double kThirdOrder = 0.2;         // phi^3 terms: ~0.06" at 1 deg
    EXPECT_NEAR(rot.theta_arcsec, bch_arcsec, kThirdOrder);  // ... and the size BCH predicts
  }
  // About a sensor axis the composition is exact.
  const AccuracyResult z =
      AnalyzeAccuracy(MakeSession(Turns(1, 1.0, Eigen::Vector3d::UnitZ(), 0.0)), Options());
  EXPECT_NEAR(z.rotations[0].theta_arcsec, 3600.0, 1e-6);
}

TEST(AnalyzeAccuracy, NoisyTurnsWithin20Arcsec) {
  Session session = Turns(6, 1.0, TiltedAxis(5.0), kSigmaRadS);
  session.seed = 2024;
  const AccuracyResult r = AnalyzeAccuracy(MakeSession(session), Options());
  ASSERT_EQ(r.rotations.size(), 6u);
  // The angle random walk between the two averaging windows (~0.33 s apart plus 2/3 of a window)
  // gives each turn a std of s sqrt(G + 2L/3), s = sigma dt, G ~ 1000 samples, L = 100: ~8".
  for (const DetectedRotation& rot : r.rotations) {
    EXPECT_NEAR(rot.theta_arcsec, 3600.0, 20.0);
    EXPECT_NEAR(rot.theta_so3_arcsec, rot.theta_arcsec, 0.5);  // same samples, tiny turn: ~0.1"
  }
  EXPECT_LT(std::abs(r.difference_mean_arcsec), 20.0);
  EXPECT_GT(r.difference_std_arcsec, 1.0);   // noise is there ...
  EXPECT_LT(r.difference_std_arcsec, 20.0);  // ... at the predicted size
  EXPECT_GT(r.noise_level_rad_s, 1e-4);
}

TEST(AnalyzeAccuracy, CloseMotionsMergeIntoOneTurn) {
  Session session;
  session.turn_deg = {0.5, 0.5, 1.0};
  session.still_s = {0.1, 1.5, 1.5};  // the first two pulses 0.1 s apart
  AccuracyOptions options = Options();
  const AccuracyResult merged = AnalyzeAccuracy(MakeSession(session), options);
  ASSERT_EQ(merged.rotations.size(), 2u);
  EXPECT_NEAR(merged.rotations[0].theta_arcsec, 3600.0, 1e-6);
  options.min_still_s = 0.05;  // now 0.1 s of stillness separates them
  const AccuracyResult split = AnalyzeAccuracy(MakeSession(session), options);
  ASSERT_EQ(split.rotations.size(), 3u);
  EXPECT_NEAR(split.rotations[0].theta_arcsec, 1800.0, 1e-6);
  EXPECT_NEAR(split.rotations[1].theta_arcsec, 1800.0, 1e-6);
}

TEST(AnalyzeAccuracy, TurnWithoutStillTimeAfterItIsSkipped) {
  Session session = Turns(3, 1.0, Eigen::Vector3d::UnitZ(), 0.0);
  session.still_s.back() = 0.03;  // the trace ends 30 ms after the last turn
  const AccuracyResult r = AnalyzeAccuracy(MakeSession(session), Options());
  EXPECT_EQ(r.rotations.size(), 2u);
  ASSERT_EQ(r.skipped_t_s.size(), 1u);
  EXPECT_NEAR(r.skipped_t_s[0], 5.5 + 2 * 1.75, 0.01);
}

TEST(AnalyzeAccuracy, NoRotationIsAClearError) {
  Session session = Turns(0, 1.0, Eigen::Vector3d::UnitZ(), kSigmaRadS);
  session.turn_deg.clear();
  session.still_s.clear();
  try {
    AnalyzeAccuracy(MakeSession(session), Options());
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no rotation found"), std::string::npos) << e.what();
  }
  AccuracyOptions bad = Options();
  bad.reference_deg = 0.0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = Options();
  bad.average_samples = 0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

TEST(AccuracyTable, HasOneRowPerTurnAndTheDifferences) {
  const AccuracyResult r =
      AnalyzeAccuracy(MakeSession(Turns(2, 1.0, TiltedAxis(5.0), 0.0)), Options());
  ASSERT_EQ(r.rotations.size(), 2u);
  const std::string table = AccuracyTable(r);
  EXPECT_NE(table.find("Turns detected: 2"), std::string::npos) << table;
  EXPECT_NE(table.find("difference"), std::string::npos);
}

}  // namespace
}  // namespace shutterlab
