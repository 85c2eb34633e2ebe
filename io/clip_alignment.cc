#include "io/clip_alignment.h"

#include "io/image_io.h"
#include "sim/check.h"
#include "sim/sensor_pair.h"  // KabschRotation
#include "sim/so3.h"
#include "sim/text_file.h"  // FormatNumber
#include "sim/trace_audit.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <filesystem>
#include <random>

namespace shutterlab {
namespace {

// A frame as tracked: grey, scaled so that its longer side is at most kTrackSidePx.
struct TrackImage {
  cv::Mat grey;
  double scale = 1.0;  // full-resolution pixels per tracking pixel
};

TrackImage LoadForTracking(const std::string& path) {
  const cv::Mat image = ReadImage(path);
  cv::Mat grey;
  if (image.channels() == 1)
    grey = image;
  else
    cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_RGBA2GRAY : cv::COLOR_RGB2GRAY);
  if (grey.depth() != CV_8U) grey.convertTo(grey, CV_8U, grey.depth() == CV_16U ? 1.0 / 257 : 255);
  TrackImage out;
  out.scale = std::max(1.0, std::max(grey.cols, grey.rows) / static_cast<double>(kTrackSidePx));
  if (out.scale > 1.0)
    cv::resize(grey, out.grey, cv::Size(), 1.0 / out.scale, 1.0 / out.scale, cv::INTER_AREA);
  else
    out.grey = grey;
  return out;
}

// The ray of a tracking pixel (full-resolution pixel centres: (p + 0.5) scale - 0.5), unit length.
Eigen::Vector3d Ray(const PinholeCamera& camera, const cv::Point2f& p, double scale) {
  const Eigen::Vector2d px((p.x + 0.5) * scale - 0.5, (p.y + 0.5) * scale - 0.5);
  return camera.CamFromImg(px).normalized();
}

// M minimising sum |later - M earlier|^2 over the chosen pairs.
Eigen::Matrix3d FitRotation(const std::vector<Eigen::Vector3d>& earlier,
                            const std::vector<Eigen::Vector3d>& later,
                            const std::vector<size_t>& chosen) {
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i : chosen) h += earlier[i] * later[i].transpose();
  return KabschRotation(h);
}

std::vector<size_t> Inliers(const std::vector<Eigen::Vector3d>& earlier,
                            const std::vector<Eigen::Vector3d>& later, const Eigen::Matrix3d& m) {
  std::vector<size_t> out;
  for (size_t i = 0; i < earlier.size(); ++i) {
    if ((later[i] - m * earlier[i]).norm() <= kInlierAngleRad) out.push_back(i);
  }
  return out;
}

// The rotation M (later = M earlier) most rays agree on, and its inliers; none below
// kMinInlierRays.
std::vector<size_t> RobustRotation(const std::vector<Eigen::Vector3d>& earlier,
                                   const std::vector<Eigen::Vector3d>& later, uint64_t seed,
                                   Eigen::Matrix3d* m) {
  if (earlier.size() < kMinInlierRays) return {};
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<size_t> pick(0, earlier.size() - 1);
  std::vector<size_t> best;
  for (int h = 0; h < kHypotheses; ++h) {
    const size_t i = pick(rng), j = pick(rng);
    if (i == j || earlier[i].cross(earlier[j]).norm() < 1e-3) continue;  // two distinct rays
    const Eigen::Matrix3d candidate = FitRotation(earlier, later, {i, j});
    std::vector<size_t> inliers = Inliers(earlier, later, candidate);
    if (inliers.size() > best.size()) best = std::move(inliers);
  }
  for (int round = 0; round < 2 && best.size() >= kMinInlierRays; ++round) {
    *m = FitRotation(earlier, later, best);
    best = Inliers(earlier, later, *m);
  }
  if (best.size() < kMinInlierRays) return {};
  *m = FitRotation(earlier, later, best);
  return best;
}

}  // namespace

ClipRotation ClipRotationRates(const std::vector<FrameEntry>& frames, const std::string& dir,
                               const RigModel& rig, const cv::Mat& mask,
                               const std::function<void(size_t, size_t)>& progress) {
  namespace fs = std::filesystem;
  ClipRotation out;
  std::vector<GyroSample> samples;
  std::vector<size_t> inlier_counts;
  TrackImage earlier;
  cv::Mat small_mask;
  for (size_t k = 0; k < frames.size(); ++k) {
    TrackImage later = LoadForTracking((fs::path(dir) / frames[k].image).string());
    if (!mask.empty() && small_mask.empty())
      cv::resize(mask, small_mask, later.grey.size(), 0, 0, cv::INTER_NEAREST);
    if (k > 0) {
      ++out.pairs;
      std::vector<cv::Point2f> corners, tracked, back;
      cv::goodFeaturesToTrack(earlier.grey, corners, kMaxCornersPerFrame, 0.01, 8, small_mask);
      std::vector<Eigen::Vector3d> rays_earlier, rays_later;
      if (!corners.empty()) {
        std::vector<uint8_t> ok, ok_back;
        std::vector<float> error;
        const cv::Size window(21, 21);
        cv::calcOpticalFlowPyrLK(earlier.grey, later.grey, corners, tracked, ok, error, window, 4);
        back = corners;
        cv::calcOpticalFlowPyrLK(later.grey, earlier.grey, tracked, back, ok_back, error, window,
                                 4);
        for (size_t i = 0; i < corners.size(); ++i) {
          if (!ok[i] || !ok_back[i] || cv::norm(back[i] - corners[i]) > kMaxRoundTripPx) continue;
          const Eigen::Vector3d a = Ray(rig.camera, corners[i], earlier.scale);
          const Eigen::Vector3d b = Ray(rig.camera, tracked[i], later.scale);
          if (!a.allFinite() || !b.allFinite()) continue;
          rays_earlier.push_back(a);
          rays_later.push_back(b);
        }
      }
      Eigen::Matrix3d m;
      const std::vector<size_t> inliers = RobustRotation(rays_earlier, rays_later, k, &m);
      const int64_t dt_ns = frames[k].t_first_row_ns - frames[k - 1].t_first_row_ns;
      if (!inliers.empty() && dt_ns > 0) {
        const double dt_s = dt_ns * 1e-9;
        const Eigen::Vector3d w = -LogSO3(Eigen::Quaterniond(m)) / dt_s;
        const int64_t t_ns =
            frames[k - 1].t_first_row_ns + dt_ns / 2 + SecondsToNs(0.5 * rig.shutter.readout_s);
        samples.push_back({t_ns, w});
        inlier_counts.push_back(inliers.size());
      }
      if (progress) progress(k, frames.size() - 1);
    }
    earlier = std::move(later);
  }
  if (!inlier_counts.empty()) {
    std::nth_element(inlier_counts.begin(), inlier_counts.begin() + inlier_counts.size() / 2,
                     inlier_counts.end());
    out.median_inliers = inlier_counts[inlier_counts.size() / 2];
  }
  out.rates = GyroTrace(std::move(samples));
  return out;
}

namespace {

// The clip's gyro on the camera's axes and the frames' clock (camera clock = gyro clock -
// time_offset_s).
GyroTrace InCameraFrame(const GyroTrace& gyro, const RigModel& rig) {
  std::vector<GyroSample> out;
  out.reserve(gyro.size());
  const int64_t shift_ns = SecondsToNs(rig.time_offset_s);
  for (const GyroSample& s : gyro.samples())
    out.push_back({s.t_ns - shift_ns, rig.cam_from_gyro * s.omega_rad_s});
  return GyroTrace(std::move(out));
}

void SetClaim(ImportClaim claim, std::vector<ImportClaim>* claims) {
  for (ImportClaim& c : *claims) {
    if (c.what == claim.what) {
      c = std::move(claim);
      return;
    }
  }
  claims->push_back(std::move(claim));
}

}  // namespace

GyroTrace AlignGyroLog(const FlightLog& log, const std::string& log_path,
                       const std::vector<FrameEntry>& frames, const std::string& dir,
                       const cv::Mat& mask, const GyroTrace* clip_gyro, RigModel* rig,
                       ImportRecord* record, const std::function<void(size_t, size_t)>& progress) {
  SHUTTERLAB_CHECK(frames.size() >= 2) << "aligning a log needs at least two frames";
  GyroLogAlignment alignment;
  alignment.path = log_path;
  alignment.format = log.format;
  alignment.gyro_source = log.gyro_source;
  alignment.log_samples = log.gyro.size();
  alignment.log_duration_s = log.gyro.DurationS();
  GyroTrace clip_rates;
  GyroTrace log_rates = log.gyro;
  if (clip_gyro) {
    alignment.method = "the clip's own gyro, on the camera's axes as declared";
    clip_rates = InCameraFrame(*clip_gyro, *rig);
  } else {
    ClipRotation rotation = ClipRotationRates(frames, dir, *rig, mask, progress);
    alignment.method =
        "the frames' rotation (corners tracked between consecutive frames), against the log "
        "averaged over one frame interval";
    alignment.pairs = rotation.pairs;
    alignment.pairs_used = rotation.rates.size();
    alignment.median_inliers = rotation.median_inliers;
    if (rotation.rates.size() < 10)
      throw IoError(IoMessage(log_path, -1,
                              "only " + std::to_string(rotation.rates.size()) + " of the clip's " +
                                  std::to_string(rotation.pairs) +
                                  " frame pairs show a rotation to align the log to (too little "
                                  "texture, or frames too far apart)"));
    const double frame_interval_s = (frames.back().t_first_row_ns - frames.front().t_first_row_ns) *
                                    1e-9 / static_cast<double>(frames.size() - 1);
    log_rates = BoxAverage(log.gyro, frame_interval_s);
    clip_rates = std::move(rotation.rates);
  }
  GyroSync sync;
  try {
    GyroSyncOptions options;
    options.a_name = "the clip's frames";
    options.b_name = log_path;
    sync = SyncGyros(clip_rates, log_rates, options);
  } catch (const std::invalid_argument& e) {
    throw IoError(IoMessage(
        log_path, -1,
        std::string("cannot put the log on the clip (is it the log of this clip's flight?): ") +
            e.what()));
  }
  const double t_mid_s =
      0.5 * (frames.front().t_first_row_ns + frames.back().t_first_row_ns) * 1e-9;
  alignment.sync = sync;
  alignment.time_offset_s =
      sync.offset_s + sync.rate_ppm.value_or(0.0) * 1e-6 * (t_mid_s - sync.reference_a_s);
  rig->time_offset_s = alignment.time_offset_s;
  rig->cam_from_gyro = sync.a_from_b;

  const int64_t from_ns =
      frames.front().t_first_row_ns + SecondsToNs(alignment.time_offset_s - kLogMarginS);
  const int64_t to_ns = frames.back().t_first_row_ns +
                        SecondsToNs(alignment.time_offset_s + rig->shutter.readout_s + kLogMarginS);
  GyroTrace written = GyroAround(log.gyro, from_ns, to_ns);
  if (written.size() < 2)
    throw IoError(IoMessage(log_path, -1, "the log holds no gyro over the clip's frames"));
  alignment.written_from_s = written.t_begin_ns() * 1e-9;
  alignment.written_to_s = written.t_end_ns() * 1e-9;

  record->gyro_samples = written.size();
  record->gyro_rate_hz = written.sampling().RateHz();
  record->gyro_columns = log.format + " " + log.gyro_source + " (rad/s), the log's own axes";
  record->clock =
      "frames.csv: the clip's clock; gyro.csv: the log's; camera.json's time_offset_s, found by "
      "import --gyro, puts the frames on the log's clock";
  record->warnings = log.warnings;
  for (LogWarning& warning : AuditTrace(written)) record->warnings.push_back(std::move(warning));
  const std::string how = "import --gyro: " + alignment.method + "; offset standard error " +
                          FormatNumber("%.2g", sync.offset_stderr_s * 1e3) +
                          " ms, peak correlation " + FormatNumber("%.2f", sync.peak_correlation);
  SetClaim({"time_offset_s", alignment.time_offset_s, ClaimStatus::kInferred, how},
           &record->claims);
  SetClaim(
      {"gyro_to_camera", rig->cam_from_gyro, ClaimStatus::kInferred,
       sync.mounting_fitted ? how : how + "; the motion was about one axis only, identity kept"},
      &record->claims);
  record->gyro_log = std::move(alignment);
  return written;
}

}  // namespace shutterlab
