// `shutterlab measure REF IMG`: the displacement field between a global-shutter reference and a
// rolling-shutter image, D, the measurement noise and, with --truth, the error against a render's
// exact field (estimate/loop/measure.h).

#include "estimate/loop/measure.h"

#include "app/command.h"
#include "estimate/report/loop_json.h"
#include "io/image_io.h"
#include "model/camera.h"
#include "sim/check.h"

#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab::app {
namespace {

struct MeasureCommand {
  std::string ref_path;
  std::string image_path;
  std::string camera_path;
  std::string out_dir;
  std::string truth_path;
  bool json = false;
  MeasureOptions options;
};

std::string SizeText(const cv::Mat& m) {
  return std::to_string(m.cols) + "x" + std::to_string(m.rows);
}

void Run(const MeasureCommand& command) {
  command.options.Check();
  // Read and check every input before measuring or writing anything.
  const cv::Mat ref = ReadImage(command.ref_path);
  const cv::Mat image = ReadImage(command.image_path);
  if (image.size() != ref.size()) {
    throw IoError(IoMessage(command.image_path, 0,
                            "image is " + SizeText(image) + " but the reference " +
                                command.ref_path + " is " + SizeText(ref)));
  }
  if (image.cols < kMinMeasuredSidePx || image.rows < kMinMeasuredSidePx) {
    throw IoError(IoMessage(
        command.image_path, 0,
        "image is " + SizeText(image) + " pixels: a measurement needs at least " +
            std::to_string(kMinMeasuredSidePx) + "x" + std::to_string(kMinMeasuredSidePx) +
            " pixels for its matching windows (use larger images)"));
  }
  MeasureReport report;
  if (!command.camera_path.empty()) {
    const RigModel rig = ReadRigModel(command.camera_path);
    if (rig.camera.width != image.cols || rig.camera.height != image.rows) {
      throw IoError(IoMessage(command.camera_path, 0,
                              "camera is " + std::to_string(rig.camera.width) + "x" +
                                  std::to_string(rig.camera.height) + " but the images are " +
                                  SizeText(image)));
    }
    report.ground_m_per_px = rig.altitude_m / ((rig.camera.fx + rig.camera.fy) / 2);
  }
  cv::Mat truth;
  if (!command.truth_path.empty()) {
    std::vector<std::string> names;
    truth = ReadFloatImage(command.truth_path, &names);
    if (truth.channels() != 2 || names.size() != 2 || names[0] != "dx" || names[1] != "dy") {
      throw IoError(IoMessage(command.truth_path, 0,
                              "a displacement field needs exactly the channels dx, dy"));
    }
    if (truth.size() != image.size()) {
      throw IoError(
          IoMessage(command.truth_path, 0,
                    "field is " + SizeText(truth) + " but the images are " + SizeText(image)));
    }
  }
  report.measurement = MeasureDisplacement(ref, image, command.options);
  if (!truth.empty()) report.truth = CompareFields(report.measurement.field, truth);
  if (!command.out_dir.empty()) WriteMeasureOutputs(command.out_dir, report.measurement);
  if (command.json) {
    std::cout << JsonText(MeasureToJson(report)) << "\n";
  } else {
    std::cout << MeasureText(report);
  }
}

const CommandRegistration kMeasureRegistration(60, [](CLI::App& app) {
  auto* cmd =
      app.add_subcommand("measure",
                         "measure the displacement field between a global-shutter reference and a "
                         "rolling-shutter image");
  auto command = std::make_shared<MeasureCommand>();
  cmd->add_option("REF", command->ref_path, "global-shutter reference image")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("IMG", command->image_path, "rolling-shutter image of the same view")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--camera", command->camera_path, "camera.json (rig/1): D in metres too")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", command->out_dir,
                  "folder for rows.csv, field.exr, heatmap.png, confidence.png");
  cmd->add_option("--truth", command->truth_path,
                  "exact displacement field (a render's truth/NNNN_disp.exr): print the error")
      ->check(CLI::ExistingFile);
  cmd->add_option("--grid", command->options.grid_step_px, "spacing of the measured points, px")
      ->capture_default_str();
  cmd->add_flag("--json", command->json, "print JSON");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
