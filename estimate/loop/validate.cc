#include "estimate/loop/validate.h"

#include "estimate/loop/frame_residuals.h"
#include "estimate/loop/validate_video.h"
#include "estimate/paper/analyze.h"
#include "io/frames_csv.h"
#include "io/image_io.h"
#include "io/rig_dataset.h"
#include "model/truth_model.h"
#include "render/pictures.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <utility>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// Grid rows or columns: every kGridStepPx-th plus the last one (as analyze's D_full).
std::vector<int> GridLines(int size) {
  std::vector<int> lines;
  for (int i = 0; i < size; i += kGridStepPx) lines.push_back(i);
  if (lines.back() != size - 1) lines.push_back(size - 1);
  return lines;
}

struct FullModelD {
  double d_px = 0.0;           // docs/FORMATS.md D of the grid
  double d_centre_px = 0.0;    // D of the grid column nearest the principal point
  double max_angle_rad = 0.0;  // largest rotation between any two grid rows' orientations
};

// The declared full model's D for one frame, on the grid.
FullModelD FullModel(const RigModel& rig, const FrameMotion& motion) {
  const PinholeCamera& cam = rig.camera;
  const FrameGeometry geometry(cam, rig.altitude_m, motion, cv::Size(cam.width, cam.height));
  const std::vector<int> rows = GridLines(cam.height), cols = GridLines(cam.width);
  cv::Mat field(static_cast<int>(rows.size()), static_cast<int>(cols.size()), CV_32FC2);
  for (size_t r = 0; r < rows.size(); ++r) {
    for (size_t c = 0; c < cols.size(); ++c) {
      const std::optional<Eigen::Vector2d> ref = geometry.RefPixel(cols[c], rows[r]);
      const float nan = std::numeric_limits<float>::quiet_NaN();
      field.at<cv::Vec2f>(static_cast<int>(r), static_cast<int>(c)) =
          ref ? cv::Vec2f(static_cast<float>(ref->x() - cols[c]),
                          static_cast<float>(ref->y() - rows[r]))
              : cv::Vec2f(nan, nan);
    }
  }
  FullModelD out;
  out.d_px = FrameDistortionPx(field);
  size_t centre = 0;
  for (size_t c = 0; c < cols.size(); ++c) {
    if (std::abs(cols[c] - cam.cx) < std::abs(cols[centre] - cam.cx)) centre = c;
  }
  out.d_centre_px = FrameDistortionPx(field.col(static_cast<int>(centre)).clone());
  // Vector criterion: the largest angle between the orientations of any two rows.
  std::vector<Eigen::Quaterniond> q;
  for (int v : rows) q.emplace_back(motion.world_from_cam[static_cast<size_t>(v)]);
  for (size_t a = 0; a < q.size(); ++a) {
    for (size_t b = a + 1; b < q.size(); ++b) {
      out.max_angle_rad = std::max(out.max_angle_rad, q[a].angularDistance(q[b]));
    }
  }
  return out;
}

RatioGroup Ratios(const std::vector<FrameValidation>& frames, int axis) {
  RatioGroup group;
  group.axis = axis;
  std::vector<double> paper, vector, full, centre;
  for (const FrameValidation& f : frames) {
    if (axis < 3 && f.dominant_axis != axis) continue;
    if (f.d_meas_px < kMinRatioDPx) continue;
    paper.push_back(f.d_paper_m / f.d_meas_m);
    vector.push_back(f.d_vector_m / f.d_meas_m);
    full.push_back(f.d_full_px / f.d_meas_px);
    if (f.d_full_px > 0) centre.push_back(f.d_centre_px / f.d_full_px);
  }
  group.frames = static_cast<int>(paper.size());
  if (paper.empty()) return group;
  group.paper_min = *std::min_element(paper.begin(), paper.end());
  group.paper_max = *std::max_element(paper.begin(), paper.end());
  group.paper_median = Median(paper);
  group.vector_median = Median(vector);
  group.full_median = Median(full);
  group.centre_median = Median(centre);
  return group;
}

Confusion Confuse(const std::vector<FrameValidation>& frames, size_t limit, double limit_m,
                  bool full) {
  Confusion c;
  c.limit_m = limit_m;
  for (const FrameValidation& f : frames) {
    const bool truth = f.flag_meas[limit];
    const bool predicted = full ? f.flag_full[limit] : f.flag_paper[limit];
    if (truth && predicted) ++c.true_positive;
    if (!truth && predicted) ++c.false_positive;
    if (truth && !predicted) ++c.false_negative;
    if (!truth && !predicted) ++c.true_negative;
  }
  return c;
}

// Each frame's motion under the declared model; a frame outside the gyro log is an error.
std::vector<FrameMotion> DeclaredMotions(const RigModel& rig, const GyroTrace& gyro,
                                         const std::vector<FrameEntry>& entries,
                                         const std::string& frames_path) {
  TrueModel declared_model;
  declared_model.rig = rig;
  const CameraMotion motion(gyro, declared_model);
  std::vector<FrameMotion> motions;
  for (size_t i = 0; i < entries.size(); ++i) {
    try {
      motions.push_back(motion.Frame(entries[i].t_first_row_ns));
    } catch (const std::out_of_range& e) {
      throw IoError(IoMessage(frames_path, static_cast<long>(i) + 2,
                              "frame " + std::to_string(entries[i].frame) + ": " + e.what()));
    }
  }
  return motions;
}

// Ground metres per pixel at the declared altitude, from the mean focal length.
double GroundMetresPerPx(const RigModel& rig) {
  const double f_px = 0.5 * (rig.camera.fx + rig.camera.fy);
  return rig.altitude_m / f_px;
}

// Measures every still frame against its ref image: fills result->frames' measured columns and
// returns each frame's points; *fields gets each frame's measured field (for D without the regions
// the screening leaves out).
std::vector<FramePoints> MeasureStillFrames(
    const RigDataset& files, const std::vector<FrameEntry>& entries, const ValidateOptions& options,
    const ValidateProgress& progress, ValidationResult* result, std::vector<cv::Mat>* fields) {
  const RigModel& rig = result->declared;
  const double m_per_px = GroundMetresPerPx(rig);
  std::vector<FramePoints> frame_points(entries.size());
  result->frames.resize(entries.size());
  for (size_t i = 0; i < entries.size(); ++i) {
    auto start = std::chrono::steady_clock::now();
    const long line = static_cast<long>(i) + 2;
    const cv::Mat ref = ReadImage((files.dir / entries[i].ref).string());
    const cv::Mat image = ReadImage((files.dir / entries[i].image).string());
    for (const auto& [name, picture] :
         {std::pair{entries[i].ref, ref}, {entries[i].image, image}}) {
      if (picture.cols != rig.camera.width || picture.rows != rig.camera.height) {
        throw IoError(IoMessage(files.frames_path, line,
                                "image '" + name + "' is " + std::to_string(picture.cols) + "x" +
                                    std::to_string(picture.rows) + ", camera.json declares " +
                                    std::to_string(rig.camera.width) + "x" +
                                    std::to_string(rig.camera.height)));
      }
    }
    result->read_s += SecondsSince(start);
    start = std::chrono::steady_clock::now();
    MeasureOptions measure = options.measure;
    measure.corner_tracks = options.screen.camera_fixed;
    DisplacementMeasurement measured = MeasureDisplacement(ref, image, measure);
    result->measure_s += SecondsSince(start);

    FrameValidation& f = result->frames[i];
    f.frame = entries[i].frame;
    f.image = entries[i].image;
    f.t_gyro_s = entries[i].t_first_row_ns * 1e-9 + rig.time_offset_s;
    f.points = measured.points.size();
    f.measured_fraction = measured.measured_fraction;
    f.noise_px = measured.noise_px;
    f.d_meas_px = measured.d_px;
    f.d_meas_m = measured.d_px * m_per_px;
    frame_points[i].frame = entries[i].frame;
    frame_points[i].t_first_row_ns = entries[i].t_first_row_ns;
    frame_points[i].points = std::move(measured.points);
    frame_points[i].tracks = std::move(measured.tracks);
    fields->push_back(measured.field);
    if (progress) progress("measure", i + 1, entries.size());
  }
  return frame_points;
}

// The paper's threshold model over the frames' readouts: `analyze` on the gyro log as given.
AnalyzeResult PaperModel(const RigModel& rig, const GyroTrace& gyro,
                         const std::vector<FrameEntry>& entries, const ValidateOptions& options) {
  AnalyzeOptions analyze;
  analyze.rig = rig;
  analyze.limits_m = options.limits_m;
  analyze.what_if = false;
  analyze.estimate_bias = false;  // gyro.csv is the calibrated log the dataset declares
  for (const FrameEntry& e : entries) {
    analyze.triggers.push_back(
        {FrameName(e.frame), e.t_first_row_ns + SecondsToNs(rig.time_offset_s)});
  }
  FlightLog log;
  log.gyro = gyro;
  log.format = "gyro.csv";
  return Analyze(log, analyze);
}

// Predict: the declared full model and the paper's threshold model for every frame, each frame's
// flags at every limit (result->frames' predicted columns).
void PredictStillFrames(const GyroTrace& gyro, const std::vector<FrameEntry>& entries,
                        const std::vector<FrameMotion>& motions, const std::string& frames_path,
                        const ValidateOptions& options, const ValidateProgress& progress,
                        ValidationResult* result) {
  const RigModel& rig = result->declared;
  const double m_per_px = GroundMetresPerPx(rig);
  // A global shutter (readout 0, as `correct` declares its output) has no readout window: the
  // paper's model predicts no distortion.
  const bool global_shutter = rig.shutter.readout_s == 0;
  const AnalyzeResult paper =
      global_shutter ? AnalyzeResult{} : PaperModel(rig, gyro, entries, options);
  for (size_t i = 0; i < entries.size(); ++i) {
    FrameValidation& f = result->frames[i];
    if (!global_shutter) {
      const ImageResult& image = paper.images[i];
      SHUTTERLAB_CHECK(image.in_trace) << frames_path << ":" << i + 2 << ": frame " << f.frame
                                       << ": the readout is outside the gyro log";
      SHUTTERLAB_CHECK(!image.too_few_samples)
          << frames_path << ":" << i + 2 << ": frame " << f.frame
          << ": the readout holds too few gyro samples (2 or fewer) for the paper's model";
      f.d_paper_m = image.d_paper_m;
      f.range_arcsec = image.range_arcsec;
      f.dominant_axis = image.dominant_axis;
    }
    const FullModelD full = FullModel(rig, motions[i]);
    f.d_full_px = full.d_px;
    f.d_full_m = full.d_px * m_per_px;
    f.d_centre_px = full.d_centre_px;
    f.d_vector_m = rig.altitude_m * std::tan(full.max_angle_rad);
    for (double limit : options.limits_m) {
      f.flag_meas.push_back(f.d_meas_m > limit);
      f.flag_full.push_back(f.d_full_m > limit);
      f.flag_paper.push_back(f.d_paper_m > limit);
    }
    if (progress) progress("predict", i + 1, entries.size());
  }
}

// The flags against the measured truth at every limit, and the ratios per dominant axis (those
// with frames) and over all frames.
void SummarisePredictions(const ValidateOptions& options, ValidationResult* result) {
  for (size_t l = 0; l < options.limits_m.size(); ++l) {
    result->confusion_paper.push_back(Confuse(result->frames, l, options.limits_m[l], false));
    result->confusion_full.push_back(Confuse(result->frames, l, options.limits_m[l], true));
  }
  for (int axis = 0; axis < 3; ++axis) {
    const RatioGroup group = Ratios(result->frames, axis);
    if (group.frames > 0) result->ratios.push_back(group);
  }
  result->ratios.push_back(Ratios(result->frames, 3));
}

// The mask the measurement uses: camera.json's and --mask's together (a pixel is measured where
// both allow it); empty when there is neither. *description says where it came from.
cv::Mat CombinedMask(const RigDataset& dataset, const std::string& mask_path,
                     std::string* description) {
  cv::Mat mask = dataset.mask.clone();
  if (!dataset.mask.empty()) *description = "camera.json's mask (" + dataset.declared.mask + ")";
  if (!mask_path.empty()) {
    const cv::Mat user =
        ReadMask(mask_path, dataset.declared.camera.width, dataset.declared.camera.height);
    mask = mask.empty() ? user : (mask & user);
    *description += (description->empty() ? "" : " and ") + std::string("--mask ") + mask_path;
  }
  return mask;
}

// The still frames' screening (estimate/loop/point_screen.h) under the declared model, and each
// frame's measured D again without the camera-fixed region.
void ScreenStillFrames(const GyroTrace& gyro, const std::vector<FramePoints>& frame_points,
                       const std::vector<cv::Mat>& fields, const ValidateOptions& options,
                       ValidationResult* result) {
  TrueModel declared;
  declared.rig = result->declared;
  std::vector<double> noise;
  for (const FrameValidation& f : result->frames) noise.push_back(f.noise_px);
  result->screen = ScreenPoints(declared, gyro, frame_points, noise, options.measure.grid_step_px,
                                options.screen);
  const CameraFixedRegion& region = result->screen.region;
  if (region.whole_image || region.cells_fixed == 0) return;
  const double m_per_px = GroundMetresPerPx(result->declared);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (size_t i = 0; i < fields.size(); ++i) {
    cv::Mat field = fields[i].clone();
    for (int v = 0; v < field.rows; ++v) {
      cv::Vec2f* row = field.ptr<cv::Vec2f>(v);
      for (int u = 0; u < field.cols; ++u) {
        if (region.Contains(u, v)) row[u] = cv::Vec2f(nan, nan);
      }
    }
    FrameValidation& f = result->frames[i];
    f.d_meas_px = FrameDistortionPx(field);
    f.d_meas_m = f.d_meas_px * m_per_px;
  }
}

// The frames' rate: the median interval between consecutive frame times (a video's; a still
// dataset's frames seconds apart give a rate no lens profile states). nullopt with fewer than two.
std::optional<double> FrameRateHz(const std::vector<FrameEntry>& frames) {
  std::vector<int64_t> t;
  for (const FrameEntry& f : frames) t.push_back(f.t_first_row_ns);
  std::sort(t.begin(), t.end());
  std::vector<int64_t> dt;
  for (size_t i = 1; i < t.size(); ++i) {
    if (t[i] > t[i - 1]) dt.push_back(t[i] - t[i - 1]);
  }
  if (dt.empty()) return std::nullopt;
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return 1e9 / static_cast<double>(dt[dt.size() / 2]);
}

}  // namespace

void ValidateOptions::Check() const {
  SHUTTERLAB_CHECK(!limits_m.empty()) << "give at least one ground limit";
  for (double limit : limits_m) {
    SHUTTERLAB_CHECK(std::isfinite(limit) && limit > 0)
        << "ground limit must be positive (got " << limit << " m)";
  }
  measure.Check();
  loop.Check();
  screen.Check();
  SHUTTERLAB_CHECK(max_points_per_pair >= 20) << "max_points_per_pair must be at least 20";
  SHUTTERLAB_CHECK(max_video_points >= max_points_per_pair)
      << "max_video_points must be at least max_points_per_pair";
}

ValidationResult ValidateDataset(const std::string& dataset_dir,
                                 const ValidateOptions& given_options,
                                 const ValidateProgress& progress) {
  given_options.Check();
  auto start = std::chrono::steady_clock::now();
  ValidationResult result;
  result.dataset = dataset_dir;
  result.limits_m = given_options.limits_m;

  // --- read and check everything that is cheap to check before the long stages
  const RigDataset dataset = ReadRigDataset(dataset_dir);
  ValidateOptions options = given_options;
  options.measure.mask = CombinedMask(dataset, given_options.mask_path, &result.mask_description);
  result.mask = options.measure.mask;
  result.declared = dataset.declared;
  const PinholeCamera& camera = dataset.declared.camera;
  if (camera.width < kMinMeasuredSidePx || camera.height < kMinMeasuredSidePx) {
    throw IoError(IoMessage(
        dataset.camera_path, 0,
        "the camera is " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
            " pixels: validate measures each frame's distortion, which needs "
            "frames of at least " +
            std::to_string(kMinMeasuredSidePx) + "x" + std::to_string(kMinMeasuredSidePx) +
            " pixels (give a dataset of larger frames)"));
  }
  if (!options.lens_profile_path.empty()) {
    result.lens_profile =
        ScaleLensProfile(ReadLensProfile(options.lens_profile_path), result.declared.camera.width,
                         result.declared.camera.height, FrameRateHz(dataset.frames));
    ApplyLensProfile(&*result.lens_profile, &result.declared);
  }
  result.warnings = dataset.gyro_warnings;
  const RigDataset& files = dataset;
  const RigModel& rig = result.declared;
  const GyroTrace& gyro = dataset.gyro;
  const std::vector<FrameEntry>& entries = dataset.frames;
  if (dataset.video) {
    result.read_s = SecondsSince(start);
    ValidateVideoDataset(dataset, options, progress, &result);
    return result;
  }
  const std::vector<FrameMotion> motions = DeclaredMotions(rig, gyro, entries, files.frames_path);
  result.read_s = SecondsSince(start);

  std::vector<cv::Mat> fields;
  const std::vector<FramePoints> frame_points =
      MeasureStillFrames(files, entries, options, progress, &result, &fields);

  start = std::chrono::steady_clock::now();
  ScreenStillFrames(gyro, frame_points, fields, options, &result);
  fields.clear();
  PredictStillFrames(gyro, entries, motions, files.frames_path, options, progress, &result);
  SummarisePredictions(options, &result);
  result.predict_s = SecondsSince(start);

  // --- close the loop over all frames' points
  start = std::chrono::steady_clock::now();
  result.loop =
      CloseTheLoop(rig, gyro, WithoutScreened(frame_points, result.screen.rotation_status),
                   PooledNoisePx(result.frames), options.loop);
  FillFrameResiduals(frame_points, result.loop, nullptr, result.screen, options.keep_residuals,
                     &result.frames);
  WithholdUncalibratedStderr(FitModel::kStill, &result.loop);
  result.loop_s = SecondsSince(start);
  return result;
}

}  // namespace shutterlab
