#include "sim/gyro_io.h"

#include "sim/check.h"
#include "sim/text_file.h"

namespace shutterlab {
namespace {

// Reads the numeric rows of a CSV whose first three columns after `t` are rates; `first_line`
// is the cursor already past the header.
GyroTrace ReadRows(const std::string& path, LineCursor* cursor, double time_scale_to_s,
                   double rate_scale_to_rad_s) {
  std::vector<GyroSample> samples;
  std::vector<std::string_view> fields;
  int64_t previous_t_ns = 0;
  while (auto line = cursor->Next()) {
    if (line->empty()) continue;
    SplitFields(*line, ',', &fields);
    const long n = cursor->line_number();
    if (fields.size() < 4) {
      throw IoError(IoMessage(path, n, "expected 4 columns t,gx,gy,gz, found " +
                                           std::to_string(fields.size())));
    }
    GyroSample s;
    const auto t = ParseDouble(fields[0]);
    if (!t) throw IoError(IoMessage(path, n, "t is not a finite number: '" + std::string(fields[0]) + "'"));
    for (int axis = 0; axis < 3; ++axis) {
      const auto value = ParseDouble(fields[axis + 1]);
      if (!value) {
        throw IoError(IoMessage(path, n, std::string("g") + "xyz"[axis] +
                                             " is not a finite number: '" +
                                             std::string(fields[axis + 1]) + "'"));
      }
      s.omega_rad_s[axis] = *value * rate_scale_to_rad_s;
    }
    const double t_s = *t * time_scale_to_s;
    if (!(std::abs(t_s) < 9.2e9)) throw IoError(IoMessage(path, n, "t out of range"));
    s.t_ns = SecondsToNs(t_s);
    if (!samples.empty() && s.t_ns < previous_t_ns) {
      throw IoError(IoMessage(path, n, "timestamp decreases (" + std::string(fields[0]) +
                                           " after an earlier, larger one)"));
    }
    previous_t_ns = s.t_ns;
    samples.push_back(s);
  }
  if (samples.empty()) throw IoError(IoMessage(path, 0, "no samples"));
  return GyroTrace(std::move(samples));
}

}  // namespace

void GyroReadOptions::Check() const {
  SHUTTERLAB_CHECK(raw_range_dps == 250 || raw_range_dps == 500 || raw_range_dps == 1000 ||
                   raw_range_dps == 2000)
      << "unknown gyro range " << raw_range_dps << " deg/s (expected 250, 500, 1000 or 2000)";
}

GyroTrace ReadGyroCsv(const std::string& path) {
  const std::string text = ReadFileToString(path);
  LineCursor cursor(text);
  const auto header = cursor.Next();
  std::vector<std::string_view> fields;
  if (header) SplitFields(*header, ',', &fields);
  if (!header || fields.size() < 4 || ToLower(fields[0]) != "t" || ToLower(fields[1]) != "gx" ||
      ToLower(fields[2]) != "gy" || ToLower(fields[3]) != "gz") {
    throw IoError(IoMessage(path, 1, "missing header 't,gx,gy,gz'"));
  }
  return ReadRows(path, &cursor, 1.0, 1.0);
}

void WriteGyroCsv(const std::string& path, const GyroTrace& trace) {
  std::string out = "t,gx,gy,gz\n";
  out.reserve(trace.size() * 64 + 16);
  for (const GyroSample& s : trace.samples()) {
    AppendSecondsFromNs(s.t_ns, &out);
    for (int axis = 0; axis < 3; ++axis) {
      out += ',';
      AppendDouble(s.omega_rad_s[axis], &out);
    }
    out += '\n';
  }
  WriteFileAtomically(path, out);
}

GyroTrace ReadGyro(const std::string& path, const GyroReadOptions& options) {
  options.Check();
  switch (options.format) {
    case GyroFormat::kAuto:
    case GyroFormat::kGyroCsv:
      return ReadGyroCsv(path);
    case GyroFormat::kRaw:
      return ReadRawCsv(path, options.raw_range_dps, options.raw_time_unit);
    default:
      throw IoError(IoMessage(path, 0, std::string("format not supported yet: ") +
                                           GyroFormatName(options.format)));
  }
}

GyroFormat ParseGyroFormat(const std::string& name) {
  const std::string n = ToLower(name);
  if (n == "auto") return GyroFormat::kAuto;
  if (n == "gyro.csv" || n == "csv") return GyroFormat::kGyroCsv;
  if (n == "gcsv") return GyroFormat::kGcsv;
  if (n == "raw") return GyroFormat::kRaw;
  SHUTTERLAB_CHECK(false) << "unknown gyro format '" << name << "' (auto, csv, gcsv, raw)";
  return GyroFormat::kAuto;
}

TimeUnit ParseTimeUnit(const std::string& name) {
  if (name == "s") return TimeUnit::kSeconds;
  if (name == "ms") return TimeUnit::kMilliseconds;
  if (name == "us") return TimeUnit::kMicroseconds;
  if (name == "ns") return TimeUnit::kNanoseconds;
  SHUTTERLAB_CHECK(false) << "unknown time unit '" << name << "' (s, ms, us, ns)";
  return TimeUnit::kSeconds;
}

const char* GyroFormatName(GyroFormat format) {
  switch (format) {
    case GyroFormat::kAuto: return "auto";
    case GyroFormat::kGyroCsv: return "gyro.csv";
    case GyroFormat::kGcsv: return "gcsv";
    case GyroFormat::kRaw: return "raw";
  }
  return "?";
}

}  // namespace shutterlab
