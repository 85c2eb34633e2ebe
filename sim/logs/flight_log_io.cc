#include "sim/logs/flight_log_io.h"

#include "sim/logs/blackbox.h"
#include "sim/check.h"
#include "sim/logs/dataflash.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "sim/logs/ulog.h"

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

GyroFormat ToGyroFormat(FlightLogFormat format) {
  switch (format) {
    case FlightLogFormat::kGyroCsv:
      return GyroFormat::kGyroCsv;
    case FlightLogFormat::kGcsv:
      return GyroFormat::kGcsv;
    case FlightLogFormat::kRaw:
      return GyroFormat::kRaw;
    default:
      return GyroFormat::kAuto;
  }
}

}  // namespace

void FlightLogReadOptions::Check() const {
  SHUTTERLAB_CHECK(log_index >= -1)
      << "log index must be -1 (longest) or >= 0 (got " << log_index << ")";
  GyroReadOptions gyro;
  gyro.raw_range_dps = raw_range_dps;
  gyro.raw_time_unit = raw_time_unit;
  gyro.Check();
}

FlightLogFormat DetectFlightLogFormat(std::string_view first_bytes, const std::string& path) {
  if (LooksLikeULog(first_bytes)) return FlightLogFormat::kULog;
  if (LooksLikeDataFlash(first_bytes)) return FlightLogFormat::kDataFlash;
  if (LooksLikeBlackbox(first_bytes)) return FlightLogFormat::kBlackbox;
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
    switch (DetectGyroFormat(text, path)) {
      case GyroFormat::kGcsv:
        return FlightLogFormat::kGcsv;
      case GyroFormat::kRaw:
        return FlightLogFormat::kRaw;
      default:
        return FlightLogFormat::kGyroCsv;
    }
  } catch (const IoError& e) {
    throw IoError(std::string(e.what()) +
                  " (unknown log format: not ULog, DataFlash, blackbox, gyro.csv, .gcsv or raw "
                  "counts)");
  }
}

FlightLog ReadFlightLog(const std::string& path, const FlightLogReadOptions& options) {
  options.Check();
  FlightLogFormat format = options.format;
  if (format == FlightLogFormat::kAuto) format = DetectFlightLogFormat(ReadPrefix(path), path);
  switch (format) {
    case FlightLogFormat::kULog:
      return ReadULog(path);
    case FlightLogFormat::kDataFlash:
      return ReadDataFlash(path);
    case FlightLogFormat::kBlackbox:
      return ReadBlackbox(path, options.log_index);
    default:
      break;
  }
  GyroReadOptions gyro_options;
  gyro_options.format = ToGyroFormat(format);
  gyro_options.raw_range_dps = options.raw_range_dps;
  gyro_options.raw_time_unit = options.raw_time_unit;
  FlightLog log;
  try {
    log.gyro = ReadGyro(path, gyro_options);
  } catch (const IoError& e) {
    if (options.format != FlightLogFormat::kAuto) throw;
    // Say what detection concluded, so that a file of an unknown kind is recognisable as such.
    throw IoError(std::string(e.what()) + " (read as " + GyroFormatName(gyro_options.format) +
                  ": not ULog, DataFlash or blackbox; --format chooses)");
  }
  log.format = GyroFormatName(gyro_options.format);
  log.gyro_source = format == FlightLogFormat::kGyroCsv ? "t,gx,gy,gz"
                    : format == FlightLogFormat::kGcsv  ? "gcsv"
                                                        : "raw counts";
  log.gyro_sources_available = {log.gyro_source};
  return log;
}

FlightLogFormat ParseFlightLogFormat(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "auto") return FlightLogFormat::kAuto;
  if (lower == "ulog" || lower == "ulg" || lower == "px4") return FlightLogFormat::kULog;
  if (lower == "dataflash" || lower == "bin" || lower == "ardupilot") {
    return FlightLogFormat::kDataFlash;
  }
  if (lower == "blackbox" || lower == "betaflight" || lower == "bbl") {
    return FlightLogFormat::kBlackbox;
  }
  if (lower == "gyro.csv" || lower == "csv") return FlightLogFormat::kGyroCsv;
  if (lower == "gcsv") return FlightLogFormat::kGcsv;
  if (lower == "raw") return FlightLogFormat::kRaw;
  SHUTTERLAB_CHECK(false) << "unknown log format '" << name
                          << "' (auto, ulog, dataflash, blackbox, gyro.csv, gcsv, raw)";
  return FlightLogFormat::kAuto;
}

const char* FlightLogFormatName(FlightLogFormat format) {
  switch (format) {
    case FlightLogFormat::kAuto:
      return "auto";
    case FlightLogFormat::kULog:
      return "ulog";
    case FlightLogFormat::kDataFlash:
      return "dataflash";
    case FlightLogFormat::kBlackbox:
      return "blackbox";
    case FlightLogFormat::kGyroCsv:
      return "gyro.csv";
    case FlightLogFormat::kGcsv:
      return "gcsv";
    case FlightLogFormat::kRaw:
      return "raw";
  }
  return "?";
}

}  // namespace shutterlab
