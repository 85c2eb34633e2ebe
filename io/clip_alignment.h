#pragma once
// `import CLIP --gyro LOG`: an outside gyro log (a flight controller's, a recorder's) put on a
// clip's clock and axes, from the motion alone.
//
// Where the clip has a gyro of its own (a GoPro's GPMF, a phone's), the two gyros are aligned by
// sim/gyro_sync.h directly. Where it has none (the commonest FPV case: a camera without a usable
// gyro and a flight controller log beside it), the frames stand in for the gyro:
//  - ClipRotationRates: between each two consecutive frames, corners (Shi-Tomasi) tracked by
//    pyramidal Lucas-Kanade on the frames scaled down to kTrackSidePx (kept only where the track
//    back returns within kMaxRoundTripPx), each pixel turned into its ray by the declared lens
//    (model/camera.h CamFromImg), and the one rotation M that maps the earlier rays onto the later
//    ones (b_later = M b_earlier; Kabsch on two rays per hypothesis, kHypotheses of them, refit on
//    the rays within kInlierAngleRad). The camera turned by Exp(w dt) between the frames, so
//    w = -Log(M) / dt in camera axes. The sample is timed at the pair's middle: the earlier
//    frame's first row + dt / 2 + half the declared readout (the rows' mean time).
//    A camera that moves as it turns shows its translation's flow as a rotation too: good enough
//    to find the clock offset, which the loop (validate) then refines.
//  - AlignGyroLog: SyncGyros(the clip's rates in camera axes on the frames' clock, the log): the
//    offset t_log = t_clip + offset and the mounting w_camera = a_from_b w_log, which become
//    camera.json's time_offset_s and gyro_to_camera. Against the frames' rotation the log's rates
//    are first averaged over one frame interval (what a pair of frames sees).

#include "io/frames_csv.h"
#include "io/import_io.h"
#include "model/camera.h"
#include "sim/gyro_sync.h"
#include "sim/gyro_trace.h"
#include "sim/logs/flight_log.h"

#include <opencv2/core.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace shutterlab {

inline constexpr int kTrackSidePx = 640;
inline constexpr int kMaxCornersPerFrame = 500;
inline constexpr double kMaxRoundTripPx = 0.5;  // at the tracking scale
inline constexpr int kHypotheses = 200;
inline constexpr double kInlierAngleRad = 3e-3;  // 0.17 deg: 3 px at f = 1000 px
inline constexpr size_t kMinInlierRays = 12;

struct ClipRotation {
  GyroTrace rates;  // camera axes, rad/s, one sample per pair that held kMinInlierRays inliers
  size_t pairs = 0;
  size_t median_inliers = 0;  // over the pairs kept
};

// frames: in time order, their images relative to dir; rig: the declared camera and readout (the
// frames' size); mask: CV_8U of the frames' size (non-zero = may be tracked) or empty.
// progress(done, total) after each pair.
ClipRotation ClipRotationRates(const std::vector<FrameEntry>& frames, const std::string& dir,
                               const RigModel& rig, const cv::Mat& mask,
                               const std::function<void(size_t, size_t)>& progress = {});

// gyro.csv holds the log from this long before the first frame to this long after the last.
inline constexpr double kLogMarginS = 1.0;

// Puts the log (as sim/logs/flight_log_io.h ReadFlightLog read it from log_path) on the clip: by
// clip_gyro (the clip's own gyro, rig's axes and clock; may be null) where given, else by
// ClipRotationRates of the frames. Sets rig->cam_from_gyro and rig->time_offset_s, and the record's
// gyro fields, warnings, claims (time_offset_s and gyro_to_camera: inferred) and gyro_log. Returns
// the log's gyro over the frames (kLogMarginS each side). Throws IoError naming the log (no
// overlap, motion too weak to align: SyncGyros' line).
GyroTrace AlignGyroLog(const FlightLog& log, const std::string& log_path,
                       const std::vector<FrameEntry>& frames, const std::string& dir,
                       const cv::Mat& mask, const GyroTrace* clip_gyro, RigModel* rig,
                       ImportRecord* record,
                       const std::function<void(size_t, size_t)>& progress = {});

}  // namespace shutterlab
