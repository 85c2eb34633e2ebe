#pragma once
// `correct --photos DIR LOG`: a folder of photos and the flight log that recorded the camera's
// motion (the per-image input of `analyze --photos`), turned into the frames `correct` corrects.
//
// The photos are read as one set (io/photo_set.h) and placed on the log's clock by its camera
// events or a trigger file (estimate/paper/photo_clock.h: by name, by MRK number, by capture time,
// in order); each placed photo's row 0 is exposed at its event + the trigger latency, on the log's
// gyro clock. The camera is camera.json's when given, else the photos' own (the most common size,
// focal length and readout among them, estimate/paper/photo_flight.h CameraFromPhotos), with a
// lens profile's lens when given. A photo that cannot be read, is not placed, or has another image
// size or focal length (a zoom) than the camera is skipped, with the reason. The ground plane's
// height: --altitude, else camera.json's, else the log's height above ground, else the photos'
// median height above take-off, else camera.json's default (50 m), each said. Each placed photo's
// velocity (PhotoVelocity) is the horizontal flight speed (north, east) its metadata records, else
// the log's (PX4 vehicle_local_position, ArduPilot's EKF or GPS) at its middle row's time; it is
// turned into the camera's axes by the photo's gimbal attitude, else the log's attitude and the
// camera's mounting.

#include "estimate/paper/photo_clock.h"
#include "io/lens_profile.h"
#include "io/photo_set.h"
#include "io/rig_dataset.h"
#include "model/camera.h"
#include "sim/logs/flight_log_io.h"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

struct PhotoInputOptions {
  std::string log_path;
  FlightLogReadOptions read;
  std::string triggers_path;       // a trigger file (.MRK, CSV, a log); "": the log's events
  double trigger_latency_s = 0.0;  // event to the exposure of row 0, s (may be negative)
  std::optional<RigModel> camera;  // camera.json (--camera): the whole camera
  std::string camera_path;         // for words
  // What wins over camera.json and the photos' own values: --readout, --focal-px, --altitude.
  std::optional<double> readout_s, focal_px, altitude_m;
  // --ground-elevation (io/photo_set.h PhotoSetOptions::ground_elevation_m).
  std::optional<double> ground_elevation_m;
  std::optional<LensProfile> lens_profile;  // --lens-profile, scaled to the photos
  PhotoClockOptions clock;
  std::function<void(double)> progress;  // fraction of the photos read (0..1); may be empty
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// A placed photo's velocity in its camera's axes at row 0 (x right, y down, z along the view: the
// frame's world, docs/FORMATS.md "The model").
struct PhotoVelocity {
  std::optional<Eigen::Vector3d> velocity_mps;  // nullopt: no speed, or no attitude to turn it
  std::string source;                           // for a person: where it came from, or why none
};
// A placed photo's velocity at t_ns (its middle row's time, on the log's clock): the horizontal
// flight speed its metadata records (north, east; the sign of the vertical one is documented
// nowhere), else the log's velocity (NED, the vertical part where the log gives it), else the
// horizontal one from the photos' GPS positions (io/photo_set.h SpeedsFromPositions); turned by the
// photo's gimbal attitude when it records one, else by the log's attitude at t_ns and
// camera_from_body (the log's body axes are its gyro's: the rig's cam_from_gyro), which
// mounting_source names for a person.
PhotoVelocity VelocityOfPhoto(const PhotoRecord& photo, const FlightLog& log, int64_t t_ns,
                              const Eigen::Matrix3d& camera_from_body,
                              const std::string& mounting_source);

struct PhotoInput {
  // dir: the photos' folder; declared: the camera; gyro: the log's trace; frames: the placed
  // photos in name order (frame = the photo's index in the folder, image = its file name,
  // t_first_row_ns = row 0's exposure on the log's clock, no reference); video false;
  // gyro_warnings: what the log and the trigger file lost.
  RigDataset dataset;
  std::string camera_source;  // for a person: where the camera came from
  std::string altitude_source;
  std::string placement;  // how the photos were placed (PhotoClock::method)
  // The gyro's bias (gyro axes) over the log's still segment; nullopt when it has none.
  std::optional<Eigen::Vector3d> still_bias_rad_s;
  std::string still_bias_source;
  std::vector<std::pair<int64_t, std::string>> skipped;  // photo index and why, name first
  std::map<int64_t, PhotoVelocity> velocity;             // per placed photo (frame)
  std::vector<std::string> notes;
};

// Reads the folder, the log and the triggers; throws IoError naming the file for what cannot be
// read, and when no photo is placed on the log.
PhotoInput ReadPhotoInput(const std::string& photos_dir, const PhotoInputOptions& options);

}  // namespace shutterlab
