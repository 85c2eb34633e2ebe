#pragma once
// A flight log's clock against UTC, fitted to the log's GPS fixes (FlightLog::utc_fixes): what
// places a GPS-timed trigger file (.MRK) or a photo's capture time on the gyro's clock.
//
// Model: UTC - t = a + b (t - t0), a straight line through the offsets (a clock offset and a rate
// error, ppm), fitted by least squares to the fixes whose offset is within 1 s of the median
// offset (a receiver's first, unsynchronised messages are left out and counted).

#include "sim/logs/flight_log.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace shutterlab {

struct LogUtcClock {
  int64_t t0_ns = 0;       // the fit's origin on the log clock (the fixes' median time)
  int64_t offset0_ns = 0;  // UTC - t at t0
  double rate = 0.0;       // d(UTC - t)/dt: the log clock's rate error (1e-6 = 1 ppm)
  size_t fixes = 0;        // fixes used
  size_t rejected = 0;     // fixes over 1 s from the median offset
  double rms_residual_s = 0.0, max_residual_s = 0.0;  // the used fixes about the line
  int64_t first_t_ns = 0, last_t_ns = 0;              // the span the used fixes cover

  int64_t UtcNsFromLog(int64_t t_ns) const;
  int64_t LogNsFromUtc(int64_t utc_ns) const;
};

// nullopt without fixes; one fix gives an offset alone (rate 0).
std::optional<LogUtcClock> FitLogUtcClock(const std::vector<UtcFix>& fixes);

}  // namespace shutterlab
