#include "sim/bias.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <cmath>
#include <string>

namespace shutterlab {

SampleRange SamplesInSegment(const GyroTrace& trace, const BiasSegment& segment) {
  if (trace.empty()) return {};
  const int64_t t0 = trace.t_begin_ns();
  return {trace.LowerBound(t0 + SecondsToNs(segment.begin_s)),
          trace.LowerBound(t0 + SecondsToNs(segment.end_s))};
}

BiasEstimate EstimateBias(const GyroTrace& trace, const BiasSegment& segment) {
  SHUTTERLAB_CHECK(segment.begin_s >= 0.0 && segment.end_s > segment.begin_s)
      << "bias segment " << segment.begin_s << ":" << segment.end_s << " is empty or negative";
  SHUTTERLAB_CHECK(!trace.empty()) << "empty gyro trace";
  const auto [begin, end] = SamplesInSegment(trace, segment);
  return BiasOverSegment(trace.samples().data() + begin, trace.samples().data() + end, segment, end,
                         trace.DurationS());
}

BiasEstimate BiasOverSegment(const GyroSample* begin, const GyroSample* end,
                             const BiasSegment& segment, size_t first_after,
                             double trace_duration_s) {
  BiasEstimate out;
  out.samples = static_cast<size_t>(end - begin);
  out.first_after = first_after;
  SHUTTERLAB_CHECK(out.samples >= kMinBiasSamples)
      << "bias segment " << segment.begin_s << ":" << segment.end_s << " s holds " << out.samples
      << " samples (need at least " << kMinBiasSamples << "; the trace lasts " << trace_duration_s
      << " s): give a --bias A:B over a still part of the log, --auto-bias, or a longer log";
  // Two passes: mean, then spread about it (no cancellation for large biases).
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const GyroSample* s = begin; s < end; ++s) sum += s->omega_rad_s;
  out.bias_rad_s = sum / static_cast<double>(out.samples);
  Eigen::Vector3d sq = Eigen::Vector3d::Zero();
  for (const GyroSample* s = begin; s < end; ++s)
    sq += (s->omega_rad_s - out.bias_rad_s).cwiseAbs2();
  out.stderr_rad_s = (sq / static_cast<double>(out.samples - 1)).cwiseSqrt() /
                     std::sqrt(static_cast<double>(out.samples));
  return out;
}

BiasSegment ParseBiasSegment(const std::string& text) {
  const size_t colon = text.find(':');
  SHUTTERLAB_CHECK(colon != std::string::npos)
      << "--bias '" << text << "': expected A:B, the still segment's start and end after the "
      << "first sample, e.g. 0:5s";
  // The shared contract (FORMATS.md) defines A:B in seconds: a bare side is seconds; a unit may be
  // given ("500ms:3s").
  const auto seconds = [](const std::string& side) {
    return ParseQuantity(ParseDouble(side) ? side + "s" : side, "s", "--bias", "s");
  };
  BiasSegment s{seconds(text.substr(0, colon)), seconds(text.substr(colon + 1))};
  SHUTTERLAB_CHECK(s.begin_s >= 0 && s.end_s > s.begin_s)
      << "--bias '" << text << "' must satisfy 0 <= A < B";
  return s;
}

}  // namespace shutterlab
