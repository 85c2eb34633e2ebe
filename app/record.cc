// `shutterlab record`: gyro from one or two sensors' FIFOs (a real MPU-9250 / MPU-6500 /
// ICM-42688-P on spidev, or an emulated one playing a trace) and camera triggers from a GPIO line,
// on one clock, into Gyroflow .gcsv files and a triggers file (record/recorder.h).

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/paper/analyze.h"
#include "estimate/report/analysis_json.h"
#include "record/device_spec.h"
#include "record/record_output.h"
#include "record/recorder.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <sys/mman.h>
#include <unistd.h>
#include <vector>

namespace shutterlab::app {
namespace {

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler sets an atomic");

extern "C" void OnStopSignal(int) { g_stop.store(true); }

struct RecordCommand {
  std::vector<std::string> devices;
  std::string out_path, out2_path;
  std::string duration;
  double rate_hz = 8000.0;
  int range_dps = 250;
  std::string part = "mpu9250";
  std::string trigger;
  std::string triggers_path;
  std::string edge = "rising";
  std::string debounce = "5ms";
  std::string gpio_bias = "as-is";
  std::string still = "5s";
  std::string ring = "8s";
  std::string orientation = "XYZ";
  std::string note;
  std::vector<std::string> also;
  std::string status_every;
  std::string stall_writer;
  std::string pause_while_writing;
  std::string clock = "monotonic";
  int priority = 0;
  bool json = false;
};

// "A@B": two durations (or a count and a duration), e.g. "300ms@2s".
std::pair<std::string, std::string> SplitAt(const std::string& text, const char* flag) {
  const size_t at = text.find('@');
  SHUTTERLAB_CHECK(at != std::string::npos && at > 0 && at + 1 < text.size())
      << flag << " takes A@B, e.g. 300ms@2s, got '" << text << "'";
  return {text.substr(0, at), text.substr(at + 1)};
}

// The second sensor's file when --out2 is not given: rec.gcsv -> rec.2.gcsv.
std::string SecondOut(const std::string& out) {
  std::filesystem::path path(out);
  return (path.parent_path() / (path.stem().string() + ".2" + path.extension().string())).string();
}

double Seconds(const std::string& text, const char* option) {
  return ParseQuantity(text, "s", option, "s");
}

RecorderOptions Options(const RecordCommand& command, bool tty) {
  RecorderOptions options;
  if (!command.duration.empty()) options.duration_s = Seconds(command.duration, "--duration");
  options.still_s = Seconds(command.still, "--still");
  options.ring_s = Seconds(command.ring, "--ring");
  options.polarity = ParseTriggerPolarity(command.edge);
  options.debounce_s = Seconds(command.debounce, "--debounce");
  options.orientation = command.orientation;
  options.note = command.note;
  for (const std::string& name : command.also) options.also.push_back(ParseAlsoFormat(name));
  options.reader_priority = command.priority;
  options.stop = &g_stop;
  if (!command.stall_writer.empty()) {
    const auto [for_text, every_text] = SplitAt(command.stall_writer, "--stall-writer");
    options.writer_stall = {Seconds(every_text, "--stall-writer"),
                            Seconds(for_text, "--stall-writer")};
  }
  if (!command.pause_while_writing.empty()) {
    const auto [count_text, write_text] =
        SplitAt(command.pause_while_writing, "--pause-while-writing");
    const auto count = ParseInt(count_text);
    SHUTTERLAB_CHECK(count && *count > 0)
        << "--pause-while-writing N@T: N samples, got '" << count_text << "'";
    options.paper_pause = {static_cast<size_t>(*count),
                           Seconds(write_text, "--pause-while-writing")};
  }
  options.status_interval_s = command.status_every.empty()
                                  ? (tty ? 1.0 : 60.0)
                                  : Seconds(command.status_every, "--status-every");
  options.on_status = [tty](const RecordStatus& status) {
    const std::string line = RecordStatusLine(status);
    std::fprintf(stderr, tty ? "\r\033[K%s" : "%s\n", line.c_str());
    std::fflush(stderr);
  };
  return options;
}

void Run(const RecordCommand& command) {
  SHUTTERLAB_CHECK(command.devices.size() <= 2)
      << "--device: one or two sensors (the Pi's two SPI buses)";
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  RecorderOptions options = Options(command, tty);
  const GyroPart default_part = ParseGyroPart(command.part);
  std::unique_ptr<Clock> clock;
  if (command.clock == "virtual") {
    clock = std::make_unique<VirtualClock>(1000000000);
  } else {
    SHUTTERLAB_CHECK(command.clock == "monotonic") << "--clock is monotonic or virtual";
    clock = std::make_unique<MonotonicClock>();
  }
  std::vector<OpenedDevice> opened;
  std::vector<RecordSensor> sensors;
  // Emulated sensors play their traces on one time line, as two parts on one camera would.
  const auto origin = std::make_shared<std::atomic<int64_t>>(INT64_MIN);
  for (size_t i = 0; i < command.devices.size(); ++i) {
    const DeviceSpec spec = ParseDeviceSpec(command.devices[i]);
    SHUTTERLAB_CHECK(spec.emulate || command.clock == "monotonic")
        << "--clock virtual is for emulated devices only";
    opened.push_back(OpenDevice(spec, default_part, clock.get(), origin));
    RecordSensor sensor;
    sensor.bus = opened.back().bus.get();
    sensor.part = opened.back().part;
    sensor.config.rate_hz = spec.rate_hz.value_or(command.rate_hz);
    sensor.config.range_dps = spec.range_dps.value_or(command.range_dps);
    sensor.device = spec.text;
    sensor.out_path =
        i == 0 ? command.out_path
               : (command.out2_path.empty() ? SecondOut(command.out_path) : command.out2_path);
    sensors.push_back(sensor);
  }
  std::unique_ptr<TriggerSource> trigger;
  if (!command.trigger.empty()) {
    trigger = OpenTriggerSpec(command.trigger, command.gpio_bias, clock.get(), opened[0].emulator,
                              options.duration_s);
    options.trigger = trigger.get();
    std::filesystem::path out(command.out_path);
    options.triggers_path =
        command.triggers_path.empty()
            ? (out.parent_path() / (out.stem().string() + ".triggers.csv")).string()
            : command.triggers_path;
  }
  if (command.priority > 0 && ::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    std::fprintf(stderr, "note: cannot lock memory (mlockall); page faults may delay reads\n");
  }
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
  const RecordSummary summary = Record(sensors, options, *clock);
  if (tty) std::fprintf(stderr, "\r\033[K");
  if (command.json) {
    std::cout << JsonText(
                     RecordSummaryToJson(summary, options.trigger ? options.triggers_path : ""))
              << "\n";
    return;
  }
  std::cout << RecordSummaryText(summary);
  for (const SensorSummary& s : summary.sensors) std::cout << "wrote " << s.out_path << "\n";
  if (options.trigger) std::cout << "wrote " << options.triggers_path << "\n";
}

const CommandRegistration kRecordRegistration(15, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "record",
      "record gyro (MPU-9250 / MPU-6500 / ICM-42688-P over SPI, or an emulated one) and camera "
      "triggers on one clock, never pausing the reads");
  auto command = std::make_shared<RecordCommand>();
  cmd->add_option(
         "--device", command->devices,
         "a sensor: /dev/spidev0.0[,part=...,rate=...,range=...] or "
         "emulate:TRACE[,part=mpu9250,rate=8kHz,range=250deg/s,ppm=40]; twice for two sensors")
      ->required();
  cmd->add_option("--out", command->out_path, "the first sensor's Gyroflow .gcsv")->required();
  cmd->add_option("--out2", command->out2_path, "the second sensor's .gcsv (default: OUT.2.gcsv)");
  cmd->add_option("--duration", command->duration,
                  "stop after this long (default: at SIGINT/SIGTERM)");
  AddQuantityOption(cmd, "--rate", &command->rate_hz, "Hz", "Hz",
                    "output data rate (the part's nearest at or above)");
  AddRangeOption(cmd, &command->range_dps, "full scale");
  cmd->add_option("--part", command->part, "mpu9250, mpu6500, icm42688p (per device: part=)")
      ->capture_default_str();
  cmd->add_option(
      "--trigger", command->trigger,
      "camera trigger line: CHIP:LINE (gpiochip0:17), or emulate:every=2s[,bounce=N] or "
      "emulate:TRIGGERS.csv");
  cmd->add_option("--triggers-out", command->triggers_path,
                  "the triggers file (default: OUT.triggers.csv)");
  cmd->add_option("--edge", command->edge, "trigger edge: rising, falling, both")
      ->capture_default_str();
  cmd->add_option("--debounce", command->debounce, "ignore edges this soon after a trigger edge")
      ->capture_default_str();
  cmd->add_option("--gpio-bias", command->gpio_bias, "trigger line bias: up, down, off, as-is")
      ->capture_default_str();
  cmd->add_option("--still", command->still, "the still bias at start: the mean over this long")
      ->capture_default_str();
  cmd->add_option("--ring", command->ring,
                  "buffer per sensor between reader and writer, a duration of samples")
      ->capture_default_str();
  cmd->add_option("--orientation", command->orientation, "the .gcsv orientation line (Gyroflow's)")
      ->capture_default_str();
  cmd->add_option("--note", command->note, "a note line for the .gcsv header");
  cmd->add_option("--also", command->also,
                  "FORMAT,...: at the end also write each sensor's rows as gyro.csv (OUT less "
                  ".gcsv + .gyro.csv: s, rad/s on the orientation) and/or raw (.raw.csv: the "
                  "source paper's counts, read with --raw --range)")
      ->delimiter(',');
  cmd->add_option("--status-every", command->status_every,
                  "status line period (default: 1 s on a terminal, else 60 s)");
  cmd->add_option(
         "--realtime-priority", command->priority,
         "SCHED_FIFO priority 1..99 for the reader (root or CAP_SYS_NICE), and lock memory")
      ->capture_default_str();
  cmd->add_option(
      "--stall-writer", command->stall_writer,
      "testing: block the writer for A every B (e.g. 300ms@2s), as a slow SD card does");
  cmd->add_option("--pause-while-writing", command->pause_while_writing,
                  "the source paper's logger, for comparison: stop reading for T after every N "
                  "samples (e.g. 500000@300ms)");
  cmd->add_flag("--json", command->json, "print the summary as JSON (docs/FORMATS.md record/1)");
  cmd->add_option(
         "--clock", command->clock,
         "monotonic (default), or virtual: emulated devices only, as fast as the machine runs")
      ->capture_default_str();
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
