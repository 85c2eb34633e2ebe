#include "estimate/paper/log_pipeline.h"

#include "sim/check.h"
#include "sim/gyro_source.h"
#include "sim/gyro_sync.h"
#include "sim/still_detect.h"
#include "sim/text_file.h"

#include <algorithm>
#include <filesystem>
#include <memory>
#include <utility>

namespace shutterlab {
namespace {

void Progress(const PipelineEvents& events, const std::string& stage, double fraction) {
  if (events.progress) events.progress(stage, fraction);
}

void Warn(const PipelineEvents& events, const std::string& path,
          const std::vector<LogWarning>& warnings) {
  if (events.warnings) events.warnings(path, warnings);
}

// The still segment found, with its note.
BiasSegment NoteStillSegment(const StillSegment& still, const PipelineEvents& events) {
  if (events.note) {
    events.note(FormatNumber("auto-bias: still segment %.3f:", still.segment.begin_s) +
                FormatNumber("%.3f s", still.segment.end_s));
  }
  return still.segment;
}

// An analysis's errors named by the log it analysed.
template <typename Work>
auto NamedByLog(const std::string& path, const Work& work) {
  try {
    return work();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

// A source that reports the share it has read after each chunk: the progress of one pass of a
// reading in several (the still search's, the pair's).
class ReportingSource : public GyroSource {
 public:
  ReportingSource(std::unique_ptr<GyroSource> source, std::function<void(double)> report)
      : source_(std::move(source)), report_(std::move(report)) {}
  GyroChunk Next() override {
    const GyroChunk chunk = source_->Next();
    if (report_) report_(source_->Fraction());
    return chunk;
  }
  double Fraction() const override { return source_->Fraction(); }
  std::vector<LogWarning> Warnings() const override { return source_->Warnings(); }

 private:
  std::unique_ptr<GyroSource> source_;
  std::function<void(double)> report_;
};

// OpenFlightLog telling the progress of a flight-controller log's first pass (tens of seconds on
// 10^8 samples) as the stage "LABEL (opening)".
FlightLogStream OpenTellingProgress(TextBlocks input, const std::string& path,
                                    FlightLogReadOptions read, const std::string& label,
                                    const PipelineEvents& events) {
  if (events.progress) {
    read.opening_progress = [&events, stage = label + " (opening)"](double fraction) {
      events.progress(stage, fraction);
    };
  }
  return OpenFlightLog(std::move(input), path, read);
}

// One log read through once as a stream, every chunk handed to consume; its warnings told when it
// has been read. file: the log opened for a reading in passes, else the path is opened for this
// one read.
StreamedLog StreamLog(const LogInput& input, const std::string& label,
                      const std::function<void(const GyroChunk&)>& consume,
                      const ReopenableFile* file, const PipelineEvents& events) {
  FlightLogStream stream = OpenTellingProgress(file ? file->Open() : TextBlocks::OfFile(input.path),
                                               input.path, input.read, label, events);
  if (input.read_ahead) stream.gyro = ReadAhead(std::move(stream.gyro));
  const StreamedLog streamed = ConsumeFlightLog(
      &stream, consume, [&](double fraction) { Progress(events, label, fraction); });
  Warn(events, input.path, streamed.warnings);
  return streamed;
}

// The still segment of a log too long to hold: the search reads it (file) five times
// (DetectStillSegment on a source) in memory bounded by its 2 s stretch.
BiasSegment StillSegmentInPasses(const ReopenableFile& file, const FlightLogReadOptions& read,
                                 const PipelineEvents& events) {
  static constexpr int kPasses = 5;  // DetectStillSegment on a source reads it at most five times
  int pass = 0;
  const auto open = [&]() -> std::unique_ptr<GyroSource> {
    const int done = std::min(pass++, kPasses - 1);
    return std::make_unique<ReportingSource>(
        OpenFlightLog(file, read).gyro,
        [&events, done](double f) { Progress(events, "auto-bias", (done + f) / kPasses); });
  };
  return NoteStillSegment(DetectStillSegment(open), events);
}

// A pair read in passes, in bounded memory whatever the logs' length: each log read through once
// for what it lost (told under its name, as the whole read tells it) and the second's sampling,
// the still segment searched on the first log when none is given (five passes), then the pair
// fitted (three passes over both: sim/sensor_pair.h FitSensorPair). The same pair as
// FuseSensorPair on the logs read whole, and the same fused samples from OpenFused.
struct PairInPasses {
  PairInPasses(ReopenableFile first_log, ReopenableFile second_log, FlightLogReadOptions options)
      : first(std::move(first_log)), second(std::move(second_log)), read(std::move(options)) {}
  ReopenableFile first, second;
  FlightLogReadOptions read;
  std::optional<GyroSync> second_clock;  // LogInput::second_own_clock: the second on the first's
  SensorPair pair;                       // every field but fused
  std::vector<LogWarning> warnings;      // the first log's, then the second's
  int64_t second_interval_ns = 0;        // the second log's median sample interval
  // The fused samples from the start (both logs opened again).
  std::unique_ptr<GyroSource> OpenFused() const {
    return FusedPairSource(OpenFlightLog(first, read).gyro, OpenSecond(), pair, second_interval_ns);
  }
  // The second log's samples from the start, on the first's clock.
  std::unique_ptr<GyroSource> OpenSecond() const {
    std::unique_ptr<GyroSource> samples = OpenFlightLog(second, read).gyro;
    return second_clock ? OnClockA(std::move(samples), *second_clock) : std::move(samples);
  }
};

// A log's whole gyro trace, read through its stream (a pipe too).
GyroTrace WholeTrace(const ReopenableFile& file, const FlightLogReadOptions& read) {
  FlightLogStream stream = OpenFlightLog(file, read);
  std::vector<GyroSample> samples;
  ConsumeFlightLog(&stream, [&](const GyroChunk& chunk) {
    samples.insert(samples.end(), chunk.begin(), chunk.end());
  });
  return GyroTrace(std::move(samples));
}

// LogInput::second_own_clock: the second log's clock against the first's, from the motion (both
// read whole). Throws IoError naming both logs when the motion cannot align them.
GyroSync SecondClock(const GyroTrace& first, const GyroTrace& second, const std::string& first_path,
                     const std::string& second_path) {
  try {
    GyroSyncOptions options;
    options.a_name = first_path;
    options.b_name = second_path;
    return SyncGyros(first, second, options);
  } catch (const std::invalid_argument& e) {
    throw IoError(
        first_path + " + " + second_path +
        ": cannot put the second log on the first's clock: " + WithoutCheckLocation(e.what()));
  }
}

void NoteClock(const GyroSync& sync, SensorPair* pair) {
  pair->clock_offset_s = sync.offset_s;
  pair->clock_offset_stderr_s = sync.offset_stderr_s;
}

// first_stream: the first log, opened already (its metadata read). still: the segment that weighs
// the fusion; nullopt: searched on the first log (equal weights when none is found). Throws
// IoError naming both logs when they do not pair.
PairInPasses FitPairInPasses(const ReopenableFile& first, const ReopenableFile& second,
                             const FlightLogReadOptions& read, bool second_own_clock,
                             FlightLogStream first_stream, const std::optional<BiasSegment>& still,
                             const PipelineEvents& events) {
  PairInPasses out(first, second, read);
  if (second_own_clock)
    out.second_clock =
        SecondClock(WholeTrace(first, read), WholeTrace(second, read), first.path(), second.path());
  const auto samples_of = [&read](const ReopenableFile& file) -> OpenGyroSource {
    return [&read, file] { return OpenFlightLog(file, read).gyro; };
  };
  // Progress over the passes: each log's, the still search's five and the fit's three (counted on
  // the first log).
  const int passes = 2 + (still ? 0 : 5) + 3;
  int passes_begun = 0;
  const auto next_pass = [&]() -> std::function<void(double)> {
    const int pass = passes_begun++;
    return [&events, pass, passes](double f) {
      Progress(events, "pair", std::min(pass + f, 1.0 * passes) / passes);
    };
  };
  const OpenGyroSource first_passes = [&] {
    return std::make_unique<ReportingSource>(samples_of(first)(), next_pass());
  };
  const auto ignore = [](const GyroChunk&) {};
  const StreamedLog first_read = ConsumeFlightLog(&first_stream, ignore, next_pass());
  Warn(events, first.path(), first_read.warnings);
  FlightLogStream second_stream = OpenFlightLog(second, read);
  const StreamedLog second_read = ConsumeFlightLog(&second_stream, ignore, next_pass());
  Warn(events, second.path(), second_read.warnings);
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
    const OpenGyroSource second_passes = [&out] { return out.OpenSecond(); };
    out.pair = FitSensorPair(first_passes, second_passes, out.second_interval_ns, options);
    if (out.second_clock) NoteClock(*out.second_clock, &out.pair);
  } catch (const std::invalid_argument& e) {
    // Named by both logs, as the whole read names them: an IoError, so that a caller's wrapping of
    // the analysis's errors in the first log's name does not name it twice.
    throw IoError(first.path() + " + " + second.path() + ": " + WithoutCheckLocation(e.what()));
  }
  return out;
}

// LOG and the second log, opened for the streamed analysis's passes.
struct AnalyzedLogs {
  ReopenableFile first;
  std::optional<ReopenableFile> second;
  explicit AnalyzedLogs(const LogInput& input) : first(input.path) {
    if (!input.second_path.empty()) second.emplace(input.second_path);
  }
  // After the last pass: it read the logs as the first did (IoError otherwise).
  void CheckUnchanged() const {
    first.CheckUnchanged();
    if (second) second->CheckUnchanged();
  }
};

// What reading the trigger file lost, named by the file: it goes with the log's warnings into the
// outputs (told already, when it was read).
std::vector<LogWarning> TriggerWarnings(const std::optional<TriggerInput>& triggers) {
  std::vector<LogWarning> warnings;
  if (!triggers) return warnings;
  const std::string name = std::filesystem::path(triggers->path).filename().string();
  for (LogWarning w : triggers->file.warnings) {
    w.message = "trigger file " + name + ": " + w.message;
    warnings.push_back(std::move(w));
  }
  return warnings;
}

// With a second log, the pair as AnalyzeStream reads it, fused on the first log's clock
// (FitPairInPasses; the still segment that weighs the fusion searched on the first log), fused
// chunk by chunk each time the analysis opens it.
AnalyzeLogSource PairStreamSource(const LogInput& input,
                                  const std::optional<TriggerInput>& triggers,
                                  FlightLogStream first, const AnalyzedLogs& logs,
                                  std::optional<SensorPair>* pair, const PipelineEvents& events) {
  FlightLog first_log = first.log;
  auto fitted = std::make_shared<const PairInPasses>(
      FitPairInPasses(logs.first, *logs.second, input.read, input.second_own_clock,
                      std::move(first), std::nullopt, events));
  *pair = fitted->pair;
  // The fused log: the first's metadata, both logs' warnings, the fused samples.
  FlightLog fused = std::move(first_log);
  fused.warnings = fitted->warnings;
  AnalyzeLogSource source;
  source.open = [fused, fitted] {
    FlightLogStream stream;
    stream.log = fused;
    stream.gyro = fitted->OpenFused();
    stream.audit_warnings = false;  // both logs' audits are in fused.warnings
    return stream;
  };
  source.more_warnings = TriggerWarnings(triggers);
  return source;
}

// The log as AnalyzeStream reads it: first is its first stream, already opened (its metadata
// read); each later pass opens the log again. Tells the log's warnings when it has been read
// through; the trigger file's go after them. With a second log, the pair fused.
AnalyzeLogSource StreamSource(const LogInput& input, const std::optional<TriggerInput>& triggers,
                              FlightLogStream first, const AnalyzedLogs& logs,
                              std::optional<SensorPair>* pair, const PipelineEvents& events) {
  if (logs.second) return PairStreamSource(input, triggers, std::move(first), logs, pair, events);
  auto first_left = std::make_shared<std::optional<FlightLogStream>>(std::move(first));
  AnalyzeLogSource source;
  source.open = [first_left, file = logs.first, &input] {
    if (!*first_left) return OpenFlightLog(file, input.read);
    FlightLogStream stream = std::move(**first_left);
    first_left->reset();
    return stream;
  };
  source.more_warnings = TriggerWarnings(triggers);
  source.on_read = [&input, &events](const std::vector<LogWarning>& warnings) {
    Warn(events, input.path, warnings);
  };
  return source;
}

}  // namespace

LoadedTrace LoadTrace(const LogInput& input, const BiasSegment& segment,
                      const PipelineEvents& events) {
  FlightLog log = ReadFlightLog(input.path, input.read);
  Warn(events, input.path, log.warnings);
  LoadedTrace loaded;
  loaded.warnings = log.warnings;
  loaded.segment =
      input.find_still_segment
          ? NamedByLog(input.path,
                       [&] { return NoteStillSegment(DetectStillSegment(log.gyro), events); })
          : segment;
  if (input.second_path.empty()) {
    loaded.trace = std::move(log.gyro);
    return loaded;
  }
  FlightLog second = ReadFlightLog(input.second_path, input.read);
  Warn(events, input.second_path, second.warnings);
  loaded.warnings.insert(loaded.warnings.end(), second.warnings.begin(), second.warnings.end());
  SensorPairOptions options;
  options.still = loaded.segment;
  std::optional<GyroSync> clock;
  if (input.second_own_clock) {
    clock = SecondClock(log.gyro, second.gyro, input.path, input.second_path);
    second.gyro = OnClockA(second.gyro, *clock);
  }
  SensorPair pair = NamedByLog(input.path + " + " + input.second_path,
                               [&] { return FuseSensorPair(log.gyro, second.gyro, options); });
  if (clock) NoteClock(*clock, &pair);
  loaded.trace = pair.fused;
  loaded.pair = TracePair{std::move(log.gyro), std::move(second.gyro), std::move(pair)};
  return loaded;
}

FlightRun RunFlight(const LogInput& input, FlightOptions options, const PipelineEvents& events) {
  options.Check();
  // Only a reading in passes (the still search, the pair's fit) opens the log for them.
  std::optional<ReopenableFile> first;
  if (input.find_still_segment || !input.second_path.empty()) first.emplace(input.path);
  if (input.find_still_segment) {
    options.bias =
        NamedByLog(input.path, [&] { return StillSegmentInPasses(*first, input.read, events); });
  }
  FlightStream flight(options);
  const auto add = [&flight](const GyroChunk& chunk) { flight.Add(chunk.data, chunk.size); };
  FlightRun run;
  if (!input.second_path.empty()) {
    const ReopenableFile second(input.second_path);
    const PairInPasses fitted =
        FitPairInPasses(*first, second, input.read, input.second_own_clock,
                        OpenFlightLog(*first, input.read), options.bias, events);
    run.pair = fitted.pair;
    run.warnings = fitted.warnings;
    std::unique_ptr<GyroSource> fused = fitted.OpenFused();
    if (input.read_ahead) fused = ReadAhead(std::move(fused));
    for (GyroChunk chunk = fused->Next(); !chunk.empty(); chunk = fused->Next()) {
      add(chunk);
      Progress(events, "flight", fused->Fraction());
    }
    second.CheckUnchanged();
  } else {
    run.warnings = StreamLog(input, "flight", add, first ? &*first : nullptr, events).warnings;
  }
  if (first) first->CheckUnchanged();
  run.result = NamedByLog(input.path, [&] { return flight.Finish(); });
  // The analysis's own warnings (windows refused as too short) are told as the reader's were.
  Warn(events, input.path, run.result.warnings);
  run.warnings.insert(run.warnings.end(), run.result.warnings.begin(), run.result.warnings.end());
  return run;
}

AnalyzeRun RunAnalyze(const LogInput& input, AnalyzeOptions options,
                      const std::optional<TriggerInput>& triggers, const PipelineEvents& events) {
  options.Check();  // before the (possibly long) read
  return NamedByLog(input.path, [&] {
    const AnalyzedLogs logs(input);
    // Opened once for the triggers (a GPS-timed file needs the log's GPS fixes); that stream is
    // the analysis's first.
    FlightLogStream first =
        OpenTellingProgress(logs.first.Open(), input.path, input.read, "analyze", events);
    if (triggers) {
      options.triggers = TriggersOnLogClock(triggers->file, first.log, triggers->path);
      options.triggers_source = "trigger file " +
                                std::filesystem::path(triggers->path).filename().string() + ": " +
                                triggers->file.source;
    }
    AnalyzeRun run;
    const AnalyzeLogSource source =
        StreamSource(input, triggers, std::move(first), logs, &run.pair, events);
    if (events.progress) {
      options.progress = [progress = events.progress](double f) { progress("analyze", f); };
    }
    run.result = AnalyzeStream(source, options);
    logs.CheckUnchanged();
    // The flight table's own warnings join the log's, as they do in the --json's list.
    if (run.result.flight) Warn(events, input.path, run.result.flight->warnings);
    return run;
  });
}

PhotosOnLogRun RunPhotosOnLog(const LogInput& input, const PhotoSet& set,
                              PhotoFlightOptions options,
                              const std::optional<TriggerInput>& triggers,
                              const PipelineEvents& events) {
  const AnalyzedLogs logs(input);
  FlightLogStream first =
      OpenTellingProgress(logs.first.Open(), input.path, input.read, "analyze", events);
  const FlightLog metadata = first.log;  // the samples stay in the stream
  PhotosOnLogRun run;
  const AnalyzeLogSource source =
      StreamSource(input, triggers, std::move(first), logs, &run.pair, events);
  if (events.progress) {
    options.analyze.progress = [progress = events.progress](double f) { progress("analyze", f); };
  }
  return NamedByLog(input.path, [&] {
    run.result = AnalyzePhotoFlightStream(set, metadata, source,
                                          triggers ? &triggers->file : nullptr, options);
    run.result.analyzed.progress = {};  // the caller's events end with the run
    logs.CheckUnchanged();
    if (run.result.log.flight) Warn(events, input.path, run.result.log.flight->warnings);
    return run;
  });
}

}  // namespace shutterlab
