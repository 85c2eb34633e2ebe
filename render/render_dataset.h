#pragma once
// `shutterlab render`: renders a rig dataset with exact ground truth from a scene image, a declared
// camera, a gyro log and capture times (docs/FORMATS.md "Rig dataset", "Render output").
//
// DIR receives:
//   camera.json, gyro.csv          the DECLARED camera and the logged gyro, as given
//   frames.csv                     frame,t_first_row,ref,image
//   images/NNNN_ref.png            global-shutter reference (every row at the true time of row 0)
//   images/NNNN_rs.png             rolling-shutter image
//   truth/NNNN_disp.exr            d(p) = p_ref - p, float32 channels dx, dy, pixels
//   truth.json                     {"injected": {...}, "frames": [{"frame", "D_px", "D_m"}, ...]}
//   truth/NNNN_heat.png, truth/NNNN_side.png, overview.png   pictures (unless pictures = false)
// The truth differs from camera.json by the --inject effects only (model/truth_model.h).
//
// With `video`, DIR is a video rig dataset (docs/FORMATS.md "Video datasets"): consecutive
// rolling-shutter frames of one continuing flight, all in the world of the first frame's row 0
// (CameraMotion::Frame with that anchor), `ref` empty, no reference images. truth/NNNN_disp.exr of
// every frame but the first holds q - p: for each pixel p of the frame, its match q in the previous
// frame of frames.csv (VideoDisplacementField). truth.json marks "video": true and names each
// frame's "previous"; D_px / D_m stay each frame's own distortion against a global shutter at its
// row 0.
// With clutter (render/clutter.h), the moving patch's clock is the camera clock from the first
// frame's first row (video) or from each frame's row 0 (stills, so that the reference sees it where
// row 0 does), and it crosses the scene point above the scene's centre (15 % of the frame height)
// in the middle of the clip (video) or at each frame's row 0 (stills).
// With a stabiliser (video only), every row of frame k is seen turned by the frame's S_k
// (render/stabiliser.h); truth.json's "stabiliser" holds the mode, the window and each frame's
// S_k as a rotation vector in degrees (camera axes), and the truth fields are of the turned frames.

#include "io/lens_profile.h"
#include "model/effects.h"
#include "render/clutter.h"
#include "render/rs_warp.h"
#include "render/stabiliser.h"
#include "sim/log_warning.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct RenderOptions {
  std::string scene_path;   // scene image (docs/FORMATS.md "The scene image")
  std::string camera_path;  // declared camera.json
  // A Gyroflow lens profile (io/lens_profile.h): its lens, scaled to camera.json's image size,
  // and its readout where it states one, replace camera.json's (the written camera.json holds
  // them).
  std::string lens_profile_path;
  std::string gyro_path;                // gyro.csv (gyro clock, gyro axes)
  std::string frames_path;              // frame,t_first_row (camera clock, first row read)
  std::string out_dir;                  // created if missing
  std::vector<std::string> injections;  // "NAME=VALUE", docs/FORMATS.md effect names
  Interpolation interpolation = Interpolation::kBilinear;
  bool pictures = true;  // heatmaps, side-by-side panels and the overview
  bool video = false;    // a video dataset (above); frame times must increase
  // Known-answer clutter (render/clutter.h): a camera-fixed patch over the bottom rows of every
  // frame and reference (truth 0 there), a patch driving over the ground (truth NaN where seen).
  // truth.json records both.
  ClutterOptions clutter;
  // A video re-rendered by a stabiliser (render/stabiliser.h); truth.json records its mode, window
  // and each frame's rotation.
  StabiliserOptions stabiliser;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct RenderedFrame {
  int64_t frame = 0;
  double d_px = 0.0;  // docs/FORMATS.md frame distortion D, pixels
  double d_m = 0.0;   // D on the ground, m
  double outside_fraction =
      0.0;  // share of rolling-shutter pixels that see outside the scene (black)
};

struct RenderSummary {
  std::optional<LensProfileUse> lens_profile;  // what --lens-profile gave, with its notes
  std::vector<Injection> injected;             // each `--inject` as truth.json records it, in order
  std::vector<RenderedFrame> frames;
  // What gyro.csv lost or doubted (sim/trace_audit.h), for the command to say: the truth is
  // rendered from the trace as it is.
  std::vector<LogWarning> gyro_warnings;
};

// Reads and checks every input (and every frame's time against the gyro trace) before writing
// anything, so bad input leaves no output; each file is written whole or not at all.
// progress(done, total) is called after each frame when given.
RenderSummary RenderDataset(const RenderOptions& options,
                            const std::function<void(size_t, size_t)>& progress = {});

// Share of pixels whose scene sample lies (partly) outside the scene: what comes out black.
double OutsideSceneFraction(const FrameGeometry& geometry, cv::Size scene_size);

}  // namespace shutterlab
