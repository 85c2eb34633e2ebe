// `shutterlab validate DATASET`: the paper's threshold model and the declared full model against
// the measured displacement, then the loop over undeclared effects (estimate/loop/validate.h).

#include "estimate/loop/validate.h"

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/report/validate_report.h"
#include "model/effects.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab::app {
namespace {

struct ValidateCommand {
  std::string dataset;
  std::string lens_profile_path;
  std::string report_path;
  std::vector<double> limits_m{0.05, 0.10};
  std::string out_dir;
  std::vector<std::string> candidates;
  int grid_step_px = MeasureOptions{}.grid_step_px;
  std::string mask_path;
  bool no_camera_fixed = false, no_consensus = false;
  bool json = false;
};

void Run(const ValidateCommand& command) {
  ValidateOptions options;
  options.limits_m = command.limits_m;
  for (const std::string& name : command.candidates) {
    options.loop.candidates.push_back(RequireEffect(name, "candidates"));
  }
  options.measure.grid_step_px = command.grid_step_px;
  options.mask_path = command.mask_path;
  options.screen.camera_fixed = !command.no_camera_fixed;
  options.screen.consensus = !command.no_consensus;
  options.lens_profile_path = command.lens_profile_path;
  options.keep_residuals = !command.out_dir.empty();
  options.Check();
  // Where the report goes must exist before the long stages: outputs are whole or absent.
  if (!command.report_path.empty()) {
    const std::filesystem::path parent =
        std::filesystem::absolute(command.report_path).parent_path();
    if (!std::filesystem::is_directory(parent)) {
      throw IoError(IoMessage(command.report_path, 0, "its folder does not exist"));
    }
  }
  ValidationResult result;
  {
    StagedProgress progress;
    result = ValidateDataset(command.dataset, options, std::ref(progress));
  }
  PrintLogWarnings((std::filesystem::path(command.dataset) / "gyro.csv").string(), result.warnings);
  const nlohmann::json json = ValidationToJson(result);
  if (!command.out_dir.empty()) {
    std::vector<std::string> written = WriteValidationPlots(command.out_dir, result);
    std::rotate(written.rbegin(), written.rbegin() + 1, written.rend());  // the page first
    SayWritten(command.out_dir, written);
  }
  if (!command.report_path.empty()) {
    WriteFileAtomically(command.report_path, JsonText(json) + "\n");
    std::cerr << "wrote " << command.report_path << "\n";
  }
  if (command.json) {
    std::cout << JsonText(json) << "\n";
  } else {
    std::cout << ValidationReport(result);
  }
}

const CommandRegistration kValidateRegistration(70, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "validate",
      "measure a rig dataset's distortion, test the paper's threshold model and the declared model "
      "against it, and identify undeclared effects");
  auto command = std::make_shared<ValidateCommand>();
  cmd->add_option("DATASET", command->dataset,
                  "rig dataset folder (camera.json, gyro.csv, frames.csv, images)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--lens-profile", command->lens_profile_path,
                  "Gyroflow lens profile (JSON): its lens, scaled to the images, and its readout "
                  "where it states one replace camera.json's")
      ->check(CLI::ExistingFile);
  cmd->add_option("--report", command->report_path,
                  "write the validation report JSON (docs/FORMATS.md validation/1) here");
  AddQuantityListOption(cmd, "--limit", &command->limits_m, "m", "cm",
                        "ground limits, e.g. 5cm,10cm");
  cmd->add_option("--out", command->out_dir,
                  "write residual pictures before/after (per frame, per row) to DIR");
  cmd->add_option(
         "--candidates", command->candidates,
         "effects to try, e.g. time_offset,readout_time (default: all of docs/FORMATS.md's)")
      ->delimiter(',');
  cmd->add_option("--grid-step", command->grid_step_px, "spacing of the measured points, px")
      ->capture_default_str();
  cmd->add_option("--mask", command->mask_path,
                  "MASK.png: measure only where it is white (non-zero), beside camera.json's own "
                  "mask; black: a dashboard, landing gear, burned-in text")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--no-camera-fixed", command->no_camera_fixed,
                "keep the points of regions that move with the camera (found by default)");
  cmd->add_flag("--no-consensus", command->no_consensus,
                "keep the points that no single camera motion of their frame explains (left out "
                "by default)");
  cmd->add_flag("--json", command->json, "print the report JSON instead of the table");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
