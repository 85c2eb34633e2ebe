#pragma once
// Small fixtures of the model shared by its tests and the tests above it: rigs (pinhole and
// fisheye) and constant-rate gyro traces.

#include "model/camera.h"
#include "sim/gyro_trace.h"
#include "sim/units.h"

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <vector>

namespace shutterlab::test {

// A nadir rig over flat ground: width x height, fx = fy = f_px, the principal point at the centre,
// no lens distortion, top-to-bottom readout, camera axes = gyro axes.
inline RigModel NadirRig(int width, int height, double f_px, double readout_s = 0.030,
                         double altitude_m = 50.0) {
  RigModel rig;
  rig.camera.width = width;
  rig.camera.height = height;
  rig.camera.fx = rig.camera.fy = f_px;
  rig.camera.cx = (width - 1) / 2.0;
  rig.camera.cy = (height - 1) / 2.0;
  rig.shutter.readout_s = readout_s;
  rig.altitude_m = altitude_m;
  return rig;
}

// A mapping camera's rig: 1280x960, f = 1100 px, 30 ms readout, 50 m over flat ground.
inline RigModel MappingRig() { return NadirRig(1280, 960, 1100.0); }

// A small nadir rig: width x height, f = 300 px (fy 310: the axes kept apart), 20 ms, 40 m.
inline RigModel SmallRig(int width = 96, int height = 72) {
  RigModel rig = NadirRig(width, height, 300.0, 0.020, 40.0);
  rig.camera.fy = 310.0;
  return rig;
}

// A nadir action camera with a fisheye lens: width x height, the GoPro MAX's Gyroflow coefficients
// (../shared/data/incoming_rs/gopro_max_heromode/reference), f such that the left and right edges
// are half_fov_deg off the axis, 30 ms readout, 50 m.
inline RigModel FisheyeRig(int width, int height, double half_fov_deg = 60.0) {
  const Fisheye lens(
      {0.0646075465207674, 0.039139647556618896, -0.041373671856156674, 0.014898789517094136});
  RigModel rig = NadirRig(width, height, 1.0);
  rig.camera.fx = rig.camera.fy = rig.camera.cx / lens.ThetaD(half_fov_deg * M_PI / 180.0);
  rig.camera.distortion = lens;
  return rig;
}

// Constant logged rate (gyro axes) from t0_s for duration_s at rate_hz; times are exact integers.
inline GyroTrace ConstantRateTrace(const Eigen::Vector3d& omega_rad_s, double t0_s = 0.0,
                                   double duration_s = 2.0, double rate_hz = 1000.0) {
  std::vector<GyroSample> samples;
  const int64_t period_ns = static_cast<int64_t>(std::llround(1e9 / rate_hz));
  const int64_t t0_ns = SecondsToNs(t0_s);
  const int64_t n = static_cast<int64_t>(std::llround(duration_s * rate_hz));
  for (int64_t k = 0; k <= n; ++k) samples.push_back({t0_ns + k * period_ns, omega_rad_s});
  return GyroTrace(std::move(samples));
}

}  // namespace shutterlab::test
