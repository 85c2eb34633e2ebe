#include "estimate/demo_dataset.h"

#include "estimate/report/validate_report.h"
#include "render/camera.h"
#include "render/render_dataset.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"

#include <filesystem>

namespace shutterlab {

namespace fs = std::filesystem;

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
