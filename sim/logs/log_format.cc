#include "sim/logs/log_format.h"

#include "sim/check.h"
#include "sim/text_file.h"

namespace shutterlab {
namespace {

// Every format with its names; the first is the one LogFormatName gives.
struct FormatNames {
  LogFormat format;
  const char* names[3];
};
constexpr FormatNames kFormatNames[] = {
    {LogFormat::kAuto, {"auto"}},
    {LogFormat::kGyroCsv, {"gyro.csv", "csv"}},
    {LogFormat::kGcsv, {"gcsv"}},
    {LogFormat::kRaw, {"raw"}},
    {LogFormat::kULog, {"ulog", "ulg", "px4"}},
    {LogFormat::kBlackbox, {"blackbox", "betaflight", "bbl"}},
    {LogFormat::kDataFlash, {"dataflash", "bin", "ardupilot"}},
    {LogFormat::kGoproMp4, {"gopro", "mp4"}},
    {LogFormat::kGyroDump, {"gyro_dump", "dump"}},
    {LogFormat::kColumns, {"columns"}},
};

// The format one of whose names is `lower`; kAuto with *found false when none is.
LogFormat FindFormat(const std::string& lower, bool* found) {
  for (const FormatNames& entry : kFormatNames) {
    for (const char* name : entry.names) {
      if (name != nullptr && lower == name) {
        *found = true;
        return entry.format;
      }
    }
  }
  *found = false;
  return LogFormat::kAuto;
}

}  // namespace

bool IsPlainGyroFormat(LogFormat format) {
  return format == LogFormat::kGyroCsv || format == LogFormat::kGcsv || format == LogFormat::kRaw;
}

const char* LogFormatName(LogFormat format) {
  for (const FormatNames& entry : kFormatNames) {
    if (entry.format == format) return entry.names[0];
  }
  return "?";
}

LogFormat ParseLogFormat(const std::string& name) {
  bool found = false;
  const LogFormat format = FindFormat(ToLower(name), &found);
  SHUTTERLAB_CHECK(found)
      << "unknown log format '" << name
      << "' (auto, ulog, dataflash, blackbox, gopro, gyro.csv, gcsv, raw, gyro_dump, columns)";
  return format;
}

LogFormat ParseGyroFormat(const std::string& name) {
  bool found = false;
  const LogFormat format = FindFormat(ToLower(name), &found);
  SHUTTERLAB_CHECK(found && (format == LogFormat::kAuto || IsPlainGyroFormat(format)))
      << "unknown gyro format '" << name << "' (auto, csv, gcsv, raw)";
  return format;
}

void RawCountOptions::Check() const {
  SHUTTERLAB_CHECK(range_dps == 250 || range_dps == 500 || range_dps == 1000 || range_dps == 2000)
      << "unknown gyro range " << range_dps << " deg/s (expected 250, 500, 1000 or 2000)";
}

}  // namespace shutterlab
