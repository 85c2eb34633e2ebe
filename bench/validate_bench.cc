// validate_bench: the issue-4 speed target. Renders a 12-frame 1280x960 rig dataset (real aerial
// scene, multirotor-like ideal gyro, 30 ms readout, 50 m, a 4 ms undeclared time offset) into a
// temporary folder, then times ValidateDataset with every candidate effect, per stage.
// Target: under 60 s on the project's 2-core machine.
//
//   build/bin/validate_bench [--frames N] [--keep DIR]

#include "estimate/validate.h"
#include "render/render_dataset.h"
#include "sim/gyro_io.h"
#include "sim/synth.h"
#include "sim/text_file.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#ifndef SHUTTERLAB_SOURCE_DIR
#define SHUTTERLAB_SOURCE_DIR "."
#endif

using namespace shutterlab;

int main(int argc, char** argv) {
  int frames = 12;
  std::string keep;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--frames") frames = std::atoi(argv[i + 1]);
    if (flag == "--keep") keep = argv[i + 1];
  }
  namespace fs = std::filesystem;
  const fs::path dir = keep.empty() ? fs::temp_directory_path() / "shutterlab_validate_bench"
                                    : fs::path(keep);
  fs::create_directories(dir);
  RigModel rig;
  rig.camera.width = 1280;
  rig.camera.height = 960;
  rig.camera.fx = rig.camera.fy = 1100.0;
  rig.camera.cx = 639.5;
  rig.camera.cy = 479.5;
  rig.shutter.readout_s = 0.030;
  rig.altitude_m = 50.0;
  WriteRigModel((dir / "camera.json").string(), rig);
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 1000.0;
  synth.duration_s = 40.0;
  synth.seed = 3;
  synth.imu = ImuErrorModel::Ideal();
  WriteGyroCsv((dir / "gyro.csv").string(), SynthesizeTrace(synth));
  std::string times = "frame,t_first_row\n";
  for (int i = 0; i < frames; ++i) times += std::to_string(i) + "," + std::to_string(8.0 + 2.5 * i) + "\n";
  WriteFileAtomically((dir / "times.csv").string(), times);
  RenderOptions render;
  render.scene_path = std::string(SHUTTERLAB_SOURCE_DIR) + "/assets/scenes/siyi_zr10_img0100.jpg";
  if (!fs::exists(render.scene_path)) render.scene_path = "assets/scenes/siyi_zr10_img0100.jpg";
  render.camera_path = (dir / "camera.json").string();
  render.gyro_path = (dir / "gyro.csv").string();
  render.frames_path = (dir / "times.csv").string();
  render.out_dir = (dir / "ds").string();
  render.injections = {"time_offset=0.004"};
  render.pictures = false;
  std::printf("rendering %d frames of 1280x960 into %s ...\n", frames, render.out_dir.c_str());
  RenderDataset(render);

  ValidateOptions options;  // every candidate (LoopOptions default)
  options.keep_residuals = false;
  const auto start = std::chrono::steady_clock::now();
  const ValidationResult result = ValidateDataset(render.out_dir, options);
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("validate %zu frames of 1280x960, all candidates: %.2f s total (target < 60 s: %s)\n",
              result.frames.size(), total_s, total_s < 60.0 ? "met" : "MISSED");
  std::printf("  read %.2f s, measure %.2f s (%.2f s/frame), predict %.2f s, loop %.2f s\n",
              result.read_s, result.measure_s, result.measure_s / result.frames.size(),
              result.predict_s, result.loop_s);
  std::printf("  found:");
  for (const IdentifiedEffect& e : result.loop.effects) std::printf(" %s", e.name.c_str());
  std::printf(" (time_offset %.5f s, truth 0.00400 s); after %.3f px, noise %.3f px\n",
              result.loop.model.rig.time_offset_s, result.loop.after.rms_px, result.loop.noise_px);
  if (keep.empty()) fs::remove_all(dir);
  return 0;
}
