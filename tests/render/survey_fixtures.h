#pragma once
// Surveys for the tests (render/survey.h): a still gyro and a small flight.

#include "render/survey.h"
#include "sim/gyro_trace.h"

#include <cstdint>
#include <vector>

namespace shutterlab::test {

// A still gyro (zero rates) at 1 kHz from 1 ms to end_s.
inline GyroTrace StillGyro(double end_s) {
  std::vector<GyroSample> samples;
  for (int64_t t_ms = 1; t_ms <= static_cast<int64_t>(end_s * 1000) + 1; ++t_ms) {
    samples.push_back({t_ms * 1'000'000, Eigen::Vector3d::Zero()});
  }
  return GyroTrace(std::move(samples));
}

// A small survey: 160x120 px, f 140 px, 2 lines of 3 photos at 40 m, 8 m/s, 30 ms readout.
inline SurveyOptions SmallSurvey() {
  SurveyOptions o;
  o.camera.width = 160;
  o.camera.height = 120;
  o.camera.fx = o.camera.fy = 140.0;
  o.camera.cx = 79.5;
  o.camera.cy = 59.5;
  o.altitude_m = 40.0;
  o.speed_mps = 8.0;
  o.lines = 2;
  o.photos_per_line = 3;
  o.terrain.cell_m = 0.5;
  return o;
}

}  // namespace shutterlab::test
