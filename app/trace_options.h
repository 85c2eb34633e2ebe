#pragma once
// CLI options shared by every command that reads a gyro trace: format selection and bias segment.

#include "sim/bias.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/sensor_pair.h"
#include "sim/still_detect.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab::app {

// --time-unit, --columns, --delimiter and --rate-unit: how to read a file by its columns (and the
// time unit of raw counts), shared by the trace commands and analyze.
struct ColumnFlags {
  std::string columns;          // "" = detect the format from the content
  std::string delimiter;        // "" = auto
  std::string rate_unit;        // "" = rad/s
  std::string time_unit = "s";  // raw counts and --columns: unit of the time column

  void Add(CLI::App* command);
  // Sets the time units and, with --columns, the column reader (options->format = kColumns).
  // Throws std::invalid_argument for a bad value, --delimiter or --rate-unit without --columns, or
  // --columns with a --format other than auto / columns.
  void Apply(FlightLogReadOptions* options) const;
};

struct TraceOptions {
  std::string path;
  std::string format = "auto";  // auto | csv | gcsv | raw | ulog | blackbox | dataflash | columns
  bool raw = false;             // shorthand for --format raw
  int range_dps = 250;          // raw counts: full-scale range
  ColumnFlags column_flags;     // --time-unit, --columns, --delimiter, --rate-unit
  std::string bias = "0:5";     // bias segment A:B, seconds after the first sample
  bool auto_bias = false;       // find the still segment automatically instead of --bias
  std::string second_path;      // --second: a second sensor's log on the same clock

  // Adds TRACE (positional) and the options above to a subcommand. with_bias: add --bias too.
  void Add(CLI::App* command, bool with_bias);
  // Adds --second (noise, flight): the second sensor of a pair.
  void AddSecond(CLI::App* command);
  FlightLogReadOptions ReadOptions() const;
  // With --second: reads it (the same read options), fuses it with `first` (sim/sensor_pair.h,
  // weights from `still`) and prints its warnings on stderr.
  // *second (optional) receives the second sensor's trace.
  SensorPair LoadSecondAndFuse(const GyroTrace& first, const BiasSegment& still,
                               FlightLog* second = nullptr) const;
  // Reads the log and prints its warnings on stderr (PrintLogWarnings).
  FlightLog Load() const;
  // Reads the log as a stream, a block at a time with the reader a chunk ahead on a second thread,
  // handing each chunk to consume; shows progress on a terminal (label), prints the warnings on
  // stderr once the log is read, and returns them with the sampling. file: the log opened for a
  // reading in passes (--auto-bias read it first), else the path is opened for this one read.
  StreamedLog Stream(const std::string& label, const std::function<void(const GyroChunk&)>& consume,
                     const ReopenableFile* file = nullptr) const;
  // The bias segment for this trace: with --auto-bias the detected still segment
  // (DetectStillSegment, default StillDetectOptions; one note "auto-bias: still segment A:B s" on
  // stderr), otherwise --bias A:B. Throws std::invalid_argument when neither gives a segment.
  BiasSegment Segment(const GyroTrace& trace) const;
  // The same for a log too long to hold, read as a stream: the still search reads the log (file)
  // five times (DetectStillSegment on a source) in memory bounded by its 2 s stretch, with the
  // same segment and note; shows progress on a terminal.
  BiasSegment StreamedSegment(const ReopenableFile& file) const;
};

// OpenFlightLog showing the progress of the opening's pass 1 (a flight-controller log's: tens of
// seconds on 10^8 samples) on a terminal, as "LABEL (opening): 42%", cleared once opened.
FlightLogStream OpenFlightLogShowingProgress(TextBlocks input, const std::string& path,
                                             FlightLogReadOptions read, const std::string& label);

// What the reader could not read or trust, one "warning: PATH: LINE" on stderr each, so that no
// command analyses less than the file holds without saying so.
void PrintLogWarnings(const std::string& path, const std::vector<LogWarning>& warnings);

// A source that reports the share it has read after each chunk: the progress of a pass of a read
// in several (the still search's, the sensor pair's).
class ReportingSource : public GyroSource {
 public:
  ReportingSource(std::unique_ptr<GyroSource> source, std::function<void(double)> report)
      : source_(std::move(source)), report_(std::move(report)) {}
  GyroChunk Next() override {
    const GyroChunk chunk = source_->Next();
    report_(source_->Fraction());
    return chunk;
  }
  double Fraction() const override { return source_->Fraction(); }
  std::vector<LogWarning> Warnings() const override { return source_->Warnings(); }

 private:
  std::unique_ptr<GyroSource> source_;
  std::function<void(double)> report_;
};

// --second's pair read in passes, in bounded memory whatever the logs' length (the streamed
// `flight` and `analyze`): each log read through once for what it lost (printed under its name, as
// the whole read prints it) and the second's sampling, the still segment searched on the first log
// when none is given (five passes), then the pair fitted (three passes over both: sim/sensor_pair.h
// FitSensorPair). The same pair as FuseSensorPair on the logs read whole, and the same fused
// samples from OpenFused.
struct PairInPasses {
  PairInPasses(ReopenableFile first_log, ReopenableFile second_log, FlightLogReadOptions options)
      : first(std::move(first_log)), second(std::move(second_log)), read(std::move(options)) {}
  ReopenableFile first, second;
  FlightLogReadOptions read;
  SensorPair pair;                   // every field but fused
  std::vector<LogWarning> warnings;  // the first log's, then the second's
  int64_t second_interval_ns = 0;    // the second log's median sample interval
  // The fused samples from the start (both logs opened again).
  std::unique_ptr<GyroSource> OpenFused() const;
};
// first_stream: the first log, opened already (its metadata read). still: the segment that weighs
// the fusion; nullopt: searched on the first log (equal weights when none is found). Shows progress
// on a terminal. Throws IoError naming both logs when they do not pair.
PairInPasses FitPairInPasses(const ReopenableFile& first, const ReopenableFile& second,
                             const FlightLogReadOptions& read, FlightLogStream first_stream,
                             const std::optional<BiasSegment>& still);

// Runs analysis(trace, options) the way every trace command does: --bias is parsed and the options
// checked before the (possibly long) read, the log's warnings are printed (and handed back in
// *warnings for --json), the segment is resolved after the read (--auto-bias detects the still
// segment), and the analysis's own errors are prefixed with the trace's path.
// With --second: each sensor's trace and their fusion.
struct TracePair {
  GyroTrace first, second;
  SensorPair pair;
  BiasSegment segment;  // the bias segment the analysis used
};

// With --second the analysis runs on the fused trace of the pair (*pair, when given, receives
// both traces and the fusion).
template <typename Options, typename Analysis>
auto AnalyzeTrace(const TraceOptions& trace_options, Options options, const Analysis& analysis,
                  std::vector<LogWarning>* warnings = nullptr, TracePair* pair = nullptr) {
  if (!trace_options.auto_bias) options.bias = ParseBiasSegment(trace_options.bias);
  options.Check();
  FlightLog log = trace_options.Load();
  if (warnings) *warnings = log.warnings;
  options.bias = trace_options.Segment(log.gyro);
  if (!trace_options.second_path.empty()) {
    FlightLog second;
    SensorPair fused = trace_options.LoadSecondAndFuse(log.gyro, options.bias, &second);
    if (warnings) warnings->insert(warnings->end(), second.warnings.begin(), second.warnings.end());
    GyroTrace first = std::move(log.gyro);
    log.gyro = fused.fused;
    if (pair) *pair = {std::move(first), std::move(second.gyro), std::move(fused), options.bias};
  }
  try {
    return analysis(log.gyro, options);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(trace_options.path + ": " + e.what());
  }
}

}  // namespace shutterlab::app
