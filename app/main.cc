// shutterlab: rolling-shutter distortion from gyro traces. Thin CLI over the libraries.

#include "app/command.h"
#include "sim/check.h"
#include "sim/units.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
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

double ParseQuantityOption(const std::string& text, const char* unit, const std::string& name,
                           const char* bare_means) {
  try {
    return ParseQuantity(text, unit, name, bare_means);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError(shutterlab::WithoutCheckLocation(e.what()));
  }
}

namespace {

// "LENGTH", "ANGULAR RATE": what --help shows after the option.
std::string TypeName(const char* unit) {
  std::string name = DimensionOf(unit);
  for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return name;
}

// A default as a person would type it, in the unit a bare number would have meant: "5cm,10cm".
std::string DefaultText(const std::vector<double>& values, const char* unit,
                        const char* bare_means) {
  std::string text;
  for (const double value : values) {
    if (std::isnan(value)) return "";
    text +=
        (text.empty() ? "" : ",") + QuantityText(ConvertUnit(value, unit, bare_means), bare_means);
  }
  return text;
}

}  // namespace

CLI::Option* AddQuantityOption(CLI::App* command, const std::string& name, double* value,
                               const char* unit, const char* bare_means, const std::string& help) {
  return command
      ->add_option_function<std::string>(
          name,
          [=](const std::string& text) {
            *value = ParseQuantityOption(text, unit, name, bare_means);
          },
          help + " (" + UnitsOf(unit) + ")")
      ->type_name(TypeName(unit))
      ->default_str(DefaultText({*value}, unit, bare_means));
}

CLI::Option* AddQuantityListOption(CLI::App* command, const std::string& name,
                                   std::vector<double>* values, const char* unit,
                                   const char* bare_means, const std::string& help) {
  return command
      ->add_option_function<std::vector<std::string>>(
          name,
          [=](const std::vector<std::string>& texts) {
            values->clear();
            for (const std::string& text : texts) {
              values->push_back(ParseQuantityOption(text, unit, name, bare_means));
            }
          },
          help + " (" + UnitsOf(unit) + ")")
      ->delimiter(',')
      ->type_name(TypeName(unit))
      ->default_str(DefaultText(*values, unit, bare_means));
}

void SayWritten(const std::string& dir, const std::vector<std::string>& files) {
  std::string line = "wrote " + dir + (dir.empty() || dir.back() == '/' ? "" : "/") + ":";
  constexpr size_t kNamed = 8;
  for (size_t i = 0; i < files.size() && i < kNamed; ++i) {
    line += (i ? ", " : " ") + std::filesystem::path(files[i]).lexically_relative(dir).string();
  }
  if (files.size() > kNamed) line += " and " + std::to_string(files.size() - kNamed) + " more";
  std::cerr << line << "\n";
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

namespace {

// The number of single-character edits that turn a into b (Levenshtein), for "did you mean".
size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// "anlyze": the closest command (within 3 edits) and the list, in one line; "" for a command
// that exists or an option.
std::string UnknownCommandLine(const CLI::App& app, const std::string& word) {
  if (word.empty() || word[0] == '-') return "";
  std::string closest, names;
  size_t best = 4;
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (sub->get_name() == word) return "";
    names += (names.empty() ? "" : ", ") + sub->get_name();
    const size_t distance = EditDistance(word, sub->get_name());
    if (distance < best) best = distance, closest = sub->get_name();
  }
  return "error: unknown command '" + word + "'" +
         (closest.empty() ? "" : ": did you mean '" + closest + "'?") + " (commands: " + names +
         ")";
}

// CLI11's refusal in one line, with where to read more.
std::string OneLineFailure(const CLI::App* app, const CLI::Error& e) {
  std::string message = e.what();
  std::replace(message.begin(), message.end(), '\n', ' ');
  std::string help = "shutterlab --help";
  for (const CLI::App* sub : app->get_subcommands())
    help = "shutterlab " + sub->get_name() + " --help";
  return "error: " + message + " (" + help + ")\n";
}

}  // namespace
}  // namespace shutterlab::app

int main(int argc, char** argv) {
  using namespace shutterlab::app;
  CLI::App app{"shutterlab: how much did the rolling shutter distort these images?"};
  app.require_subcommand(1);
  app.set_version_flag("--version", kShutterlabVersion);
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
  if (argc > 1) {
    const std::string unknown = UnknownCommandLine(app, argv[1]);
    if (!unknown.empty()) {
      std::cerr << unknown << "\n";
      return 2;
    }
  }
  app.failure_message(OneLineFailure);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const std::invalid_argument& e) {  // an option's own check
    std::cerr << "error: " << shutterlab::WithoutCheckLocation(e.what()) << "\n";
    return 2;
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
