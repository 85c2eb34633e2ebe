// `shutterlab noise`: the source paper's static-noise tables and the Allan deviation of a still
// trace.

#include "estimate/paper/noise.h"

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/report/analysis_json.h"
#include "sim/text_file.h"

#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

namespace shutterlab::app {
namespace {

struct NoiseCommand {
  TraceOptions trace;
  NoiseOptions noise;
  bool json = false;
  std::string allan_path;
};

void Run(const NoiseCommand& command) {
  std::vector<LogWarning> warnings;
  const NoiseResult result = AnalyzeTrace(command.trace, command.noise, AnalyzeNoise, &warnings);
  if (!command.allan_path.empty()) WriteFileAtomically(command.allan_path, AllanCsv(result.allan));
  if (command.json) {
    auto json = NoiseToJson(result);
    json["warnings"] = WarningsToJson(warnings);
    std::cout << json.dump(2) << "\n";
  } else {
    std::cout << NoiseTable(result);
  }
}

const CommandRegistration kRegistration(20, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "noise",
      "static noise of a still gyro: sliding-window sigma and range of the angle, Allan deviation");
  auto command = std::make_shared<NoiseCommand>();
  command->trace.Add(cmd, /*with_bias=*/true);
  cmd->add_option("--window", command->noise.window_samples, "window length, samples")
      ->capture_default_str();
  cmd->add_flag("--json", command->json, "print JSON (docs/FORMATS.md `noise`) instead of a table");
  cmd->add_option("--allan", command->allan_path,
                  "write the Allan deviation to this CSV (tau_s,adev_x,adev_y,adev_z; rad/s)");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
