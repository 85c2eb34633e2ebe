#pragma once
// Choosing the gyro trace of a flight log among the streams it holds: every reader that finds
// several (ULog topics and instances, DataFlash GYR / ISBD / IMU) cleans and ranks them here, so
// that all do it the same way.

#include "sim/gyro_trace.h"
#include "sim/logs/flight_log.h"

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {
namespace internal {

// One gyro stream found in a log, before the best one is chosen.
struct GyroCandidate {
  std::string name;                 // e.g. "sensor_gyro_fifo.x,y,z" or "GYR/1"
  int preference = 0;               // lower is better among candidates of similar rate
  std::vector<GyroSample> samples;  // in log order; cleaned by ChooseGyroSource
  // Messages whose time could not be read (beyond int64 nanoseconds, or not an integer field):
  // left out of samples, counted here so that the warning says what they were.
  size_t unreadable_time = 0;
};

// Adds a sample read from a message with time t_ns (nullopt: unreadable, counted).
inline void AddCandidateSample(const std::optional<int64_t>& t_ns, const Eigen::Vector3d& rate,
                               GyroCandidate* candidate) {
  if (!t_ns) {
    ++candidate->unreadable_time;
    return;
  }
  candidate->samples.push_back({*t_ns, rate});
}

// Cleans every candidate (drops t <= 0, non-finite rates and isolated timestamp spikes, i.e. a
// sample outside the span of both its neighbours in log order; sorts what is left by time; drops
// an end sample more than 60 s beyond its neighbour), then
// picks the one with the highest median rate, preferring lower `preference` among those within
// 10% of the best rate. Fills log->gyro, gyro_source, gyro_sources_available, and adds warnings
// and records_skipped for what was dropped. Returns false when no candidate has 2 samples.
bool ChooseGyroSource(std::vector<GyroCandidate> candidates, FlightLog* log);

}  // namespace internal
}  // namespace shutterlab
