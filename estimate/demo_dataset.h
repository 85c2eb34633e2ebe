#pragma once
// The demo's closing-the-loop dataset: rendered with one undeclared effect, then validated.

#include "estimate/loop/validate.h"

#include <cstdint>
#include <string>

namespace shutterlab {

// For the demo: renders a small rig dataset with ONE effect in the truth that camera.json does not
// declare (a multirotor-like ideal gyro, sim/motion.h; 30 ms readout, 50 m, f = 1100 px at 1280
// wide scaled to `width`), validates it and writes out_dir/dataset (the rig dataset and its truth),
// out_dir/report.json and out_dir/plots (WriteValidationPlots, validate.html).
struct InjectedDemoOptions {
  std::string scene_path;                       // nadir scene image
  std::string out_dir;                          // created if missing
  std::string injection = "time_offset=0.004";  // render --inject NAME=VALUE
  int frames = 6;
  int width = 640, height = 480;
  uint64_t seed = 3;  // the flight motion
  void Check() const;
};
ValidationResult RenderAndValidate(const InjectedDemoOptions& options,
                                   const ValidateProgress& progress = {});

}  // namespace shutterlab
