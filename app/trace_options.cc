#include "app/trace_options.h"

#include "app/command.h"
#include "sim/check.h"

#include <algorithm>
#include <cstdio>
#include <functional>
#include <memory>
#include <utility>

namespace shutterlab::app {

void ColumnFlags::Add(CLI::App* command) {
  command
      ->add_option("--time-unit", time_unit,
                   "unit of the time column for raw counts and --columns (s, ms, us, ns)")
      ->capture_default_str();
  command->add_option("--columns", columns,
                      "read any delimited file by its columns TIME,X,Y,Z: header names "
                      "(t,gx,gy,gz) or 1-based numbers (4,1,2,3); content detection otherwise");
  command->add_option("--delimiter", delimiter,
                      "with --columns: comma, semicolon, tab, whitespace (default: from the first "
                      "line)");
  command->add_option("--rate-unit", rate_unit, "with --columns: rad/s (default) or deg/s");
}

void ColumnFlags::Apply(FlightLogReadOptions* options) const {
  const TimeUnit unit = ParseTimeUnit(time_unit);
  options->raw.time_unit = unit;
  if (columns.empty()) {
    SHUTTERLAB_CHECK(delimiter.empty() && rate_unit.empty())
        << "--delimiter and --rate-unit are for --columns: give --columns TIME,X,Y,Z too";
    return;
  }
  SHUTTERLAB_CHECK(options->format == LogFormat::kAuto || options->format == LogFormat::kColumns)
      << "--columns reads the file by its columns; it cannot go with --format "
      << LogFormatName(options->format);
  options->format = LogFormat::kColumns;
  options->columns.columns = ParseColumnList(columns);
  options->columns.delimiter = delimiter.empty() ? '\0' : ParseDelimiter(delimiter);
  options->columns.rate_unit =
      rate_unit.empty() ? RateUnit::kRadPerSecond : ParseRateUnit(rate_unit);
  options->columns.time_unit = unit;
}

void TraceOptions::Add(CLI::App* command, bool with_bias) {
  CheckLogPath(command
                   ->add_option("TRACE", path,
                                "gyro log: gyro.csv, Gyroflow .gcsv, raw-count CSV, PX4 ULog, "
                                "Betaflight blackbox, ArduPilot DataFlash, GoPro MP4 (- = stdin)")
                   ->required());
  command
      ->add_option("--format", format,
                   "log format: auto, csv, gcsv, raw, ulog, blackbox, dataflash, gopro, gyro_dump "
                   "(columns: set by "
                   "--columns)")
      ->capture_default_str();
  command->add_flag("--raw", raw, "the log holds raw int16 counts (the source paper's logger)");
  command
      ->add_option("--range", range_dps,
                   "raw counts: gyro full-scale range, deg/s (250, 500, 1000, 2000)")
      ->capture_default_str();
  column_flags.Add(command);
  if (with_bias) {
    command
        ->add_option("--bias", bias,
                     "still segment for the bias, A:B seconds after the first sample")
        ->capture_default_str();
    command->add_flag(
        "--auto-bias", auto_bias,
        "detect the still segment automatically (longest stretch >= 2 s whose 0.1 s mean "
        "and variance stay at the quiet level); overrides --bias");
  }
}

void TraceOptions::AddSecond(CLI::App* command) {
  CheckLogPath(command->add_option(
      "--second", second_path,
      "a second sensor's log on the same clock (record --device twice): paired, the mounting "
      "fitted from the motion, and fused"));
}

SensorPair TraceOptions::LoadSecondAndFuse(const GyroTrace& first, const BiasSegment& still,
                                           FlightLog* second_out) const {
  FlightLog second = ReadFlightLog(second_path, ReadOptions());
  PrintLogWarnings(second_path, second.warnings);
  if (second_out) *second_out = second;
  SensorPairOptions options;
  options.still = still;
  try {
    return FuseSensorPair(first, second.gyro, options);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + " + " + second_path + ": " + e.what());
  }
}

FlightLogReadOptions TraceOptions::ReadOptions() const {
  FlightLogReadOptions options;
  options.format = raw ? LogFormat::kRaw : ParseLogFormat(format);
  options.raw.range_dps = range_dps;
  SHUTTERLAB_CHECK(!raw || column_flags.columns.empty())
      << "--raw and --columns exclude each other";
  column_flags.Apply(&options);
  options.Check();
  return options;
}

// Any supported log: the gyro formats and the flight logs (ULog, blackbox, DataFlash) alike.
FlightLog TraceOptions::Load() const {
  FlightLog log = ReadFlightLog(path, ReadOptions());
  PrintLogWarnings(path, log.warnings);
  return log;
}

FlightLogStream OpenFlightLogShowingProgress(TextBlocks input, const std::string& path,
                                             FlightLogReadOptions read, const std::string& label) {
  Progress progress(label + " (opening)", 1000);
  if (progress.enabled()) {
    read.opening_progress = [&progress](double fraction) {
      progress.Update(static_cast<size_t>(fraction * 1000));
    };
  }
  return OpenFlightLog(std::move(input), path, read);
}

StreamedLog TraceOptions::Stream(const std::string& label,
                                 const std::function<void(const GyroChunk&)>& consume,
                                 const ReopenableFile* file) const {
  FlightLogStream stream = OpenFlightLogShowingProgress(
      file ? file->Open() : TextBlocks::OfFile(path), path, ReadOptions(), label);
  stream.gyro = ReadAhead(std::move(stream.gyro));
  StreamedLog streamed;
  {
    Progress progress(label, 1000);
    streamed = ConsumeFlightLog(&stream, consume, [&progress](double fraction) {
      progress.Update(static_cast<size_t>(fraction * 1000));
    });
  }
  PrintLogWarnings(path, streamed.warnings);
  return streamed;
}

void PrintLogWarnings(const std::string& path, const std::vector<LogWarning>& warnings) {
  for (const LogWarning& w : warnings)
    std::fprintf(stderr, "warning: %s: %s\n", path.c_str(), WarningLine(w).c_str());
}

namespace {

// The detected still segment, with its note on stderr.
BiasSegment NoteStillSegment(const StillSegment& still) {
  std::fprintf(stderr, "auto-bias: still segment %.3f:%.3f s\n", still.segment.begin_s,
               still.segment.end_s);
  return still.segment;
}

}  // namespace

BiasSegment TraceOptions::Segment(const GyroTrace& trace) const {
  if (!auto_bias) return ParseBiasSegment(bias);
  return NoteStillSegment(DetectStillSegment(trace));
}

std::unique_ptr<GyroSource> PairInPasses::OpenFused() const {
  return FusedPairSource(OpenFlightLog(first, read).gyro, OpenFlightLog(second, read).gyro, pair,
                         second_interval_ns);
}

PairInPasses FitPairInPasses(const ReopenableFile& first, const ReopenableFile& second,
                             const FlightLogReadOptions& read, FlightLogStream first_stream,
                             const std::optional<BiasSegment>& still) {
  PairInPasses out(first, second, read);
  const auto samples_of = [&read](const ReopenableFile& file) -> OpenGyroSource {
    return [&read, file] { return OpenFlightLog(file, read).gyro; };
  };
  // Progress over the passes: each log's, the still search's five and the fit's three (counted on
  // the first log).
  const int passes = 2 + (still ? 0 : 5) + 3;
  int passes_begun = 0;
  Progress progress("pair", 1000);
  const auto next_pass = [&]() -> std::function<void(double)> {
    const int pass = passes_begun++;
    return [&progress, pass, passes](double f) {
      progress.Update(static_cast<size_t>(std::min(pass + f, 1.0 * passes) / passes * 1000));
    };
  };
  const OpenGyroSource first_passes = [&] {
    return std::make_unique<ReportingSource>(samples_of(first)(), next_pass());
  };
  const auto ignore = [](const GyroChunk&) {};
  const StreamedLog first_read = ConsumeFlightLog(&first_stream, ignore, next_pass());
  PrintLogWarnings(first.path(), first_read.warnings);
  FlightLogStream second_stream = OpenFlightLog(second, read);
  const StreamedLog second_read = ConsumeFlightLog(&second_stream, ignore, next_pass());
  PrintLogWarnings(second.path(), second_read.warnings);
  out.warnings = first_read.warnings;
  out.warnings.insert(out.warnings.end(), second_read.warnings.begin(), second_read.warnings.end());
  SensorPairOptions options;
  options.still = still;
  if (!still) {
    try {
      options.still = DetectStillSegment(first_passes).segment;
    } catch (const std::invalid_argument&) {
    }
  }
  out.second_interval_ns = second_read.sampling.median_interval_ns;
  try {
    out.pair = FitSensorPair(first_passes, samples_of(second), out.second_interval_ns, options);
  } catch (const std::invalid_argument& e) {
    // Named by both logs, as the whole read names them: an IoError, so that a caller's wrapping of
    // the analysis's errors in the first log's name does not name it twice.
    throw IoError(first.path() + " + " + second.path() + ": " + WithoutCheckLocation(e.what()));
  }
  return out;
}

BiasSegment TraceOptions::StreamedSegment(const ReopenableFile& file) const {
  if (!auto_bias) return ParseBiasSegment(bias);
  constexpr size_t kPasses = 5;  // DetectStillSegment on a source reads it at most five times
  Progress progress("auto-bias", kPasses * 1000);
  size_t pass = 0;
  const auto open = [&]() -> std::unique_ptr<GyroSource> {
    const size_t done = std::min(pass++, kPasses - 1) * 1000;
    return std::make_unique<ReportingSource>(
        OpenFlightLog(file, ReadOptions()).gyro,
        [&progress, done](double f) { progress.Update(done + static_cast<size_t>(f * 1000)); });
  };
  return NoteStillSegment(DetectStillSegment(open));
}

}  // namespace shutterlab::app
