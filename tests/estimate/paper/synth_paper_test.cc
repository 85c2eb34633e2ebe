// The synthesiser's default traces against the source paper's figures, measured with the paper's
// window statistics (Tables 1 and 4).
#include "estimate/paper/window_stats.h"
#include "sim/bias.h"
#include "sim/integrate.h"
#include "sim/synth/synth.h"
#include "sim/units.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace shutterlab {
namespace {

// Window ends of fixed-count windows (k + n) over m samples.
std::vector<uint32_t> CountWindows(size_t m, size_t n) {
  std::vector<uint32_t> ends;
  for (size_t k = 0; k + n <= m; ++k) ends.push_back(static_cast<uint32_t>(k + n));
  return ends;
}

double Mean(const std::vector<double>& x) {
  double s = 0.0;
  for (double v : x) s += v;
  return s / x.size();
}

TEST(SynthesizedStill, DefaultStillTraceMatchesPaperTable1) {
  constexpr size_t kWindow = 120;
  for (uint64_t seed : {1, 2, 3}) {
    SynthOptions o;
    o.seed = seed;
    o.duration_s = 12.0;  // 5 s bias + 7 s of statistics: ~21000 windows per axis
    const GyroTrace trace = SynthesizeTrace(o);
    const BiasEstimate bias = EstimateBias(trace, BiasSegment{0.0, 5.0});
    const PerAxisAngles angles = IntegratePerAxis(trace, bias.bias_rad_s, bias.first_after);
    const auto ends = CountWindows(angles.size(), kWindow);
    for (int a = 0; a < 3; ++a) {
      const double sigma = Mean(SlidingStdDevBruteForce(angles.angle_rad[a], ends)) * kArcsecPerRad;
      const double range = Mean(SlidingRangeBruteForce(angles.angle_rad[a], ends)) * kArcsecPerRad;
      EXPECT_GE(sigma, 1.0) << "seed " << seed << " axis " << a;
      EXPECT_LE(sigma, 1.3) << "seed " << seed << " axis " << a;
      EXPECT_GE(range, 3.6) << "seed " << seed << " axis " << a;
      EXPECT_LE(range, 4.7) << "seed " << seed << " axis " << a;
    }
  }
}

TEST(SynthesizedFlight, FlightFlagsAPlausibleShareOfWindows) {
  SynthOptions o;
  o.profile = MotionProfile::kFlight;
  o.duration_s = 60.0;
  const Motion motion = MakeMotion(o);
  EXPECT_EQ(motion.OmegaRadS(o.flight.lead_still_s - 0.01), Eigen::Vector3d::Zero());
  EXPECT_GT(motion.OmegaRadS(o.flight.lead_still_s + 5.0).norm(), 0.0);
  const GyroTrace trace = SynthesizeTrace(o);
  const BiasEstimate bias = EstimateBias(trace, BiasSegment{0.0, 5.0});
  const PerAxisAngles angles = IntegratePerAxis(trace, bias.bias_rad_s, bias.first_after);
  const double threshold_rad = std::atan(0.05 / 50.0) + 20.0 / kArcsecPerRad;
  double share[2];
  const double windows_s[2] = {0.010, 0.020};
  for (int w = 0; w < 2; ++w) {
    const auto ends = WindowEndsByDuration(angles.t_ns, SecondsToNs(windows_s[w]));
    std::vector<char> flagged(ends.size(), 0);
    for (int a = 0; a < 3; ++a) {
      const auto range = SlidingRangeBruteForce(angles.angle_rad[a], ends);
      for (size_t k = 0; k < ends.size(); ++k) flagged[k] |= range[k] > threshold_rad;
    }
    share[w] = 100.0 * std::count(flagged.begin(), flagged.end(), 1) / flagged.size();
  }
  EXPECT_GT(share[0], 12.0);
  EXPECT_LT(share[0], 40.0);
  EXPECT_GT(share[1], 35.0);
  EXPECT_LT(share[1], 75.0);
  EXPECT_GT(share[1], share[0]);
}

}  // namespace
}  // namespace shutterlab
