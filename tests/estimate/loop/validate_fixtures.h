#pragma once
// What the validation tests (still, foreign and video datasets, and the report's) share: the
// acceptance, the rendered datasets with one undeclared effect, a loop's summary.

#include "estimate/loop/validate.h"
#include "io/frames_csv.h"
#include "model/effect_io.h"
#include "render/render_dataset.h"
#include "sim/logs/gyro_io.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"
#include "tests/estimate/loop/effect_fixtures.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab::test {

// Acceptance for "at the noise level": a residual no more than this times the measured noise.
// Identified cases reach it after the loop; a dataset with nothing undeclared, before it.
inline constexpr double kAtNoiseRatio = 1.5;

// ValidateDataset with its defaults, but no residual images kept (the tests read only numbers).
inline ValidationResult ValidateWithoutResiduals(const std::string& dataset) {
  ValidateOptions options;
  options.keep_residuals = false;
  return ValidateDataset(dataset, options);
}

// Still datasets (tests/estimate/loop/validate_test.cc): 8 frames of 1280x960, fx = 1100 px, 30 ms
// readout, 50 m (a typical mapping camera); under AddressSanitizer 6 frames of 640x480.
// Smaller and fewer frames under ASan, where the loop runs several times slower.
inline constexpr int kStillWidth = test::kAsan ? 640 : 1280;
inline constexpr int kStillHeight = test::kAsan ? 480 : 960;
inline constexpr int kStillFrames = test::kAsan ? 6 : 8;
inline constexpr double kStillFocalPx =
    1100.0 * kStillWidth / 1280.0;  // same field of view at either size
inline constexpr double kStillReadoutS = 0.030;
inline constexpr double kStillAltitudeM = 50.0;

struct DatasetSpec {
  std::vector<std::string> injections;  // render --inject NAME=VALUE ("" none)
  double log_s = 30.0;                  // gyro log length, s (motion starts after 6 s still + 1 s)
  double first_frame_s = 8.0, last_frame_s = 28.0;  // frame times spread evenly between these
  uint64_t seed = 3;                                // the flight motion's seed
  uint64_t scene_seed = 1;                          // the procedural ground texture's
  ClutterOptions clutter = {};                      // render --camera-fixed-patch, --moving-patch
};

inline RigModel DeclaredRig() {
  RigModel rig;
  rig.camera.width = kStillWidth;
  rig.camera.height = kStillHeight;
  rig.camera.fx = rig.camera.fy = kStillFocalPx;
  rig.camera.cx = 0.5 * (kStillWidth - 1);
  rig.camera.cy = 0.5 * (kStillHeight - 1);
  rig.shutter.readout_s = kStillReadoutS;
  rig.altitude_m = kStillAltitudeM;
  return rig;
}

// A perfect gyro (no noise or bias: the only undeclared effect is the injected one) on a
// multirotor-like motion (sim/synth/motion.h defaults), 1 kHz.
inline GyroTrace FlightGyro(const DatasetSpec& spec) {
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 1000.0;
  synth.duration_s = spec.log_s;
  synth.seed = spec.seed;
  synth.imu = ImuErrorModel::Ideal();
  return SynthesizeTrace(synth);
}

// Renders the dataset into dir/ds and returns that folder.
inline std::string MakeDataset(const test::TempDir& dir, const DatasetSpec& spec) {
  WriteRigModel(dir / "camera.json", DeclaredRig());
  WriteGyroCsv(dir / "gyro.csv", FlightGyro(spec));
  std::string times = "frame,t_first_row\n";
  for (int i = 0; i < kStillFrames; ++i) {
    const double t_s =
        spec.first_frame_s + (spec.last_frame_s - spec.first_frame_s) * i / (kStillFrames - 1);
    times += std::to_string(i) + "," + std::to_string(t_s) + "\n";
  }
  WriteFileAtomically(dir / "times.csv", times);
  RenderOptions render;
  render.scene_path = test::GroundScenePath(spec.scene_seed);
  render.camera_path = dir / "camera.json";
  render.gyro_path = dir / "gyro.csv";
  render.frames_path = dir / "times.csv";
  render.out_dir = dir / "ds";
  render.injections = spec.injections;
  render.pictures = false;
  render.clutter = spec.clutter;
  RenderDataset(render);
  return dir / "ds";
}

// A loop's result in a few lines, for a failing test's message: what each loop found, with its
// values, and the residual against the noise (the report's own text is estimate/report's, above
// the loop).
inline std::string LoopSummary(const ValidationResult& result) {
  std::string text;
  const auto loop_lines = [&text](const char* name, const LoopResult& loop) {
    text += std::string(name) + ": before rms " + std::to_string(loop.before.rms_px) + " px";
    for (const IdentifiedEffect& e : loop.effects) {
      text += "; + " + Spec(e.effect).name + " = " + EffectValueToJson(e.value).dump() + " +- " +
              EffectValueToJson(e.stderr_value).dump();
    }
    text += "; after rms " + std::to_string(loop.after.rms_px) + " px, noise " +
            std::to_string(loop.noise_px) + " px" + (loop.unexplained ? ", unexplained" : "") +
            "\n";
  };
  loop_lines("loop", result.loop);
  if (result.video) loop_lines("translation loop", result.translation_loop);
  if (result.video) text += "preferred: " + result.preferred + "\n";
  return text;
}

// Video datasets (tests/estimate/loop/validate_video_test.cc): 16 frames of 640x480 at 30 fps.
struct ClipSpec {
  std::vector<std::string> injections;
  RigModel declared = test::VideoRig();
  int frames = 16;
  double first_s = 12.6, fps = 30.0;
  double log_s = 20.0;
  ClutterOptions clutter = {};        // render --camera-fixed-patch, --moving-patch
  StabiliserOptions stabiliser = {};  // render --stabiliser, --stabiliser-window
};

// The clutter of the known-answer tests with it: the bottom quarter of every frame fixed to the
// camera (a dashboard) and a car driving across the ground at 10 m/s (about 4 px a frame).
inline ClutterOptions Clutter() {
  ClutterOptions clutter;
  clutter.camera_fixed_share = 0.25;
  clutter.moving_patch_mps = 10.0;
  return clutter;
}

inline std::string MakeClip(const test::TempDir& dir, const ClipSpec& spec) {
  WriteRigModel(dir / "camera.json", spec.declared);
  WriteGyroCsv(dir / "gyro.csv", test::FlightTrace(spec.log_s, 3));
  std::string times = "frame,t_first_row\n";
  for (int i = 0; i < spec.frames; ++i) {
    times += std::to_string(i) + "," + FormatNumber("%.9f", spec.first_s + i / spec.fps) + "\n";
  }
  WriteFileAtomically(dir / "times.csv", times);
  RenderOptions render;
  render.scene_path = test::GroundScenePath(2);
  render.camera_path = dir / "camera.json";
  render.gyro_path = dir / "gyro.csv";
  render.frames_path = dir / "times.csv";
  render.out_dir = dir / "clip";
  render.injections = spec.injections;
  render.pictures = false;
  render.video = true;
  render.clutter = spec.clutter;
  render.stabiliser = spec.stabiliser;
  RenderDataset(render);
  return dir / "clip";
}

}  // namespace shutterlab::test
