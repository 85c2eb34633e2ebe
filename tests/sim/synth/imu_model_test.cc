#include "sim/synth/imu_model.h"

#include "sim/logs/raw_csv.h"
#include "sim/units.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

namespace shutterlab {
namespace {

// Operations on rad/s values of order 1: a few ulps.
constexpr double kRoundingTol = 1e-15;

// Relative tolerance for a sample std from n independent draws: its relative standard error is
// 1/sqrt(2n); four of them make a false failure a ~1e-4 event.
double StdTolerance(size_t n) { return 4.0 / std::sqrt(2.0 * static_cast<double>(n)); }

double SampleStd(const std::vector<double>& x) {
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= x.size();
  double ss = 0.0;
  for (double v : x) ss += (v - mean) * (v - mean);
  return std::sqrt(ss / (x.size() - 1));
}

ImuErrorModel OnlyWhiteNoise(double density) {
  ImuErrorModel m = ImuErrorModel::Ideal();
  m.noise_density_rad_s_sqrt_hz = density;
  return m;
}

TEST(NoiseSource, SameSeedAndStreamRepeat) {
  NoiseSource a(42, 7), b(42, 7), c(42, 8), d(43, 7);
  bool differs_c = false, differs_d = false;
  for (int i = 0; i < 100; ++i) {
    const double x = a.Normal();
    EXPECT_EQ(x, b.Normal());
    differs_c |= x != c.Normal();
    differs_d |= x != d.Normal();
  }
  EXPECT_TRUE(differs_c);
  EXPECT_TRUE(differs_d);
}

TEST(NoiseSource, NormalHasUnitVariance) {
  NoiseSource rng(1, 0);
  constexpr size_t kN = 200000;
  std::vector<double> x(kN);
  double mean = 0.0;
  for (double& v : x) {
    v = rng.Normal();
    mean += v;
  }
  mean /= kN;
  EXPECT_NEAR(mean, 0.0, 4.0 / std::sqrt(kN));  // 4 standard errors of the mean
  EXPECT_NEAR(SampleStd(x), 1.0, StdTolerance(kN));
}

// Integrated white rate noise is a random walk: the angle after T seconds has std density * sqrt(T)
// (the paper's angle random walk). Many independent segments give the std.
TEST(ImuSimulator, IntegratedWhiteNoiseGrowsAsSqrtTime) {
  constexpr double kDensity = 1e-3;  // rad/s/sqrt(Hz)
  constexpr double kRateHz = 500.0;
  constexpr int kSamplesPerSegment = 250;  // T = 0.5 s
  constexpr size_t kSegments = 2000;
  ImuSimulator imu(OnlyWhiteNoise(kDensity), kRateHz, NoiseSource(3, 0));
  std::vector<double> angles[3];
  for (size_t s = 0; s < kSegments; ++s) {
    Eigen::Vector3d angle = Eigen::Vector3d::Zero();
    for (int k = 0; k < kSamplesPerSegment; ++k)
      angle += imu.Measure(Eigen::Vector3d::Zero()) / kRateHz;
    for (int a = 0; a < 3; ++a) angles[a].push_back(angle[a]);
  }
  const double expected = kDensity * std::sqrt(kSamplesPerSegment / kRateHz);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(SampleStd(angles[a]) / expected, 1.0, StdTolerance(kSegments)) << "axis " << a;
  }
}

TEST(ImuSimulator, ConstantBiasScaleAndMisalignmentAreExactWithoutNoise) {
  ImuErrorModel m = ImuErrorModel::Ideal();
  m.bias_rad_s = Eigen::Vector3d(0.01, -0.02, 0.003);
  m.scale_error = Eigen::Vector3d(0.01, -0.005, 0.002);
  m.misalignment_rad << 0.0, 0.002, -0.001, 0.0015, 0.0, 0.0007, -0.0009, 0.0011, 0.0;
  ImuSimulator imu(m, 1000.0, NoiseSource(1, 0));
  const Eigen::Vector3d omega(0.3, -1.2, 2.5);
  Eigen::Matrix3d t;
  t << 1.01, 0.002, -0.001, 0.0015, 0.995, 0.0007, -0.0009, 0.0011, 1.002;
  const Eigen::Vector3d expected = t * omega + m.bias_rad_s;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d measured = imu.Measure(omega);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(measured[a], expected[a], kRoundingTol) << "axis " << a;
  }
  // A perfect sensor passes the rate through bit for bit.
  ImuSimulator ideal(ImuErrorModel::Ideal(), 1000.0, NoiseSource(1, 0));
  EXPECT_EQ(ideal.Measure(omega), omega);
}

TEST(ImuSimulator, QuantisationStepIsOneLsb) {
  for (int range_dps : {250, 500, 1000, 2000}) {
    ImuErrorModel m = ImuErrorModel::Ideal();
    m.range_dps = range_dps;
    m.quantize = true;
    ImuSimulator imu(m, 1000.0, NoiseSource(1, 0));
    const double lsb_per_dps = RawSensitivityLsbPerDps(range_dps);
    const double step_rad_s = kRadPerDeg / lsb_per_dps;
    std::set<double> levels;
    // A slow ramp over a few dozen counts: every output is a whole count, neighbours one count
    // apart.
    for (int i = 0; i <= 1000; ++i) {
      const double rate = (-20.0 + 0.04 * i) * step_rad_s + 1e-3 * step_rad_s;
      const double out = imu.Measure(Eigen::Vector3d(rate, 0, 0))[0];
      const double counts = out / kRadPerDeg * lsb_per_dps;
      EXPECT_NEAR(counts, std::round(counts), 1e-9) << range_dps;
      EXPECT_LE(std::abs(out - rate), 0.5 * step_rad_s * (1 + 1e-9)) << range_dps;  // nearest count
      levels.insert(out);
    }
    ASSERT_GT(levels.size(), 30u);
    double previous = *levels.begin();
    for (auto it = std::next(levels.begin()); it != levels.end(); ++it) {
      EXPECT_NEAR((*it - previous) / step_rad_s, 1.0, 1e-9) << range_dps;
      previous = *it;
    }
  }
}

TEST(ImuSimulator, SaturationClipsAtTheInt16Register) {
  ImuErrorModel m = ImuErrorModel::Ideal();
  m.range_dps = 250;
  m.quantize = true;
  m.saturate = true;
  ImuSimulator imu(m, 1000.0, NoiseSource(1, 0));
  const Eigen::Vector3d out = imu.Measure(Eigen::Vector3d(300.0, -300.0, 100.0) * kRadPerDeg);
  EXPECT_DOUBLE_EQ(out[0], 32767.0 / 131.0 * kRadPerDeg);
  EXPECT_DOUBLE_EQ(out[1], -32768.0 / 131.0 * kRadPerDeg);
  EXPECT_NEAR(out[2], 100.0 * kRadPerDeg, 0.5 / 131.0 * kRadPerDeg);  // in range: only quantised
  EXPECT_EQ(imu.saturated_values(), 2u);

  m.saturate = false;
  m.quantize = false;
  ImuSimulator open(m, 1000.0, NoiseSource(1, 0));
  EXPECT_EQ(open.Measure(Eigen::Vector3d(300.0 * kRadPerDeg, 0, 0))[0], 300.0 * kRadPerDeg);
  EXPECT_EQ(open.saturated_values(), 0u);
}

// The Gauss-Markov bias keeps its stationary std; the rate random walk grows as K * sqrt(T).
TEST(ImuSimulator, DriftingBiasesHaveTheirStatedSize) {
  {
    ImuErrorModel m = ImuErrorModel::Ideal();
    m.bias_instability_rad_s = 0.01;
    m.bias_correlation_s = 0.05;
    constexpr double kRateHz = 200.0;
    constexpr size_t kSamples = 400000;  // 2000 s = 40000 correlation times
    ImuSimulator imu(m, kRateHz, NoiseSource(5, 0));
    std::vector<double> x(kSamples);
    for (double& v : x) v = imu.Measure(Eigen::Vector3d::Zero())[1];
    // Correlated samples: about one independent value per two correlation times.
    const size_t independent = static_cast<size_t>(kSamples / (kRateHz * 2 * m.bias_correlation_s));
    EXPECT_NEAR(SampleStd(x) / m.bias_instability_rad_s, 1.0, StdTolerance(independent));
  }
  {
    ImuErrorModel m = ImuErrorModel::Ideal();
    m.rate_random_walk_rad_s2_sqrt_hz = 0.02;
    constexpr double kRateHz = 100.0;
    constexpr int kSteps = 100;  // T = 1 s
    constexpr size_t kRuns = 1000;
    std::vector<double> finals;
    for (size_t r = 0; r < kRuns; ++r) {
      ImuSimulator imu(m, kRateHz, NoiseSource(6, r));
      Eigen::Vector3d last;
      for (int k = 0; k < kSteps; ++k) last = imu.Measure(Eigen::Vector3d::Zero());
      finals.push_back(last[2]);
    }
    EXPECT_NEAR(SampleStd(finals) / (0.02 * std::sqrt(kSteps / kRateHz)), 1.0, StdTolerance(kRuns));
  }
}

TEST(ImuErrorModel, CheckNamesTheBadField) {
  const auto message = [](const ImuErrorModel& m) -> std::string {
    try {
      m.Check();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message(ImuErrorModel()), "");
  EXPECT_EQ(message(ImuErrorModel::Ideal()), "");
  ImuErrorModel m;
  m.range_dps = 300;
  EXPECT_NE(message(m).find("range"), std::string::npos);
  m = ImuErrorModel();
  m.noise_density_rad_s_sqrt_hz = -1;
  EXPECT_NE(message(m).find("noise density"), std::string::npos);
  m = ImuErrorModel();
  m.misalignment_rad(1, 1) = 0.01;
  EXPECT_NE(message(m).find("misalignment"), std::string::npos);
  m = ImuErrorModel();
  m.gap_period_s = 1.0;
  m.gap_duration_s = 2.0;
  EXPECT_NE(message(m).find("gap duration"), std::string::npos);
}

}  // namespace
}  // namespace shutterlab
