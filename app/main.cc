// shutterlab: rolling-shutter distortion from gyro traces. Thin CLI over the libraries.

#include "app/command.h"
#include "sim/check.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <unistd.h>

namespace shutterlab::app {

std::vector<RegisteredCommand>& Registry() {
  static std::vector<RegisteredCommand> registry;
  return registry;
}

CommandRegistration::CommandRegistration(int order, CommandSetup setup) {
  Registry().push_back({order, std::move(setup)});
}

Progress::Progress(std::string label, size_t total)
    : label_(std::move(label)), total_(total), enabled_(::isatty(STDERR_FILENO) != 0) {}

void Progress::Update(size_t done) {
  if (!enabled_ || total_ == 0) return;
  const int percent = static_cast<int>(100.0 * std::min(done, total_) / total_);
  if (percent == last_percent_) return;
  last_percent_ = percent;
  std::fprintf(stderr, "\r%s: %3d%%", label_.c_str(), percent);
  std::fflush(stderr);
}

Progress::~Progress() {
  if (enabled_ && last_percent_ >= 0) std::fprintf(stderr, "\r\033[K");
}

}  // namespace shutterlab::app

int main(int argc, char** argv) {
  using namespace shutterlab::app;
  CLI::App app{"shutterlab: how much did the rolling shutter distort these images?"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "shutterlab 0.1");
  auto& registry = Registry();
  std::sort(
      registry.begin(), registry.end(),
      [](const RegisteredCommand& a, const RegisteredCommand& b) { return a.order < b.order; });
  std::vector<std::pair<CLI::App*, std::function<void()>>> runners;
  for (const auto& command : registry) {
    const size_t before = app.get_subcommands({}).size();
    std::function<void()> run = command.setup(app);
    runners.emplace_back(app.get_subcommands({})[before], std::move(run));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    for (auto& [sub, run] : runners) {
      if (sub->parsed()) run();
    }
  } catch (const shutterlab::IoError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    // The option or the data the user gave cannot be used: the message says why and what to do;
    // the source location is for developers.
    std::cerr << "error: " << shutterlab::WithoutCheckLocation(e.what()) << "\n";
    return 2;
  } catch (const std::out_of_range& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
