// `shutterlab import SOURCE --out DATASET`: a GoPro MP4 with GPMF telemetry or a phone clip folder
// into a video rig dataset (io/video_import.h).

#include "app/command.h"
#include "app/trace_options.h"  // PrintLogWarnings
#include "io/video_import.h"

#include <cstdio>
#include <memory>
#include <variant>

namespace shutterlab::app {
namespace {

// What `--gyro LOG` found: the log, the frames tracked, the offset and the mounting.
void PrintGyroLogAlignment(const GyroLogAlignment& log) {
  const GyroSync& sync = log.sync;
  std::printf("log      %s: %s %s, %zu samples over %.1f s\n", log.path.c_str(), log.format.c_str(),
              log.gyro_source.c_str(), log.log_samples, log.log_duration_s);
  if (log.pairs > 0)
    std::printf("tracked  %zu of %zu frame pairs show a rotation (median %zu rays)\n",
                log.pairs_used, log.pairs, log.median_inliers);
  std::printf(
      "aligned  log clock = clip clock + %.6f s (+- %.2f ms), mounting %.1f deg%s, by %s "
      "(peak correlation %.2f, next %.2f)\n",
      log.time_offset_s, sync.offset_stderr_s * 1e3, sync.mounting_angle_deg,
      sync.mounting_fitted ? "" : " (one axis only: identity kept)", log.method.c_str(),
      sync.peak_correlation, sync.runner_up_correlation);
}

const CommandRegistration kImportRegistration(55, [](CLI::App& app) {
  auto* cmd = app.add_subcommand("import",
                                 "real footage with its own gyro (GoPro MP4 with GPMF, phone clip "
                                 "folder) or with a flight log's (--gyro) -> video rig dataset");
  auto options = std::make_shared<ImportOptions>();
  cmd->add_option(
         "SOURCE", options->source,
         "a GoPro .mp4 with a gpmd track, a folder with gyro.txt, framestamp.txt, frames/, or "
         "with --gyro any .mp4 / .mov")
      ->required();
  cmd->add_option("--gyro", options->gyro_log,
                  "LOG: a flight controller's or recorder's log (any format analyze reads) whose "
                  "gyro the dataset takes, put on the clip's clock and axes from the motion (the "
                  "clip's own gyro, else the frames' rotation)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--camera", options->camera_path,
                  "camera.json (rig/1) of a video that states no camera (with --gyro): its "
                  "camera, lens and readout")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", options->out_dir,
                  "output dataset folder (replaced only if it is an earlier import)")
      ->required();
  cmd->add_option("--lens-profile", options->lens_profile_path,
                  "Gyroflow lens profile (JSON): the declared lens, scaled to the frames, and its "
                  "readout where the clip states none")
      ->check(CLI::ExistingFile);
  cmd->add_option("--max-frames", options->max_frames, "import at most N frames");
  cmd->add_option(
      "--start-frame", options->start_frame,
      "first frame id to import (GoPro: video frame index from 0; phone: frame number)");
  cmd->add_option("--mask", options->mask_path,
                  "MASK.png of the frames' size: white = may be measured, black = never (a "
                  "dashboard, landing gear, burned-in text); becomes the dataset's mask.png")
      ->check(CLI::ExistingFile);
  return std::function<void()>([options] {
    options->Check();
    std::unique_ptr<Progress> bar;
    size_t bar_total = 0;
    // The frames, then (--gyro on a video without a gyro) the pairs of frames tracked.
    const ImportSummary summary = ImportVideo(*options, [&](size_t done, size_t total) {
      if (!bar || total != bar_total) {
        bar.reset();
        bar = std::make_unique<Progress>(bar_total == 0 ? "import" : "track", total);
        bar_total = total;
      }
      bar->Update(done);
    });
    bar.reset();
    PrintLogWarnings(options->source, summary.record.warnings);
    const char* kind = summary.kind == ImportSource::kGoproMp4      ? "GoPro MP4 (GPMF)"
                       : summary.kind == ImportSource::kPhoneFolder ? "phone clip"
                                                                    : "video without a gyro";
    std::printf("source   %s: %s\n", kind, options->source.c_str());
    std::printf("gyro     %zu samples, %.2f Hz\n", summary.gyro_samples, summary.gyro_rate_hz);
    std::printf("frames   %zu, t_first_row %.6f .. %.6f s\n", summary.frames, summary.t_first_s,
                summary.t_last_s);
    const ImportRecord& record = summary.record;
    const auto* gopro = std::get_if<GoproImportDetails>(&record.details);
    const auto* video = std::get_if<VideoFileImportDetails>(&record.details);
    const int failed_grabs = gopro   ? gopro->decoding.failed_grabs
                             : video ? video->decoding.failed_grabs
                                     : 0;
    if (failed_grabs > 0)
      std::printf("note     the video reader failed %d grab(s) and went on\n", failed_grabs);
    if (gopro && gopro->settings.present) {
      const GoproSettings& s = gopro->settings;
      std::printf("camera   %s, firmware %s, stabiliser %s%s\n", s.model.c_str(),
                  s.firmware.c_str(), s.StabilizerOn() ? "ON: " : "off",
                  s.StabilizerOn() ? s.stabilizer_mode.c_str() : "");
    }
    if (gopro && gopro->iori_samples > 0)
      std::printf(
          "note     image_orientation.csv: the stabiliser's IORI for %zu frames, up to "
          "%.1f deg\n",
          gopro->orientation_frames, gopro->iori_max_deg);
    if (record.gyro_log) PrintGyroLogAlignment(*record.gyro_log);
    if (record.lens_profile) {
      for (const std::string& line : record.lens_profile->notes)
        std::printf("lens     %s\n", line.c_str());
    }
    for (const ImportClaim& claim : record.claims)
      std::printf("declared %-15s %-14s %s\n", claim.what.c_str(), ClaimStatusName(claim.status),
                  ClaimValueJson(claim.value).c_str());
    std::printf("wrote %s (camera.json, gyro.csv, frames.csv, images/, import.json)\n",
                options->out_dir.c_str());
  });
});

}  // namespace
}  // namespace shutterlab::app
