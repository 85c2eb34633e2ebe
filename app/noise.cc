// `shutterlab noise`: the source paper's static-noise tables and the Allan deviation of a still
// trace.

#include "estimate/paper/noise.h"

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/report/analysis_json.h"
#include "sim/text_file.h"

#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
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
  LoadedTrace loaded;
  const NoiseResult result = AnalyzeTrace(command.trace, command.noise, AnalyzeNoise, &loaded);
  if (!command.allan_path.empty()) WriteFileAtomically(command.allan_path, AllanCsv(result.allan));
  // With --second, the table is the fused trace's; each sensor alone is analysed for the gain.
  std::optional<NoiseResult> first, second;
  if (loaded.pair) {
    NoiseOptions options = command.noise;
    options.bias = loaded.segment;
    first = AnalyzeNoise(loaded.pair->first, options);
    second = AnalyzeNoise(loaded.pair->second, options);
  }
  if (command.json) {
    auto json = NoiseToJson(result);
    if (first)
      json["pair"] =
          NoisePairToJson(loaded.pair->pair, command.trace.second_path, *first, *second, result);
    json["warnings"] = WarningsToJson(loaded.warnings);
    json["assumptions"] = AssumptionsToJson(command.trace.BiasAssumptions());
    std::cout << JsonText(json) << "\n";
  } else {
    if (first)
      std::cout << SensorPairText(loaded.pair->pair, command.trace.path, command.trace.second_path)
                << "\n";
    std::cout << NoiseTable(result);
    if (first) std::cout << NoisePairTable(*first, *second, result);
    PrintAssumptions(command.trace.BiasAssumptions());
  }
}

const CommandRegistration kNoiseRegistration(20, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "noise",
      "static noise of a still gyro: sliding-window sigma and range of the angle, Allan deviation");
  auto command = std::make_shared<NoiseCommand>();
  command->trace.Add(cmd, /*with_bias=*/true);
  command->trace.AddSecond(cmd);
  // The paper counts its windows in samples (120 at ~3 kHz); flight's --window is a duration, so
  // --window here is one too, and the count has its own option, the unit in its name.
  auto* samples = cmd->add_option("--window-samples", command->noise.window_samples,
                                  "window length in samples (the paper: 120)")
                      ->capture_default_str();
  auto* duration =
      cmd->add_option_function<std::string>(
             "--window",
             [command](const std::string& text) {
               char* end = nullptr;
               std::strtod(text.c_str(), &end);
               if (!text.empty() && *end == '\0') {  // a bare number: a duration or a count?
                 throw CLI::ValidationError("--window '" + text +
                                            "': a duration needs a unit: did you mean " + text +
                                            "ms, or --window-samples " + text + "?");
               }
               command->noise.window_s = ParseQuantityOption(text, "s", "--window", "ms");
             },
             "window length as a duration, e.g. 40ms (s, ms, us, ns); instead of "
             "--window-samples")
          ->type_name("DURATION");
  duration->excludes(samples);
  cmd->add_flag("--json", command->json, "print JSON (docs/FORMATS.md `noise`) instead of a table");
  cmd->add_option("--allan", command->allan_path,
                  "write the Allan deviation to this CSV (tau_s,adev_x,adev_y,adev_z; rad/s)");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
