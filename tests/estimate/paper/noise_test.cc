#include "estimate/paper/noise.h"

#include "estimate/paper/window_stats.h"
#include "sim/integrate.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace shutterlab {
namespace {

constexpr double kRateHz = 3000.0;
constexpr int64_t kNoisePeriodNs = 333'333;  // 3 kHz, an integer period as a logger would stamp it
// Per-sample rate noise of an MPU-9250 at 3 kHz that gives the paper's ~1.1" window sigma.
constexpr double kNoiseSigmaRadS = 0.0036;

// Still trace: white noise of per-sample std sigma on each axis plus a constant bias, uniform
// times.
GyroTrace StillTrace(double duration_s, double sigma_rad_s, const Eigen::Vector3d& bias_rad_s,
                     uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const size_t n = static_cast<size_t>(std::llround(duration_s * kRateHz));
  std::vector<GyroSample> samples(n);
  for (size_t k = 0; k < n; ++k) {
    samples[k].t_ns = static_cast<int64_t>(k) * kNoisePeriodNs;
    for (int a = 0; a < 3; ++a) samples[k].omega_rad_s[a] = bias_rad_s[a] + sigma_rad_s * unit(rng);
  }
  return GyroTrace(std::move(samples));
}

TEST(AnalyzeNoise, ConstantRateGivesExactWindowStatistics) {
  // Still (zero rate) for the 1 s bias segment, then a constant rate on x only: the angle is a
  // line, so every window of N samples (N-1 intervals) has range w dt (N-1) and sigma w dt
  // sqrt((N^2-1)/12).
  constexpr double kW = 1e-3;
  std::vector<GyroSample> samples;
  for (int64_t k = 0; k < 6000; ++k) {
    const int64_t t_ns = k * kNoisePeriodNs;
    samples.push_back({t_ns, Eigen::Vector3d(t_ns < 1'000'000'000 ? 0.0 : kW, 0.0, 0.0)});
  }
  NoiseOptions options;
  options.window_samples = 120;
  options.bias = {0.0, 1.0};
  const NoiseResult r = AnalyzeNoise(GyroTrace(std::move(samples)), options);
  // 1 s at 333333 ns holds samples 0..3000 (t = 0.999999 s), so 2999 remain after it.
  EXPECT_EQ(r.samples_analysed, 2999u);
  EXPECT_EQ(r.windows, 2999u - 120u + 1u);
  const double step = kW * kNoisePeriodNs * 1e-9 * kArcsecPerRad;
  constexpr double kTol = 1e-9;  // arcsec: rounding of the running angle only
  EXPECT_NEAR(r.axes[0].range_mean_arcsec, step * 119, kTol);
  EXPECT_NEAR(r.axes[0].range_max_arcsec, step * 119, kTol);
  EXPECT_NEAR(r.axes[0].sigma_mean_arcsec, step * std::sqrt((120.0 * 120.0 - 1.0) / 12.0), kTol);
  EXPECT_NEAR(r.axes[0].sigma_max_arcsec, step * std::sqrt((120.0 * 120.0 - 1.0) / 12.0), kTol);
  for (int a = 1; a < 3; ++a) {
    EXPECT_EQ(r.axes[a].range_max_arcsec, 0.0);
    EXPECT_EQ(r.axes[a].sigma_max_arcsec, 0.0);
  }
}

TEST(AnalyzeNoise, WhiteNoiseWindowSigmaAndRangeMatchTheory) {
  // The angle of white rate noise is a random walk with step s = sigma dt. Over N points (N-1
  // steps) its population variance has expectation s^2 (N^2 - 1) / (6N) exactly; the residual bias
  // error db adds a line whose variance is (db dt)^2 (N^2 - 1) / 12. The mean range of an n-step
  // Gaussian walk is s (2 sqrt(2n/pi) + 2 zeta(1/2)/sqrt(2 pi)) + O(n^-1/2) (Comtet & Majumdar
  // 2005).
  constexpr int kN = 120;
  const Eigen::Vector3d true_bias(0.01, -0.02, 0.005);
  const GyroTrace trace = StillTrace(65.0, kNoiseSigmaRadS, true_bias, 42);
  NoiseOptions options;
  options.window_samples = kN;
  const NoiseResult r = AnalyzeNoise(trace, options);
  const double dt = kNoisePeriodNs * 1e-9;
  const double s = kNoiseSigmaRadS * dt * kArcsecPerRad;
  for (int a = 0; a < 3; ++a) {
    const double db = (r.bias.bias_rad_s[a] - true_bias[a]) * dt * kArcsecPerRad;
    const double var = s * s * (kN * kN - 1.0) / (6.0 * kN) + db * db * (kN * kN - 1.0) / 12.0;
    // 180k samples, ~1500 independent windows: the mean square scatters by ~2.5% (1 sigma, seen
    // over 45 seeded runs); 10% is 4 sigma.
    constexpr double kVarTol = 0.10;
    EXPECT_NEAR(r.axes[a].sigma_rms_arcsec * r.axes[a].sigma_rms_arcsec / var, 1.0, kVarTol)
        << "axis " << a;
    EXPECT_LT(r.axes[a].sigma_mean_arcsec, r.axes[a].sigma_rms_arcsec);  // Jensen
    EXPECT_GT(r.axes[a].sigma_max_arcsec, r.axes[a].sigma_rms_arcsec);
    const double zeta_half = -1.4603545088095868;
    const double range =
        s * (2.0 * std::sqrt(2.0 * (kN - 1) / M_PI) + 2.0 * zeta_half / std::sqrt(2 * M_PI));
    constexpr double kRangeTol = 0.05;  // mean range scatters by ~1% (45 seeded runs): 5 sigma
    EXPECT_NEAR(r.axes[a].range_mean_arcsec / range, 1.0, kRangeTol) << "axis " << a;
    // The paper's Table 1 band for an MPU-9250 at ~3 kHz: mean sigma 1.0-1.3", mean range 3.6-4.7".
    EXPECT_GT(r.axes[a].sigma_mean_arcsec, 0.9);
    EXPECT_LT(r.axes[a].sigma_mean_arcsec, 1.3);
    EXPECT_GT(r.axes[a].range_mean_arcsec, 3.6);
    EXPECT_LT(r.axes[a].range_mean_arcsec, 4.7);
    // Allan deviation read on the same samples: N = sigma sqrt(dt).
    constexpr double kArwTol = 0.05;
    EXPECT_NEAR(r.allan.axes[a].arw_rad_s_sqrt_hz / (kNoiseSigmaRadS * std::sqrt(dt)), 1.0,
                kArwTol);
  }
}

TEST(AnalyzeNoise, AgreesWithTheBruteForceWindowTwins) {
  const GyroTrace trace = StillTrace(6.0, kNoiseSigmaRadS, Eigen::Vector3d(0.2, 0.0, -0.1), 8);
  NoiseOptions options;
  options.window_samples = 37;
  const NoiseResult r = AnalyzeNoise(trace, options);
  const BiasEstimate bias = EstimateBias(trace, options.bias);
  const PerAxisAngles angles = IntegratePerAxis(trace, bias.bias_rad_s, bias.first_after);
  std::vector<uint32_t> ends;
  for (size_t k = 0; k + 37 <= angles.size(); ++k) ends.push_back(static_cast<uint32_t>(k + 37));
  ASSERT_EQ(r.windows, ends.size());
  for (int a = 0; a < 3; ++a) {
    const std::vector<double> sigma = SlidingStdDevBruteForce(angles.angle_rad[a], ends);
    const std::vector<double> range = SlidingRangeBruteForce(angles.angle_rad[a], ends);
    double sigma_sum = 0, range_max = 0;
    for (size_t k = 0; k < ends.size(); ++k) {
      sigma_sum += sigma[k];
      range_max = std::max(range_max, range[k]);
    }
    constexpr double kRelTol = 1e-9;  // the O(N) sigma's running sums: ~1e-12 relative
    EXPECT_NEAR(r.axes[a].sigma_mean_arcsec, sigma_sum / ends.size() * kArcsecPerRad,
                kRelTol * r.axes[a].sigma_mean_arcsec);
    EXPECT_DOUBLE_EQ(r.axes[a].range_max_arcsec, range_max * kArcsecPerRad);
  }
}

TEST(AnalyzeNoise, InjectedBiasIsRecoveredAndRemoved) {
  const Eigen::Vector3d true_bias(0.05, -0.3, 0.8);  // rad/s: large, as an uncalibrated MEMS gyro
  const GyroTrace biased = StillTrace(8.0, kNoiseSigmaRadS, true_bias, 5);
  const GyroTrace unbiased = StillTrace(8.0, kNoiseSigmaRadS, Eigen::Vector3d::Zero(), 5);
  NoiseOptions options;
  const NoiseResult rb = AnalyzeNoise(biased, options);
  const NoiseResult ru = AnalyzeNoise(unbiased, options);
  ASSERT_EQ(rb.bias.samples, 15001u);  // 0:5 s at 333333 ns: samples 0..15000 (t = 4.999995 s)
  for (int a = 0; a < 3; ++a) {
    // The mean of 15000 samples has standard error sigma / sqrt(15000); 4 standard errors.
    EXPECT_NEAR(rb.bias.bias_rad_s[a], true_bias[a], 4.0 * kNoiseSigmaRadS / std::sqrt(15000.0));
    EXPECT_NEAR(rb.bias.stderr_rad_s[a], kNoiseSigmaRadS / std::sqrt(15001.0),
                0.05 * kNoiseSigmaRadS / 122.0);
    // Same noise, bias removed: the statistics agree to rounding.
    constexpr double kTol = 1e-9;  // arcsec
    EXPECT_NEAR(rb.axes[a].sigma_mean_arcsec, ru.axes[a].sigma_mean_arcsec, kTol);
    EXPECT_NEAR(rb.axes[a].range_max_arcsec, ru.axes[a].range_max_arcsec, kTol);
  }
}

TEST(AnalyzeNoise, WindowLongerThanTheRestOfTheTraceIsAnError) {
  // 15061 samples: 15001 in 0:5 s, 60 after.
  const GyroTrace trace =
      StillTrace(15061.0 / kRateHz, kNoiseSigmaRadS, Eigen::Vector3d::Zero(), 1);
  ASSERT_EQ(trace.size(), 15061u);
  NoiseOptions options;
  options.window_samples = 61;
  try {
    AnalyzeNoise(trace, options);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("longer than the 60 samples"), std::string::npos)
        << e.what();
  }
  options.window_samples = 60;
  EXPECT_EQ(AnalyzeNoise(trace, options).windows, 1u);
  options.window_samples = 1;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options.window_samples = 120;
  options.bias = {0.0, 0.001};  // 3 samples: too few for a bias
  EXPECT_THROW(AnalyzeNoise(trace, options), std::invalid_argument);
}

TEST(NoiseTable, HasTheWindowStatisticsAndTheAllanCoefficients) {
  const NoiseResult r =
      AnalyzeNoise(StillTrace(6.0, kNoiseSigmaRadS, Eigen::Vector3d::Zero(), 2), {});
  ASSERT_FALSE(r.allan.empty());
  const std::string table = NoiseTable(r);
  EXPECT_NE(table.find("sigma mean"), std::string::npos);
  EXPECT_NE(table.find("ARW"), std::string::npos);
  EXPECT_NE(table.find(FormatNumber("%.2f", r.axes[1].range_max_arcsec)), std::string::npos)
      << table;
}

TEST(NoisePairTable, GainIsEachSensorsNoiseOverTheFusedOnes) {
  NoiseResult first, second, fused;
  for (int a = 0; a < 3; ++a) {
    first.axes[a].sigma_mean_arcsec = 1.0 + a;
    second.axes[a].sigma_mean_arcsec = 2.0 * (1.0 + a);
    fused.axes[a].sigma_mean_arcsec = 0.5 * (1.0 + a);
  }
  const NoisePairGain gain = FusedNoiseGain(first, second, fused);
  for (int a = 0; a < 3; ++a) {
    EXPECT_DOUBLE_EQ(gain.sigma_vs_first[a], 2.0);
    EXPECT_DOUBLE_EQ(gain.sigma_vs_second[a], 4.0);
    EXPECT_EQ(gain.arw_vs_first[a], 0.0);  // no Allan deviations: no ARW gain
  }
  const std::string table = NoisePairTable(first, second, fused);
  EXPECT_NE(table.find("Fused gain"), std::string::npos) << table;
  EXPECT_NE(table.find("  y "), std::string::npos) << table;
  EXPECT_NE(table.find("4.000"), std::string::npos) << table;
}

}  // namespace
}  // namespace shutterlab
