// validate_bench: validate's speed target (under 60 s). Renders a 12-frame 1280x960 rig dataset
// (real aerial scene, multirotor-like ideal gyro, 30 ms readout, 50 m, a 4 ms undeclared time
// offset) with RenderAndValidate and prints ValidateDataset's time per stage, every candidate
// effect tried. Target: validate under 60 s on the project's 2-core machine (rendering and plots
// not counted).
//
//   build/bin/validate_bench [--frames N] [--keep DIR]     (run from the repository root)

#include "bench/bench_util.h"
#include "estimate/demo_dataset.h"
#include "estimate/loop/validate.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

int main(int argc, char** argv) {
  using namespace shutterlab;
  namespace fs = std::filesystem;
  InjectedDemoOptions options;
  options.frames = 12;
  options.width = 1280;
  options.height = 960;
  options.scene_path = bench::RealDataPath("images/siyi_zr10/IMG_0100.jpg");
  std::string keep;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--frames") options.frames = std::atoi(argv[i + 1]);
    if (flag == "--keep") keep = argv[i + 1];
  }
  options.out_dir =
      keep.empty() ? (fs::temp_directory_path() / "shutterlab_validate_bench").string() : keep;
  std::printf("rendering and validating %d frames of 1280x960 in %s ...\n", options.frames,
              options.out_dir.c_str());
  const ValidationResult result = RenderAndValidate(options);
  const double total_s = result.read_s + result.measure_s + result.predict_s + result.loop_s;
  std::printf("validate %zu frames of 1280x960, all candidates: %.2f s (target < 60 s: %s)\n",
              result.frames.size(), total_s, total_s < 60.0 ? "met" : "MISSED");
  std::printf("  read %.2f s, measure %.2f s (%.2f s/frame), predict %.2f s, loop %.2f s\n",
              result.read_s, result.measure_s, result.measure_s / result.frames.size(),
              result.predict_s, result.loop_s);
  std::printf("  found:");
  for (const IdentifiedEffect& e : result.loop.effects)
    std::printf(" %s", Spec(e.effect).name.c_str());
  std::printf(" (time_offset %.5f s, truth 0.00400 s); after %.3f px, noise %.3f px\n",
              result.loop.model.rig.time_offset_s, result.loop.after.rms_px, result.loop.noise_px);
  if (keep.empty()) fs::remove_all(options.out_dir);
  return 0;
}
