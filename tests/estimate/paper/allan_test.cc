#include "estimate/paper/allan.h"

#include "sim/check.h"
#include "sim/units.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <vector>

namespace shutterlab {
namespace {

// Angle (phase) form of a rate series: theta_0 = 0, theta_{k+1} = theta_k + rate_k * tau0.
std::vector<double> AngleOf(const std::vector<double>& rate, double tau0_s) {
  std::vector<double> angle(rate.size() + 1, 0.0);
  for (size_t i = 0; i < rate.size(); ++i) angle[i + 1] = angle[i] + rate[i] * tau0_s;
  return angle;
}

std::vector<double> WhiteRates(size_t n, double sigma, double mean, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(mean, sigma);
  std::vector<double> rate(n);
  for (double& r : rate) r = noise(rng);
  return rate;
}

// A uniformly sampled trace with independent white noise on each axis plus a constant rate.
GyroTrace WhiteTrace(size_t n, double rate_hz, const Eigen::Vector3d& sigma,
                     const Eigen::Vector3d& constant, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const int64_t period_ns = static_cast<int64_t>(std::llround(1e9 / rate_hz));
  std::vector<GyroSample> samples(n);
  for (size_t k = 0; k < n; ++k) {
    samples[k].t_ns = 1'000'000'000 + static_cast<int64_t>(k) * period_ns;
    for (int a = 0; a < 3; ++a) samples[k].omega_rad_s[a] = constant[a] + sigma[a] * unit(rng);
  }
  return GyroTrace(std::move(samples));
}

// Equivalent degrees of freedom of the overlapping ADEV for white rate noise (Howe, Allan, Barnes
// 1981, "Properties of signal sources and measurement methods", Table 1 / Stable32 manual).
double WhiteNoiseEdf(size_t n_rates, size_t m) {
  const double n = static_cast<double>(n_rates + 1), md = static_cast<double>(m);
  return (3.0 * (n - 1.0) / (2.0 * md) - 2.0 * (n - 2.0) / n) * 4.0 * md * md /
         (4.0 * md * md + 5.0);
}

TEST(AllanClusterSizes, LogSpacedFromOneToATenth) {
  const std::vector<size_t> m = AllanClusterSizes(100000, 10);
  ASSERT_FALSE(m.empty());
  EXPECT_EQ(m.front(), 1u);
  EXPECT_LE(m.back(), 10000u);
  EXPECT_GE(m.back(), 7944u);  // within one log step (10^0.1 = 1.26) of the tenth
  for (size_t i = 1; i < m.size(); ++i) EXPECT_GT(m[i], m[i - 1]);
  // 4 decades at 10 per decade, minus the repeats of the rounding below m = 10
  // (1,1,2,2,3,3,4,5,6,8).
  EXPECT_EQ(m.size(), 38u);
  EXPECT_TRUE(AllanClusterSizes(9, 10).empty());
  EXPECT_EQ(AllanClusterSizes(10, 10), std::vector<size_t>{1});
}

TEST(OverlappingAllanDeviation, MatchesBruteForceTwin) {
  // Short data with a drift and a sine, so every term of the estimator matters.
  std::vector<double> rate = WhiteRates(1500, 0.01, 0.2, 7);
  for (size_t i = 0; i < rate.size(); ++i) rate[i] += 1e-5 * i + 0.02 * std::sin(0.05 * i);
  const double tau0_s = 0.004;
  const std::vector<size_t> m = {1, 2, 3, 5, 17, 100, 333, 750};
  const std::vector<double> fast = OverlappingAllanDeviation(AngleOf(rate, tau0_s), tau0_s, m);
  const std::vector<double> brute = OverlappingAllanDeviationBruteForce(rate, m);
  ASSERT_EQ(fast.size(), m.size());
  constexpr double kRelTol = 1e-9;  // the angle form cancels large cumulative sums: ~1e-12 seen
  for (size_t i = 0; i < m.size(); ++i) {
    EXPECT_NEAR(fast[i], brute[i], kRelTol * brute[i]) << "m = " << m[i];
  }
}

TEST(OverlappingAllanDeviation, RejectsClusterLongerThanHalfTheRecord) {
  const std::vector<double> angle(11, 0.0);  // 10 rates
  EXPECT_NO_THROW(OverlappingAllanDeviation(angle, 0.01, {5}));
  EXPECT_THROW(OverlappingAllanDeviation(angle, 0.01, {6}), std::invalid_argument);
  EXPECT_THROW(OverlappingAllanDeviation(angle, 0.0, {1}), std::invalid_argument);
}

TEST(OverlappingAllanDeviation, WhiteNoiseIsSigmaOverSqrtTau) {
  constexpr size_t kRates = 200000;
  constexpr double kSigma = 0.005, kTau0 = 1e-3;
  const std::vector<double> rate = WhiteRates(kRates, kSigma, 0.0, 11);
  const std::vector<size_t> m = AllanClusterSizes(kRates, 5);
  const std::vector<double> adev = OverlappingAllanDeviation(AngleOf(rate, kTau0), kTau0, m);
  for (size_t i = 0; i < m.size(); ++i) {
    const double expected = kSigma / std::sqrt(static_cast<double>(m[i]));
    // chi-square with EDF degrees of freedom: relative std of the deviation ~ 1/sqrt(2 EDF); 4
    // sigma.
    const double tolerance = 4.0 / std::sqrt(2.0 * WhiteNoiseEdf(kRates, m[i]));
    EXPECT_NEAR(adev[i] / expected, 1.0, tolerance) << "m = " << m[i];
  }
}

TEST(AllanAnalysis, ConstantRateGivesZero) {
  const GyroTrace trace =
      WhiteTrace(5000, 1000.0, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.3, -1.7, 12.5), 1);
  const AllanResult result = AllanAnalysis(trace);
  ASSERT_FALSE(result.empty());
  constexpr double kZero = 1e-12;  // rad/s: rounding of the mean only
  for (int a = 0; a < 3; ++a) {
    for (double v : result.adev_rad_s[a]) EXPECT_LE(v, kZero);
    EXPECT_LE(result.axes[a].arw_rad_s_sqrt_hz, kZero);
  }
}

TEST(AllanAnalysis, WhiteNoiseGivesArwAndUnaffectedByBias) {
  constexpr double kRateHz = 2000.0;
  const Eigen::Vector3d sigma(0.002, 0.004, 0.008);
  const GyroTrace still = WhiteTrace(100000, kRateHz, sigma, Eigen::Vector3d::Zero(), 3);
  const GyroTrace biased = WhiteTrace(100000, kRateHz, sigma, Eigen::Vector3d(0.1, -0.2, 0.05), 3);
  const AllanResult a = AllanAnalysis(still);
  const AllanResult b = AllanAnalysis(biased);
  ASSERT_FALSE(a.empty());
  EXPECT_NEAR(a.tau0_s, 1.0 / kRateHz, 1e-12);
  EXPECT_NEAR(a.tau_s.front(), 1.0 / kRateHz, 1e-12);
  EXPECT_LE(a.tau_s.back(), 0.1 * 100000 / kRateHz + 1e-9);
  for (int axis = 0; axis < 3; ++axis) {
    // White rate noise of per-sample std sigma: N = sigma * sqrt(tau0) (rad/s/sqrt(Hz)).
    const double n_expected = sigma[axis] * std::sqrt(1.0 / kRateHz);
    constexpr double kArwTol = 0.03;  // the fit leans on short taus with ~1e5 clusters: <1% seen
    EXPECT_NEAR(a.axes[axis].arw_rad_s_sqrt_hz / n_expected, 1.0, kArwTol);
    EXPECT_NEAR(a.axes[axis].arw_deg_sqrt_h, a.axes[axis].arw_rad_s_sqrt_hz * kDegPerRad * 60.0,
                1e-12);
    // White noise only: the minimum is on the -1/2 line (within its scatter), not a floor.
    EXPECT_TRUE(a.axes[axis].bias_instability_upper_bound);
    EXPECT_GT(a.axes[axis].bias_instability_tau_s, 0.1 * a.tau_s.back());
    for (size_t i = 0; i < a.tau_s.size(); ++i) {
      constexpr double kBiasInvariance = 1e-9;  // relative: only rounding differs
      EXPECT_NEAR(b.adev_rad_s[axis][i], a.adev_rad_s[axis][i],
                  kBiasInvariance * a.adev_rad_s[axis][i]);
    }
  }
}

TEST(ReadAllanCoefficients, RecoversArwAndBiasInstabilityFromAnalyticCurve) {
  // sigma^2(tau) = N^2/tau + (0.664 B)^2 + K^2 tau / 3 (IEEE 952 C.1-C.3 terms), log-spaced tau.
  const double n_arw = 1e-4;    // rad/sqrt(s)
  const double b_rad_s = 2e-5;  // bias instability, rad/s
  const double k_rrw = 1e-8;    // rate random walk, rad/s^1.5: tiny, so the floor is flat
  std::vector<double> tau, adev;
  for (int j = -30; j <= 50; ++j) {
    const double t = std::pow(10.0, j / 10.0);
    tau.push_back(t);
    adev.push_back(
        std::sqrt(n_arw * n_arw / t + std::pow(0.664 * b_rad_s, 2) + k_rrw * k_rrw * t / 3));
  }
  const AllanCoefficients c = ReadAllanCoefficients(tau, adev);
  constexpr double kArwTol =
      0.02;  // the floor term bends the -1/2 region by < 2% where slope ~ -1/2
  EXPECT_NEAR(c.arw_rad_s_sqrt_hz / n_arw, 1.0, kArwTol);
  constexpr double kBiTol = 0.02;  // the minimum sits on the floor plus a little N and K
  EXPECT_NEAR(c.bias_instability_deg_h / (b_rad_s * kDegPerRad * 3600.0), 1.0, kBiTol);
  EXPECT_FALSE(c.bias_instability_upper_bound);
  EXPECT_GT(c.bias_instability_tau_s, 1.0);
  EXPECT_LT(c.bias_instability_tau_s, 1e5);
}

TEST(ReadAllanCoefficients, MinimumOnTheWhiteLineIsOnlyAnUpperBound) {
  // Pure white noise up to a tenth of a 1000 s record: the minimum is the last point, on the line.
  std::vector<double> tau, white, floored;
  for (int j = -30; j <= 20; ++j) {
    const double t = std::pow(10.0, j / 10.0);
    tau.push_back(t);
    white.push_back(1e-4 / std::sqrt(t));
    // A floor (0.664 B = 3e-5) and rate random walk make a minimum well above the white line.
    floored.push_back(std::sqrt(1e-8 / t + 9e-10 + 1e-11 * t));
  }
  EXPECT_TRUE(ReadAllanCoefficients(tau, white, 1000.0).bias_instability_upper_bound);
  const AllanCoefficients c = ReadAllanCoefficients(tau, floored, 1000.0);
  EXPECT_FALSE(c.bias_instability_upper_bound);
  EXPECT_LT(c.bias_instability_tau_s, tau.back());
}

TEST(AllanCsv, HeaderAndOneLinePerTau) {
  AllanResult r;
  r.tau_s = {0.5, 1.0};
  for (int a = 0; a < 3; ++a) r.adev_rad_s[a] = {1.0 + a, 0.25 * (a + 1)};
  EXPECT_EQ(AllanCsv(r), "tau_s,adev_x,adev_y,adev_z\n0.5,1,2,3\n1,0.25,0.5,0.75\n");
}

// AllanStream against AllanAnalysis on the segment held whole: the same taus; the exact clusters
// equal to the bit; the longer ones, from every s-th term, within a small part of the estimate's
// own scatter; the same coefficients within that. White noise, a random walk and a slow swing,
// with jittered intervals and a logging gap (each sample's own interval enters the angle).
TEST(AllanStream, EqualsAllanAnalysisOnTheWholeSegment) {
  std::mt19937_64 rng(21);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int64_t> jitter(-20'000, 20'000);
  const size_t n = 40000;
  std::vector<GyroSample> samples(n);
  Eigen::Vector3d walk(0.01, -0.02, 0.005);
  for (size_t k = 0; k < n; ++k) {
    samples[k].t_ns = 5'000'000'000 + static_cast<int64_t>(k) * 1'000'000 + jitter(rng) +
                      (k >= 30000 ? 40'000'000 : 0);
    for (int a = 0; a < 3; ++a) walk[a] += 2e-5 * unit(rng);
    samples[k].omega_rad_s = walk + 0.003 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) +
                             Eigen::Vector3d(0.002 * std::sin(k * 1e-3), 0.0, 0.0);
  }
  const GyroTrace trace(samples);
  const AllanResult whole = AllanAnalysis(trace);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();  // AllanAnalysis's: the rates after the first
  for (size_t k = 1; k < n; ++k) mean += trace[k].omega_rad_s;
  mean /= static_cast<double>(n - 1);
  AllanStream stream(n, trace.sampling().median_interval_ns, mean);
  for (const GyroSample& s : trace.samples()) stream.Add(s);
  const AllanResult streamed = stream.Finish();
  ASSERT_EQ(streamed.tau_s, whole.tau_s);
  EXPECT_EQ(streamed.tau0_s, whole.tau0_s);
  size_t sparse = 0;
  double worst = 0.0;
  for (size_t i = 0; i < whole.tau_s.size(); ++i) {
    const size_t m = static_cast<size_t>(std::llround(whole.tau_s[i] / whole.tau0_s));
    for (int a = 0; a < 3; ++a) {
      const double w = whole.adev_rad_s[a][i], s = streamed.adev_rad_s[a][i];
      if (m <= kAllanExactClusterMax) {
        ASSERT_EQ(s, w) << "m " << m << " axis " << a;
      } else {
        worst = std::max(worst, std::abs(s / w - 1.0));
        // The overlapping estimate's own relative scatter at this m is ~ 1 / sqrt(n / m).
        EXPECT_NEAR(s / w, 1.0, 0.1 * std::sqrt(static_cast<double>(m) / n)) << "m " << m;
      }
    }
    sparse += m > kAllanExactClusterMax;
  }
  EXPECT_GE(sparse, 5u);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(streamed.axes[a].arw_deg_sqrt_h, whole.axes[a].arw_deg_sqrt_h,
                1e-3 * whole.axes[a].arw_deg_sqrt_h);
    EXPECT_NEAR(streamed.axes[a].bias_instability_deg_h, whole.axes[a].bias_instability_deg_h,
                0.02 * whole.axes[a].bias_instability_deg_h);
  }
  std::cout << "AllanStream: " << sparse << " sparse taus, largest relative difference " << worst
            << "\n";
  // Fewer or more samples than announced is a caller's error; too short a segment is empty.
  AllanStream short_of_one(n, trace.sampling().median_interval_ns, mean);
  for (size_t k = 0; k + 1 < n; ++k) short_of_one.Add(trace[k]);
  EXPECT_THROW(short_of_one.Finish(), std::invalid_argument);
  AllanStream tiny(5, 1'000'000, mean);
  for (size_t k = 0; k < 5; ++k) tiny.Add(trace[k]);
  EXPECT_TRUE(tiny.Finish().empty());
}

}  // namespace
}  // namespace shutterlab
