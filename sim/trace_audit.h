#pragma once
// What a gyro trace itself shows was lost or is doubtful, whatever file it came from: gaps,
// duplicated timestamps, sample-rate changes and saturation. Readers add what only the bytes show
// (truncation, corrupt records, partial batches); sim/logs/flight_log_io.h joins the two lists.

#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// Full-scale ranges of MEMS gyros (deg/s). When a log does not state its range, a peak that lands
// on one of these is taken as the range (the same for every axis of one sensor).
inline constexpr double kCommonGyroFullScalesDps[] = {125, 250, 500, 1000, 2000, 4000};

struct TraceAuditOptions {
  // The sensor's full scale when the log states it (raw counts: the configured range).
  std::optional<double> full_scale_rad_s;
  // A sample is clipped when within this fraction of the full scale.
  double saturation_margin = 0.02;
  // Consecutive 1 s blocks whose median sample interval differs by more than this factor make a
  // sample-rate change.
  double rate_change_factor = 1.25;
};

// One warning per kind of loss (gap, duplicate_time, rate_change, saturated per axis), each with
// its count, the time of the first occurrence and a line with the times on the trace's clock, e.g.
//   gap: "3 interval(s) over 3x the median 1.000 ms, 0.412 s missing in all; longest 0.300 s at
//         12.345 s"
//   saturated: "axis y, 1 sample(s) within 2 % of the +-2000 deg/s full scale (where the peak
//         lands), peak 2023 deg/s, from 239.159 s to 239.159 s: the rotation there is
//         under-reported"
// A gap is judged against the local rate (1 s blocks), so a rate change is not a run of gaps.
// Empty when nothing is wrong.
std::vector<LogWarning> AuditTrace(const GyroTrace& trace, const TraceAuditOptions& options = {});

// The full scale (rad/s) that clipped the trace, when one shows: the stated one, or the common
// range that the trace's peak (over all axes) lands on within [1 - margin, 1 + 2.5 margin] of it.
std::optional<double> SaturationFullScale(const GyroTrace& trace, const TraceAuditOptions& options);

}  // namespace shutterlab
