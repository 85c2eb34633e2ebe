#include "estimate/paper/accuracy.h"

#include "sim/check.h"
#include "sim/integrate.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

namespace shutterlab {
namespace {

struct Segment {
  size_t begin;  // first sample of the motion
  size_t end;    // one past its last sample
};

// Mean of x[begin, end).
double Mean(const std::vector<double>& x, size_t begin, size_t end) {
  double sum = 0.0;
  for (size_t i = begin; i < end; ++i) sum += x[i];
  return sum / static_cast<double>(end - begin);
}

// Chordal mean of unit quaternions q[begin, end), signs aligned to the first: fine for the tiny
// spread of a still window (Markley et al. 2007 would be the general answer).
Eigen::Quaterniond MeanOrientation(const std::vector<Eigen::Quaterniond>& q, size_t begin,
                                   size_t end) {
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  for (size_t i = begin; i < end; ++i) {
    const Eigen::Vector4d c = q[i].coeffs();
    sum += c.dot(q[begin].coeffs()) < 0.0 ? -c : c;
  }
  Eigen::Quaterniond mean;
  mean.coeffs() = sum.normalized();
  return mean;
}

// Smoothed bias-corrected rate magnitude: centred moving average of the vector (half samples on
// each side) via prefix sums (averaging the vector, not the magnitude, is what lowers the noise).
std::vector<double> SmoothedMagnitude(const GyroTrace& trace, const Eigen::Vector3d& bias_rad_s,
                                      size_t half) {
  const size_t n = trace.size();
  std::vector<Eigen::Vector3d> prefix(n + 1, Eigen::Vector3d::Zero());
  for (size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + (trace[i].omega_rad_s - bias_rad_s);
  std::vector<double> magnitude(n);
  for (size_t k = 0; k < n; ++k) {
    const size_t lo = k >= half ? k - half : 0;
    const size_t hi = std::min(n, k + half + 1);
    magnitude[k] = ((prefix[hi] - prefix[lo]) / static_cast<double>(hi - lo)).norm();
  }
  return magnitude;
}

// Still noise level over the bias segment [bias_begin, first), where the smoothing window lies
// inside it, and the detection thresholds from it.
void SetNoiseLevel(const std::vector<double>& magnitude, size_t bias_begin, size_t first,
                   size_t half, const AccuracyOptions& options, AccuracyResult* result) {
  size_t lo = bias_begin + half, hi = first >= half ? first - half : 0;
  if (lo >= hi) lo = bias_begin, hi = first;
  double sum_sq = 0.0;
  for (size_t k = lo; k < hi; ++k) sum_sq += magnitude[k] * magnitude[k];
  result->noise_level_rad_s =
      std::max(options.min_noise_rad_s, std::sqrt(sum_sq / static_cast<double>(hi - lo)));
  result->enter_rad_s = options.enter_factor * result->noise_level_rad_s;
  result->exit_rad_s = options.exit_factor * result->noise_level_rad_s;
}

// The motions from sample first on: hysteresis, then merge motions closer than min_still_s.
std::vector<Segment> DetectMotions(const GyroTrace& trace, const std::vector<double>& magnitude,
                                   size_t first, double min_still_s, const AccuracyResult& result) {
  const size_t n = trace.size();
  std::vector<Segment> segments;
  for (size_t k = first; k < n; ++k) {
    if (magnitude[k] <= result.enter_rad_s) continue;
    size_t begin = k;
    while (begin > first && magnitude[begin - 1] > result.exit_rad_s) --begin;
    size_t end = k + 1;
    while (end < n && magnitude[end] > result.exit_rad_s) ++end;
    const int64_t min_still_ns = SecondsToNs(min_still_s);
    if (!segments.empty() &&
        trace[begin].t_ns - trace[segments.back().end - 1].t_ns < min_still_ns) {
      segments.back().end = end;
    } else {
      segments.push_back({begin, end});
    }
    k = end;  // the loop's ++k then skips the sample at end, which is at or below exit
  }
  return segments;
}

// SO(3) orientations of the bias-corrected samples from sample first on.
OrientationTrace CorrectedOrientation(const GyroTrace& trace, const Eigen::Vector3d& bias_rad_s,
                                      size_t first) {
  std::vector<GyroSample> corrected;
  corrected.reserve(trace.size() - first);
  for (size_t i = first; i < trace.size(); ++i) {
    corrected.push_back({trace[i].t_ns, trace[i].omega_rad_s - bias_rad_s});
  }
  return OrientationTrace{GyroTrace(std::move(corrected))};
}

// What measuring each motion's turn needs.
struct TurnContext {
  const GyroTrace& trace;
  const std::vector<Segment>& segments;
  const PerAxisAngles& angles;  // per-axis angles from sample first on
  const OrientationTrace& orientation;
  size_t first;
  size_t average;  // samples averaged before and after
  int64_t guard_ns;
  int64_t t0_ns;
  double reference_deg;
};

// The turn of motion s from the still samples around it; nullopt when either side has too little
// still time to average.
std::optional<DetectedRotation> MeasureTurn(const TurnContext& c, size_t s) {
  const GyroTrace& trace = c.trace;
  const size_t n = trace.size(), average = c.average;
  const Segment& seg = c.segments[s];
  const size_t lower = s == 0 ? c.first : c.segments[s - 1].end;
  const size_t upper = s + 1 == c.segments.size() ? n : c.segments[s + 1].begin;
  const size_t before_end = trace.LowerBound(trace[seg.begin].t_ns - c.guard_ns);
  const size_t after_begin = trace.LowerBound(trace[seg.end - 1].t_ns + c.guard_ns + 1);
  if (before_end < lower + average || after_begin + average > upper) return std::nullopt;
  DetectedRotation r;
  r.t_start_s = (trace[seg.begin].t_ns - c.t0_ns) * 1e-9;
  r.t_end_s = (trace[seg.end - 1].t_ns - c.t0_ns) * 1e-9;
  const size_t b0 = before_end - average - c.first, a0 = after_begin - c.first;
  Eigen::Vector3d before_rad, after_rad;
  for (int a = 0; a < 3; ++a) {
    before_rad[a] = Mean(c.angles.angle_rad[a], b0, b0 + average);
    after_rad[a] = Mean(c.angles.angle_rad[a], a0, a0 + average);
  }
  const Eigen::Vector3d d = after_rad - before_rad;
  r.before_arcsec = before_rad * kArcsecPerRad;
  r.after_arcsec = after_rad * kArcsecPerRad;
  r.theta_arcsec = AngleFromTrace(RotationZYX(d.z(), d.y(), d.x())) * kArcsecPerRad;
  r.difference_arcsec = r.theta_arcsec - c.reference_deg * 3600.0;
  r.theta_vector_arcsec = d.norm() * kArcsecPerRad;
  const auto& q = c.orientation.world_from_body();
  r.theta_so3_arcsec =
      AngularDistance(MeanOrientation(q, b0, b0 + average), MeanOrientation(q, a0, a0 + average)) *
      kArcsecPerRad;
  return r;
}

// The mean and (with more than one turn) standard deviation of the turns' differences.
void SetDifferenceStats(AccuracyResult* result) {
  double sum = 0.0;
  for (const auto& r : result->rotations) sum += r.difference_arcsec;
  result->difference_mean_arcsec = sum / result->rotations.size();
  if (result->rotations.size() > 1) {
    double ss = 0.0;
    for (const auto& r : result->rotations) {
      ss += (r.difference_arcsec - result->difference_mean_arcsec) *
            (r.difference_arcsec - result->difference_mean_arcsec);
    }
    result->difference_std_arcsec = std::sqrt(ss / (result->rotations.size() - 1));
  }
}

}  // namespace

void AccuracyOptions::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(reference_deg) && reference_deg > 0.0 && reference_deg < 180.0)
      << "reference angle must be in (0, 180) degrees (got " << reference_deg << ")";
  SHUTTERLAB_CHECK(average_samples >= 1)
      << "samples to average must be at least 1 (got " << average_samples << ")";
  SHUTTERLAB_CHECK(bias.begin_s >= 0.0 && bias.end_s > bias.begin_s)
      << "bias segment " << bias.begin_s << ":" << bias.end_s << " must satisfy 0 <= A < B";
  SHUTTERLAB_CHECK(smooth_s >= 0.0 && std::isfinite(smooth_s)) << "smoothing time must be >= 0";
  SHUTTERLAB_CHECK(exit_factor > 0.0 && enter_factor > exit_factor)
      << "detection factors must satisfy enter > exit > 0 (got " << enter_factor << ", "
      << exit_factor << ")";
  SHUTTERLAB_CHECK(min_noise_rad_s > 0.0) << "noise floor must be positive";
  SHUTTERLAB_CHECK(guard_s >= 0.0 && std::isfinite(guard_s)) << "guard time must be >= 0";
  SHUTTERLAB_CHECK(min_still_s >= 0.0 && std::isfinite(min_still_s))
      << "minimum still time must be >= 0";
}

AccuracyResult AnalyzeAccuracy(const GyroTrace& trace, const AccuracyOptions& options) {
  options.Check();
  AccuracyResult result;
  result.reference_deg = options.reference_deg;
  result.average_samples = options.average_samples;
  const BiasEstimate bias = options.zero_bias ? BiasEstimate() : EstimateBias(trace, options.bias);
  const size_t n = trace.size();
  const size_t first = bias.first_after;
  SHUTTERLAB_CHECK(first < n) << "no samples after the bias segment " << options.bias.begin_s << ":"
                              << options.bias.end_s << " s (the trace lasts " << trace.DurationS()
                              << " s): give an earlier --bias A:B or a longer log";
  const int64_t t0_ns = trace.t_begin_ns();

  const double rate_hz = trace.sampling().RateHz();
  const size_t half = static_cast<size_t>(std::llround(0.5 * options.smooth_s * rate_hz));
  const std::vector<double> magnitude = SmoothedMagnitude(trace, bias.bias_rad_s, half);
  const size_t bias_begin = trace.LowerBound(t0_ns + SecondsToNs(options.bias.begin_s));
  SetNoiseLevel(magnitude, bias_begin, first, half, options, &result);
  const std::vector<Segment> segments =
      DetectMotions(trace, magnitude, first, options.min_still_s, result);
  SHUTTERLAB_CHECK(!segments.empty())
      << "no rotation found after the bias segment: the smoothed rate never exceeded "
      << result.enter_rad_s << " rad/s (" << options.enter_factor << " x the still noise level "
      << result.noise_level_rad_s
      << " rad/s): accuracy needs a log of turns between still stretches (a total-station test) "
         "whose --bias A:B segment is still";

  // Per-axis angles and SO(3) orientations of the bias-corrected samples after the bias segment.
  const PerAxisAngles angles = IntegratePerAxis(trace, bias.bias_rad_s, first);
  const OrientationTrace orientation = CorrectedOrientation(trace, bias.bias_rad_s, first);

  const size_t average = static_cast<size_t>(options.average_samples);
  const TurnContext context{trace,
                            segments,
                            angles,
                            orientation,
                            first,
                            average,
                            SecondsToNs(options.guard_s),
                            t0_ns,
                            options.reference_deg};
  for (size_t s = 0; s < segments.size(); ++s) {
    const std::optional<DetectedRotation> r = MeasureTurn(context, s);
    if (r) {
      result.rotations.push_back(*r);
    } else {
      result.skipped_t_s.push_back((trace[segments[s].begin].t_ns - t0_ns) * 1e-9);
    }
  }
  SHUTTERLAB_CHECK(!result.rotations.empty())
      << "found " << segments.size() << " motion(s) after the bias segment but none has "
      << options.guard_s << " s + " << average
      << " samples of still time on both sides to average (first motion at "
      << (trace[segments[0].begin].t_ns - t0_ns) * 1e-9
      << " s): hold the gyro still before and after each turn, or give a shorter --guard or "
         "--average";

  SetDifferenceStats(&result);
  return result;
}

std::string AccuracyTable(const AccuracyResult& result) {
  std::string out = "Turns detected: " + std::to_string(result.rotations.size()) + "; reference " +
                    FormatNumber("%g", result.reference_deg) +
                    " deg = " + FormatNumber("%g", result.reference_deg * 3600.0) + " arcsec; " +
                    std::to_string(result.average_samples) +
                    " samples averaged before and after each turn\n\n";
  out +=
      "turn  t (s)  |   before x   before y   before z |    after x    after y    after z |"
      "      theta  difference |  theta SO(3)   (arcsec)\n";
  for (size_t i = 0; i < result.rotations.size(); ++i) {
    const DetectedRotation& r = result.rotations[i];
    out +=
        FormatNumber("%4.0f", static_cast<double>(i + 1)) + FormatNumber(" %6.2f |", r.t_start_s);
    for (int a = 0; a < 3; ++a) out += FormatNumber(" %10.1f", r.before_arcsec[a]);
    out += " |";
    for (int a = 0; a < 3; ++a) out += FormatNumber(" %10.1f", r.after_arcsec[a]);
    out += " |" + FormatNumber(" %10.1f", r.theta_arcsec) +
           FormatNumber(" %11.1f", r.difference_arcsec) + " |" +
           FormatNumber(" %12.1f", r.theta_so3_arcsec) + "\n";
  }
  out += "\ndifference: mean " + FormatNumber("%.1f", result.difference_mean_arcsec) +
         " arcsec, std " + FormatNumber("%.1f", result.difference_std_arcsec) + " arcsec over " +
         std::to_string(result.rotations.size()) + " turn(s)\n";
  out += "detection: still noise " + FormatNumber("%.3g", result.noise_level_rad_s) +
         " rad/s (smoothed magnitude), enter " + FormatNumber("%.3g", result.enter_rad_s) +
         ", exit " + FormatNumber("%.3g", result.exit_rad_s) + " rad/s\n";
  if (!result.skipped_t_s.empty()) {
    out += "skipped (too little still time around them to average): motions at";
    for (double t : result.skipped_t_s) out += FormatNumber(" %.2f", t) + " s";
    out += "\n";
  }
  return out;
}

}  // namespace shutterlab
