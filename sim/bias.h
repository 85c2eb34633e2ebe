#pragma once
// Gyro bias from a still segment.

#include "sim/gyro_trace.h"

#include <Eigen/Core>

namespace shutterlab {

// A segment of a trace in seconds after its first sample: [begin_s, end_s).
struct BiasSegment {
  double begin_s = 0.0;
  double end_s = 5.0;  // the source paper averages the first 5 s while still
};

struct BiasEstimate {
  Eigen::Vector3d bias_rad_s = Eigen::Vector3d::Zero();  // per-axis mean rate over the segment
  Eigen::Vector3d stderr_rad_s =
      Eigen::Vector3d::Zero();  // standard error of that mean (white-noise assumption)
  size_t samples = 0;           // samples inside the segment
  size_t first_after = 0;       // index of the first sample at or after end_s: analyses start here
};

// The samples of a trace inside the segment, as an index range [begin, end): a sample at exactly
// end_s is outside, as the segment's [begin_s, end_s) says. The one place that turns a segment's
// seconds into samples (the bias, the Allan deviation on a still segment).
struct SampleRange {
  size_t begin = 0, end = 0;
};
SampleRange SamplesInSegment(const GyroTrace& trace, const BiasSegment& segment);

// Minimum samples a bias segment must hold to give a meaningful mean.
inline constexpr size_t kMinBiasSamples = 10;

// Mean rate over the segment. Throws std::invalid_argument when the segment is malformed or holds
// fewer than kMinBiasSamples samples (the message says how many it holds).
BiasEstimate EstimateBias(const GyroTrace& trace, const BiasSegment& segment);
// The same over the segment's samples [begin, end) alone, for a trace that is streamed: the
// analyses start at first_after, and trace_duration_s goes into the message when the segment
// holds too few samples.
BiasEstimate BiasOverSegment(const GyroSample* begin, const GyroSample* end,
                             const BiasSegment& segment, size_t first_after,
                             double trace_duration_s);

// Parses `--bias A:B`, the still segment's start and end after the first sample: seconds, as the
// shared contract defines it ("0:5"), or with a unit ("500ms:3s"; a bare side is seconds).
// Throws std::invalid_argument on anything else.
BiasSegment ParseBiasSegment(const std::string& text);

}  // namespace shutterlab
