#include "estimate/correct/photo_input.h"

#include "estimate/paper/photo_flight.h"
#include "sim/bias.h"
#include "sim/check.h"
#include "sim/logs/trigger_file.h"
#include "sim/still_detect.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <cmath>
#include <filesystem>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// A photo whose own focal length differs from the camera's by more than this share is another
// zoom setting (0.5 %: 6 px at the edge of a 2400 px half-width).
constexpr double kFocalTolerance = 0.005;

// What the user gave wins over the photos' own focal length, readout and altitude.
PhotoSetOptions PhotoSetOptionsFrom(const PhotoInputOptions& options) {
  PhotoSetOptions set;
  if (options.camera) {
    set.readout_s = options.camera->shutter.readout_s;
    set.readout_origin = ReadoutOrigin::kCameraFile;
    set.readout_text = "--camera " + options.camera_path;
    set.focal_px = 0.5 * (options.camera->camera.fx + options.camera->camera.fy);
    set.focal_text = "--camera " + options.camera_path;
  }
  if (options.readout_s) {
    set.readout_s = options.readout_s;
    set.readout_origin = ReadoutOrigin::kUser;
    set.readout_text = "--readout";
  }
  if (options.focal_px) {
    set.focal_px = options.focal_px;
    set.focal_text = "--focal-px";
  }
  set.altitude_m = options.altitude_m;
  set.ground_elevation_m = options.ground_elevation_m;
  set.lens_profile = options.lens_profile;
  set.progress = options.progress;
  set.check_image_data = false;  // each photo's one full decode finds a cut (ReadWholeImage)
  return set;
}

// The camera: camera.json's (with the flags over it), else the photos' own; a lens profile's lens.
RigModel PhotosCamera(const PhotoSet& set, const PhotoInputOptions& options, std::string* source) {
  RigModel rig;
  rig.shutter.readout_s = 0.030;
  if (options.camera) {
    rig = *options.camera;
    *source = "--camera " + options.camera_path;
  } else {
    if (options.readout_s) rig.shutter.readout_s = *options.readout_s;
    CameraFromPhotos(set, options.readout_s.has_value(), &rig, source);
    if (rig.camera.width <= 0) {
      throw IoError(IoMessage(set.source, 0,
                              "no photo gives its image size and focal length: give --camera "
                              "camera.json or --focal-px"));
    }
  }
  if (options.readout_s) rig.shutter.readout_s = *options.readout_s;
  if (options.focal_px) rig.camera.fx = rig.camera.fy = *options.focal_px;
  if (options.lens_profile) {
    LensProfileUse use =
        ScaleLensProfile(*options.lens_profile, rig.camera.width, rig.camera.height);
    ApplyLensProfile(&use, &rig, options.readout_s.has_value() || options.camera.has_value());
    *source += "; its lens from the lens profile " + use.name;
  }
  return rig;
}

// The ground plane's height, first that applies: --altitude, camera.json, the log, the photos.
std::string ChooseAltitude(const PhotoInputOptions& options, const FlightLog& log,
                           const PhotoSet& set, RigModel* rig) {
  if (options.altitude_m) {
    rig->altitude_m = *options.altitude_m;
    return "--altitude";
  }
  if (options.camera) return "--camera " + options.camera_path;
  if (log.altitude_above_ground_m && *log.altitude_above_ground_m > 0) {
    rig->altitude_m = *log.altitude_above_ground_m;
    return "the log: " + log.altitude_source + FormatNumber(" (%.1f m)", rig->altitude_m);
  }
  std::vector<double> heights;
  for (const PhotoRecord& r : set.photos) {
    if (r.ok() && r.altitude_m) heights.push_back(*r.altitude_m);
  }
  if (!heights.empty()) {
    rig->altitude_m = Median(std::move(heights));
    return "the photos' median height above take-off (" + FormatNumber("%.1f m)", rig->altitude_m);
  }
  return FormatNumber("assumed %g m (give --altitude)", rig->altitude_m);
}

// The log's bias over its still segment, gyro axes.
void StillBias(const GyroTrace& gyro, PhotoInput* input) {
  try {
    const StillSegment still = DetectStillSegment(gyro);
    input->still_bias_rad_s = EstimateBias(gyro, still.segment).bias_rad_s;
    input->still_bias_source = "the log's still segment " +
                               FormatNumber("%.1f", still.segment.begin_s) + "-" +
                               FormatNumber("%.1f s", still.segment.end_s);
  } catch (const std::invalid_argument& e) {
    input->still_bias_source = e.what();
  }
}

// What the gyro's axes are to the camera, said: a flight controller's gyro turns with the
// airframe, a gimbal's camera does not.
void AddMountingNotes(const PhotoSet& set, const PhotoInputOptions& options, PhotoInput* input) {
  if (!options.camera) {
    input->notes.push_back(
        "mounting unknown: the log's gyro axes are taken as the camera's (x right, y down, z "
        "along the view); give --camera camera.json with gyro_to_camera, or --effect "
        "gyro_to_camera=...");
  }
  size_t on_gimbal = 0;
  for (const PhotoRecord& r : set.photos) on_gimbal += r.ok() && r.metadata.gimbal ? 1 : 0;
  if (on_gimbal == 0) return;
  const std::string taken = std::to_string(on_gimbal) + " of " + std::to_string(set.photos.size()) +
                            " photos were taken from a gimbal";
  if (options.camera) {
    // camera.json declares the gyro's mounting on the camera: a gyro on the gimbal's camera (a
    // recorder's) turns with it, and nothing here says otherwise.
    input->notes.push_back(taken + ": " + options.camera_path +
                           " declares the gyro's mounting on the camera, so the gyro is taken to "
                           "turn with it (a flight controller's gyro would not)");
    return;
  }
  input->notes.push_back(taken +
                         ": a stabilised camera does not turn with the airframe, so a flight "
                         "controller's gyro does not describe its motion (the correction is right "
                         "only with a gyro on the camera)");
}

// Why a photo is not corrected: unreadable, not placed, another image size, or (own_focal: the
// camera is the photos' own) another focal length, a zoom camera's other setting; "" when it is.
std::string WhyNotCorrected(const PhotoRecord& r, const PhotoPlacement& placement,
                            const PinholeCamera& camera, bool own_focal) {
  if (!r.ok()) return r.error;
  if (!placement.t_ns) return "not placed on the log: " + placement.problem;
  if (r.metadata.width != camera.width || r.metadata.height != camera.height) {
    return "is " + std::to_string(r.metadata.width) + "x" + std::to_string(r.metadata.height) +
           ", the camera " + std::to_string(camera.width) + "x" + std::to_string(camera.height);
  }
  const double focal_px = 0.5 * (camera.fx + camera.fy);
  if (own_focal && r.focal_px && std::abs(*r.focal_px - focal_px) > kFocalTolerance * focal_px) {
    return FormatNumber("focal length %.0f px", *r.focal_px) +
           FormatNumber(", the camera's %.0f px", focal_px);
  }
  return "";
}

// "5.00 m/s toward 90 deg" of a NED velocity (its horizontal part's direction).
std::string SpeedText(const Eigen::Vector3d& ned) {
  return FormatNumber("%.2f m/s", ned.norm()) +
         FormatNumber(" toward %.0f deg", CourseDeg(ned.x(), ned.y()));
}

// The camera's axes (x right, y down, z along the view) from NED, by a DJI gimbal's attitude.
Eigen::Matrix3d CameraFromNed(const AttitudeDeg& gimbal) {
  const Eigen::Matrix3d ned_from_gimbal = NedFromGimbal(gimbal);
  Eigen::Matrix3d ned_from_camera;
  ned_from_camera << ned_from_gimbal.col(1), ned_from_gimbal.col(2), ned_from_gimbal.col(0);
  return ned_from_camera.transpose();
}

std::string GimbalText(const AttitudeDeg& gimbal) {
  return FormatNumber("gimbal's yaw %.1f deg", gimbal.yaw_deg) +
         FormatNumber(" and pitch %.1f deg", gimbal.pitch_deg);
}

}  // namespace

PhotoVelocity VelocityOfPhoto(const PhotoRecord& photo, const FlightLog& log, int64_t t_ns,
                              const Eigen::Matrix3d& camera_from_body,
                              const std::string& mounting_source) {
  const PhotoMetadata& metadata = photo.metadata;
  PhotoVelocity out;
  Eigen::Vector3d ned;
  std::string what;
  const std::optional<Eigen::Vector3d> logged = VelocityAt(log.velocity, t_ns);
  if (metadata.speed_m_s) {
    // DJI documents the sign of neither vertical speed: the horizontal part only.
    ned = Eigen::Vector3d(metadata.speed_m_s->x(), metadata.speed_m_s->y(), 0.0);
    what = SpeedText(ned) + " from the photo's " + metadata.flight_state_source;
  } else if (logged) {
    // The log's down axis is documented (NED): kept where the log gives it.
    ned = *logged;
    if (!std::isfinite(ned.z())) ned.z() = 0.0;
    what = SpeedText(ned) + " from the log's " + log.velocity_source +
           FormatNumber(" at %.3f s", t_ns * 1e-9);
  } else if (photo.speed_from_positions && photo.ground_speed_m_s) {
    const double course_rad = photo.course_deg.value_or(0.0) * kRadPerDeg;
    ned =
        *photo.ground_speed_m_s * Eigen::Vector3d(std::cos(course_rad), std::sin(course_rad), 0.0);
    what = SpeedText(ned) + " from " + photo.speed_source;
  } else {
    out.source = log.velocity.empty() ? "the photo records no flight speed, nor does the log"
                                      : "the photo records no flight speed, and the log's (" +
                                            log.velocity_source + ") does not reach its time";
    return out;
  }
  if (metadata.gimbal) {
    out.velocity_mps = CameraFromNed(*metadata.gimbal) * ned;
    out.source = what + ", turned by the photo's " + GimbalText(*metadata.gimbal);
    return out;
  }
  const std::optional<Eigen::Quaterniond> attitude = AttitudeAt(log.attitude, t_ns);
  if (!attitude) {
    out.source = what + ", but neither the photo nor the log gives the camera's attitude";
    return out;
  }
  out.velocity_mps = camera_from_body * attitude->toRotationMatrix().transpose() * ned;
  out.source = what + ", turned by the log's " + log.attitude_source + " and " + mounting_source;
  return out;
}

void PhotoInputOptions::Check() const {
  SHUTTERLAB_CHECK(!log_path.empty()) << "--photos needs the LOG that recorded the flight";
  SHUTTERLAB_CHECK(std::isfinite(trigger_latency_s) && std::abs(trigger_latency_s) < 10)
      << "--latency must be below 10 s (got " << trigger_latency_s << " s)";
  SHUTTERLAB_CHECK(!readout_s || (*readout_s > 0 && *readout_s < 10))
      << "--readout must be positive (below 10 s)";
  SHUTTERLAB_CHECK(!focal_px || (*focal_px > 0 && std::isfinite(*focal_px)))
      << "--focal-px must be positive";
  SHUTTERLAB_CHECK(!altitude_m || (*altitude_m > 0 && std::isfinite(*altitude_m)))
      << "--altitude must be positive";
  if (camera) camera->Check();
  read.Check();
  clock.Check();
}

PhotoInput ReadPhotoInput(const std::string& photos_dir, const PhotoInputOptions& options) {
  options.Check();
  const PhotoSetOptions set_options = PhotoSetOptionsFrom(options);
  set_options.Check();
  const PhotoSet set = ReadPhotoSet(photos_dir, set_options);
  PhotoInput input;
  RigDataset& dataset = input.dataset;
  dataset.dir =
      fs::is_directory(photos_dir) ? fs::path(photos_dir) : fs::path(photos_dir).parent_path();
  dataset.camera_path = options.camera_path;
  dataset.gyro_path = options.log_path;
  dataset.frames_path = options.triggers_path.empty() ? options.log_path : options.triggers_path;
  dataset.declared = PhotosCamera(set, options, &input.camera_source);
  if (!dataset.declared.mask.empty()) {  // camera.json's mask, beside camera.json
    dataset.mask =
        ReadMask((fs::path(options.camera_path).parent_path() / dataset.declared.mask).string(),
                 dataset.declared.camera.width, dataset.declared.camera.height);
  }

  FlightLog log = ReadFlightLog(options.log_path, options.read);
  std::optional<TriggerFile> triggers;
  if (!options.triggers_path.empty()) triggers = ReadTriggerFile(options.triggers_path);
  input.altitude_source = ChooseAltitude(options, log, set, &dataset.declared);
  dataset.declared.Check();
  const PhotoClock clock = PlacePhotos(set, log, triggers ? &*triggers : nullptr, options.clock);
  input.placement = clock.method;
  dataset.gyro_warnings = log.warnings;
  if (triggers) {
    const std::string name = fs::path(options.triggers_path).filename().string();
    for (LogWarning w : triggers->warnings) {
      w.message = "trigger file " + name + ": " + w.message;
      dataset.gyro_warnings.push_back(std::move(w));
    }
  }
  StillBias(log.gyro, &input);
  dataset.gyro = std::move(log.gyro);

  const PinholeCamera& camera = dataset.declared.camera;
  // Each photo's own focal length counts only where the photos' EXIF gives the camera's.
  const bool own_focal = !options.camera && !options.focal_px && !options.lens_profile;
  const int64_t latency_ns = SecondsToNs(options.trigger_latency_s);
  const int64_t readout_half_ns = SecondsToNs(0.5 * dataset.declared.shutter.readout_s);
  const std::string mounting_source =
      options.camera ? options.camera_path + "'s gyro_to_camera"
                     : "the mounting assumed (the log's body axes as the camera's: give "
                       "camera.json's gyro_to_camera)";
  for (size_t i = 0; i < set.photos.size(); ++i) {
    const std::string why = WhyNotCorrected(set.photos[i], clock.placements[i], camera, own_focal);
    if (!why.empty()) {
      input.skipped.emplace_back(static_cast<int64_t>(i), set.photos[i].name + ": " + why);
      continue;
    }
    FrameEntry e;
    e.frame = static_cast<int64_t>(i);
    e.image = set.photos[i].name;
    e.t_first_row_ns = *clock.placements[i].t_ns + latency_ns;
    input.velocity[e.frame] =
        VelocityOfPhoto(set.photos[i], log, e.t_first_row_ns + readout_half_ns,
                        dataset.declared.cam_from_gyro, mounting_source);
    dataset.frames.push_back(std::move(e));
  }

  if (dataset.frames.empty()) {
    throw IoError(IoMessage(
        set.source, 0,
        "no photo could be corrected" +
            (input.skipped.empty() ? std::string() : " (" + input.skipped[0].second + ")")));
  }
  input.notes.push_back("camera: " + input.camera_source);
  input.notes.push_back(
      "photos placed on " + fs::path(options.log_path).filename().string() + ": " + clock.method +
      (latency_ns != 0 ? FormatNumber(", latency %g ms", options.trigger_latency_s * 1e3)
                       : std::string()));
  input.notes.push_back("ground plane height: " + input.altitude_source);
  AddMountingNotes(set, options, &input);
  return input;
}

}  // namespace shutterlab
