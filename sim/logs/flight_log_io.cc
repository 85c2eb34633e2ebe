#include "sim/logs/flight_log_io.h"

#include "sim/check.h"
#include "sim/logs/blackbox.h"
#include "sim/logs/dataflash.h"
#include "sim/logs/gcsv.h"
#include "sim/logs/gopro_telemetry.h"
#include "sim/logs/gyro_dump.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/ulog.h"
#include "sim/text_file.h"
#include "sim/trace_audit.h"
#include "sim/units.h"

#include <algorithm>
#include <filesystem>
#include <utility>

namespace shutterlab {
namespace {

// Enough for every magic and for a blackbox / CSV header line.
constexpr size_t kDetectBytes = 16 * 1024;

}  // namespace

void FlightLogReadOptions::Check() const {
  SHUTTERLAB_CHECK(log_index >= -1)
      << "log index must be -1 (longest) or >= 0 (got " << log_index << ")";
  raw.Check();
  if (format == LogFormat::kColumns) columns.Check();
}

LogFormat DetectFlightLogFormat(std::string_view first_bytes, const std::string& path) {
  if (LooksLikeULog(first_bytes)) return LogFormat::kULog;
  if (LooksLikeDataFlash(first_bytes)) return LogFormat::kDataFlash;
  if (LooksLikeBlackbox(first_bytes)) return LogFormat::kBlackbox;
  if (LooksLikeMp4(first_bytes)) return LogFormat::kGoproMp4;
  // A binary file is none of the text formats; say so instead of quoting line 1 of garbage.
  const size_t probe = std::min<size_t>(first_bytes.size(), 512);
  for (size_t i = 0; i < probe; ++i) {
    if (first_bytes[i] == '\0') {
      throw IoError(IoMessage(path, 0,
                              "unknown log format: not ULog, DataFlash, blackbox, GoPro MP4, "
                              "gyro.csv, .gcsv, raw counts or a gyro dump (binary content)"));
    }
  }
  // The prefix may end mid-line; drop the partial last line so that it cannot mislead detection.
  std::string_view text = first_bytes;
  if (first_bytes.size() == kDetectBytes) {
    const size_t last_newline = text.rfind('\n');
    if (last_newline != std::string_view::npos) text = text.substr(0, last_newline + 1);
  }
  if (LooksLikeGyroDump(text)) return LogFormat::kGyroDump;
  try {
    return DetectGyroFormat(text, path);  // kGyroCsv, kGcsv or kRaw
  } catch (const IoError& e) {
    throw IoError(
        std::string(e.what()) +
        " (unknown log format: not ULog, DataFlash, blackbox, GoPro MP4, gyro.csv, .gcsv, "
        "raw counts or a gyro dump; --columns reads any delimited file)");
  }
}

namespace {

// A detected plain gyro log's errors say what detection concluded, so that a file of an unknown
// kind is recognisable as such; they may come while the rows are streamed.
std::string DetectedAs(LogFormat format) {
  return std::string(" (read as ") + LogFormatName(format) +
         ": not ULog, DataFlash, blackbox or GoPro MP4; --format chooses)";
}

class DetectedSource : public GyroSource {
 public:
  DetectedSource(std::unique_ptr<GyroSource> source, LogFormat format)
      : source_(std::move(source)), format_(format) {}
  GyroChunk Next() override {
    try {
      return source_->Next();
    } catch (const IoError& e) {
      throw IoError(std::string(e.what()) + DetectedAs(format_));
    }
  }
  bool NextInto(std::vector<GyroSample>* out) override {
    try {
      return source_->NextInto(out);
    } catch (const IoError& e) {
      throw IoError(std::string(e.what()) + DetectedAs(format_));
    }
  }
  double Fraction() const override { return source_->Fraction(); }
  std::vector<LogWarning> Warnings() const override { return source_->Warnings(); }

 private:
  std::unique_ptr<GyroSource> source_;
  LogFormat format_;
};

// The plain gyro logs and the column reader, streamed a block at a time from input (path's).
FlightLogStream OpenText(TextBlocks input, const std::string& path, LogFormat format,
                         const FlightLogReadOptions& options) {
  FlightLogStream stream;
  FlightLog& log = stream.log;
  log.format = LogFormatName(format);
  if (format == LogFormat::kColumns) {
    ColumnCsvStream columns = OpenColumnCsv(std::move(input), path, options.columns);
    log.gyro_source = std::move(columns.log.source);
    stream.gyro = std::move(columns.samples);
  } else if (format == LogFormat::kGcsv) {
    GcsvStream gcsv = OpenGcsv(std::move(input), path);  // its header's assumptions: warnings
    log.warnings = std::move(gcsv.log.warnings);
    log.gyro_source = "gcsv";
    stream.gyro = std::move(gcsv.samples);
  } else if (format == LogFormat::kGyroDump) {
    log.gyro_source = "frameid/gyro lines (x,y,z rad/s, ts us)";
    stream.gyro = OpenGyroDump(std::move(input), path);
  } else if (format == LogFormat::kRaw) {
    options.raw.Check();
    log.gyro_source = "raw counts";
    stream.gyro = OpenRawCsv(std::move(input), path, options.raw.range_dps, options.raw.time_unit);
    stream.audit.full_scale_rad_s = options.raw.range_dps * kRadPerDeg;
  } else {
    log.gyro_source = "t,gx,gy,gz";
    stream.gyro = OpenGyroCsv(std::move(input), path);
  }
  log.gyro_sources_available = {log.gyro_source};
  return stream;
}

// A binary log decoded whole (the best gyro stream is chosen once every one is known), handed on
// in slices.
FlightLogStream WholeLogStream(FlightLog log) {
  FlightLogStream stream;
  stream.log = std::move(log);
  stream.gyro = std::make_unique<TraceSource>(std::move(stream.log.gyro));
  stream.log.gyro = GyroTrace();
  return stream;
}

// One open function per binary format, each returning its own stream, read in two passes over
// the mapped input: a file's own mapping; a pipe's bytes copied to a temporary file first
// (TextBlocks::TakeMapped, the one place a pipe is taken whole), so that a log on a pipe is read
// in the same bounded memory as a file. progress: pass 1's (may be empty).
FlightLogStream OpenULogLog(TextBlocks input, const OpeningProgress& progress) {
  ULogStream ulog = OpenULog(input.TakeMapped(), FillingSource::kDefaultChunkSamples, progress);
  FlightLogStream stream;
  stream.log = std::move(ulog.log);
  stream.gyro = std::move(ulog.gyro);
  return stream;
}

FlightLogStream OpenDataFlashLog(TextBlocks input, const OpeningProgress& progress) {
  DataFlashStream dataflash =
      OpenDataFlash(input.TakeMapped(), FillingSource::kDefaultChunkSamples, progress);
  FlightLogStream stream;
  stream.log = std::move(dataflash.log);
  stream.gyro = std::move(dataflash.samples);
  return stream;
}

FlightLogStream OpenBlackboxLog(TextBlocks input, int log_index, const OpeningProgress& progress) {
  BlackboxStream blackbox =
      OpenBlackbox(input.TakeMapped(), log_index, FillingSource::kDefaultChunkSamples, progress);
  FlightLogStream stream;
  stream.log = std::move(blackbox.log);
  stream.gyro = std::move(blackbox.samples);
  return stream;
}

// Decoded whole: its gyro is ~200 Hz (an hour is 720,000 samples), and its sample tables may
// follow its samples (moov after mdat), so it needs a file to seek.
FlightLogStream OpenGoproLog(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw IoError(IoMessage(path, 0, "a GoPro MP4 cannot be read from a pipe: save it to a file"));
  return WholeLogStream(ReadGoproFlightLog(path));
}

FlightLogStream OpenBinary(TextBlocks input, const std::string& path, LogFormat format,
                           const FlightLogReadOptions& options) {
  if (format == LogFormat::kGoproMp4) return OpenGoproLog(path);
  // Never less than before: a reader may read some bytes twice (DataFlash's pass 1 again without
  // its limits).
  OpeningProgress progress;
  double shown = 0.0;
  if (options.opening_progress) {
    progress = [&options, &shown](double fraction) {
      shown = std::max(shown, std::min(fraction, 1.0));
      options.opening_progress(shown);
    };
  }
  FlightLogStream stream;
  if (format == LogFormat::kULog) {
    stream = OpenULogLog(std::move(input), progress);
  } else if (format == LogFormat::kDataFlash) {
    stream = OpenDataFlashLog(std::move(input), progress);
  } else {
    stream = OpenBlackboxLog(std::move(input), options.log_index, progress);
  }
  if (progress) progress(1.0);
  return stream;
}

}  // namespace

FlightLogStream OpenFlightLog(const std::string& path, const FlightLogReadOptions& options) {
  options.Check();
  return OpenFlightLog(TextBlocks::OfFile(path), path, options);
}

FlightLogStream OpenFlightLog(TextBlocks input, const std::string& path,
                              const FlightLogReadOptions& options) {
  options.Check();
  // Its start is looked at through the same opening: a pipe can be read only once.
  LogFormat format = options.format;
  if (format == LogFormat::kAuto) format = DetectFlightLogFormat(input.Peek(kDetectBytes), path);
  if (format == LogFormat::kULog || format == LogFormat::kDataFlash ||
      format == LogFormat::kBlackbox || format == LogFormat::kGoproMp4) {
    return OpenBinary(std::move(input), path, format, options);
  }
  try {
    FlightLogStream stream = OpenText(std::move(input), path, format, options);
    if (options.format == LogFormat::kAuto)
      stream.gyro = std::make_unique<DetectedSource>(std::move(stream.gyro), format);
    return stream;
  } catch (const IoError& e) {
    if (options.format != LogFormat::kAuto) throw;
    throw IoError(std::string(e.what()) + DetectedAs(format));
  }
}

FlightLogStream OpenFlightLog(const ReopenableFile& file, const FlightLogReadOptions& options) {
  options.Check();
  return OpenFlightLog(file.Open(), file.path(), options);
}

FlightLog ReadFlightLog(const std::string& path, const FlightLogReadOptions& options) {
  FlightLogStream stream = OpenFlightLog(path, options);
  FlightLog log = std::move(stream.log);
  log.gyro = ReadAllSamples(stream.gyro.get());
  for (LogWarning& warning : stream.gyro->Warnings()) log.warnings.push_back(std::move(warning));
  for (LogWarning& warning : AuditTrace(log.gyro, stream.audit))
    log.warnings.push_back(std::move(warning));
  return log;
}

StreamedLog ConsumeFlightLog(FlightLogStream* stream,
                             const std::function<void(const GyroChunk&)>& consume,
                             const std::function<void(double)>& progress) {
  TraceAuditor auditor(stream->audit);
  for (GyroChunk chunk = stream->gyro->Next(); !chunk.empty(); chunk = stream->gyro->Next()) {
    auditor.Add(chunk.data, chunk.size);
    consume(chunk);
    if (progress) progress(stream->gyro->Fraction());
  }
  StreamedLog out;
  out.warnings = stream->log.warnings;
  for (LogWarning& warning : stream->gyro->Warnings()) out.warnings.push_back(std::move(warning));
  std::vector<LogWarning> audit = auditor.Finish();
  if (stream->audit_warnings) {
    for (LogWarning& warning : audit) out.warnings.push_back(std::move(warning));
  }
  out.sampling = auditor.Sampling();
  return out;
}

}  // namespace shutterlab
