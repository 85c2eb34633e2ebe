// `shutterlab accuracy`: the source paper's total-station test; each turn detected and measured.

#include "estimate/paper/accuracy.h"

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/report/analysis_json.h"

#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

namespace shutterlab::app {
namespace {

struct AccuracyCommand {
  TraceOptions trace;
  AccuracyOptions accuracy;
  bool json = false;
};

void Run(const AccuracyCommand& command) {
  LoadedTrace loaded;
  const AccuracyResult result =
      AnalyzeTrace(command.trace, command.accuracy, AnalyzeAccuracy, &loaded);
  if (command.json) {
    auto json = AccuracyToJson(result);
    json["warnings"] = WarningsToJson(loaded.warnings);
    json["assumptions"] = AssumptionsToJson(command.trace.BiasAssumptions());
    std::cout << JsonText(json) << "\n";
  } else {
    std::cout << AccuracyTable(result);
    PrintAssumptions(command.trace.BiasAssumptions());
  }
}

const CommandRegistration kAccuracyRegistration(30, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "accuracy",
      "total-station test: detect each turn, measure it, compare with the reference angle");
  auto command = std::make_shared<AccuracyCommand>();
  command->trace.Add(cmd, /*with_bias=*/true);
  cmd->add_option("--reference-deg", command->accuracy.reference_deg, "the turn angle, degrees")
      ->required();
  cmd->add_option("--average", command->accuracy.average_samples,
                  "samples averaged just before and just after each turn")
      ->capture_default_str();
  AddQuantityOption(cmd, "--guard", &command->accuracy.guard_s, "s", "s",
                    "still time between a turn and its averaging windows");
  AddQuantityOption(cmd, "--min-still", &command->accuracy.min_still_s, "s", "s",
                    "motions closer than this are one turn");
  cmd->add_flag("--json", command->json,
                "print JSON (docs/FORMATS.md `accuracy`) instead of a table");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
