#include "sim/logs/flight_log_io.h"

#include "sim/check.h"
#include "sim/logs/blackbox.h"
#include "sim/logs/dataflash.h"
#include "sim/logs/gcsv.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/ulog.h"
#include "sim/text_file.h"
#include "sim/trace_audit.h"
#include "sim/units.h"

#include <algorithm>
#include <fstream>
#include <utility>

namespace shutterlab {
namespace {

// Enough for every magic and for a blackbox / CSV header line.
constexpr size_t kDetectBytes = 16 * 1024;

std::string ReadPrefix(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(IoMessage(path, 0, "cannot open file"));
  std::string bytes(kDetectBytes, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<size_t>(in.gcount()));
  return bytes;
}

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
  // A binary file is none of the text formats; say so instead of quoting line 1 of garbage.
  const size_t probe = std::min<size_t>(first_bytes.size(), 512);
  for (size_t i = 0; i < probe; ++i) {
    if (first_bytes[i] == '\0') {
      throw IoError(IoMessage(path, 0,
                              "unknown log format: not ULog, DataFlash, blackbox, gyro.csv, .gcsv "
                              "or raw counts (binary content)"));
    }
  }
  // The prefix may end mid-line; drop the partial last line so that it cannot mislead detection.
  std::string_view text = first_bytes;
  if (first_bytes.size() == kDetectBytes) {
    const size_t last_newline = text.rfind('\n');
    if (last_newline != std::string_view::npos) text = text.substr(0, last_newline + 1);
  }
  try {
    return DetectGyroFormat(text, path);  // kGyroCsv, kGcsv or kRaw
  } catch (const IoError& e) {
    throw IoError(std::string(e.what()) +
                  " (unknown log format: not ULog, DataFlash, blackbox, gyro.csv, .gcsv or raw "
                  "counts)");
  }
}

namespace {

FlightLog ReadColumns(const std::string& path, const ColumnCsvOptions& options) {
  ColumnCsvLog columns = ReadColumnCsv(path, options);
  FlightLog log;
  log.gyro = std::move(columns.trace);
  log.format = LogFormatName(LogFormat::kColumns);
  log.gyro_source = std::move(columns.source);
  log.gyro_sources_available = {log.gyro_source};
  return log;
}

FlightLog ReadDetected(const std::string& path, LogFormat format,
                       const FlightLogReadOptions& options) {
  switch (format) {
    case LogFormat::kULog:
      return ReadULog(path);
    case LogFormat::kDataFlash:
      return ReadDataFlash(path);
    case LogFormat::kBlackbox:
      return ReadBlackbox(path, options.log_index);
    case LogFormat::kColumns:
      return ReadColumns(path, options.columns);
    default:
      break;
  }
  GyroReadOptions gyro_options;
  gyro_options.format = format;
  gyro_options.raw = options.raw;
  FlightLog log;
  try {
    if (format == LogFormat::kGcsv) {
      GcsvLog gcsv = ReadGcsv(path);  // its header's assumptions become warnings too
      log.gyro = std::move(gcsv.trace);
      log.warnings = std::move(gcsv.warnings);
    } else {
      log.gyro = ReadGyro(path, gyro_options);
    }
  } catch (const IoError& e) {
    if (options.format != LogFormat::kAuto) throw;
    // Say what detection concluded, so that a file of an unknown kind is recognisable as such.
    throw IoError(std::string(e.what()) + " (read as " + LogFormatName(gyro_options.format) +
                  ": not ULog, DataFlash or blackbox; --format chooses)");
  }
  log.format = LogFormatName(gyro_options.format);
  log.gyro_source = format == LogFormat::kGyroCsv ? "t,gx,gy,gz"
                    : format == LogFormat::kGcsv  ? "gcsv"
                                                  : "raw counts";
  log.gyro_sources_available = {log.gyro_source};
  return log;
}

}  // namespace

FlightLog ReadFlightLog(const std::string& path, const FlightLogReadOptions& options) {
  options.Check();
  LogFormat format = options.format;
  if (format == LogFormat::kAuto) format = DetectFlightLogFormat(ReadPrefix(path), path);
  FlightLog log = ReadDetected(path, format, options);
  TraceAuditOptions audit;
  if (format == LogFormat::kRaw) audit.full_scale_rad_s = options.raw.range_dps * kRadPerDeg;
  for (LogWarning& warning : AuditTrace(log.gyro, audit))
    log.warnings.push_back(std::move(warning));
  return log;
}

}  // namespace shutterlab
