#pragma once
// Subcommand registry: each app/<name>.cc defines its CLI11 subcommand and registers it with a
// static CommandRegistration, so adding a command touches no shared file.
//
// Exit codes: 0 success; 2 bad input or usage (one line on stderr naming file, line and problem);
// 1 an internal error.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab::app {

// What --version prints, and what a batch item records as the tool that made it.
inline constexpr char kShutterlabVersion[] = "shutterlab 0.1";

// Adds the subcommand to app and returns the function to run once parsing succeeded.
using CommandSetup = std::function<std::function<void()>(CLI::App& app)>;

struct CommandRegistration {
  CommandRegistration(int order, CommandSetup setup);
};

struct RegisteredCommand {
  int order;  // position in --help
  CommandSetup setup;
};
std::vector<RegisteredCommand>& Registry();

// A --json document as printed: indented, with any byte that is not UTF-8 (a file name, or a
// topic name read from a damaged log) replaced by U+FFFD instead of stopping the command.
template <typename Json>
std::string JsonText(const Json& json) {
  return json.dump(2, ' ', false, Json::error_handler_t::replace);
}

// A log named on the command line: "-" reads the standard input (`cat log.ulg | shutterlab flight
// -`, as /dev/stdin); anything else must be an existing file.
inline CLI::Option* CheckLogPath(CLI::Option* option) {
  return option
      ->transform([](std::string path) { return path == "-" ? std::string("/dev/stdin") : path; },
                  "- = stdin")
      ->check(CLI::ExistingFile);
}

// ParseQuantity (sim/units.h) in an option's callback: a refusal is thrown as CLI11's, so it is
// printed like every other bad option.
double ParseQuantityOption(const std::string& text, const char* unit, const std::string& name,
                           const char* bare_means);
// An option that takes a quantity with its unit (sim/units.h ParseQuantity): "--altitude 50m".
// *value is in `unit`; bare_means is the unit a bare number most likely meant, named in the
// suggestion. The text is parsed with the command line, so a bare number or a wrong unit is refused
// in one line before anything runs; *value's current value is shown as the default.
CLI::Option* AddQuantityOption(CLI::App* command, const std::string& name, double* value,
                               const char* unit, const char* bare_means, const std::string& help);
// The same for a comma-separated list ("--limit 5cm,10cm"); *values' current values are the
// default.
CLI::Option* AddQuantityListOption(CLI::App* command, const std::string& name,
                                   std::vector<double>* values, const char* unit,
                                   const char* bare_means, const std::string& help);

// Says on stderr (stdout may be a --json document) what a command's --out folder received:
// "wrote DIR/: a, b, c" with the names relative to DIR, the first 8 and how many more.
void SayWritten(const std::string& dir, const std::vector<std::string>& files);

// Prints progress "label: 42%" on a terminal (stderr), overwriting the line; silent when stderr
// is not a terminal, so logs and CI stay clean.
class Progress {
 public:
  Progress(std::string label, size_t total);
  void Update(size_t done);
  // Whether it prints (stderr is a terminal): work done only to feed it can be left undone.
  bool enabled() const { return enabled_; }
  ~Progress();

 private:
  std::string label_;
  size_t total_;
  int last_percent_ = -1;
  bool enabled_;
};

// Progress of work in named stages ("render", "measure", ...): a new bar when the stage changes.
// Call it as the library's (stage, done, total) callback.
class StagedProgress {
 public:
  void operator()(const std::string& stage, size_t done, size_t total) {
    if (!bar_ || stage != stage_) {
      bar_.reset();
      bar_ = std::make_unique<Progress>(stage, total);
      stage_ = stage;
    }
    bar_->Update(done);
  }
  // Clears the bar (before a line is printed under it); the next call starts a new one.
  void Clear() { bar_.reset(); }

 private:
  std::string stage_;
  std::unique_ptr<Progress> bar_;
};

}  // namespace shutterlab::app
