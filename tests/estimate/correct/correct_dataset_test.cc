// End-to-end tests of `correct` on rendered datasets (render/render_dataset.h), whose truth is
// exact: with the true model the corrected frames match the renderer's global-shutter references
// to interpolation error for every effect of docs/FORMATS.md's table; with a model error of known
// size, or a noisy gyro, the residual is what the prediction said. Small frames (320x240, f = 400
// px: the field of view of a 1280x960 mapping camera with f = 1600 px), a few frames each.

#include "estimate/correct/correct_dataset.h"

#include "estimate/loop/measure.h"
#include "estimate/loop/validate.h"
#include "estimate/report/loop_json.h"
#include "io/frames_csv.h"
#include "io/image_io.h"
#include "io/rig_dataset.h"
#include "model/effect_io.h"
#include "render/ground_texture.h"
#include "render/render_dataset.h"
#include "render/survey.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/ulog_write.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/io/photo_fixtures.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <variant>
#include <vector>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 320, kHeight = 240;
constexpr double kFocalPx = 400.0, kAltitudeM = 50.0;
// The bar for "interpolation only": the corrected frame against the exact truth.
constexpr double kInterpolationRmsPx = 0.05;

RigModel DeclaredRig() {
  RigModel rig = test::NadirRig(kWidth, kHeight, kFocalPx, 0.030, kAltitudeM);
  return rig;
}

// The scene at the rig's ground sample distance, 900x700 (margin for the motion), written once per
// test folder.
std::string Scene(const test::TempDir& dir) {
  const std::string path = dir / "scene.png";
  if (!fs::exists(path)) {
    GroundTextureOptions options;
    options.width_px = 900;
    options.height_px = 700;
    options.ground_sample_distance_m = kAltitudeM / kFocalPx;
    WriteImage(path, MakeGroundTexture(options));
  }
  return path;
}

// A multirotor-like flight (6 s still, then motion), perfect sensor, 1 kHz.
GyroTrace FlightGyro(double duration_s = 30.0) {
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 1000.0;
  synth.duration_s = duration_s;
  synth.seed = 3;
  synth.imu = ImuErrorModel::Ideal();
  return SynthesizeTrace(synth);
}

struct Rendered {
  std::string dataset;
  TrueModel truth;  // the declared model plus the injections
};

Rendered Render(const test::TempDir& dir, const std::string& name,
                const std::vector<std::string>& injections, const std::vector<double>& times_s,
                bool video = false, const RigModel& declared = DeclaredRig()) {
  WriteRigModel(dir / "camera.json", declared);
  WriteGyroCsv(dir / "gyro.csv", FlightGyro());
  std::string times = "frame,t_first_row\n";
  for (size_t i = 0; i < times_s.size(); ++i) {
    times += std::to_string(i) + "," + FormatNumber("%.6f", times_s[i]) + "\n";
  }
  WriteFileAtomically(dir / "times.csv", times);
  RenderOptions render;
  render.scene_path = Scene(dir);
  render.camera_path = dir / "camera.json";
  render.gyro_path = dir / "gyro.csv";
  render.frames_path = dir / "times.csv";
  render.out_dir = dir / name;
  render.injections = injections;
  render.pictures = false;
  render.video = video;
  RenderDataset(render);
  Rendered out{dir / name, {}};
  out.truth.rig = declared;
  for (const std::string& injection : injections) ApplyInjection(injection, &out.truth);
  return out;
}

// A validation report whose fitted model is `model`, with the given effects' covariances.
std::string Report(const test::TempDir& dir, const std::string& name, const TrueModel& model,
                   const std::vector<IdentifiedEffect>& effects = {}) {
  LoopResult loop;
  loop.model = model;
  loop.effects = effects;
  const std::string path = dir / name;
  WriteFileAtomically(path, LoopToJson(loop, 1).dump());
  return path;
}

CorrectSummary Correct(const std::string& dataset, const std::string& out,
                       const std::string& report = "", int draws = 32) {
  CorrectOptions options;
  options.prediction.draws = draws;
  options.dataset_dir = dataset;
  options.out_dir = out;
  options.report_path = report;
  options.check_truth = true;
  options.pictures = false;
  return CorrectDataset(options);
}

TEST(CorrectEndToEnd, TrueModelLeavesOnlyInterpolationForEveryEffect) {
  // Each effect of docs/FORMATS.md's table in the truth and not in camera.json: corrected with the
  // true model (a report holding it), the frames match the renderer's references to interpolation
  // error; corrected with camera.json alone, they do not.
  const std::vector<std::string> effects = {
      "time_offset=4ms",
      "readout_time=36ms",
      "gyro_scale=1.05,0.95,1.04",
      "gyro_bias=0.02rad/s,-0.015rad/s,0.01rad/s",
      "velocity=6m/s,-3m/s,0",
      "lens_distortion=-0.12,0.02",
      "readout_direction=bottom_to_top",
      "clock_rate=300ppm",
      "gyro_to_camera=0.99756405,-0.06975647,0,0.06975647,0.99756405,0,0,0,1"};
  test::TempDir dir;
  // Under ASan (3 to 10 times slower) every other effect of the table.
  for (size_t k = 0; k < effects.size(); k += test::kAsan ? 2 : 1) {
    const std::string& effect = effects[k];
    const std::string name = effect.substr(0, effect.find('='));
    const Rendered rendered = Render(dir, name, {effect}, {12.0, 20.0});
    const CorrectSummary fixed = Correct(rendered.dataset, dir / (name + "_fixed"),
                                         Report(dir, name + ".json", rendered.truth));
    const CorrectSummary declared = Correct(rendered.dataset, dir / (name + "_declared"));
    ASSERT_EQ(fixed.frames.size(), 2u) << name;
    for (size_t i = 0; i < fixed.frames.size(); ++i) {
      const TruthResidual& after = *fixed.frames[i].truth;
      const TruthResidual& wrong = *declared.frames[i].truth;
      EXPECT_LE(after.rms_px, kInterpolationRmsPx) << name << " frame " << i;
      // D of the residual: twice the map's checked tolerance at most (a kink between checks).
      EXPECT_LE(after.d_px, 2 * CorrectionMapOptions{}.tolerance_px + 0.02)
          << name << " frame " << i;
      EXPECT_GT(after.d_before_px, 0.5) << name << ": the frame must be distorted to test anything";
      EXPECT_GT(wrong.rms_px, 2 * after.rms_px) << name << ": the declared model leaves more";
      std::printf(
          "  %-18s frame %zu: D before %.3f px, after %.4f px (rms %.4f); declared model "
          "leaves rms %.3f px\n",
          name.c_str(), i, after.d_before_px, after.d_px, after.rms_px, wrong.rms_px);
    }
  }
}

TEST(CorrectEndToEnd, FisheyeTrueModelLeavesOnlyInterpolation) {
  // A 90-degree fisheye (the GoPro MAX's coefficients, f 254 px) over the ground, the truth with
  // a lens error (added to the fisheye's k1, k2), a translation and a clock offset: corrected with
  // the true model, the frames match the renderer's references to interpolation error.
  test::TempDir dir;
  RigModel fisheye = test::FisheyeRig(kWidth, kHeight, 45.0);
  fisheye.altitude_m = kAltitudeM;
  const Rendered rendered = Render(
      dir, "fisheye", {"lens_distortion=-0.03,0.01", "velocity=6m/s,-3m/s,0", "time_offset=4ms"},
      {12.0, 20.0}, /*video=*/false, fisheye);
  ASSERT_TRUE(std::holds_alternative<Fisheye>(rendered.truth.rig.camera.distortion));
  const CorrectSummary fixed =
      Correct(rendered.dataset, dir / "fixed", Report(dir, "fisheye.json", rendered.truth));
  const CorrectSummary declared = Correct(rendered.dataset, dir / "declared");
  ASSERT_EQ(fixed.frames.size(), 2u);
  for (size_t i = 0; i < fixed.frames.size(); ++i) {
    const TruthResidual& after = *fixed.frames[i].truth;
    EXPECT_LE(after.rms_px, kInterpolationRmsPx) << "frame " << i;
    EXPECT_LE(after.d_px, 2 * CorrectionMapOptions{}.tolerance_px + 0.02) << "frame " << i;
    EXPECT_GT(after.d_before_px, 0.5) << "the frame must be distorted to test anything";
    EXPECT_GT(declared.frames[i].truth->rms_px, 2 * after.rms_px);
    std::printf(
        "  fisheye frame %zu: D before %.3f px, after %.4f px (rms %.4f); declared model leaves "
        "rms %.3f px\n",
        i, after.d_before_px, after.d_px, after.rms_px, declared.frames[i].truth->rms_px);
  }
  const RigModel written = ReadRigModel((dir.path() / "fixed" / "camera.json").string());
  EXPECT_EQ(written.camera.distortion, rendered.truth.rig.camera.distortion)
      << "the output declares the lens it was corrected through";
}

TEST(CorrectEndToEnd, OutputIsARigDatasetThatValidateFindsGlobal) {
  test::TempDir dir;
  const Rendered rendered =
      Render(dir, "ds", {"velocity=6m/s,-3m/s,0", "time_offset=4ms"}, {12.0, 16.0, 20.0});
  const std::string out = dir / "out";
  Correct(rendered.dataset, out, Report(dir, "report.json", rendered.truth));
  const RigModel written = ReadRigModel((fs::path(out) / "camera.json").string());
  EXPECT_EQ(written.shutter.readout_s, 0.0);
  EXPECT_NEAR(written.time_offset_s, 0.004, 1e-12);
  EXPECT_EQ(written.velocity_mps, Eigen::Vector3d(6, -3, 0));
  const std::vector<FrameEntry> frames = ReadFramesCsv((fs::path(out) / "frames.csv").string());
  const std::vector<FrameEntry> input =
      ReadFramesCsv((fs::path(rendered.dataset) / "frames.csv").string());
  ASSERT_EQ(frames.size(), input.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].image, input[i].image) << "the same relative paths";
    EXPECT_EQ(frames[i].ref, input[i].ref);
    EXPECT_EQ(frames[i].t_first_row_ns, input[i].t_first_row_ns) << "row 0 is the first row read";
    EXPECT_TRUE(fs::is_regular_file(fs::path(out) / ("masks/" + frames[i].image + ".png")));
  }
  EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "colmap/image_list.txt"));
  EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "odm/images/0000_rs_mask.png"));
  // validate, measuring each corrected frame against its reference: the declared global shutter
  // already explains it (the residual at the noise, nothing to add); the input's is far above.
  ValidateOptions validate;
  validate.keep_residuals = false;
  const ValidationResult corrected = ValidateDataset(out, validate);
  const ValidationResult original = ValidateDataset(rendered.dataset, validate);
  EXPECT_FALSE(corrected.loop.above_noise_before) << corrected.loop.before.rms_px;
  EXPECT_TRUE(corrected.loop.effects.empty());
  EXPECT_LE(corrected.loop.before.rms_px, 1.5 * corrected.loop.noise_px);
  EXPECT_GT(original.loop.before.rms_px, 3 * corrected.loop.before.rms_px);
  std::printf("  validate before: rms %.4f px on the input, %.4f px corrected (noise %.4f px)\n",
              original.loop.before.rms_px, corrected.loop.before.rms_px, corrected.loop.noise_px);
}

TEST(CorrectEndToEnd, PredictsTheResidualOfAReportedModelError) {
  // The truth's clock offset is 6 ms; the report says 3.5 ms +- 2.5 ms: the model is off by one
  // standard error. The draws spread |error| as a half-normal (median 0.67, 90 % 1.64 standard
  // errors), so one standard error lies between the prediction's median and 90th percentile.
  test::TempDir dir;
  const Rendered rendered = Render(dir, "ds", {"time_offset=6ms"}, {14.0, 18.0, 22.0, 26.0});
  TrueModel reported = rendered.truth;
  reported.rig.time_offset_s = 0.0035;
  IdentifiedEffect effect;
  effect.effect = Effect::kTimeOffset;
  effect.value = 0.0035;
  effect.parameters = Eigen::VectorXd::Constant(1, 0.0035);
  effect.covariance = Eigen::MatrixXd::Constant(1, 1, 0.0025 * 0.0025);
  const CorrectSummary summary =
      Correct(rendered.dataset, dir / "out", Report(dir, "report.json", reported, {effect}));
  for (const CorrectedFrame& f : summary.frames) {
    const double measured = f.truth->d_px;
    EXPECT_GE(measured, 0.8 * f.predicted_d_after_px) << "frame " << f.frame;
    EXPECT_LE(measured, 1.25 * f.predicted_d_after_p90_px) << "frame " << f.frame;
    EXPECT_GT(f.residual.d_after_px, 0.05) << "the error must be visible to test anything";
    std::printf("  frame %lld: predicted D after %.3f px (90 %%: %.3f), measured %.3f px\n",
                static_cast<long long>(f.frame), f.predicted_d_after_px, f.predicted_d_after_p90_px,
                measured);
  }
  const auto worse_noted = [](const CorrectSummary& s) {
    return std::any_of(s.notes.begin(), s.notes.end(), [](const std::string& n) {
      return n.rfind("the correction is predicted to leave more distortion than it removes", 0) ==
             0;
    });
  };
  EXPECT_FALSE(worse_noted(summary));
  // The same offset known only within a second: the correction would move the image by more than
  // the rolling shutter did, and it says so (and the notes reach correct.json). 512 draws: the
  // medians settle (upper medians 2.4 against 2.2 px); 32 draws of an offset this uncertain,
  // about a third of them outside the second of log around a frame, left them a coin's throw.
  effect.covariance = Eigen::MatrixXd::Constant(1, 1, 1.0);
  const CorrectSummary unsure =
      Correct(rendered.dataset, dir / "out2", Report(dir, "report2.json", reported, {effect}), 512);
  for (const CorrectedFrame& f : unsure.frames) {
    std::printf("  unsure frame %lld: D before %.3f px, predicted after %.3f px\n",
                static_cast<long long>(f.frame), f.residual.d_before_px, f.predicted_d_after_px);
  }
  EXPECT_TRUE(worse_noted(unsure));
  EXPECT_NE(ReadFileToString(dir / "out2/correct.json")
                .find("the correction is predicted to leave more distortion"),
            std::string::npos);
}

TEST(CorrectEndToEnd, PredictsTheResidualOfGyroNoise) {
  // Rendered with a perfect gyro, corrected with the same trace plus white noise (its still lead
  // shows the noise to the estimate): each frame's residual is one draw of what the prediction
  // spreads; over the frames the measured D follows the predicted median.
  test::TempDir dir;
  const Rendered rendered = Render(dir, "ds", {}, {9.0, 11.0, 13.0, 15.0, 17.0, 19.0, 21.0, 23.0});
  constexpr double kDensity = 2e-3;  // rad/s/sqrt(Hz): a poor MEMS gyro, to see it at 320x240
  std::vector<GyroSample> samples = FlightGyro().samples();
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal(0.0, kDensity / std::sqrt(1e-3));
  for (GyroSample& s : samples)
    s.omega_rad_s += Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  WriteGyroCsv((fs::path(rendered.dataset) / "gyro.csv").string(), GyroTrace(std::move(samples)));
  const CorrectSummary summary = Correct(rendered.dataset, dir / "out");
  EXPECT_NEAR(summary.model.gyro_noise_rad_s_sqrt_hz, kDensity, 0.1 * kDensity)
      << summary.model.gyro_noise_source;
  std::vector<double> ratios;
  for (const CorrectedFrame& f : summary.frames) {
    ratios.push_back(f.truth->d_px / f.predicted_d_after_px);
    EXPECT_LE(f.truth->d_px, 2.0 * f.predicted_d_after_p90_px) << "frame " << f.frame;
    std::printf("  frame %lld: predicted D after %.3f px (90 %%: %.3f), measured %.3f px\n",
                static_cast<long long>(f.frame), f.predicted_d_after_px, f.predicted_d_after_p90_px,
                f.truth->d_px);
  }
  const double median = UpperMedian(ratios);
  EXPECT_GT(median, 0.5);
  EXPECT_LT(median, 2.0);
}

// The rendered frames as JPEG photos in DIR/photos under `names` (frames.csv order).
fs::path PhotoFolder(const test::TempDir& dir, const Rendered& rendered,
                     const std::vector<std::string>& names) {
  const fs::path photos = dir.path() / "photos";
  fs::create_directories(photos);
  const std::vector<FrameEntry> frames = ReadFramesCsv(rendered.dataset + "/frames.csv");
  for (size_t i = 0; i < names.size(); ++i) {
    WriteImage((photos / names[i]).string(), ReadImage(rendered.dataset + "/" + frames[i].image));
  }
  return photos;
}

// correct --photos PHOTOS LOG with the rendered dataset's camera.json and a report holding the
// true model, measured against the render's truth.
CorrectOptions PhotoOptions(const test::TempDir& dir, const Rendered& rendered,
                            const fs::path& photos, const std::string& log) {
  CorrectOptions options;
  options.dataset_dir = photos.string();
  options.out_dir = dir / "out";
  options.report_path = Report(dir, "truth.json", rendered.truth);
  options.check_truth = true;
  options.truth_dir = rendered.dataset + "/truth";
  options.pictures = false;
  options.photos.emplace();
  options.photos->log_path = log;
  options.photos->camera = ReadRigModel(rendered.dataset + "/camera.json");
  options.photos->camera_path = "camera.json";
  return options;
}

void ExpectTheTruth(const CorrectSummary& summary, const std::vector<std::string>& names,
                    const std::vector<double>& times_s) {
  EXPECT_TRUE(summary.photos);
  ASSERT_EQ(summary.frames.size(), names.size());
  for (size_t i = 0; i < summary.frames.size(); ++i) {
    const CorrectedFrame& f = summary.frames[i];
    EXPECT_EQ(f.source_image, names[i]);
    EXPECT_EQ(f.image, "images/" + names[i]) << "a plain folder of the corrected photos";
    EXPECT_EQ(f.t_first_row_ns, SecondsToNs(times_s[i])) << f.image;
    EXPECT_LE(f.truth->rms_px, kInterpolationRmsPx) << f.image;
    EXPECT_LE(f.truth->d_px, 2 * CorrectionMapOptions{}.tolerance_px + 0.02) << f.image;
    EXPECT_GT(f.truth->d_before_px, 0.5) << "the photo must be distorted to test anything";
    EXPECT_TRUE(fs::is_regular_file(fs::path(summary.out_dir) / f.image));
    EXPECT_TRUE(
        fs::is_regular_file(fs::path(summary.out_dir) / "masks" / (f.source_image + ".png")));
    std::printf("  %s: D before %.3f px, after %.4f px (rms %.4f) against the truth\n",
                f.image.c_str(), f.truth->d_before_px, f.truth->d_px, f.truth->rms_px);
  }
}

TEST(CorrectPhotos, RenderedStillsPlacedByTheirTriggersMatchTheTruth) {
  // Three stills rendered from one flight, written as JPEG photos, with the flight's gyro log and
  // a trigger file naming them 5 ms before row 0 (--latency 5 ms) and a fourth photo that no
  // trigger names: corrected with the true model, the three match the renderer's exact truth to
  // interpolation error, the fourth is skipped with its reason, and a second run keeps them. A
  // fifth, a copy cut short inside its image data, is found when it is decoded and skipped.
  test::TempDir dir;
  const std::vector<double> times_s = {12.0, 16.0, 20.0};
  const std::vector<std::string> names = {"DJI_0001.JPG", "DJI_0002.JPG", "DJI_0003.JPG"};
  const Rendered rendered = Render(dir, "ds", {"velocity=6m/s,-3m/s,0"}, times_s);
  const fs::path photos = PhotoFolder(dir, rendered, names);
  fs::copy_file(photos / "DJI_0001.JPG", photos / "DJI_0099.JPG");
  const std::string whole = ReadFileToString(photos / "DJI_0002.JPG");
  WriteFileAtomically(photos / "DJI_0004.JPG", whole.substr(0, whole.size() * 3 / 4));
  std::string triggers = "image,t\n";
  for (size_t i = 0; i < names.size(); ++i) {
    triggers += names[i] + "," + FormatNumber("%.6f", times_s[i] - 0.005) + "\n";
  }
  triggers += "DJI_0004.JPG," + FormatNumber("%.6f", times_s[1] - 0.005) + "\n";
  WriteFileAtomically(dir / "triggers.csv", triggers);
  CorrectOptions options = PhotoOptions(dir, rendered, photos, rendered.dataset + "/gyro.csv");
  options.photos->triggers_path = dir / "triggers.csv";
  options.photos->trigger_latency_s = 0.005;
  const CorrectSummary summary = CorrectDataset(options);
  ExpectTheTruth(summary, names, times_s);
  ASSERT_EQ(summary.skipped.size(), 2u);
  EXPECT_NE(summary.skipped[0].second.find("DJI_0099.JPG"), std::string::npos)
      << summary.skipped[0].second;
  EXPECT_EQ(summary.skipped[1].second,
            "DJI_0004.JPG: its image data does not decode (Premature end of JPEG file): a cut or "
            "damaged file; copy it from the card again");
  EXPECT_FALSE(fs::exists(fs::path(options.out_dir) / "images/DJI_0004.JPG"));
  EXPECT_EQ(ReadFramesCsv((fs::path(options.out_dir) / "frames.csv").string()).size(), 3u);
  EXPECT_TRUE(fs::is_regular_file(fs::path(options.out_dir) / "correct.json"));
  options.check_truth = false;
  for (const CorrectedFrame& f : CorrectDataset(options).frames) EXPECT_TRUE(f.kept) << f.image;
}

TEST(CorrectPhotos, PlacedInOrderOnAPx4LogsOwnCameraEvents) {
  // The same flight as a PX4 ULog whose camera_capture events are the photos' exposures, and no
  // trigger file: the photos are paired with the log's events in order.
  test::TempDir dir;
  const std::vector<double> times_s = {14.0, 18.0};
  const std::vector<std::string> names = {"a.jpg", "b.jpg"};
  const Rendered rendered = Render(dir, "ds", {"time_offset=4ms"}, times_s);
  const fs::path photos = PhotoFolder(dir, rendered, names);
  std::vector<GyroSample> samples = FlightGyro().samples();
  samples.erase(samples.begin());  // PX4 times are unsigned and 0 means unset: start at 1 ms
  std::vector<CameraEvent> events;
  // Row 0 on the log's clock: the camera's time plus the truth's clock offset.
  for (size_t i = 0; i < times_s.size(); ++i) {
    events.push_back({SecondsToNs(times_s[i] + 0.004), static_cast<int64_t>(i), ""});
  }
  WriteULog(dir / "flight.ulg", GyroTrace(std::move(samples)), events);
  const CorrectSummary summary =
      CorrectDataset(PhotoOptions(dir, rendered, photos, dir / "flight.ulg"));
  ExpectTheTruth(summary, names, {times_s[0] + 0.004, times_s[1] + 0.004});
  EXPECT_TRUE(summary.skipped.empty());
}

// A DJI photo of `image` whose metadata records the gimbal looking straight down at `yaw_deg` and
// the flight speed that is `velocity_cam_mps` (horizontal, camera axes) in north and east.
std::string DjiPhotoMovingAt(const cv::Mat& image, double yaw_deg,
                             const std::optional<Eigen::Vector2d>& velocity_cam_mps,
                             bool records_gimbal = true) {
  test::FixturePhoto p;
  p.pixels = image;
  p.width = image.cols;
  p.height = image.rows;
  std::map<std::string, std::string> xmp;
  if (records_gimbal) {
    xmp = {{"GimbalPitchDegree", "-90.0"},
           {"GimbalRollDegree", "0.0"},
           {"GimbalYawDegree", FormatNumber("%.1f", yaw_deg)}};
  }
  if (velocity_cam_mps) {
    // Looking straight down with the image's top toward the yaw (0: north), image right points to
    // the yaw + 90 deg and image down to the yaw + 180 deg: (north, east) of each.
    const double yaw = yaw_deg * kRadPerDeg;
    const Eigen::Vector2d right(-std::sin(yaw), std::cos(yaw)),
        down(-std::cos(yaw), -std::sin(yaw));
    const Eigen::Vector2d north_east = velocity_cam_mps->x() * right + velocity_cam_mps->y() * down;
    xmp["FlightXSpeed"] = FormatNumber("%.6f", north_east.x());
    xmp["FlightYSpeed"] = FormatNumber("%.6f", north_east.y());
    xmp["FlightZSpeed"] = "0.0";
  }
  p.xmp = test::DjiXmp(xmp, false);
  return test::JpegWithMetadata(p);
}

// correct --photos PHOTOS LOG --triggers TRIGGERS --camera camera.json (DeclaredRig) into
// DIR/corrected, first row as the reference (the truth's), measured against the truth.
CorrectOptions DjiPhotoOptions(const test::TempDir& dir, const fs::path& photos,
                               const std::string& log, const std::string& triggers) {
  CorrectOptions options;
  options.dataset_dir = photos.string();
  options.out_dir = dir / "corrected";
  options.check_truth = true;
  options.pictures = false;
  options.reference = CorrectionReference::kFirstRow;
  options.photos.emplace();
  options.photos->log_path = log;
  options.photos->triggers_path = triggers;
  options.photos->camera = DeclaredRig();
  options.photos->camera_path = "camera.json";
  return options;
}

TEST(CorrectPhotos, EachPhotoIsCorrectedWithTheVelocityItRecords) {
  // A survey flown at a fixed heading (yaw 30 deg), lines in both directions: two photos flying
  // one way, one the other, and one that records no speed, each rendered with its true velocity,
  // written as DJI photos recording it (flight speed north/east and gimbal attitude), corrected
  // with camera.json's zero velocity. Each photo's own velocity, turned into its camera's axes,
  // leaves interpolation only; the photo with no speed keeps its translation (rotation only,
  // said); --effect velocity= sets one velocity for all, which the photo flown back then misses.
  test::TempDir dir;
  const Eigen::Vector2d out_mps(6.0, -3.0), back_mps(-6.0, 3.0);
  const Rendered out_line = Render(dir, "out_line", {"velocity=6m/s,-3m/s,0"}, {12.0, 16.0});
  const Rendered back_line = Render(dir, "back_line", {"velocity=-6m/s,3m/s,0"}, {20.0, 24.0});
  struct Shot {
    const Rendered* rendered;
    int index;
    double t_s;
    std::optional<Eigen::Vector2d> recorded;
  };
  const std::map<std::string, Shot> shots = {{"DJI_0001.JPG", {&out_line, 0, 12.0, out_mps}},
                                             {"DJI_0002.JPG", {&out_line, 1, 16.0, out_mps}},
                                             {"DJI_0003.JPG", {&back_line, 0, 20.0, back_mps}},
                                             {"DJI_0004.JPG", {&back_line, 1, 24.0, {}}}};
  const fs::path photos = dir.path() / "photos";
  fs::create_directories(photos);
  std::string triggers = "image,t\n";
  for (const auto& [name, shot] : shots) {
    const FrameEntry frame = ReadFramesCsv(shot.rendered->dataset + "/frames.csv")[shot.index];
    WriteFileAtomically(
        photos / name, DjiPhotoMovingAt(ReadImage(shot.rendered->dataset + "/" + frame.image), 30.0,
                                        shot.recorded));
    triggers += name + "," + FormatNumber("%.6f", shot.t_s) + "\n";
  }
  WriteFileAtomically(dir / "triggers.csv", triggers);
  CorrectOptions options =
      DjiPhotoOptions(dir, photos, out_line.dataset + "/gyro.csv", dir / "triggers.csv");
  // The truth of each photo: its frame of its render.
  const fs::path truth = dir.path() / "truth";
  fs::create_directories(truth);
  int64_t index = 0;
  for (const auto& [name, shot] : shots) {
    fs::copy_file(
        fs::path(shot.rendered->dataset) / "truth" / (FrameName(shot.index) + "_disp.exr"),
        truth / (FrameName(index++) + "_disp.exr"));
  }
  options.truth_dir = truth.string();

  const CorrectSummary summary = CorrectDataset(options);
  ASSERT_EQ(summary.frames.size(), 4u);
  const std::vector<Eigen::Vector2d> expected = {out_mps, out_mps, back_mps, {0.0, 0.0}};
  for (size_t i = 0; i < 4; ++i) {
    const CorrectedFrame& f = summary.frames[i];
    std::printf("  %s: velocity (%.3f, %.3f, %.3f) m/s, D before %.3f px, after %.4f px: %s\n",
                f.source_image.c_str(), f.velocity_mps.x(), f.velocity_mps.y(), f.velocity_mps.z(),
                f.truth->d_before_px, f.truth->d_px, f.translation.c_str());
    EXPECT_NEAR((f.velocity_mps.head<2>() - expected[i]).norm(), 0.0, 1e-5) << f.source_image;
    EXPECT_NEAR(f.velocity_mps.z(), 0.0, 1e-9) << f.source_image;
    if (i < 3) {
      EXPECT_LE(f.truth->rms_px, kInterpolationRmsPx) << f.source_image;
      EXPECT_NE(f.translation.find("from the photo's XMP drone-dji"), std::string::npos)
          << f.translation;
    } else {
      EXPECT_GT(f.truth->d_px, 0.5) << "its translation is not corrected";
      EXPECT_EQ(f.translation.rfind("rotation only: the photo records no flight speed", 0), 0u)
          << f.translation;
    }
  }
  EXPECT_NE(summary.translation.find("3 of 4 photos"), std::string::npos) << summary.translation;
  // A plain folder of corrected photos; masks and lists beside it.
  std::vector<std::string> in_images;
  for (const auto& entry : fs::directory_iterator(dir / "corrected/images"))
    in_images.push_back(entry.path().filename().string());
  std::sort(in_images.begin(), in_images.end());
  EXPECT_EQ(in_images, (std::vector<std::string>{"DJI_0001.JPG", "DJI_0002.JPG", "DJI_0003.JPG",
                                                 "DJI_0004.JPG"}));
  EXPECT_TRUE(fs::is_regular_file(dir / "corrected/masks/DJI_0003.JPG.png"));
  EXPECT_EQ(ReadFileToString(dir / "corrected/colmap/image_list.txt"),
            "DJI_0001.JPG\nDJI_0002.JPG\nDJI_0003.JPG\nDJI_0004.JPG\n");
  EXPECT_EQ(ReadFramesCsv(dir / "corrected/frames.csv")[2].image, "images/DJI_0003.JPG");
  EXPECT_EQ(ReadRigDataset(dir / "corrected").frames.size(), 4u) << "a rig dataset again";

  options.effects = {"velocity=6m/s,-3m/s,0"};
  options.out_dir = dir / "one_velocity";
  const CorrectSummary one = CorrectDataset(options);
  ASSERT_EQ(one.frames.size(), 4u);
  EXPECT_LE(one.frames[0].truth->rms_px, kInterpolationRmsPx);
  EXPECT_GT(one.frames[2].truth->d_px, 1.0) << "flown back: the one velocity is wrong for it";
  std::printf("  --effect velocity= for all: %s D after %.4f px, %s D after %.3f px\n",
              one.frames[0].source_image.c_str(), one.frames[0].truth->d_px,
              one.frames[2].source_image.c_str(), one.frames[2].truth->d_px);
}

// The navigation a PX4 log would record of a nadir camera flying velocity_cam_mps (camera axes,
// horizontal) with its image's top toward yaw_deg, its body axes the camera's: velocity (NED) at
// 10 Hz and attitude at 50 Hz from 0 to until_s.
ULogWriteOptions NavigationOf(const Eigen::Vector2d& velocity_cam_mps, double yaw_deg,
                              double until_s) {
  const double yaw = yaw_deg * kRadPerDeg;
  Eigen::Matrix3d ned_from_camera;  // columns: image right, image down, the view (down)
  ned_from_camera << -std::sin(yaw), -std::cos(yaw), 0.0, std::cos(yaw), -std::sin(yaw), 0.0, 0.0,
      0.0, 1.0;
  const Eigen::Vector3d ned =
      ned_from_camera * Eigen::Vector3d(velocity_cam_mps.x(), velocity_cam_mps.y(), 0.0);
  ULogWriteOptions out;
  for (int64_t t_ns = 1'000'000; t_ns <= SecondsToNs(until_s); t_ns += 20'000'000) {
    if (t_ns % 100'000'000 == 1'000'000) out.velocity.push_back({t_ns, ned});
    out.attitude.push_back({t_ns, Eigen::Quaterniond(ned_from_camera)});
  }
  return out;
}

TEST(CorrectPhotos, APhotoThatRecordsNoSpeedTakesTheLogsVelocity) {
  // A line flown at (-6, 3, 0) m/s in camera axes, heading 30 deg, as a PX4 ULog with its
  // navigation (vehicle_local_position's velocity, vehicle_attitude). DJI_0001 records its gimbal
  // but no speed: the log's velocity turned by the gimbal. DJI_0002 records neither (a camera
  // without DJI's XMP): the log's velocity turned by the log's attitude and camera.json's mounting
  // (identity: the camera's axes are the log's body axes). DJI_0003 records its speed but not its
  // gimbal: its own speed turned by the log's attitude. All are corrected to interpolation. A log
  // whose navigation ends before the photos leaves their translation, said.
  test::TempDir dir;
  const Eigen::Vector2d line_mps(-6.0, 3.0);
  const std::vector<double> times_s = {20.0, 24.0, 28.0};
  const Rendered rendered = Render(dir, "line", {"velocity=-6m/s,3m/s,0"}, times_s);
  const std::vector<FrameEntry> frames = ReadFramesCsv(rendered.dataset + "/frames.csv");
  const fs::path photos = dir.path() / "photos";
  fs::create_directories(photos);
  WriteFileAtomically(
      photos / "DJI_0001.JPG",
      DjiPhotoMovingAt(ReadImage(rendered.dataset + "/" + frames[0].image), 30.0, std::nullopt));
  WriteImage((photos / "DJI_0002.JPG").string(),
             ReadImage(rendered.dataset + "/" + frames[1].image));
  WriteFileAtomically(
      photos / "DJI_0003.JPG",
      DjiPhotoMovingAt(ReadImage(rendered.dataset + "/" + frames[2].image), 30.0, line_mps, false));
  WriteFileAtomically(dir / "triggers.csv",
                      "image,t\nDJI_0001.JPG,20\nDJI_0002.JPG,24\nDJI_0003.JPG,28\n");
  std::vector<GyroSample> samples = FlightGyro().samples();
  samples.erase(samples.begin());  // PX4 times are unsigned and 0 means unset: start at 1 ms
  const GyroTrace gyro(std::move(samples));
  WriteULog(dir / "flight.ulg", gyro, {}, NavigationOf(line_mps, 30.0, 30.0));
  WriteULog(dir / "short.ulg", gyro, {}, NavigationOf(line_mps, 30.0, 10.0));

  CorrectOptions options = DjiPhotoOptions(dir, photos, dir / "flight.ulg", dir / "triggers.csv");
  options.truth_dir = rendered.dataset + "/truth";
  const CorrectSummary summary = CorrectDataset(options);
  ASSERT_EQ(summary.frames.size(), 3u);
  const std::string log_velocity = "from the log's vehicle_local_position.vx,vy,vz";
  const std::vector<std::string> from = {log_velocity, log_velocity,
                                         "from the photo's XMP drone-dji, turned"};
  const std::string log_attitude =
      "turned by the log's vehicle_attitude.q and camera.json's gyro_to_camera";
  const std::vector<std::string> turned_by = {"turned by the photo's gimbal's yaw 30.0 deg",
                                              log_attitude, log_attitude};
  for (size_t i = 0; i < 3; ++i) {
    const CorrectedFrame& f = summary.frames[i];
    std::printf("  %s: velocity (%.4f, %.4f, %.4f) m/s, D before %.3f px, after %.4f px: %s\n",
                f.source_image.c_str(), f.velocity_mps.x(), f.velocity_mps.y(), f.velocity_mps.z(),
                f.truth->d_before_px, f.truth->d_px, f.translation.c_str());
    // float32 in the log: a few micrometres a second.
    EXPECT_NEAR((f.velocity_mps.head<2>() - line_mps).norm(), 0.0, 1e-5) << f.source_image;
    EXPECT_NEAR(f.velocity_mps.z(), 0.0, 1e-6) << f.source_image;
    EXPECT_LE(f.truth->rms_px, kInterpolationRmsPx) << f.source_image;
    EXPECT_NE(f.translation.find("6.71 m/s toward "), std::string::npos) << f.translation;
    EXPECT_NE(f.translation.find(from[i]), std::string::npos) << f.translation;
    EXPECT_NE(f.translation.find(turned_by[i]), std::string::npos) << f.translation;
  }

  options.photos->log_path = dir / "short.ulg";
  options.out_dir = dir / "short";
  const std::string beyond_the_log =
      "the photo records no flight speed, and the log's (vehicle_local_position.vx,vy,vz (where "
      "v_xy_valid)) does not reach its time";
  const std::vector<std::string> why = {
      beyond_the_log, beyond_the_log,
      "6.71 m/s toward 273 deg from the photo's XMP drone-dji, but neither the photo nor the "
      "log gives the camera's attitude"};
  const std::vector<CorrectedFrame> short_log = CorrectDataset(options).frames;
  ASSERT_EQ(short_log.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_GT(short_log[i].truth->d_px, 0.5) << "its translation is not corrected";
    EXPECT_EQ(short_log[i].translation, "rotation only: " + why[i]);
  }
}

TEST(CorrectPhotos, ASurveysPhotosMatchTheirGlobalShutterReferences) {
  // A survey (render/survey.h) over flat ground with a multirotor's rotation and the flight's
  // translation, corrected as a mapper would run it: its photos, its ULog, its camera. The
  // survey's ray-traced truth and the correction's model are two implementations of the same
  // geometry: the D each says of a photo agree, and each corrected photo matches its
  // global-shutter reference (same middle-row pose) far better than the photo did.
  test::TempDir dir;
  SurveyOptions survey;
  survey.camera = DeclaredRig().camera;
  survey.altitude_m = kAltitudeM;
  survey.speed_mps = 7.0;
  survey.lines = 2;
  survey.photos_per_line = 2;
  survey.terrain.hill_height_m = 0.0;
  survey.terrain.buildings = 0;
  survey.terrain.cell_m = 0.5;
  std::vector<GyroSample> samples = FlightGyro().samples();
  samples.erase(samples.begin());  // PX4 times start above 0
  const SurveySummary written = WriteSurvey(survey, GyroTrace(std::move(samples)), dir / "survey");
  CorrectOptions options;
  options.dataset_dir = dir / "survey/images";
  options.out_dir = dir / "corrected";
  options.reference = CorrectionReference::kMidReadout;
  options.pictures = false;
  options.photos.emplace();
  options.photos->log_path = dir / "survey/flight.ulg";
  options.photos->camera = ReadRigModel(dir / "survey/truth/camera.json");
  options.photos->camera_path = dir / "survey/truth/camera.json";
  const CorrectSummary summary = CorrectDataset(options);
  ASSERT_EQ(summary.frames.size(), written.photos.size());
  for (size_t k = 0; k < written.photos.size(); ++k) {
    const std::string name = written.photos[k].name;
    const CorrectedFrame& f = summary.frames[k];
    ASSERT_EQ(f.source_image, name);
    // D measured in the images (dense flow against the reference, estimate/loop/measure.h).
    const cv::Mat reference = ReadImage(dir / ("survey/reference/" + name));
    const double before =
        MeasureDisplacement(reference, ReadImage(dir / ("survey/images/" + name))).d_px;
    const double after =
        MeasureDisplacement(reference, ReadImage(dir / ("corrected/images/" + name))).d_px;
    std::printf(
        "  %s: D %.3f px (survey's truth) against %.3f px (the correction's model); "
        "measured %.3f px before, %.3f px after\n",
        name.c_str(), written.photos[k].d_px, f.residual.d_before_px, before, after);
    EXPECT_NEAR(f.residual.d_before_px, written.photos[k].d_px, 0.03 * written.photos[k].d_px)
        << name;
    EXPECT_NEAR(before, written.photos[k].d_px, 0.15 * written.photos[k].d_px + 0.2) << name;
    // The measurement's own floor on these small JPEGs is a few tenths of a pixel.
    EXPECT_LT(after, std::min(0.6, 0.5 * before)) << name;
  }
}

TEST(CorrectEndToEnd, CameraMaskMovesWithEachFrame) {
  // camera.json's mask (the left quarter not to be used): each frame's mask in DIR is the
  // has-a-source mask less the camera mask moved with the frame, and DIR's camera.json names a
  // copy of it, so that DIR reads as a rig dataset again.
  test::TempDir dir;
  const Rendered rendered = Render(dir, "ds", {}, {12.0});
  const std::string plain = dir / "plain";
  Correct(rendered.dataset, plain);
  cv::Mat camera_mask(kHeight, kWidth, CV_8U, cv::Scalar(255));
  camera_mask.colRange(0, kWidth / 4).setTo(0);
  WriteImage(rendered.dataset + "/mask.png", camera_mask);
  RigModel rig = ReadRigModel(rendered.dataset + "/camera.json");
  rig.mask = "mask.png";
  WriteRigModel(rendered.dataset + "/camera.json", rig);
  const std::string masked = dir / "masked";
  Correct(rendered.dataset, masked);
  const cv::Mat without = ReadImage(plain + "/masks/images/0000_rs.png.png");
  const cv::Mat with = ReadImage(masked + "/masks/images/0000_rs.png.png");
  constexpr int kMarginPx = 12;  // beyond the frame's displacement
  EXPECT_EQ(cv::countNonZero(with.colRange(0, kWidth / 4 - kMarginPx)), 0);
  EXPECT_EQ(cv::norm(with.colRange(kWidth / 4 + kMarginPx, kWidth),
                     without.colRange(kWidth / 4 + kMarginPx, kWidth), cv::NORM_INF),
            0.0);
  const RigDataset out = ReadRigDataset(masked);
  EXPECT_EQ(out.declared.mask, "camera_mask.png");
  EXPECT_EQ(cv::norm(out.mask, camera_mask, cv::NORM_INF), 0.0);
}

TEST(CorrectEndToEnd, OverviewFromTheFramesInMemoryMatchesTheOneFromTheFiles) {
  // A first run draws overview.png's pictures while it corrects; a second, keeping every image,
  // draws them from the files (PNGs here: whole; a JPEG through libjpeg's scaled decode, which
  // tests/io/image_check_test.cc checks): the same overview.
  // Frames 1040 pixels wide, so that the pictures in memory are shrunk by 2 before the tile's 480.
  test::TempDir dir;
  const Rendered rendered = Render(dir, "ds", {}, {8.0, 12.0}, false,
                                   test::NadirRig(1040, 780, 1300.0, 0.030, kAltitudeM));
  CorrectOptions options;
  options.dataset_dir = rendered.dataset;
  options.out_dir = dir / "out";
  ASSERT_EQ(CorrectDataset(options).frames.size(), 2u);
  const std::string overview = (fs::path(options.out_dir) / "overview.png").string();
  const cv::Mat drawn = ReadImage(overview);
  const CorrectSummary again = CorrectDataset(options);
  ASSERT_TRUE(again.frames[0].kept && again.frames[1].kept);
  const cv::Mat from_files = ReadImage(overview);
  ASSERT_EQ(drawn.size(), from_files.size());
  // Whole blocks then the tile's width, against a resize straight to it: 3.2 levels RMS apart on
  // a rendered aerial texture; the recorded frame in the corrected one's place is 10.3 apart.
  // Not 0: the first run drew from memory (from the files both runs would be the same).
  const double rms =
      cv::norm(drawn, from_files, cv::NORM_L2) / std::sqrt(static_cast<double>(drawn.total()));
  EXPECT_LT(rms, 5.0);
  EXPECT_GT(rms, 0.5) << "the first run's pictures were not drawn in memory";
  EXPECT_GT(cv::mean(drawn)[0], 20.0) << "a picture, not black";
}

TEST(CorrectEndToEnd, ResumesKeepsInputsAndRefusesToOverwriteThem) {
  test::TempDir dir;
  const Rendered rendered = Render(dir, "ds", {}, {12.0});
  const std::string out = dir / "out";
  Correct(rendered.dataset, out);
  const fs::path image = fs::path(out) / "images/0000_rs.png";
  const auto written = fs::last_write_time(image);
  const CorrectSummary again = Correct(rendered.dataset, out);
  ASSERT_EQ(again.frames.size(), 1u);
  EXPECT_TRUE(again.frames[0].kept);
  EXPECT_EQ(fs::last_write_time(image), written) << "an image already written is skipped";
  CorrectOptions force;
  force.dataset_dir = rendered.dataset;
  force.out_dir = out;
  force.force = true;
  force.pictures = false;
  EXPECT_FALSE(CorrectDataset(force).frames[0].kept);
  force.out_dir = rendered.dataset;
  EXPECT_THROW(CorrectDataset(force), IoError) << "never into the input";
}

TEST(CorrectEndToEnd, JpegInputKeepsItsQualityAndVideoIsRotationOnly) {
  test::TempDir dir;
  const Rendered rendered = Render(dir, "video", {}, {12.0, 12.033, 12.066}, /*video=*/true);
  // The same dataset with its frames as JPEG at quality 80.
  const fs::path jpeg = dir.path() / "jpeg";
  fs::create_directories(jpeg / "images");
  for (const char* file : {"camera.json", "gyro.csv"}) {
    fs::copy_file(fs::path(rendered.dataset) / file, jpeg / file);
  }
  std::vector<FrameEntry> frames = ReadFramesCsv(rendered.dataset + "/frames.csv");
  for (FrameEntry& f : frames) {
    const cv::Mat image = ReadImage(rendered.dataset + "/" + f.image);
    f.image = fs::path(f.image).replace_extension(".jpg").string();
    ImageLike like;
    like.info.jpeg_quality = 80;
    WriteImageLike((jpeg / f.image).string(), image, like, {{"Xmp.dc.source", "a test"}});
  }
  WriteFramesCsv((jpeg / "frames.csv").string(), frames);
  CorrectOptions options;
  options.dataset_dir = jpeg.string();
  options.out_dir = dir / "out";
  const CorrectSummary summary = CorrectDataset(options);
  EXPECT_TRUE(summary.video);
  EXPECT_FALSE(summary.setting.plane_depth_m);
  EXPECT_NE(summary.translation.find("rotation only"), std::string::npos) << summary.translation;
  ASSERT_EQ(summary.frames.size(), 3u);
  const std::string first = (fs::path(options.out_dir) / frames[0].image).string();
  EXPECT_EQ(ReadImageFileInfo(first).jpeg_quality, 80);
  const auto metadata = ReadImageMetadata(first);
  const auto has = [&](const std::string& key, const std::string& value) {
    return std::find(metadata.begin(), metadata.end(), std::make_pair(key, value)) !=
           metadata.end();
  };
  EXPECT_TRUE(has("Xmp.dc.source", "a test")) << "the input's metadata is carried";
  EXPECT_TRUE(has("Xmp.shutterlab.Reference", "row0"));
  for (const FrameEntry& f : ReadFramesCsv((fs::path(options.out_dir) / "frames.csv").string())) {
    EXPECT_TRUE(f.ref.empty()) << "a video dataset again";
  }
  EXPECT_TRUE(fs::is_regular_file(fs::path(options.out_dir) / "overview.png"));
  // With a depth, video corrects translation too; its truth is frame-to-frame, which --truth
  // refuses.
  options.depth_m = 40.0;
  options.out_dir = dir / "out_depth";
  options.pictures = false;
  const CorrectSummary with_depth = CorrectDataset(options);
  EXPECT_EQ(with_depth.setting.plane_depth_m, 40.0);
  EXPECT_NE(with_depth.translation.find("--depth"), std::string::npos) << with_depth.translation;
  options.check_truth = true;
  EXPECT_THROW(CorrectDataset(options), std::invalid_argument);
  // A dataset's frame cut short is not skipped as a photo would be: the run stops, naming it.
  options.check_truth = false;
  options.out_dir = dir / "out_cut";
  const fs::path second = jpeg / frames[1].image;
  const std::string whole = ReadFileToString(second);
  WriteFileAtomically(second, whole.substr(0, whole.size() * 3 / 4));
  try {
    CorrectDataset(options);
    ADD_FAILURE() << "a cut frame was corrected";
  } catch (const UndecodableImage& e) {
    EXPECT_EQ(std::string(e.what()), second.string() +
                                         ": its image data does not decode (Premature end of JPEG "
                                         "file): a cut or damaged file; copy it from the card "
                                         "again");
  }
}

}  // namespace
}  // namespace shutterlab
