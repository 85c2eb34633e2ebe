#pragma once
// Small fixtures shared by the paper's tests and the report tests above them: flight logs that
// rest, then turn, at 1 kHz, the rate that smears a given length on the ground, and a comparison
// of two flight tables.

#include "estimate/paper/flight.h"
#include "sim/gyro_trace.h"
#include "sim/logs/flight_log.h"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab::test {

inline constexpr int64_t kLogDtNs = 1'000'000;  // 1 kHz
inline constexpr double kLogStillS = 4.0;  // the still lead-in: the bias segment the search finds

// A 1 kHz log (format "test", gyro source `source`), still (zero rate) up to and including the
// sample at kLogStillS, then rate_rad_s(t_s) (gyro axes, t_s after the first sample) until total_s.
inline FlightLog StillThenRateLog(double total_s,
                                  const std::function<Eigen::Vector3d(double t_s)>& rate_rad_s,
                                  const std::string& source) {
  std::vector<GyroSample> samples;
  const int64_t n = static_cast<int64_t>(total_s * 1e9) / kLogDtNs + 1;
  const int64_t still_n = static_cast<int64_t>(kLogStillS * 1e9) / kLogDtNs;
  for (int64_t k = 0; k < n; ++k) {
    samples.push_back(
        {k * kLogDtNs, k <= still_n ? Eigen::Vector3d::Zero() : rate_rad_s(k * kLogDtNs * 1e-9)});
  }
  FlightLog log;
  log.gyro = GyroTrace(std::move(samples));
  log.format = "test";
  log.gyro_source = source;
  return log;
}

// Still for kLogStillS, then a constant rate (gyro axes) until total_s.
inline FlightLog ConstantRateLog(const Eigen::Vector3d& rate_rad_s, double total_s) {
  return StillThenRateLog(
      total_s, [&rate_rad_s](double) { return rate_rad_s; }, "constant");
}

// The rate about one camera axis for which the paper's model smears d_m on the ground: a readout
// of readout_s at altitude_m turns by atan(d_m / altitude_m).
inline double RateForGroundSmear(double d_m, double altitude_m = 50.0, double readout_s = 0.030) {
  return std::atan(d_m / altitude_m) / readout_s;
}

// Two flight tables count the same windows and flags, row by row (per axis, any axis, vector).
inline void ExpectSameFlightRows(const FlightResult& got, const FlightResult& expected) {
  ASSERT_EQ(got.rows.size(), expected.rows.size());
  for (size_t i = 0; i < got.rows.size(); ++i) {
    EXPECT_EQ(got.rows[i].windows, expected.rows[i].windows) << i;
    EXPECT_EQ(got.rows[i].flagged, expected.rows[i].flagged) << i;
    EXPECT_EQ(got.rows[i].flagged_axis, expected.rows[i].flagged_axis) << i;
    EXPECT_EQ(got.rows[i].flagged_vector, expected.rows[i].flagged_vector) << i;
  }
}

}  // namespace shutterlab::test
