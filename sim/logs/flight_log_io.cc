#include "sim/logs/flight_log_io.h"

#include "sim/check.h"
#include "sim/logs/blackbox.h"
#include "sim/logs/dataflash.h"
#include "sim/logs/gcsv.h"
#include "sim/logs/gopro_telemetry.h"
#include "sim/logs/gyro_dump.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/mp4.h"
#include "sim/logs/raw_csv.h"
#include "sim/logs/ulog.h"
#include "sim/text_file.h"
#include "sim/trace_audit.h"
#include "sim/units.h"

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <optional>
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

namespace {

// The formats' names for a person, joined: "ULog, DataFlash, blackbox or GoPro MP4".
std::string JoinedDisplayNames(bool (*include)(const LogReader&)) {
  std::vector<const char*> names;
  for (const LogReader& reader : LogReaders()) {
    if (include(reader)) names.push_back(reader.display_name);
  }
  std::string out;
  for (size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + std::string(names[i]);
  return out;
}

bool Detected(const LogReader& reader) { return reader.detection != LogDetection::kNever; }
bool DetectedByBytes(const LogReader& reader) { return reader.detection == LogDetection::kBytes; }

// A detected plain gyro log's errors say what detection concluded, so that a file of an unknown
// kind is recognisable as such; they may come while the rows are streamed.
std::string DetectedAs(LogFormat format) {
  return std::string(" (read as ") + LogFormatName(format) + ": not " +
         JoinedDisplayNames(DetectedByBytes) + "; --format chooses)";
}

}  // namespace

LogFormat DetectFlightLogFormat(std::string_view first_bytes, const std::string& path) {
  for (const LogReader& reader : LogReaders()) {
    if (reader.detection == LogDetection::kBytes && reader.recognise(first_bytes))
      return reader.format;
  }
  const std::string unknown = "unknown log format: not " + JoinedDisplayNames(Detected);
  // A binary file is none of the text formats; say so instead of quoting line 1 of garbage.
  const size_t probe = std::min<size_t>(first_bytes.size(), 512);
  for (size_t i = 0; i < probe; ++i) {
    if (first_bytes[i] == '\0') throw IoError(IoMessage(path, 0, unknown + " (binary content)"));
  }
  // The prefix may end mid-line; drop the partial last line so that it cannot mislead detection.
  std::string_view text = first_bytes;
  if (first_bytes.size() == kDetectBytes) {
    const size_t last_newline = text.rfind('\n');
    if (last_newline != std::string_view::npos) text = text.substr(0, last_newline + 1);
  }
  for (const LogReader& reader : LogReaders()) {
    if (reader.detection == LogDetection::kText && reader.recognise(text)) return reader.format;
  }
  try {
    return DetectGyroFormat(text, path);  // the LogDetection::kPlainGyro formats
  } catch (const IoError& e) {
    throw IoError(std::string(e.what()) + " (" + unknown + "; --columns reads any delimited file)");
  }
}

namespace {

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

// The openers of the reader table, one per format. The text logs are streamed a block at a time
// from input (path's). The binary logs are read in two passes over the mapped input: a file's own
// mapping; a pipe's bytes copied to a temporary file first (TextBlocks::TakeMapped, the one place
// a pipe is taken whole), so that a log on a pipe is read in the same bounded memory as a file.
// progress: pass 1's (may be empty).

// A stream of a text log: no metadata but its format and source.
FlightLogStream TextStream(LogFormat format, std::string gyro_source,
                           std::unique_ptr<GyroSource> samples) {
  FlightLogStream stream;
  stream.log.format = LogFormatName(format);
  stream.log.gyro_source = std::move(gyro_source);
  stream.log.gyro_sources_available = {stream.log.gyro_source};
  stream.gyro = std::move(samples);
  return stream;
}

FlightLogStream OpenGyroCsvLog(TextBlocks input, const std::string& path,
                               const FlightLogReadOptions&, const OpeningProgress&) {
  return TextStream(LogFormat::kGyroCsv, "t,gx,gy,gz", OpenGyroCsv(std::move(input), path));
}

FlightLogStream OpenGcsvLog(TextBlocks input, const std::string& path, const FlightLogReadOptions&,
                            const OpeningProgress&) {
  GcsvStream gcsv = OpenGcsv(std::move(input), path);  // its header's assumptions: warnings
  FlightLogStream stream = TextStream(LogFormat::kGcsv, "gcsv", std::move(gcsv.samples));
  stream.log.warnings = std::move(gcsv.log.warnings);
  return stream;
}

FlightLogStream OpenRawLog(TextBlocks input, const std::string& path,
                           const FlightLogReadOptions& options, const OpeningProgress&) {
  options.raw.Check();
  FlightLogStream stream =
      TextStream(LogFormat::kRaw, "raw counts",
                 OpenRawCsv(std::move(input), path, options.raw.range_dps, options.raw.time_unit));
  stream.audit.full_scale_rad_s = options.raw.range_dps * kRadPerDeg;
  return stream;
}

FlightLogStream OpenGyroDumpLog(TextBlocks input, const std::string& path,
                                const FlightLogReadOptions&, const OpeningProgress&) {
  return TextStream(LogFormat::kGyroDump, "frameid/gyro lines (x,y,z rad/s, ts us)",
                    OpenGyroDump(std::move(input), path));
}

FlightLogStream OpenColumnsLog(TextBlocks input, const std::string& path,
                               const FlightLogReadOptions& options, const OpeningProgress&) {
  ColumnCsvStream columns = OpenColumnCsv(std::move(input), path, options.columns);
  return TextStream(LogFormat::kColumns, std::move(columns.log.source), std::move(columns.samples));
}

FlightLogStream OpenULogLog(TextBlocks input, const std::string&, const FlightLogReadOptions&,
                            const OpeningProgress& progress) {
  ULogStream ulog = OpenULog(input.TakeMapped(), FillingSource::kDefaultChunkSamples, progress);
  FlightLogStream stream;
  stream.log = std::move(ulog.log);
  stream.gyro = std::move(ulog.gyro);
  return stream;
}

FlightLogStream OpenDataFlashLog(TextBlocks input, const std::string&, const FlightLogReadOptions&,
                                 const OpeningProgress& progress) {
  DataFlashStream dataflash =
      OpenDataFlash(input.TakeMapped(), FillingSource::kDefaultChunkSamples, progress);
  FlightLogStream stream;
  stream.log = std::move(dataflash.log);
  stream.gyro = std::move(dataflash.samples);
  return stream;
}

FlightLogStream OpenBlackboxLog(TextBlocks input, const std::string&,
                                const FlightLogReadOptions& options,
                                const OpeningProgress& progress) {
  BlackboxStream blackbox = OpenBlackbox(input.TakeMapped(), options.log_index,
                                         FillingSource::kDefaultChunkSamples, progress);
  FlightLogStream stream;
  stream.log = std::move(blackbox.log);
  stream.gyro = std::move(blackbox.samples);
  return stream;
}

// Decoded whole: its gyro is ~200 Hz (an hour is 720,000 samples), and its sample tables may
// follow its samples (moov after mdat), so it needs a file to seek; handed on in slices.
FlightLogStream OpenGoproLog(TextBlocks, const std::string& path, const FlightLogReadOptions&,
                             const OpeningProgress&) {
  if (!std::filesystem::is_regular_file(path))
    throw IoError(IoMessage(path, 0, "a GoPro MP4 cannot be read from a pipe: save it to a file"));
  FlightLogStream stream;
  stream.log = ReadGoproFlightLog(path);
  stream.gyro = std::make_unique<TraceSource>(std::move(stream.log.gyro));
  stream.log.gyro = GyroTrace();
  return stream;
}

bool NeverRecognised(std::string_view) { return false; }

}  // namespace

namespace {

// Detection tries the kBytes readers in this order, then the kText ones, then the plain gyro
// logs' rules (DetectGyroFormat); messages list the formats in this order. Each entry: format,
// names, display name, detection, recogniser, opener, opening pass, camera events, fuzz target,
// reader's header (LogReader).
const LogReader kLogReaders[] = {
    {LogFormat::kULog,
     {"ulog", "ulg", "px4"},
     "ULog",
     LogDetection::kBytes,
     LooksLikeULog,
     OpenULogLog,
     true,
     true,
     "ulog",
     "sim/logs/ulog.h"},
    {LogFormat::kDataFlash,
     {"dataflash", "bin", "ardupilot"},
     "DataFlash",
     LogDetection::kBytes,
     LooksLikeDataFlash,
     OpenDataFlashLog,
     true,
     true,
     "dataflash",
     "sim/logs/dataflash.h"},
    {LogFormat::kBlackbox,
     {"blackbox", "betaflight", "bbl"},
     "blackbox",
     LogDetection::kBytes,
     LooksLikeBlackbox,
     OpenBlackboxLog,
     true,
     false,
     "blackbox",
     "sim/logs/blackbox.h"},
    {LogFormat::kGoproMp4,
     {"gopro", "mp4"},
     "GoPro MP4",
     LogDetection::kBytes,
     LooksLikeMp4,
     OpenGoproLog,
     false,
     false,
     "mp4",
     "sim/logs/gopro_telemetry.h"},
    {LogFormat::kGyroCsv,
     {"gyro.csv", "csv"},
     "gyro.csv",
     LogDetection::kPlainGyro,
     NeverRecognised,
     OpenGyroCsvLog,
     false,
     false,
     "gyro_csv",
     "sim/logs/gyro_io.h"},
    {LogFormat::kGcsv,
     {"gcsv"},
     ".gcsv",
     LogDetection::kPlainGyro,
     NeverRecognised,
     OpenGcsvLog,
     false,
     false,
     "gcsv",
     "sim/logs/gcsv.h"},
    {LogFormat::kRaw,
     {"raw"},
     "raw counts",
     LogDetection::kPlainGyro,
     NeverRecognised,
     OpenRawLog,
     false,
     false,
     "raw_csv",
     "sim/logs/raw_csv.h"},
    {LogFormat::kGyroDump,
     {"gyro_dump", "dump"},
     "a gyro dump",
     LogDetection::kText,
     LooksLikeGyroDump,
     OpenGyroDumpLog,
     false,
     false,
     "gyro_dump",
     "sim/logs/gyro_dump.h"},
    {LogFormat::kColumns,
     {"columns"},
     "columns",
     LogDetection::kNever,
     NeverRecognised,
     OpenColumnsLog,
     false,
     false,
     "column_csv",
     "sim/logs/column_csv.h"},
};

}  // namespace

const std::vector<LogReader>& LogReaders() {
  static const std::vector<LogReader> readers(std::begin(kLogReaders), std::end(kLogReaders));
  return readers;
}

const LogReader& ReaderOf(LogFormat format) {
  for (const LogReader& reader : LogReaders()) {
    if (reader.format == format) return reader;
  }
  SHUTTERLAB_CHECK(false) << "no reader for format " << static_cast<int>(format);
  return LogReaders().front();
}

const char* LogFormatName(LogFormat format) {
  return format == LogFormat::kAuto ? "auto" : ReaderOf(format).names[0];
}

std::vector<std::string> LogFormatNames() {
  std::vector<std::string> names = {"auto"};
  for (const LogReader& reader : LogReaders()) names.push_back(reader.names[0]);
  return names;
}

namespace {

// The format one of whose names is `lower`; nullopt when none is.
std::optional<LogFormat> FindFormat(const std::string& lower) {
  if (lower == "auto") return LogFormat::kAuto;
  for (const LogReader& reader : LogReaders()) {
    for (const char* name : reader.names) {
      if (name != nullptr && lower == name) return reader.format;
    }
  }
  return std::nullopt;
}

}  // namespace

LogFormat ParseLogFormat(const std::string& name) {
  const std::optional<LogFormat> format = FindFormat(ToLower(name));
  if (!format) {
    std::string names;
    for (const std::string& n : LogFormatNames()) names += (names.empty() ? "" : ", ") + n;
    SHUTTERLAB_CHECK(false) << "unknown log format '" << name << "' (" << names << ")";
  }
  return *format;
}

LogFormat ParseGyroFormat(const std::string& name) {
  const std::optional<LogFormat> format = FindFormat(ToLower(name));
  SHUTTERLAB_CHECK(format && (*format == LogFormat::kAuto || IsPlainGyroFormat(*format)))
      << "unknown gyro format '" << name << "' (auto, csv, gcsv, raw)";
  return *format;
}

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
  const LogReader& reader = ReaderOf(format);
  if (reader.opening_pass) {
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
    FlightLogStream stream = reader.open(std::move(input), path, options, progress);
    if (progress) progress(1.0);
    return stream;
  }
  // A format told by its magic bytes is what it says; one read from text content may be a file
  // of another kind, so its errors say what detection concluded.
  const bool detected_from_text = options.format == LogFormat::kAuto && !DetectedByBytes(reader);
  try {
    FlightLogStream stream = reader.open(std::move(input), path, options, {});
    if (detected_from_text)
      stream.gyro = std::make_unique<DetectedSource>(std::move(stream.gyro), format);
    return stream;
  } catch (const IoError& e) {
    if (!detected_from_text) throw;
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
