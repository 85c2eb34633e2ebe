#include "estimate/demo_dataset.h"

#include "estimate/report/validate_report.h"
#include "io/image_io.h"
#include "model/camera.h"
#include "render/ground_texture.h"
#include "render/render_dataset.h"
#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"

#include <filesystem>

namespace shutterlab {

namespace fs = std::filesystem;

RigModel DemoRenderCamera() {
  RigModel rig;
  rig.camera.width = 1280;
  rig.camera.height = 720;
  rig.camera.fx = rig.camera.fy = 1400.0;
  rig.camera.cx = (rig.camera.width - 1) / 2.0;
  rig.camera.cy = (rig.camera.height - 1) / 2.0;
  rig.shutter.readout_s = 0.030;
  rig.cam_from_gyro << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  rig.altitude_m = 50.0;
  return rig;
}

RigModel DemoAnalyzeCamera() {
  RigModel rig = DemoRenderCamera();
  rig.camera.height = 960;
  rig.camera.fx = rig.camera.fy = 1100.0;
  rig.camera.cy = (rig.camera.height - 1) / 2.0;
  return rig;
}

DemoInputs WriteDemoInputs(const std::string& log_path, const std::string& scene_path) {
  constexpr double kDemoAltitudeM = 50.0;
  SynthOptions flight;
  flight.profile = MotionProfile::kFlight;
  flight.rate_hz = 1000.0;
  flight.duration_s = 60.0;
  flight.t0_s = 1.0;  // ULog times start after 0
  flight.seed = 7;
  SynthOutputOptions output;
  output.out_path = log_path;
  output.ulog = true;
  output.trigger_every_s = 2.0;
  output.altitude_m = kDemoAltitudeM;
  WriteSynthetic(flight, output);
  DemoInputs inputs;
  inputs.log = ReadFlightLog(log_path);
  // The scene as docs/FORMATS.md "The scene image" takes it: seen by a pinhole with the rig's
  // focal length from the world origin.
  const RigModel rig = DemoRenderCamera();
  GroundTextureOptions scene;
  scene.width_px = 2 * rig.camera.width;
  scene.height_px = 2 * rig.camera.height;
  scene.ground_sample_distance_m = kDemoAltitudeM / rig.camera.fx;
  WriteImage(scene_path, MakeGroundTexture(scene));
  inputs.scene_width_px = scene.width_px;
  inputs.scene_height_px = scene.height_px;
  inputs.scene_m_per_px = scene.ground_sample_distance_m;
  return inputs;
}

std::vector<int64_t> DemoFrameTimesNs(const GyroTrace& gyro, double readout_s, double every_s) {
  SHUTTERLAB_CHECK(every_s > 0) << "the frame interval must be positive";
  std::vector<int64_t> times_ns;
  for (int64_t t = gyro.t_begin_ns() + SecondsToNs(2.0);
       t + SecondsToNs(readout_s + 0.1) < gyro.t_end_ns(); t += SecondsToNs(every_s)) {
    times_ns.push_back(t);
  }
  return times_ns;
}

void InjectedDemoOptions::Check() const {
  SHUTTERLAB_CHECK(!scene_path.empty()) << "a scene image is required";
  SHUTTERLAB_CHECK(!out_dir.empty()) << "an output folder is required";
  SHUTTERLAB_CHECK(frames >= 2 && frames <= 100)
      << "frames must be in 2..100 (got " << frames << ")";
  SHUTTERLAB_CHECK(width >= 64 && height >= 48) << "image must be at least 64x48";
}

ValidationResult RenderAndValidate(const InjectedDemoOptions& options,
                                   const ValidateProgress& progress) {
  options.Check();
  const fs::path out(options.out_dir);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw IoError(IoMessage(options.out_dir, 0, "cannot create folder: " + ec.message()));
  RigModel rig;
  rig.camera.width = options.width;
  rig.camera.height = options.height;
  rig.camera.fx = rig.camera.fy =
      1100.0 * options.width / 1280.0;  // a mapping camera's field of view
  rig.camera.cx = 0.5 * (options.width - 1);
  rig.camera.cy = 0.5 * (options.height - 1);
  rig.shutter.readout_s = 0.030;
  rig.altitude_m = 50.0;
  WriteRigModel((out / "camera.json").string(), rig);
  // A perfect gyro: the injected effect is the only thing camera.json does not declare.
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 1000.0;
  synth.seed = options.seed;
  synth.imu = ImuErrorModel::Ideal();
  const double first_s = 8.0, every_s = 1.7;  // after the 6 s still lead and 1 s spin-up
  synth.duration_s = first_s + every_s * options.frames + 2.0;
  WriteGyroCsv((out / "gyro.csv").string(), SynthesizeTrace(synth));
  std::string times = "frame,t_first_row\n";
  for (int i = 0; i < options.frames; ++i) {
    times += std::to_string(i) + "," + FormatNumber("%.6f", first_s + every_s * i) + "\n";
  }
  WriteFileAtomically((out / "times.csv").string(), times);
  RenderOptions render;
  render.scene_path = options.scene_path;
  render.camera_path = (out / "camera.json").string();
  render.gyro_path = (out / "gyro.csv").string();
  render.frames_path = (out / "times.csv").string();
  render.out_dir = (out / "dataset").string();
  if (!options.injection.empty()) render.injections = {options.injection};
  RenderDataset(render, [&](size_t done, size_t total) {
    if (progress) progress("render", done, total);
  });
  ValidateOptions validate;
  const ValidationResult result = ValidateDataset(render.out_dir, validate, progress);
  WriteValidationPlots((out / "plots").string(), result);
  WriteFileAtomically((out / "report.json").string(), ValidationToJson(result).dump(2) + "\n");
  return result;
}

}  // namespace shutterlab
