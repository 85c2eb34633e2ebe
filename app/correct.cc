// `shutterlab correct DATASET --out DIR`: rolling-shutter images to their global-shutter view, a
// rig dataset again (estimate/correct/correct_dataset.h).

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/correct/correct_dataset.h"
#include "estimate/correct/correct_io.h"
#include "sim/check.h"

#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <string>

namespace shutterlab::app {
namespace {

struct CorrectCommand {
  CorrectOptions options;
  std::string reference = "row0";
  std::string interpolation = "bilinear";
  double depth_m = 0.0;
  double gyro_noise = -1.0;
  bool json = false;
};

void Run(CorrectCommand& command) {
  CorrectOptions& options = command.options;
  const std::optional<CorrectionReference> reference = ParseCorrectionReference(command.reference);
  SHUTTERLAB_CHECK(reference) << "--reference must be row0 or mid (got " << command.reference
                              << ")";
  options.reference = *reference;
  options.interpolation =
      command.interpolation == "bicubic" ? Interpolation::kBicubic : Interpolation::kBilinear;
  if (command.depth_m != 0.0) options.depth_m = command.depth_m;
  if (command.gyro_noise >= 0.0) options.gyro_noise_rad_s_sqrt_hz = command.gyro_noise;
  options.Check();
  std::unique_ptr<Progress> bar;
  const CorrectSummary summary = CorrectDataset(options, [&](size_t done, size_t total) {
    if (!bar) bar = std::make_unique<Progress>("correct", total);
    bar->Update(done);
  });
  bar.reset();
  PrintLogWarnings((std::filesystem::path(options.dataset_dir) / "gyro.csv").string(),
                   summary.warnings);
  for (const std::string& note : summary.model.notes) std::cerr << "note: " << note << "\n";
  for (const std::string& note : summary.notes) std::cerr << "note: " << note << "\n";
  for (const CorrectedFrame& f : summary.frames) {
    for (const std::string& note : f.notes) std::cerr << "note: " << note << "\n";
  }
  if (command.json) {
    std::cout << CorrectionToJson(summary).dump(2) << "\n";
  } else {
    std::cout << CorrectionTable(summary);
  }
}

const CommandRegistration kRegistration(75, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "correct",
      "correct the rolling shutter of a rig dataset's images (still or video): the global-shutter "
      "view from the pose at a reference instant, a rig dataset again");
  auto command = std::make_shared<CorrectCommand>();
  CorrectOptions& o = command->options;
  cmd->add_option("DATASET", o.dataset_dir,
                  "rig dataset folder (camera.json, gyro.csv, frames.csv, images): render's or "
                  "import's")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", o.out_dir, "output dataset folder (images already there are kept)")
      ->required();
  cmd->add_option("--report", o.report_path,
                  "a validation report (validate --report): correct with the effects it found")
      ->check(CLI::ExistingFile);
  cmd->add_option("--effect", o.effects,
                  "NAME=VALUE: set an effect on top of camera.json and the report (as render "
                  "--inject: readout_time=0.0235, gyro_to_camera=..., ...); repeatable");
  cmd->add_option("--reference", command->reference,
                  "the instant the corrected image shows: row0 (the first row, as render's "
                  "reference) or mid (mid-readout)")
      ->capture_default_str();
  cmd->add_option("--depth", command->depth_m,
                  "video: the scene's depth, m, to correct translation too (camera.json velocity); "
                  "without it video is rotation only");
  cmd->add_option("--interpolation", command->interpolation, "bilinear or bicubic")
      ->check(CLI::IsMember({"bilinear", "bicubic"}))
      ->capture_default_str();
  cmd->add_option("--tolerance", o.map.tolerance_px,
                  "largest interpolation error of the correction map, px")
      ->capture_default_str();
  cmd->add_option("--gyro-noise", command->gyro_noise,
                  "the gyro's white noise, rad/s/sqrt(Hz), for the predicted residual (default: "
                  "estimated from gyro.csv)");
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
