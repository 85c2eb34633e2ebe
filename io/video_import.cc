#include "io/video_import.h"

#include "io/clip_alignment.h"
#include "io/codecs.h"
#include "io/frames_csv.h"
#include "io/image_io.h"
#include "io/lens_profile.h"
#include "io/rig_dataset.h"
#include "model/camera.h"
#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gopro_telemetry.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/phone_clip.h"
#include "sim/text_file.h"
#include "sim/trace_audit.h"
#include "sim/units.h"

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <unistd.h>

namespace shutterlab {
namespace fs = std::filesystem;
namespace {

// GoPro HERO5 Black, Wide field of view, 16:9 video: GoPro's published horizontal field of view.
// The lens is a fisheye; an equidistant projection over that field gives the focal length declared
// as a pinhole with no distortion (a guess: karma.mp4 is an 854x480 copy and states no lens).
constexpr double kHero5WideHfovDeg = 118.2;
// Full-frame readout of the HERO5 in this mode is not published; a guess of the usual order for
// its 1080p/30 modes, to be fitted by validate.
constexpr double kHero5ReadoutGuessS = 0.015;
// The readout declared for a video that states none (no camera.json, a profile without one): the
// usual order of consumer cameras' video modes, for validate to fit.
constexpr double kVideoReadoutGuessS = 0.015;
// OpenCV's reader fails an occasional grab and then goes on (OpenCV 4.6 on karma.mp4: once, near
// frame 29); this many failures in a row means the end.
constexpr int kMaxConsecutiveGrabFailures = 8;
constexpr size_t kWriteBatch =
    32;  // frames held in memory for parallel PNG writing (~40 MB at 854x480)

// The phone clip's calibration, as the source repository's example states it (the shared data
// folder's SOURCES.md).
constexpr double kPhoneFx = 573.8534, kPhoneFy = 575.0448, kPhoneCx = 406.0101, kPhoneCy = 309.0112;
constexpr double kPhoneSkew = -0.6974;
constexpr double kPhoneFullFrameS = 0.033312;

// Frame ids [first, end) of the ids available, after --start-frame and --max-frames.
std::vector<int64_t> SelectFrames(const std::vector<int64_t>& ids, const ImportOptions& options) {
  std::vector<int64_t> selected;
  for (int64_t id : ids) {
    if (options.start_frame >= 0 && id < options.start_frame) continue;
    if (options.max_frames >= 0 && static_cast<int64_t>(selected.size()) >= options.max_frames)
      break;
    selected.push_back(id);
  }
  if (selected.empty())
    throw IoError(IoMessage(
        options.source, -1,
        "no frame to import with --start-frame " + std::to_string(options.start_frame) +
            " (frames " +
            (ids.empty() ? std::string("none")
                         : std::to_string(ids.front()) + ".." + std::to_string(ids.back())) +
            ")"));
  return selected;
}

// A dataset folder under construction: removed unless Commit() moved it to its final place.
class StagingDir {
 public:
  explicit StagingDir(const std::string& out_dir) : out_(fs::absolute(out_dir).lexically_normal()) {
    if (!out_.has_filename()) out_ = out_.parent_path();  // "DIR/" names DIR
    const fs::path parent = out_.parent_path().empty() ? fs::path(".") : out_.parent_path();
    if (!fs::is_directory(parent))
      throw IoError(IoMessage(out_dir, -1, "its parent folder does not exist"));
    if (fs::exists(out_) && !fs::is_empty(out_) && !fs::exists(out_ / "import.json"))
      throw IoError(IoMessage(out_dir, -1, "exists and is not an import; not overwritten"));
    staging_ = parent / (out_.filename().string() + ".importing-" + std::to_string(::getpid()));
    fs::remove_all(staging_);
    fs::create_directories(staging_ / "images");
  }
  ~StagingDir() {
    std::error_code ec;
    if (!committed_) fs::remove_all(staging_, ec);
  }
  const fs::path& path() const { return staging_; }
  void Commit() {
    std::error_code ec;
    const fs::path old = staging_.string() + ".old";
    if (fs::exists(out_)) fs::rename(out_, old);
    fs::rename(staging_, out_);
    committed_ = true;
    fs::remove_all(old, ec);
  }

 private:
  fs::path out_, staging_;
  bool committed_ = false;
};

// GoPro's own axis labels (gpmf-parser's README, "IMU Orientation Uses These Axis Labels") in the
// camera frame of docs/FORMATS.md: X forward along the optical axis, Y to the left, Z up; so camera
// x = -Y, y = -Z, z = X.
Eigen::Matrix3d GoproCamFromImu() {
  Eigen::Matrix3d cam_from_imu;
  cam_from_imu << 0, -1, 0,  //
      0, 0, -1,              //
      1, 0, 0;
  return cam_from_imu;
}

RigModel BaseRig(int width, int height) {
  RigModel rig;
  rig.camera.width = width;
  rig.camera.height = height;
  rig.shutter.direction = ReadoutDirection::kTopToBottom;
  rig.altitude_m =
      50.0;  // not used by a rotation-only video comparison; docs/FORMATS.md requires one
  return rig;
}

ImportSummary WriteDataset(const fs::path& dir, ImportSource kind, const RigModel& rig,
                           const GyroTrace& gyro, const std::vector<FrameEntry>& frames,
                           ImportRecord record) {
  rig.Check();
  // Every frame is kept; those whose declared readout the gyro log does not cover are listed
  // (karma.mp4's gyro starts 8 ms after its first frame), so that a consumer can skip them.
  record.outside_gyro.clear();
  for (const FrameEntry& frame : frames) {
    const int64_t t0_ns = frame.t_first_row_ns + SecondsToNs(rig.time_offset_s);
    if (t0_ns < gyro.t_begin_ns() || t0_ns + SecondsToNs(rig.shutter.readout_s) > gyro.t_end_ns())
      record.outside_gyro.push_back(frame.frame);
  }
  WriteRigModel((dir / "camera.json").string(), rig);
  WriteGyroCsv((dir / "gyro.csv").string(), gyro);
  WriteFramesCsv((dir / "frames.csv").string(), frames);
  WriteImportJson((dir / "import.json").string(), record);
  ImportSummary summary;
  summary.kind = kind;
  summary.gyro_samples = gyro.size();
  summary.gyro_rate_hz = record.gyro_rate_hz;
  summary.frames = frames.size();
  summary.t_first_s = frames.front().t_first_row_ns * 1e-9;
  summary.t_last_s = frames.back().t_first_row_ns * 1e-9;
  summary.record = std::move(record);
  return summary;
}

// Writes (path, RGB image) pairs in parallel and empties *pending: encoding a PNG takes several
// times longer than decoding the frame. The first failure is thrown once all are done.
void WriteImagesInParallel(std::vector<std::pair<std::string, cv::Mat>>* pending) {
  std::mutex mutex;
  std::string error;
  cv::parallel_for_(cv::Range(0, static_cast<int>(pending->size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      try {
        WriteImage((*pending)[i].first, (*pending)[i].second);
      } catch (const std::exception& e) {  // exceptions must not cross the worker threads
        std::lock_guard<std::mutex> lock(mutex);
        if (error.empty()) error = e.what();
      }
    }
  });
  pending->clear();
  if (!error.empty()) throw IoError(error);
}

// The selected frames as OpenCV decoded them, written under the dataset folder, with what the
// decoding met.
struct DecodedFrames {
  std::vector<FrameEntry> entries;
  std::vector<FrameExposure> exposures;
  cv::Size size;
  int64_t decoded = 0;  // index of the next frame the reader returns
  int failures = 0, time_mismatches = 0;
};

DecodedFrames DecodeSelectedFrames(const std::string& path, const fs::path& dir,
                                   const GoproTelemetry& telemetry,
                                   const std::vector<double>& frame_times_s,
                                   const std::vector<int64_t>& selected,
                                   const std::function<void(size_t, size_t)>& progress) {
  VideoFrames video(path);
  DecodedFrames out;
  cv::Mat frame;
  // Frames are written in batches of kWriteBatch, in parallel.
  std::vector<std::pair<std::string, cv::Mat>> pending;
  const auto flush = [&] {
    WriteImagesInParallel(&pending);
    if (progress) progress(out.entries.size(), selected.size());
  };
  int consecutive = 0;
  const double period_s =
      frame_times_s.size() > 1
          ? (frame_times_s.back() - frame_times_s.front()) / (frame_times_s.size() - 1)
          : 0.0;
  while (out.decoded <= selected.back() && consecutive < kMaxConsecutiveGrabFailures) {
    double reader_ms = 0;
    if (!video.Read(&frame, &reader_ms)) {
      ++out.failures;
      ++consecutive;
      continue;
    }
    consecutive = 0;
    const int64_t index = out.decoded++;
    // After a read OpenCV reports the time of the frame it returned (not for the first or last);
    // a disagreement with the sample table would mean a frame was dropped.
    const double reader_s = reader_ms * 1e-3;
    if (index > 0 && index + 1 < static_cast<int64_t>(frame_times_s.size()) && period_s > 0 &&
        std::abs(reader_s - frame_times_s[index]) > 0.5 * period_s)
      ++out.time_mismatches;
    if (index < selected.front()) continue;
    if (out.size.empty()) out.size = frame.size();
    if (frame.size() != out.size)
      throw IoError(IoMessage(path, -1, "frame " + std::to_string(index) + " changes size"));
    FrameEntry entry;
    entry.frame = index;
    entry.t_first_row_ns = SecondsToNs(frame_times_s[index]);
    entry.image = "images/" + FrameName(index) + ".png";
    cv::Mat rgb;
    cv::cvtColor(frame, rgb, frame.channels() == 4 ? cv::COLOR_BGRA2RGB : cv::COLOR_BGR2RGB);
    pending.emplace_back((dir / entry.image).string(), rgb);
    out.entries.push_back(entry);
    out.exposures.push_back({index, NearestShutterS(telemetry, frame_times_s[index], period_s)});
    if (pending.size() >= kWriteBatch) flush();
  }
  flush();
  return out;
}

VideoDecoding Decoding(const DecodedFrames& frames, size_t video_samples) {
  return {video_samples, frames.decoded, frames.failures, frames.time_mismatches};
}

// The HERO5 Black's declared rig for frames of `size`: the Wide field of view's focal length, the
// readout guess and the sensor-to-camera axes.
RigModel Hero5Rig(const cv::Size& size) {
  RigModel rig = BaseRig(size.width, size.height);
  const double f_px = 0.5 * rig.camera.width / (0.5 * kHero5WideHfovDeg * kPi / 180.0);
  rig.camera.fx = rig.camera.fy = f_px;
  rig.camera.cx = 0.5 * (rig.camera.width - 1);
  rig.camera.cy = 0.5 * (rig.camera.height - 1);
  rig.shutter.readout_s = kHero5ReadoutGuessS;
  // Sensor axes -> camera axes. In karma.mp4 the accelerometer (same stream layout) reads +9.7
  // m/s^2 on the sensor's z with the gimbal level, and the horizontal image shift follows the z
  // rate (correlation 0.99): z points up, camera y = -z. The gimbal holds pitch and roll, so the
  // clip cannot tell x from y: x along the optical axis and y to the left complete a right-handed
  // frame.
  rig.cam_from_gyro = GoproCamFromImu();
  return rig;
}

// What a GoPro import declares: the rig and, for each number of it, where it came from.
struct GoproDeclaration {
  RigModel rig;
  std::vector<ImportClaim> claims;
  std::optional<LensProfileUse> lens;
};

// The HERO5's declaration as it has always been (karma.mp4): every number a guess or an inference.
GoproDeclaration Hero5Declaration(const cv::Size& size) {
  GoproDeclaration d;
  d.rig = Hero5Rig(size);
  const RigModel& rig = d.rig;
  d.claims = {
      ImportClaim{"intrinsics",
                  std::map<std::string, double>{{"fx", rig.camera.fx},
                                                {"fy", rig.camera.fy},
                                                {"cx", rig.camera.cx},
                                                {"cy", rig.camera.cy}},
                  ClaimStatus::kGuess,
                  "equidistant focal length over GoPro's published 118.2 deg horizontal field of "
                  "view (HERO5 Black, Wide); pinhole with no distortion declared although the lens "
                  "is a fisheye"},
      ImportClaim{"readout_s", kHero5ReadoutGuessS, ClaimStatus::kGuess,
                  "not published for the HERO5; order of magnitude only"},
      ImportClaim{"gyro_to_camera", rig.cam_from_gyro, ClaimStatus::kInferred,
                  "camera y = -sensor z: the accelerometer's mean is +9.7 m/s^2 on z, and the "
                  "horizontal image shift between frames follows the integrated z rate "
                  "(correlation 0.99, checked when this importer was written). x forward, y left "
                  "is a guess: the gimbal holds pitch and roll, so the clip cannot tell x from y"},
      ImportClaim{"direction", std::string(ReadoutDirectionName(rig.shutter.direction)),
                  ClaimStatus::kGuess, "CMOS default"},
      ImportClaim{"time_offset_s", 0.0, ClaimStatus::kGuess,
                  "telemetry and video share the MP4 timeline"}};
  return d;
}

std::map<std::string, double> IntrinsicsClaim(const PinholeCamera& camera) {
  return {{"fx", camera.fx}, {"fy", camera.fy}, {"cx", camera.cx}, {"cy", camera.cy}};
}

std::string Joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& line : lines) out += (out.empty() ? "" : "; ") + line;
  return out;
}

// The lens: a lens profile's, else an equidistant fisheye over the camera's diagonal field of view
// (ZFOV), else the HERO5's pinhole guess.
void DeclareGoproLens(const GoproTelemetry& t, const cv::Size& size, std::optional<double> fps,
                      const std::optional<LensProfile>& profile, GoproDeclaration* d) {
  RigModel& rig = d->rig;
  if (profile) {
    d->lens = ScaleLensProfile(*profile, size.width, size.height, fps);
    rig.camera = d->lens->camera;
    const std::string source =
        "Gyroflow " +
        Joined({d->lens->notes.begin(), d->lens->notes.begin() + 1 + d->lens->aspect_differs});
    d->claims.push_back(
        {"intrinsics", IntrinsicsClaim(rig.camera), ClaimStatus::kSourceClaim, source});
    d->claims.push_back(
        {"lens_distortion", rig.camera.distortion, ClaimStatus::kSourceClaim, source});
    return;
  }
  rig.camera.cx = 0.5 * (size.width - 1);
  rig.camera.cy = 0.5 * (size.height - 1);
  if (t.settings.diagonal_fov_deg && *t.settings.diagonal_fov_deg > 0 &&
      *t.settings.diagonal_fov_deg < 360) {
    // Equidistant: the corner's distance from the centre is f times its angle off the axis.
    const double half_diagonal_px = 0.5 * std::hypot(size.width, size.height);
    rig.camera.fx = rig.camera.fy =
        half_diagonal_px / (0.5 * *t.settings.diagonal_fov_deg * kRadPerDeg);
    rig.camera.distortion = Fisheye();
    const std::string source =
        "an equidistant fisheye whose image diagonal spans the camera's ZFOV " +
        FormatNumber("%.2f", *t.settings.diagonal_fov_deg) +
        " deg (GPMF global settings), principal point at the image centre; no lens profile given";
    d->claims.push_back(
        {"intrinsics", IntrinsicsClaim(rig.camera), ClaimStatus::kInferred, source});
    d->claims.push_back({"lens_distortion", rig.camera.distortion, ClaimStatus::kInferred, source});
    return;
  }
  const RigModel hero5 = Hero5Rig(size);
  rig.camera = hero5.camera;
  d->claims.push_back({"intrinsics", IntrinsicsClaim(rig.camera), ClaimStatus::kGuess,
                       "equidistant focal length over the HERO5 Black's published 118.2 deg "
                       "horizontal field of view, pinhole; the clip states no field of view"});
}

// A GoPro that states its own facts (global settings: HERO8, MAX and later), or any GoPro with a
// lens profile: the lens (DeclareGoproLens), the readout (SROT, else the profile's, else a guess),
// the axes (the camera's own X, Y, Z: ORIN / ORIO / MTRX, then GoPro's labels), the stabiliser.
GoproDeclaration GoproDeclared(const GoproTelemetry& t, const cv::Size& size,
                               std::optional<double> fps,
                               const std::optional<LensProfile>& profile) {
  GoproDeclaration d;
  d.rig = BaseRig(size.width, size.height);
  RigModel& rig = d.rig;
  DeclareGoproLens(t, size, fps, profile, &d);
  const GoproSettings& s = t.settings;
  if (s.readout_s) {
    rig.shutter.readout_s = *s.readout_s;
    d.claims.push_back(
        {"readout_s", *s.readout_s, ClaimStatus::kSourceClaim,
         "GPMF SROT (global settings): the sensor readout time as the camera wrote "
         "it" +
             std::string(d.lens && d.lens->readout
                             ? "; it wins over the lens profile's " +
                                   FormatNumber("%.3f", *d.lens->readout->readout_s * 1e3) + " ms"
                             : "")});
  } else if (d.lens && d.lens->readout) {
    ApplyLensProfile(&*d.lens, &rig);
    d.claims.push_back({"readout_s", rig.shutter.readout_s, ClaimStatus::kSourceClaim,
                        "Gyroflow lens profile " + d.lens->name + ": " +
                            d.lens->notes[1 + d.lens->aspect_differs]});
  } else {
    rig.shutter.readout_s = kHero5ReadoutGuessS;
    d.claims.push_back({"readout_s", kHero5ReadoutGuessS, ClaimStatus::kGuess,
                        "neither the clip (no SROT) nor a lens profile states it; order of "
                        "magnitude only"});
  }
  if (d.lens && s.readout_s && d.lens->readout) {
    ApplyLensProfile(&*d.lens, &rig, /*keep_readout=*/true);
  }
  rig.cam_from_gyro = GoproCamFromImu();
  if (!t.gyro_orin.empty()) {
    std::string up;
    if (t.accel_mean_mps2) {
      up = "; the accelerometer's mean on these axes is (" +
           FormatNumber("%.2f", t.accel_mean_mps2->x()) + ", " +
           FormatNumber("%.2f", t.accel_mean_mps2->y()) + ", " +
           FormatNumber("%.2f", t.accel_mean_mps2->z()) + ") m/s^2";
    }
    d.claims.push_back({"gyro_to_camera", rig.cam_from_gyro, ClaimStatus::kSourceClaimInferred,
                        "the camera's " + t.axis_order_source +
                            " put GYRO on its own axes X, Y, Z (gyro.csv gx, gy, gz); Z up (as "
                            "on the HERO5's karma.mp4), X forward and Y left as assumed for the "
                            "HERO5, whose gimbal could not tell them apart" +
                            up});
  } else {
    for (const ImportClaim& claim : Hero5Declaration(size).claims) {
      if (claim.what == "gyro_to_camera") d.claims.push_back(claim);  // the HERO5's inference
    }
  }
  d.claims.push_back({"direction", std::string(ReadoutDirectionName(rig.shutter.direction)),
                      ClaimStatus::kGuess,
                      s.model.find("Max") != std::string::npos
                          ? "CMOS default; a MAX's HERO mode is reprojected from one of its two "
                            "fisheyes, so its rows need not be sensor rows"
                          : "CMOS default"});
  d.claims.push_back(
      {"time_offset_s", 0.0, ClaimStatus::kGuess, "telemetry and video share the MP4 timeline"});
  if (!s.stabilizer.empty()) {
    const std::string value =
        s.StabilizerOn()
            ? "on (" + (s.stabilizer_mode.empty() ? std::string("EISE Y") : s.stabilizer_mode) + ")"
            : "off";
    d.claims.push_back(
        {"stabilizer", value, ClaimStatus::kSourceClaim,
         "GPMF global settings EISE '" + s.stabilizer + "', EISA '" + s.stabilizer_mode + "'" +
             (s.StabilizerOn()
                  ? ": the camera re-rendered each image from its own orientation estimate, so "
                    "the image does not follow the body gyro (its per-frame correction, IORI, is "
                    "in image_orientation.csv); a claim to test before trusting any fit"
                  : "")});
  }
  return d;
}

// import.json for a GoPro clip: the source, the clock, the gyro stream and frames as read, and the
// declaration's claims.
ImportRecord GoproRecord(const std::string& path, const GoproTelemetry& telemetry,
                         const GoproDeclaration& declared, const DecodedFrames& frames,
                         size_t video_samples) {
  ImportRecord record;
  record.path = path;
  record.time_origin_s = 0.0;
  record.clock =
      "movie timeline of the MP4 (s); gyro and frames share it, time_offset_s 0 declared";
  record.gyro_samples = telemetry.gyro.size();
  record.gyro_rate_hz = telemetry.gyro_rate_hz;
  record.gyro_columns = telemetry.gyro_orin.empty()
                            ? "gyro.csv gx,gy,gz = the sensor's x, y, z (GPMF storage reordered)"
                            : "gyro.csv gx,gy,gz = the camera's own axes X, Y, Z (" +
                                  telemetry.axis_order_source + ")";
  record.warnings = AuditTrace(telemetry.gyro);
  record.frame_count = frames.entries.size();
  record.t_first_row = "frame presentation time; what it marks in the exposure is unknown";
  record.exposures = frames.exposures;
  GoproImportDetails gopro;
  gopro.device = telemetry.device;
  gopro.stream_name = telemetry.gyro_name;
  gopro.axis_order = telemetry.axis_order_source;
  gopro.scal = telemetry.gyro_scale;
  gopro.payload_samples = telemetry.gyro_payload_samples;
  gopro.timing =
      "one least-squares line of payload start time (gpmd sample table) against samples before it";
  gopro.fit_max_residual_s = telemetry.gyro_fit_max_residual_s;
  gopro.decoding = Decoding(frames, video_samples);
  gopro.times = "presentation times of the MP4 video track (stts/ctts/elst)";
  gopro.gyro_orin = telemetry.gyro_orin;
  gopro.gyro_orio = telemetry.gyro_orio;
  gopro.gyro_mtrx = telemetry.gyro_mtrx;
  gopro.settings = telemetry.settings;
  record.details = std::move(gopro);
  record.claims = declared.claims;
  record.lens_profile = declared.lens;
  return record;
}

// Angle of a rotation quaternion (w, x, y, z), deg.
double QuaternionAngleDeg(const std::array<double, 4>& q) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  return norm > 0 ? 2.0 * std::acos(std::min(1.0, std::abs(q[0]) / norm)) * kDegPerRad : 0.0;
}

// The sample of a per-frame stream nearest in time to t_s, within half a frame period.
std::optional<size_t> NearestSample(const GoproQuaternions& q, double t_s, double period_s) {
  if (q.empty()) return std::nullopt;
  const size_t k = std::lower_bound(q.t_s.begin(), q.t_s.end(), t_s) - q.t_s.begin();
  size_t best = std::min(k, q.t_s.size() - 1);
  if (k > 0 && std::abs(q.t_s[k - 1] - t_s) < std::abs(q.t_s[best] - t_s)) best = k - 1;
  if (std::abs(q.t_s[best] - t_s) <= 0.5 * period_s) return best;
  return std::nullopt;
}

// image_orientation.csv: for each imported frame its IORI and CORI samples (docs/FORMATS.md
// "Import output"); the counts go into import.json. Nothing is written without IORI and CORI.
void WriteImageOrientation(const fs::path& dir, const GoproTelemetry& t,
                           const std::vector<FrameEntry>& frames, double period_s,
                           GoproImportDetails* gopro) {
  gopro->iori_samples = t.image_orientation.t_s.size();
  gopro->cori_samples = t.camera_orientation.t_s.size();
  if (t.image_orientation.empty() && t.camera_orientation.empty()) return;
  std::string text =
      "frame,t,iori_t,iori_w,iori_x,iori_y,iori_z,cori_t,cori_w,cori_x,cori_y,cori_z\n";
  const auto sample = [&](const GoproQuaternions& q, std::optional<size_t> i) {
    if (!i) return std::string(",,,,");
    std::string out = FormatNumber("%.6f", q.t_s[*i]);
    for (double c : q.wxyz[*i]) out += "," + FormatNumber("%.6f", c);
    return out;
  };
  for (const FrameEntry& frame : frames) {
    const double t_s = frame.t_first_row_ns * 1e-9;
    const std::optional<size_t> iori = NearestSample(t.image_orientation, t_s, period_s);
    const std::optional<size_t> cori = NearestSample(t.camera_orientation, t_s, period_s);
    if (iori || cori) ++gopro->orientation_frames;
    if (iori) {
      gopro->iori_max_deg =
          std::max(gopro->iori_max_deg, QuaternionAngleDeg(t.image_orientation.wxyz[*iori]));
    }
    text += std::to_string(frame.frame) + "," + FormatNumber("%.6f", t_s) + "," +
            sample(t.image_orientation, iori) + "," + sample(t.camera_orientation, cori) + "\n";
  }
  WriteFileAtomically((dir / "image_orientation.csv").string(), text);
}

ImportSummary ImportGopro(const ImportOptions& options, const FlightLog* log,
                          const std::optional<LensProfile>& profile, const fs::path& dir,
                          const std::function<void(size_t, size_t)>& progress) {
  const std::string& path = options.source;
  const GoproTelemetry telemetry = ReadGoproTelemetry(path);
  const std::vector<double> frame_times_s = ReadVideoFrameTimesS(path);
  std::vector<int64_t> ids(frame_times_s.size());
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<int64_t>(i);
  const std::vector<int64_t> selected = SelectFrames(ids, options);

  const DecodedFrames frames =
      DecodeSelectedFrames(path, dir, telemetry, frame_times_s, selected, progress);
  if (frames.entries.empty())
    throw IoError(IoMessage(path, -1, "OpenCV decoded no frame of the selection"));
  if (static_cast<int64_t>(frames.entries.size()) < static_cast<int64_t>(selected.size()))
    std::fprintf(stderr, "warning: %s: OpenCV decoded %zu of the %zu frames selected\n",
                 path.c_str(), frames.entries.size(), selected.size());
  const double period_s =
      frame_times_s.size() > 1
          ? (frame_times_s.back() - frame_times_s.front()) / (frame_times_s.size() - 1)
          : 0.0;
  const std::optional<double> fps =
      period_s > 0 ? std::optional<double>(1.0 / period_s) : std::nullopt;
  // A clip that states nothing about itself (the HERO5's karma.mp4) and no profile: as always.
  const GoproDeclaration declared = telemetry.settings.present || profile
                                        ? GoproDeclared(telemetry, frames.size, fps, profile)
                                        : Hero5Declaration(frames.size);
  ImportRecord record = GoproRecord(path, telemetry, declared, frames, frame_times_s.size());
  WriteImageOrientation(dir, telemetry, frames.entries, period_s,
                        &std::get<GoproImportDetails>(record.details));
  RigModel rig = declared.rig;
  const GyroTrace gyro = !log ? telemetry.gyro
                              : AlignGyroLog(*log, options.gyro_log, frames.entries, dir.string(),
                                             cv::Mat(), &telemetry.gyro, &rig, &record);
  return WriteDataset(dir, ImportSource::kGoproMp4, rig, gyro, frames.entries, std::move(record));
}

// The phone clip's declared rig for frames of `size`: the source's calibration and full-frame
// time, and the gyro-to-camera axes.
RigModel PhoneRig(const cv::Size& size) {
  RigModel rig = BaseRig(size.width, size.height);
  rig.camera.fx = kPhoneFx;
  rig.camera.fy = kPhoneFy;
  rig.camera.cx = kPhoneCx;
  rig.camera.cy = kPhoneCy;
  rig.shutter.readout_s = kPhoneFullFrameS;
  // The source says the gyro x axis is the camera y axis. Android's sensor axes (natural portrait:
  // x right, y up, z out of the screen) and the usual rear-camera sensor orientation (90 degrees:
  // the sensor's top row lies along device +x) give the signs: camera x = -gyro y, y = -gyro x, z =
  // -gyro z.
  Eigen::Matrix3d cam_from_gyro;
  cam_from_gyro << 0, -1, 0,  //
      -1, 0, 0,               //
      0, 0, -1;
  rig.cam_from_gyro = cam_from_gyro;
  return rig;
}

// import.json for a phone clip: the source, the clock, the gyro and frames as read, and the
// source's claims.
ImportRecord PhoneRecord(const std::string& path, const PhoneClip& clip, const RigModel& rig,
                         size_t frame_count, std::vector<FrameExposure> exposures) {
  ImportRecord record;
  record.path = path;
  record.time_origin_s = clip.time_origin_ns * 1e-9;
  record.clock = "device monotonic clock minus time_origin_s; gyro and frames share it";
  record.gyro_samples = clip.gyro.size();
  record.gyro_rate_hz = clip.gyro.sampling().RateHz();
  record.gyro_columns = "gyro.txt gx,gy,gz (rad/s), the phone's sensor axes";
  record.warnings = clip.warnings;
  for (LogWarning& warning : AuditTrace(clip.gyro)) record.warnings.push_back(std::move(warning));
  record.frame_count = frame_count;
  record.t_first_row = "start-of-frame time from framestamp.txt (line N = frame N)";
  record.exposures = std::move(exposures);
  PhoneImportDetails phone;
  phone.origin = "lhaippp/gyro-video-stabilization 20200109_145447 (MIT)";
  phone.sof_times = clip.sof_ns.size();
  phone.images_in_source = clip.frame_images.size();
  phone.dump_sof_max_diff_s = clip.dump_sof_max_diff_s;
  phone.exposure_min_s = INFINITY;
  phone.exposure_max_s = -INFINITY;
  for (const auto& [frame, value] : clip.exposure_s) {
    phone.exposure_min_s = std::min(phone.exposure_min_s, value);
    phone.exposure_max_s = std::max(phone.exposure_max_s, value);
  }
  record.details = std::move(phone);
  record.claims = {
      ImportClaim{"intrinsics",
                  std::map<std::string, double>{{"fx", kPhoneFx},
                                                {"fy", kPhoneFy},
                                                {"cx", kPhoneCx},
                                                {"cy", kPhoneCy},
                                                {"skew", kPhoneSkew}},
                  ClaimStatus::kSourceClaim,
                  "the source repository's example K for the 800x600 frames; its skew is not in "
                  "rig/1 and is dropped"},
      ImportClaim{"readout_s", kPhoneFullFrameS, ClaimStatus::kSourceClaim,
                  "the example's full-frame time"},
      ImportClaim{"gyro_to_camera", rig.cam_from_gyro, ClaimStatus::kSourceClaimInferred,
                  "the example's comment that the gyro x axis is the camera y axis; signs from "
                  "Android's sensor axes and the usual 90 degree rear-camera sensor orientation. "
                  "The image shift between the 20 frames against the integrated rates agreed when "
                  "this importer was written (correlation 0.91 for u, 0.95 for v)"},
      ImportClaim{"frame_images", std::string("RE_frame-N is frame N of framestamp.txt"),
                  ClaimStatus::kSourceClaim, "inferred from the example, not verified"},
      ImportClaim{"direction", std::string(ReadoutDirectionName(rig.shutter.direction)),
                  ClaimStatus::kGuess, "CMOS default"},
      ImportClaim{
          "time_offset_s", 0.0, ClaimStatus::kGuess,
          "gyro and SOF times are on the same device clock; SOF marks the start of the frame"}};
  return record;
}

ImportSummary ImportPhone(const ImportOptions& options, const FlightLog* log,
                          const std::optional<LensProfile>& profile, const fs::path& dir,
                          const std::function<void(size_t, size_t)>& progress) {
  const PhoneClip clip = ReadPhoneClip(options.source);
  std::vector<int64_t> ids;
  for (const auto& [frame, image] : clip.frame_images) ids.push_back(frame);
  const std::vector<int64_t> selected = SelectFrames(ids, options);
  std::vector<FrameEntry> entries;
  std::vector<FrameExposure> exposures;
  cv::Size size;
  for (int64_t frame : selected) {
    const std::string& source_image = clip.frame_images.at(frame);
    // The image is checked (it must decode, all of one size) but copied byte for byte: no
    // re-encoding.
    const cv::Mat image = ReadImage(source_image);
    if (size.area() == 0) size = image.size();
    if (image.size() != size)
      throw IoError(IoMessage(source_image, -1,
                              "size " + std::to_string(image.cols) + "x" +
                                  std::to_string(image.rows) + " differs from the first frame's"));
    FrameEntry entry;
    entry.frame = frame;
    entry.t_first_row_ns = clip.sof_ns[frame - 1];
    entry.image = "images/" + FrameName(frame) + fs::path(source_image).extension().string();
    fs::copy_file(source_image, dir / entry.image, fs::copy_options::overwrite_existing);
    entries.push_back(entry);
    const auto exposure = clip.exposure_s.find(frame);
    exposures.push_back({frame, exposure == clip.exposure_s.end()
                                    ? std::nullopt
                                    : std::optional<double>(exposure->second)});
    if (progress) progress(entries.size(), selected.size());
  }
  RigModel rig = PhoneRig(size);
  ImportRecord record =
      PhoneRecord(options.source, clip, rig, entries.size(), std::move(exposures));
  if (profile) {
    // The profile's lens and readout replace the example's calibration, and say so.
    LensProfileUse use = ScaleLensProfile(*profile, size.width, size.height);
    ApplyLensProfile(&use, &rig);
    for (ImportClaim& claim : record.claims) {
      const std::string source = "Gyroflow " + use.notes.front();
      if (claim.what == "intrinsics")
        claim = {"intrinsics", IntrinsicsClaim(rig.camera), ClaimStatus::kSourceClaim, source};
      if (claim.what == "readout_s" && use.readout)
        claim = {"readout_s", rig.shutter.readout_s, ClaimStatus::kSourceClaim,
                 "Gyroflow lens profile " + use.name + ": frame_readout_time"};
    }
    record.claims.push_back({"lens_distortion", rig.camera.distortion, ClaimStatus::kSourceClaim,
                             "Gyroflow " + use.notes.front()});
    record.lens_profile = use;
  }
  const GyroTrace gyro = !log ? clip.gyro
                              : AlignGyroLog(*log, options.gyro_log, entries, dir.string(),
                                             cv::Mat(), &clip.gyro, &rig, &record);
  return WriteDataset(dir, ImportSource::kPhoneFolder, rig, gyro, entries, std::move(record));
}

// The camera a video without a gyro of its own declares: camera.json's (--camera), else the lens
// profile's, with a claim for each number.
RigModel VideoFileRig(const ImportOptions& options, const std::optional<LensProfile>& profile,
                      const cv::Size& size, ImportRecord* record) {
  RigModel rig = BaseRig(size.width, size.height);
  std::string source;
  if (!options.camera_path.empty()) {
    rig = ReadRigModel(options.camera_path);
    rig.mask.clear();  // relative to the camera.json given; import --mask makes the dataset's
    if (rig.camera.width != size.width || rig.camera.height != size.height)
      throw IoError(IoMessage(options.camera_path, -1,
                              "declares " + std::to_string(rig.camera.width) + "x" +
                                  std::to_string(rig.camera.height) +
                                  " but the clip's frames are " + std::to_string(size.width) + "x" +
                                  std::to_string(size.height)));
    source = "--camera " + options.camera_path;
    record->claims.push_back(
        {"readout_s", rig.shutter.readout_s, ClaimStatus::kSourceClaim, source});
  } else {
    LensProfileUse use = ScaleLensProfile(*profile, size.width, size.height);
    rig.shutter.readout_s = kVideoReadoutGuessS;
    ApplyLensProfile(&use, &rig);
    source = "Gyroflow " + use.notes.front();
    record->claims.push_back(
        use.readout ? ImportClaim{"readout_s", rig.shutter.readout_s, ClaimStatus::kSourceClaim,
                                  "Gyroflow lens profile " + use.name + ": frame_readout_time"}
                    : ImportClaim{"readout_s", kVideoReadoutGuessS, ClaimStatus::kGuess,
                                  "the clip and the profile state none; the usual order of "
                                  "consumer cameras' video modes"});
    record->lens_profile = use;
  }
  record->claims.push_back(
      {"intrinsics", IntrinsicsClaim(rig.camera), ClaimStatus::kSourceClaim, source});
  if (rig.camera.HasDistortion())
    record->claims.push_back(
        {"lens_distortion", rig.camera.distortion, ClaimStatus::kSourceClaim, source});
  record->claims.push_back(
      {"direction", std::string(ReadoutDirectionName(rig.shutter.direction)),
       options.camera_path.empty() ? ClaimStatus::kGuess : ClaimStatus::kSourceClaim,
       options.camera_path.empty() ? "CMOS default" : source});
  return rig;
}

// Any MP4 or MOV without a gyro of its own, with --gyro LOG: its frames as a GoPro's, its camera
// from --camera or --lens-profile, its gyro the log's (AlignGyroLog by the frames' rotation).
ImportSummary ImportVideoFile(const ImportOptions& options, const FlightLog* log,
                              const std::optional<LensProfile>& profile, const fs::path& dir,
                              const std::function<void(size_t, size_t)>& progress) {
  const std::string& path = options.source;
  const std::vector<double> frame_times_s = ReadVideoFrameTimesS(path);
  std::vector<int64_t> ids(frame_times_s.size());
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<int64_t>(i);
  const std::vector<int64_t> selected = SelectFrames(ids, options);
  const DecodedFrames frames =
      DecodeSelectedFrames(path, dir, GoproTelemetry{}, frame_times_s, selected, progress);
  if (frames.entries.size() < 2)
    throw IoError(IoMessage(path, -1,
                            "OpenCV decoded " + std::to_string(frames.entries.size()) +
                                " frame(s) of the selection; aligning a log needs the motion "
                                "between frames"));
  ImportRecord record;
  record.path = path;
  record.frame_count = frames.entries.size();
  record.t_first_row = "frame presentation time; what it marks in the exposure is unknown";
  record.exposures = frames.exposures;
  record.details = VideoFileImportDetails{Decoding(frames, frame_times_s.size())};
  RigModel rig = VideoFileRig(options, profile, frames.size, &record);
  const cv::Mat mask = options.mask_path.empty()
                           ? cv::Mat()
                           : ReadMask(options.mask_path, frames.size.width, frames.size.height);
  const GyroTrace gyro = AlignGyroLog(*log, options.gyro_log, frames.entries, dir.string(), mask,
                                      nullptr, &rig, &record, progress);
  return WriteDataset(dir, ImportSource::kVideoFile, rig, gyro, frames.entries, std::move(record));
}

}  // namespace

void ImportOptions::Check() const {
  SHUTTERLAB_CHECK(!source.empty()) << "SOURCE is empty";
  SHUTTERLAB_CHECK(!out_dir.empty()) << "--out is empty";
  SHUTTERLAB_CHECK(max_frames == -1 || max_frames >= 1) << "--max-frames must be at least 1";
  SHUTTERLAB_CHECK(start_frame >= -1) << "--start-frame must be a frame id (>= 0)";
  SHUTTERLAB_CHECK(camera_path.empty() || lens_profile_path.empty())
      << "give --camera or --lens-profile, not both";
}

ImportSource DetectImportSource(const std::string& source, bool with_gyro_log) {
  if (fs::is_directory(source)) {
    const std::string missing = MissingPhoneClipPart(source);
    if (!missing.empty())
      throw IoError(IoMessage(source, -1,
                              "a folder, but not a phone clip: no " + missing +
                                  " (expected gyro.txt, framestamp.txt, gyro_dump.txt, frames/)"));
    return ImportSource::kPhoneFolder;
  }
  if (!fs::is_regular_file(source)) throw IoError(IoMessage(source, -1, "no such file or folder"));
  if (HasGoproTelemetry(source)) return ImportSource::kGoproMp4;
  if (with_gyro_log) return ImportSource::kVideoFile;
  throw IoError(IoMessage(source, -1,
                          "an MP4 without a GoPro 'gpmd' metadata track: no gyro of its own; give "
                          "--gyro LOG (a flight controller's or recorder's log) to import it with "
                          "that"));
}

// import --mask: the mask checked against the frames' size, written as DIR/mask.png (0 / 255),
// named in camera.json and recorded in import.json.
void AddMask(const std::string& mask_path, const fs::path& dir, ImportRecord* record) {
  const std::string camera_path = (dir / "camera.json").string();
  RigModel rig = ReadRigModel(camera_path);
  const cv::Mat mask = ReadMask(mask_path, rig.camera.width, rig.camera.height);
  rig.mask = "mask.png";
  WriteImage((dir / rig.mask).string(), mask);
  WriteRigModel(camera_path, rig);
  record->mask_file = rig.mask;
  record->mask_source = mask_path;
  WriteImportJson((dir / "import.json").string(), *record);
}

ImportSummary ImportVideo(const ImportOptions& options,
                          const std::function<void(size_t, size_t)>& progress) {
  options.Check();
  const ImportSource kind = DetectImportSource(options.source, !options.gyro_log.empty());
  if (kind == ImportSource::kVideoFile && options.camera_path.empty() &&
      options.lens_profile_path.empty())
    throw IoError(IoMessage(options.source, -1,
                            "states no camera: give --camera camera.json or --lens-profile "
                            "PROFILE.json (the frames' rays are what the log is aligned to)"));
  if (kind != ImportSource::kVideoFile && !options.camera_path.empty())
    throw IoError(IoMessage(options.camera_path, -1,
                            "--camera is for a video that states no camera; this clip declares "
                            "its own (--lens-profile replaces its lens)"));
  // Read before the long decoding: a bad profile or log fails at once.
  std::optional<LensProfile> profile;
  if (!options.lens_profile_path.empty()) profile = ReadLensProfile(options.lens_profile_path);
  if (!options.camera_path.empty()) ReadRigModel(options.camera_path);
  std::optional<FlightLog> log;
  if (!options.gyro_log.empty()) log = ReadFlightLog(options.gyro_log);
  const FlightLog* outside = log ? &*log : nullptr;
  StagingDir staging(options.out_dir);
  ImportSummary summary =
      kind == ImportSource::kGoproMp4
          ? ImportGopro(options, outside, profile, staging.path(), progress)
      : kind == ImportSource::kPhoneFolder
          ? ImportPhone(options, outside, profile, staging.path(), progress)
          : ImportVideoFile(options, outside, profile, staging.path(), progress);
  if (!options.mask_path.empty()) AddMask(options.mask_path, staging.path(), &summary.record);
  staging.Commit();
  return summary;
}

}  // namespace shutterlab
