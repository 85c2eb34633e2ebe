#pragma once
// What a GoPro MP4 says besides its pictures: the gyro (GPMF 'GYRO' in the 'gpmd' metadata track,
// HERO5 and later), the exposure per video frame ('SHUT') and the video track's frame times, read
// through sim/logs/mp4.h and sim/logs/gpmf.h. Decoding the frames themselves is render's business.

#include "sim/gyro_trace.h"

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// What the GoPro's telemetry holds, in the sensor's x, y, z (GPMF stores the HERO5's as z, x, y).
struct GoproTelemetry {
  GyroTrace gyro;         // movie timeline seconds, rad/s, sensor axes x, y, z
  std::string gyro_name;  // STNM
  std::string axis_order_source;
  std::vector<double> gyro_scale;  // SCAL
  std::vector<size_t> gyro_payload_samples;
  double gyro_rate_hz = 0.0;  // from the linear fit over the track
  double gyro_fit_max_residual_s = 0.0;
  std::vector<double> shutter_s;    // SHUT values (per video frame), empty when absent
  std::vector<double> shutter_t_s;  // their times (their own linear fit)
  std::string device;               // DVNM of the GYRO stream
};

// True when the MP4 has a GoPro 'gpmd' metadata track. Throws IoError("PATH: offset N: problem")
// when the file is not a readable MP4.
bool HasGoproTelemetry(const std::string& mp4_path);

// Reads GYRO (3 elements, reordered to the sensor's x, y, z by GpmfAxisOrder) and, when the
// firmware writes it, SHUT. Throws IoError when there is no gpmd track or GYRO is unreadable.
GoproTelemetry ReadGoproTelemetry(const std::string& mp4_path);

// The presentation times of the MP4's video track, ascending (a video reader returns frames in
// presentation order), s. Throws IoError when there is no video track.
std::vector<double> ReadVideoFrameTimesS(const std::string& mp4_path);

// The SHUT exposure nearest in time to t_s (SHUT is written once per video frame); nullopt when
// none lies within period_s of it.
std::optional<double> NearestShutterS(const GoproTelemetry& telemetry, double t_s, double period_s);

}  // namespace shutterlab
