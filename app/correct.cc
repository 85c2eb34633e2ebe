// `shutterlab correct DATASET --out DIR`: rolling-shutter images to their global-shutter view, a
// rig dataset again (estimate/correct/correct_dataset.h); `correct --photos DIR LOG --out OUT`: a
// folder of photos with the flight log that recorded them (estimate/correct/photo_input.h).

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/correct/correct_dataset.h"
#include "estimate/correct/correct_io.h"
#include "io/lens_profile.h"
#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/log_format.h"
#include "sim/units.h"

#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <mutex>
#include <string>

namespace shutterlab::app {
namespace {

struct CorrectCommand {
  CorrectOptions options;
  std::string input;  // the dataset folder, or with --photos the LOG
  // --photos DIR LOG, with analyze's flags for the log, the triggers and the camera.
  std::string photos_dir;
  std::string format = "auto";
  ColumnFlags column_flags;
  std::string triggers_path;
  std::string latency = "0";
  std::string camera_path;
  std::string lens_profile_path;
  std::string readout;
  double focal_px = 0.0;
  double altitude_m = 0.0;
  double ground_elevation_m = std::numeric_limits<double>::quiet_NaN();  // NaN: not given
  std::string photo_utc_offset;
  std::string reference;  // "": mid for photos, row0 for a dataset
  std::string interpolation = "bilinear";
  double depth_m = 0.0;
  double gyro_noise = std::numeric_limits<double>::quiet_NaN();  // NaN: from gyro.csv
  bool json = false;
};

// --photos DIR LOG: the photo input's options from the flags.
PhotoInputOptions PhotoOptionsFromFlags(const CorrectCommand& command) {
  PhotoInputOptions photos;
  photos.log_path = command.input;
  photos.read.format = ParseLogFormat(command.format);
  command.column_flags.Apply(&photos.read);
  photos.triggers_path = command.triggers_path;
  photos.trigger_latency_s = ParseQuantity(command.latency, "s", "--latency", "ms");
  if (!command.camera_path.empty()) {
    photos.camera = ReadRigModel(command.camera_path);
    photos.camera_path = command.camera_path;
  }
  if (!command.lens_profile_path.empty())
    photos.lens_profile = ReadLensProfile(command.lens_profile_path);
  if (!command.readout.empty()) {
    photos.readout_s = ParseQuantity(command.readout, "s", "--readout", "ms");
  }
  if (command.focal_px != 0.0) photos.focal_px = command.focal_px;
  if (command.altitude_m != 0.0) photos.altitude_m = command.altitude_m;
  if (!std::isnan(command.ground_elevation_m))
    photos.ground_elevation_m = command.ground_elevation_m;
  if (!command.photo_utc_offset.empty()) {
    photos.clock.camera_utc_offset_s = ParseUtcOffset(command.photo_utc_offset);
    SHUTTERLAB_CHECK(photos.clock.camera_utc_offset_s)
        << "--photo-utc-offset must be +HH:MM or -HH:MM (got '" << command.photo_utc_offset << "')";
  }
  photos.Check();
  return photos;
}

void Run(CorrectCommand& command) {
  CorrectOptions& options = command.options;
  const bool photo_flags = !command.triggers_path.empty() || command.latency != "0" ||
                           !command.camera_path.empty() || !command.lens_profile_path.empty() ||
                           !command.readout.empty() || command.focal_px != 0.0 ||
                           command.altitude_m != 0.0 || !std::isnan(command.ground_elevation_m) ||
                           !command.photo_utc_offset.empty() || command.format != "auto";
  if (command.photos_dir.empty()) {
    SHUTTERLAB_CHECK(!photo_flags)
        << "--triggers, --latency, --camera, --lens-profile, --readout, "
           "--focal-px, --altitude, --ground-elevation, --photo-utc-offset "
           "and --format "
           "are for --photos DIR LOG (a rig dataset has camera.json)";
    SHUTTERLAB_CHECK(std::filesystem::is_directory(command.input))
        << command.input << ": not a folder (a rig dataset; for photos: --photos DIR LOG)";
    options.dataset_dir = command.input;
  } else {
    SHUTTERLAB_CHECK(!options.check_truth) << "--truth is for a rendered rig dataset";
    options.dataset_dir = command.photos_dir;
    options.photos = PhotoOptionsFromFlags(command);
  }
  // Reading the photos' metadata, then correcting them: one bar each.
  std::unique_ptr<Progress> reading;
  if (options.photos) {
    options.photos->progress = [&reading](double f) {
      if (!reading) reading = std::make_unique<Progress>("photos", 1000);
      reading->Update(static_cast<size_t>(f * 1000));
      if (f >= 1.0) reading.reset();
    };
  }
  // Photos go to a photogrammetry tool, which takes each as one pose: the middle of its readout.
  // A rig dataset's default is the renderer's reference, the first row.
  const std::string reference_name =
      !command.reference.empty() ? command.reference : (options.photos ? "mid" : "row0");
  const std::optional<CorrectionReference> reference = ParseCorrectionReference(reference_name);
  SHUTTERLAB_CHECK(reference) << "--reference must be row0 or mid (got " << command.reference
                              << ")";
  options.reference = *reference;
  options.interpolation =
      command.interpolation == "bicubic" ? Interpolation::kBicubic : Interpolation::kBilinear;
  if (command.depth_m != 0.0) options.depth_m = command.depth_m;
  if (!std::isnan(command.gyro_noise)) options.gyro_noise_rad_s_sqrt_hz = command.gyro_noise;
  options.Check();
  std::unique_ptr<Progress> bar;
  const CorrectSummary summary = CorrectDataset(options, [&](size_t done, size_t total) {
    if (!bar) bar = std::make_unique<Progress>("correct", total);
    bar->Update(done);
  });
  bar.reset();
  PrintLogWarnings(options.photos
                       ? options.photos->log_path
                       : (std::filesystem::path(options.dataset_dir) / "gyro.csv").string(),
                   summary.warnings);
  if (command.reference.empty() && options.photos) {
    std::cerr << "note: the corrected photos show the instant of their middle row (a "
                 "photogrammetry tool takes a photo as one pose); --reference row0 for the first\n";
  }
  for (const std::string& note : summary.model.notes) std::cerr << "note: " << note << "\n";
  for (const std::string& note : summary.notes) std::cerr << "note: " << note << "\n";
  for (const CorrectedFrame& f : summary.frames) {
    for (const std::string& note : f.notes) std::cerr << "note: " << note << "\n";
  }
  if (command.json) {
    std::cout << JsonText(CorrectionToJson(summary)) << "\n";
  } else {
    std::cout << CorrectionTable(summary);
  }
}

const CommandRegistration kCorrectRegistration(75, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "correct",
      "correct the rolling shutter of a rig dataset's images (still or video) or of a folder of "
      "photos with its flight log: the global-shutter view from the pose at a reference instant");
  auto command = std::make_shared<CorrectCommand>();
  CorrectOptions& o = command->options;
  cmd->add_option("DATASET", command->input,
                  "rig dataset folder (camera.json, gyro.csv, frames.csv, images): render's or "
                  "import's; with --photos DIR, the flight log (ULog, DataFlash, blackbox, "
                  "gyro.csv, any CSV by --columns)")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--photos", command->photos_dir,
                  "a folder of photos (JPEG, TIFF, DNG) taken during the flight DATASET logged")
      ->check(CLI::ExistingPath);
  AddFormatOption(cmd, &command->format, "--photos: the log's format");
  command->column_flags.Add(cmd);
  cmd->add_option("--triggers", command->triggers_path,
                  "--photos: trigger file (.MRK, CSV image,t or t, a log's camera events); "
                  "default: the log's camera events")
      ->check(CLI::ExistingFile);
  cmd->add_option("--latency", command->latency,
                  "--photos: trigger to the exposure of row 0, e.g. 40ms (may be negative)")
      ->capture_default_str();
  cmd->add_option("--camera", command->camera_path,
                  "--photos: camera.json (default: the photos' own size, focal length and readout)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--lens-profile", command->lens_profile_path,
                  "--photos: Gyroflow lens profile (JSON), scaled to the photos")
      ->check(CLI::ExistingFile);
  cmd->add_option("--readout", command->readout,
                  "--photos: the readout, e.g. 30ms, over camera.json and the readout table");
  cmd->add_option("--focal-px", command->focal_px, "--photos: focal length, pixels");
  AddQuantityOption(cmd, "--altitude", &command->altitude_m, "m", "m",
                    "--photos: height of the ground plane below the camera (default: camera.json, "
                    "the log's height above ground, the photos' height above take-off)")
      ->default_str("");
  AddQuantityOption(cmd, "--ground-elevation", &command->ground_elevation_m, "m", "m",
                    "--photos: the ground's elevation (the take-off point's) in the photos' "
                    "absolute altitude's datum, for photos with no height above take-off")
      ->default_str("");
  cmd->add_option("--photo-utc-offset", command->photo_utc_offset,
                  "--photos: the camera clock's zone, +HH:MM (placing photos by capture time)");
  cmd->add_option("--out", o.out_dir, "output dataset folder (images already there are kept)")
      ->required();
  cmd->add_option("--report", o.report_path,
                  "a validation report (validate --report): correct with the effects it found")
      ->check(CLI::ExistingFile);
  cmd->add_option("--effect", o.effects,
                  "NAME=VALUE: set an effect on top of camera.json and the report (as render "
                  "--inject: readout_time=23.5ms, gyro_to_camera=..., ...); repeatable");
  cmd->add_option("--reference", command->reference,
                  "the instant the corrected image shows: row0 (the first row, as render's "
                  "reference) or mid (mid-readout)")
      ->default_str("row0 for a dataset, mid for --photos");
  AddQuantityOption(cmd, "--depth", &command->depth_m, "m", "m",
                    "video: the scene's depth, to correct translation too (camera.json velocity); "
                    "without it video is rotation only")
      ->default_str("");
  cmd->add_option("--interpolation", command->interpolation, "bilinear or bicubic")
      ->check(CLI::IsMember({"bilinear", "bicubic"}))
      ->capture_default_str();
  cmd->add_option("--tolerance", o.map.tolerance_px,
                  "largest interpolation error of the correction map, px")
      ->capture_default_str();
  AddQuantityOption(cmd, "--gyro-noise", &command->gyro_noise, "rad/s/rtHz", "rad/s/rtHz",
                    "the gyro's white noise, for the predicted residual (default: estimated from "
                    "gyro.csv)");
  cmd->add_option("--draws", o.prediction.draws, "draws of the truth for the predicted residual")
      ->capture_default_str();
  cmd->add_option("--jobs", o.jobs, "frames corrected at once (0: the cores, at most 4)")
      ->capture_default_str();
  cmd->add_flag("--force", o.force, "rewrite corrected images that the output already holds");
  cmd->add_flag("--truth", o.check_truth,
                "a rendered dataset: measure the corrected frames against truth/ (exact)");
  cmd->add_flag("!--no-pictures", o.pictures, "skip overview.png");
  cmd->add_flag("--json", command->json, "print correct.json instead of the table");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
