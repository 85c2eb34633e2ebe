// `shutterlab export SOURCE --to FORMAT --out DIR`: the camera, readout, time offset and lens
// shutterlab found, in the files COLMAP, ODM / OpenSfM, Kalibr, Gyroflow or Metashape read
// (estimate/export/exports.h).

#include "app/command.h"
#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"
#include "estimate/export/exports.h"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab::app {
namespace {

struct ExportCommand {
  std::string source;
  std::string format;
  std::string out_dir;
  bool force = false;
  bool json = false;
};

void Run(const ExportCommand& command) {
  const ExportFormat& format = FindExportFormat(command.format);
  const ExportCamera camera = ReadExportSource(command.source);
  ExportOptions options;
  options.force = command.force;
  const ExportOutput output = format.write(camera, options);  // every text made first
  const std::vector<std::string> written = WriteExport(output, command.out_dir);
  if (command.json) {
    nlohmann::json json = {{"format", "export/1"},
                           {"to", format.name},
                           {"source", camera.source},
                           {"files", written},
                           {"notes", output.notes}};
    std::cout << JsonText(json) << "\n";
    return;
  }
  std::cout << "exported " << camera.source << " for " << format.name << ":\n";
  for (size_t i = 0; i < written.size(); ++i)
    std::cout << "  " << written[i] << "  (" << output.files[i].what << ")\n";
  for (const std::string& note : output.notes) std::cout << "note: " << note << "\n";
}

const CommandRegistration kExportRegistration(95, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "export", "write the camera, readout, time offset and lens found into another tool's files");
  auto command = std::make_shared<ExportCommand>();
  cmd->add_option("SOURCE", command->source,
                  "a validation report (validate --report), a camera.json or a folder holding one "
                  "(a rig dataset, a correction's output), or an analyze --photos --json result")
      ->required()
      ->check(CLI::ExistingPath);
  std::string formats;
  for (const ExportFormat& format : ExportFormats())
    formats += std::string("\n  ") + format.name + ": " + format.what;
  cmd->add_option("--to", command->format, "the tool:" + formats)->required();
  cmd->add_option("--out", command->out_dir, "the folder to write into (created)")->required();
  cmd->add_flag("--force", command->force,
                "write values the data did not determine, and leave out what the tool's files "
                "cannot hold, instead of refusing");
  cmd->add_flag("--json", command->json, "print what was written as JSON (export/1)");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
