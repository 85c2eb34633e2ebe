// `shutterlab render`: a rolling-shutter rig dataset with exact ground truth
// (render/render_dataset.h).

#include "app/command.h"
#include "app/trace_options.h"  // PrintLogWarnings
#include "render/render_dataset.h"

#include <cstdio>
#include <memory>

namespace shutterlab::app {
namespace {

const CommandRegistration kRenderRegistration(50, [](CLI::App& app) {
  auto* cmd =
      app.add_subcommand("render", "render rolling-shutter frames and their exact ground truth");
  auto options = std::make_shared<RenderOptions>();
  auto interpolation = std::make_shared<std::string>("bilinear");
  cmd->add_option("--scene", options->scene_path, "scene image (nadir ground texture)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--camera", options->camera_path, "declared camera.json (rig/1)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--gyro", options->gyro_path, "gyro.csv (t,gx,gy,gz)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--frames", options->frames_path, "capture times: frame,t_first_row")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--lens-profile", options->lens_profile_path,
                  "Gyroflow lens profile (JSON): its lens, scaled to camera.json's image size, and "
                  "its readout where it states one, replace camera.json's")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", options->out_dir, "output dataset folder")->required();
  cmd->add_option(
      "--inject", options->injections,
      "NAME=VALUE: render with a true effect that camera.json does not declare (time_offset, "
      "readout_time, gyro_to_camera, gyro_scale, gyro_bias, velocity, lens_distortion, "
      "readout_direction, clock_rate); repeatable");
  cmd->add_option("--interpolation", *interpolation, "bilinear or bicubic")
      ->check(CLI::IsMember({"bilinear", "bicubic"}));
  cmd->add_flag("!--no-pictures", options->pictures,
                "skip heatmaps, side-by-side panels and overview");
  cmd->add_option("--camera-fixed-patch", options->clutter.camera_fixed_share,
                  "SHARE: the bottom SHARE of every frame's rows show a textured patch that moves "
                  "with the camera (a dashboard, landing gear); truth 0 there")
      ->check(CLI::Range(0.0, 0.9));
  AddQuantityOption(cmd, "--moving-patch", &options->clutter.moving_patch_mps, "m/s", "m/s",
                    "a textured square drives over the ground at this speed (along x), seen at "
                    "each row's own time; truth NaN where it is seen")
      ->default_str("");
  cmd->add_flag("--video", options->video,
                "a video dataset: consecutive rolling-shutter frames of one flight, no reference "
                "images; the truth of each frame is its match in the previous one");
  auto stabiliser = std::make_shared<std::string>("off");
  CLI::Option* stabiliser_option =
      cmd->add_option(
             "--stabiliser", *stabiliser,
             "with --video, a stabiliser re-renders the clip: whole (all axes smoothed), roll "
             "(horizon levelling: only the roll about the optical axis smoothed), roll-lock "
             "(the roll held at the first frame's), off")
          ->check(CLI::IsMember({"off", "whole", "roll", "roll-lock"}));
  AddQuantityOption(cmd, "--stabiliser-window", &options->stabiliser.window_s, "s", "s",
                    "the stabiliser's smoothing (the sigma of its Gaussian over time)")
      ->needs(stabiliser_option);
  return std::function<void()>([options, interpolation, stabiliser] {
    options->stabiliser.mode = *ParseStabiliserMode(*stabiliser);
    options->interpolation =
        *interpolation == "bicubic" ? Interpolation::kBicubic : Interpolation::kBilinear;
    options->Check();
    std::unique_ptr<Progress> bar;
    const RenderSummary summary = RenderDataset(*options, [&](size_t done, size_t total) {
      if (!bar) bar = std::make_unique<Progress>("render", total);
      bar->Update(done);
    });
    bar.reset();
    PrintLogWarnings(options->gyro_path, summary.gyro_warnings);
    if (summary.lens_profile) {
      for (const std::string& note : summary.lens_profile->notes) std::printf("%s\n", note.c_str());
    }
    std::printf("frame      D_px       D_m\n");
    for (const RenderedFrame& f : summary.frames) {
      std::printf("%5lld %9.3f %9.4f\n", static_cast<long long>(f.frame), f.d_px, f.d_m);
      if (f.outside_fraction > 0) {
        std::fprintf(
            stderr,
            "warning: frame %lld: %.2f%% of pixels see outside the scene (rendered black)\n",
            static_cast<long long>(f.frame), 100.0 * f.outside_fraction);
      }
    }
    std::printf("wrote %zu frames to %s\n", summary.frames.size(), options->out_dir.c_str());
  });
});

}  // namespace
}  // namespace shutterlab::app
