#pragma once
// What a GoPro MP4 says besides its pictures: the gyro (GPMF 'GYRO' in the 'gpmd' metadata track,
// HERO5 and later), the exposure per video frame ('SHUT') and the video track's frame times, read
// through sim/logs/mp4.h and sim/logs/gpmf.h. Decoding the frames themselves is render's business.

#include "sim/gyro_trace.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/mp4.h"

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// The camera's global settings: the GPMF in the movie's user data ('moov/udta/GPMF', DEVC "Global
// Settings"; HERO8, MAX and later write it, the HERO5 does not). Keys as gpmf-parser's README and
// AdrianEddy/telemetry-parser read them.
struct GoproSettings {
  bool present = false;                    // the box was there and parsed
  std::string model;                       // MINF, e.g. "GoPro Max"
  std::string firmware;                    // FMWR
  std::optional<double> readout_s;         // SROT: the sensor readout time (ms in the file)
  std::optional<double> diagonal_fov_deg;  // ZFOV
  std::string fov;                         // VFOV: "W" wide, "L" linear, "S" superview, ...
  std::string stabilizer;                  // EISE: "Y" or "N" ("" when absent)
  std::string stabilizer_mode;             // EISA: e.g. "HS HLevel" (HyperSmooth, horizon levelled)
  std::string projection;                  // PRJT (a FourCC)
  std::optional<double> camera_mode;       // CMOD
  std::string unreadable;  // why a 'udta/GPMF' box was there but could not be read ("" if fine)
  // EISE "Y": the camera re-rendered each image from its own orientation estimate.
  bool StabilizerOn() const { return stabilizer == "Y"; }
};

// A per-frame quaternion stream (CORI, IORI) as the camera wrote it: (w, x, y, z) divided by SCAL,
// on the movie timeline (its own linear fit, as SHUT). GoPro documents neither the axes nor the
// sense (AdrianEddy/telemetry-parser negates x to use them); they are passed on, not interpreted.
struct GoproQuaternions {
  std::vector<double> t_s;
  std::vector<std::array<double, 4>> wxyz;
  bool empty() const { return t_s.empty(); }
};

// What the GoPro's telemetry holds, in the camera's own axes X, Y, Z (GoPro's labels: ORIN, ORIO,
// MTRX on HERO6 and later; GPMF stores the HERO5's as z, x, y).
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
  // The GYRO stream's orientation keys as written ("" / empty when absent).
  std::string gyro_orin, gyro_orio;
  std::vector<double> gyro_mtrx;
  GoproSettings settings;
  // The accelerometer's mean over the clip on the same camera axes (ACCL, its own axis keys),
  // m/s^2: which way is up while the camera was held (nullopt without ACCL).
  std::optional<Eigen::Vector3d> accel_mean_mps2;
  GoproQuaternions camera_orientation;  // CORI: the camera body's orientation since the start
  GoproQuaternions image_orientation;   // IORI: the image's relative to the body (the stabiliser's)
};

// The global settings of an open MP4 (present false when it has no 'udta/GPMF' "Global Settings";
// an SROT outside (0, 1000) ms is left out). Throws IoError for a GPMF box that does not parse.
GoproSettings ReadGoproSettings(Mp4File& mp4);

// True when the MP4 has a GoPro 'gpmd' metadata track. Throws IoError("PATH: offset N: problem")
// when the file is not a readable MP4.
bool HasGoproTelemetry(const std::string& mp4_path);

// Reads GYRO (3 elements, put on the camera's X, Y, Z by GpmfAxisOrder) and, when the firmware
// writes them, SHUT, CORI, IORI and the global settings. Throws IoError when there is no gpmd track
// or GYRO is unreadable (a missing optional stream is only missing).
GoproTelemetry ReadGoproTelemetry(const std::string& mp4_path);

// A GoPro MP4 as every command reads a log (format "gopro"): the GYRO trace on the camera's axes,
// gyro_source naming the stream, no camera events and no altitude; a settings box that does not
// parse is a warning. Throws IoError as ReadGoproTelemetry does.
FlightLog ReadGoproFlightLog(const std::string& mp4_path);

// The presentation times of the MP4's video track, ascending (a video reader returns frames in
// presentation order), s. Throws IoError when there is no video track.
std::vector<double> ReadVideoFrameTimesS(const std::string& mp4_path);

// The SHUT exposure nearest in time to t_s (SHUT is written once per video frame); nullopt when
// none lies within period_s of it.
std::optional<double> NearestShutterS(const GoproTelemetry& telemetry, double t_s, double period_s);

}  // namespace shutterlab
