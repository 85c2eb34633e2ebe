#include "estimate/paper/noise.h"

#include "estimate/paper/window_stats.h"
#include "sim/check.h"
#include "sim/gyro_trace.h"
#include "sim/integrate.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace shutterlab {
namespace {}  // namespace

void NoiseOptions::Check() const {
  SHUTTERLAB_CHECK(window_samples >= 2)
      << "window must hold at least 2 samples (got " << window_samples << ")";
  SHUTTERLAB_CHECK(window_s >= 0.0 && window_s < 1e6)
      << "window of " << window_s << " s must be 0 (counted in samples) or positive";
  SHUTTERLAB_CHECK(bias.begin_s >= 0.0 && bias.end_s > bias.begin_s)
      << "bias segment " << bias.begin_s << ":" << bias.end_s << " must satisfy 0 <= A < B";
  SHUTTERLAB_CHECK(allan_points_per_decade >= 1 && allan_points_per_decade <= 100)
      << "Allan points per decade must be in 1..100 (got " << allan_points_per_decade << ")";
}

NoiseResult AnalyzeNoise(const GyroTrace& trace, const NoiseOptions& options) {
  options.Check();
  NoiseResult result;
  result.bias = options.zero_bias ? BiasEstimate() : EstimateBias(trace, options.bias);
  result.rate_hz = trace.sampling().RateHz();
  result.window_samples = options.window_samples;
  if (options.window_s > 0.0) {
    const double n = std::round(options.window_s * result.rate_hz);
    SHUTTERLAB_CHECK(n >= 2) << "a window of " << QuantityText(options.window_s * 1e3, "ms")
                             << " holds " << n << " sample(s) at " << result.rate_hz
                             << " Hz: give a window of at least 2 sample intervals";
    SHUTTERLAB_CHECK(n < 1e9) << "a window of " << QuantityText(options.window_s * 1e3, "ms")
                              << " is longer than any trace";
    result.window_samples = static_cast<int>(n);
  }
  const size_t first = result.bias.first_after;
  result.samples_analysed = trace.size() - first;
  const size_t n_window = static_cast<size_t>(result.window_samples);
  SHUTTERLAB_CHECK(result.samples_analysed >= n_window || options.zero_bias)
      << "window of " << n_window << " samples is longer than the " << result.samples_analysed
      << " samples after the bias segment (" << options.bias.begin_s << ":" << options.bias.end_s
      << " s; the trace lasts " << trace.DurationS()
      << " s): give an earlier --bias A:B, a shorter --window, or a longer log";
  SHUTTERLAB_CHECK(result.samples_analysed >= n_window)
      << "window of " << n_window << " samples is longer than the trace's "
      << result.samples_analysed << " samples: give a shorter --window or a longer log";
  SHUTTERLAB_CHECK(result.samples_analysed < (1ull << 32)) << "trace too long for 32-bit windows";

  const PerAxisAngles angles = IntegratePerAxis(trace, result.bias.bias_rad_s, first);
  result.windows = result.samples_analysed - n_window + 1;

  for (int a = 0; a < 3; ++a) {
    // O(N) sliding statistics (estimate/paper/window_stats.h); their brute-force twins are the
    // definition.
    const std::vector<double> sigma = SlidingStdDevByCount(angles.angle_rad[a], n_window);
    const std::vector<double> range = SlidingRangeByCount(angles.angle_rad[a], n_window);
    SHUTTERLAB_CHECK(sigma.size() == result.windows && range.size() == result.windows)
        << "window statistics returned " << sigma.size() << " windows, expected " << result.windows;
    double sigma_sum = 0.0, sigma_sq_sum = 0.0, range_sum = 0.0;
    double sigma_max = 0.0, range_max = 0.0;
    for (size_t k = 0; k < result.windows; ++k) {
      sigma_sum += sigma[k];
      sigma_sq_sum += sigma[k] * sigma[k];
      range_sum += range[k];
      sigma_max = std::max(sigma_max, sigma[k]);
      range_max = std::max(range_max, range[k]);
    }
    const double count = static_cast<double>(result.windows);
    AxisNoise& axis = result.axes[a];
    axis.sigma_mean_arcsec = sigma_sum / count * kArcsecPerRad;
    axis.sigma_max_arcsec = sigma_max * kArcsecPerRad;
    axis.sigma_rms_arcsec = std::sqrt(sigma_sq_sum / count) * kArcsecPerRad;
    axis.range_mean_arcsec = range_sum / count * kArcsecPerRad;
    axis.range_max_arcsec = range_max * kArcsecPerRad;
  }
  result.allan = AllanAnalysis(trace, first, options.allan_points_per_decade);
  return result;
}

std::string NoiseTable(const NoiseResult& result) {
  std::string out;
  out += "Noise of the per-axis integrated angle, sliding windows of " +
         std::to_string(result.window_samples) + " samples (" +
         FormatNumber("%.1f",
                      result.rate_hz > 0 ? 1e3 * result.window_samples / result.rate_hz : 0.0) +
         " ms at " + FormatNumber("%.1f", result.rate_hz) + " Hz), " +
         std::to_string(result.windows) + " windows\n";
  out += "bias from " + std::to_string(result.bias.samples) + " samples; statistics over the " +
         std::to_string(result.samples_analysed) + " samples after it\n\n";
  out += "axis   sigma mean   sigma max   range mean   range max   (arcsec)\n";
  for (int a = 0; a < 3; ++a) {
    const AxisNoise& n = result.axes[a];
    out += std::string("  ") + kAxisNames[a] + FormatNumber("  %11.2f", n.sigma_mean_arcsec) +
           FormatNumber(" %11.2f", n.sigma_max_arcsec) +
           FormatNumber("  %11.2f", n.range_mean_arcsec) +
           FormatNumber(" %11.2f", n.range_max_arcsec) + "\n";
  }
  if (result.allan.empty()) {
    out += "\nAllan deviation: " +
           (result.allan.not_computed.empty() ? "record too short"
                                              : "not computed: " + result.allan.not_computed) +
           "\n";
    return out;
  }
  out += "\nAllan deviation (tau " + FormatNumber("%.3g", result.allan.tau_s.front()) + " .. " +
         FormatNumber("%.3g", result.allan.tau_s.back()) + " s)\n";
  out += "axis   ARW deg/sqrt(h)   ARW rad/s/sqrt(Hz)   bias instability deg/h (at tau s)\n";
  for (int a = 0; a < 3; ++a) {
    const AllanCoefficients& c = result.allan.axes[a];
    out += std::string("  ") + kAxisNames[a] + FormatNumber("  %15.4f", c.arw_deg_sqrt_h) +
           FormatNumber("   %18.3e", c.arw_rad_s_sqrt_hz) +
           FormatNumber("   %10.3f", c.bias_instability_deg_h) +
           (c.bias_instability_upper_bound ? " <=" : "   ") +
           FormatNumber(" (%.3g)", c.bias_instability_tau_s) + "\n";
  }
  bool any_upper = false;
  for (const auto& c : result.allan.axes) any_upper |= c.bias_instability_upper_bound;
  if (any_upper) {
    out +=
        "  <= : upper bound: the minimum is still on the -1/2 (white-noise) line; the record is "
        "too "
        "short to reach the floor\n";
  }
  return out;
}

NoisePairGain FusedNoiseGain(const NoiseResult& first, const NoiseResult& second,
                             const NoiseResult& fused) {
  NoisePairGain gain;
  auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
  const bool allan = !first.allan.empty() && !second.allan.empty() && !fused.allan.empty();
  for (int a = 0; a < 3; ++a) {
    gain.sigma_vs_first[a] =
        ratio(first.axes[a].sigma_mean_arcsec, fused.axes[a].sigma_mean_arcsec);
    gain.sigma_vs_second[a] =
        ratio(second.axes[a].sigma_mean_arcsec, fused.axes[a].sigma_mean_arcsec);
    if (!allan) continue;
    const double f = fused.allan.axes[a].arw_rad_s_sqrt_hz;
    gain.arw_vs_first[a] = ratio(first.allan.axes[a].arw_rad_s_sqrt_hz, f);
    gain.arw_vs_second[a] = ratio(second.allan.axes[a].arw_rad_s_sqrt_hz, f);
  }
  return gain;
}

std::string NoisePairTable(const NoiseResult& first, const NoiseResult& second,
                           const NoiseResult& fused) {
  const NoisePairGain gain = FusedNoiseGain(first, second, fused);
  std::string text =
      "\nFused gain: the sensors' noise over the fused trace's (about 1.41 for two equal "
      "independent sensors)\n"
      "axis   sigma mean (arcsec): first  second  fused   gain vs first  vs second"
      "   ARW (rad/s/sqrt(Hz)): first     second      fused   gain vs first  vs second\n";
  for (int a = 0; a < 3; ++a) {
    text += "  " + std::string(1, "xyz"[a]) + "    ";
    text += FormatNumber("%26.3f", first.axes[a].sigma_mean_arcsec) +
            FormatNumber("%8.3f", second.axes[a].sigma_mean_arcsec) +
            FormatNumber("%7.3f", fused.axes[a].sigma_mean_arcsec) +
            FormatNumber("%16.3f", gain.sigma_vs_first[a]) +
            FormatNumber("%11.3f", gain.sigma_vs_second[a]);
    if (!first.allan.empty() && !second.allan.empty() && !fused.allan.empty()) {
      text += FormatNumber("%29.3e", first.allan.axes[a].arw_rad_s_sqrt_hz) +
              FormatNumber("%11.3e", second.allan.axes[a].arw_rad_s_sqrt_hz) +
              FormatNumber("%11.3e", fused.allan.axes[a].arw_rad_s_sqrt_hz) +
              FormatNumber("%16.3f", gain.arw_vs_first[a]) +
              FormatNumber("%11.3f", gain.arw_vs_second[a]);
    }
    text += "\n";
  }
  return text;
}

}  // namespace shutterlab
