#pragma once
// The demo's data, made here: its cameras, its inputs (a survey flight written as a PX4 ULog and a
// procedural nadir ground texture), the frame times it renders, and its closing-the-loop dataset
// (rendered with one undeclared effect, then validated).

#include "estimate/loop/validate.h"
#include "model/camera.h"
#include "sim/gyro_trace.h"
#include "sim/logs/flight_log.h"

#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab {

// The demo camera: a 1280x720 mapping camera, 30 ms readout, 50 m above ground, looking down with
// the image top towards the nose. The flight log's gyro is about the body's roll, pitch, yaw axes
// (x forward, y right, z down, as PX4 logs it), so camera x (right) = body y, camera y (down the
// image) = -body x.
RigModel DemoRenderCamera();

// The analyze camera: a typical mapping camera (1280x960, f = 1100 px, 30 ms readout, 50 m),
// mounted as DemoRenderCamera.
RigModel DemoAnalyzeCamera();

// The demo's survey flight, a multirotor with an MPU-9250-like gyro at 1 kHz (60 s, a still lead
// for the bias, seed 7), written as a PX4 ULog with a camera trigger every 2 s and its altitude
// (50 m) to log_path and read back; the scene (render/ground_texture.h) at the render camera's
// ground sample distance, twice its frame's size, written to scene_path.
struct DemoInputs {
  FlightLog log;  // the ULog as the readers read it
  int scene_width_px = 0, scene_height_px = 0;
  double scene_m_per_px = 0.0;
};
DemoInputs WriteDemoInputs(const std::string& log_path, const std::string& scene_path);

// Frame times a mapping camera would take over the trace: every every_s from 2 s in, each frame's
// readout (and 0.1 s) inside the trace; ns on the trace's clock.
std::vector<int64_t> DemoFrameTimesNs(const GyroTrace& gyro, double readout_s, double every_s);

// For the demo: renders a small rig dataset with ONE effect in the truth that camera.json does not
// declare (a multirotor-like ideal gyro, sim/synth/motion.h; 30 ms readout, 50 m, f = 1100 px at
// 1280 wide scaled to `width`), validates it and writes out_dir/dataset (the rig dataset and its
// truth), out_dir/report.json and out_dir/plots (WriteValidationPlots, validate.html).
struct InjectedDemoOptions {
  std::string scene_path;                     // nadir scene image
  std::string out_dir;                        // created if missing
  std::string injection = "time_offset=4ms";  // render --inject NAME=VALUE
  int frames = 6;
  int width = 640, height = 480;
  uint64_t seed = 3;  // the flight motion
  void Check() const;
};
ValidationResult RenderAndValidate(const InjectedDemoOptions& options,
                                   const ValidateProgress& progress = {});

}  // namespace shutterlab
