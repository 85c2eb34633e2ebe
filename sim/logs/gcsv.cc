#include "sim/logs/gcsv.h"

#include "sim/check.h"
#include "sim/text_file.h"

#include <cmath>
#include <string_view>

namespace shutterlab {
namespace {

// The exact time unit a tscale names, if it is one of 1, 1e-3, 1e-6, 1e-9 (these parse to the same
// doubles as the literals below, so == is the right test).
std::optional<TimeUnit> ExactUnit(double tscale) {
  if (tscale == 1.0) return TimeUnit::kSeconds;
  if (tscale == 1e-3) return TimeUnit::kMilliseconds;
  if (tscale == 1e-6) return TimeUnit::kMicroseconds;
  if (tscale == 1e-9) return TimeUnit::kNanoseconds;
  return std::nullopt;
}

const char* TscaleText(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::kSeconds:
      return "1";
    case TimeUnit::kMilliseconds:
      return "0.001";
    case TimeUnit::kMicroseconds:
      return "0.000001";
    case TimeUnit::kNanoseconds:
      return "0.000000001";
  }
  return "1";
}

// Gyroflow's frame_readout_direction codes and names (telemetry-parser src/gyroflow/gcsv.rs).
std::optional<ReadoutDirection> GyroflowReadoutDirection(const std::string& value) {
  if (value == "0" || value == "TopToBottom") return ReadoutDirection::kTopToBottom;
  if (value == "1" || value == "180" || value == "BottomToTop")
    return ReadoutDirection::kBottomToTop;
  if (value == "2" || value == "270" || value == "LeftToRight")
    return ReadoutDirection::kLeftToRight;
  if (value == "3" || value == "90" || value == "RightToLeft")
    return ReadoutDirection::kRightToLeft;
  return std::nullopt;
}

int GyroflowReadoutCode(ReadoutDirection direction) {
  switch (direction) {
    case ReadoutDirection::kTopToBottom:
      return 0;
    case ReadoutDirection::kBottomToTop:
      return 1;
    case ReadoutDirection::kLeftToRight:
      return 2;
    case ReadoutDirection::kRightToLeft:
      return 3;
  }
  return 0;
}

// Value of a "key,value" line: everything after the first comma, trimmed (a note may hold commas).
std::string ValueAfterKey(std::string_view line) {
  const size_t comma = line.find(',');
  std::string_view value =
      comma == std::string_view::npos ? std::string_view() : line.substr(comma + 1);
  while (!value.empty() && (value.front() == ' ' || value.front() == '\t')) value.remove_prefix(1);
  while (!value.empty() && (value.back() == ' ' || value.back() == '\t')) value.remove_suffix(1);
  return std::string(value);
}

bool IsReservedKey(const std::string& key) {
  static const char* const kReserved[] = {"version",
                                          "id",
                                          "orientation",
                                          "tscale",
                                          "gscale",
                                          "frame_readout_time",
                                          "frame_readout_direction",
                                          "t",
                                          "time"};
  for (const char* reserved : kReserved) {
    if (ToLower(key) == reserved) return true;
  }
  return false;
}

}  // namespace

Eigen::Matrix3d GcsvOrientationMatrix(const std::string& orientation) {
  SHUTTERLAB_CHECK(orientation.size() == 3)
      << "orientation '" << orientation << "' must be three letters of xXyYzZ, e.g. XYZ or yXz";
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  bool used[3] = {false, false, false};
  for (int out = 0; out < 3; ++out) {
    const char c = orientation[out];
    const char lower = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    SHUTTERLAB_CHECK(lower == 'x' || lower == 'y' || lower == 'z')
        << "orientation '" << orientation << "' must be three letters of xXyYzZ, e.g. XYZ or yXz";
    const int in = lower - 'x';
    SHUTTERLAB_CHECK(!used[in]) << "orientation '" << orientation << "' names an axis twice";
    used[in] = true;
    m(out, in) = c == lower ? -1.0 : 1.0;  // lowercase: negated
  }
  return m;
}

namespace {

// What the header lines before the column line say (line numbers 0 when absent).
struct GcsvHeader {
  std::optional<double> tscale, gscale, readout_ms;
  long orientation_line = 0, readout_line = 0;
  std::string orientation;
  long column_line = 0;
  std::vector<std::string> columns;  // the column line's fields
};

// The first line names the format.
void CheckFirstLine(const std::string& path, LineReader* cursor) {
  const auto first = cursor->Next();
  std::vector<std::string_view> fields;
  if (first) SplitFields(StripBom(*first), '\x01', &fields);  // no split: just trim
  if (!first || (fields[0] != "GYROFLOW IMU LOG" && fields[0] != "CAMERA IMU LOG")) {
    throw IoError(IoMessage(path, 1, "missing first line 'GYROFLOW IMU LOG' (not a .gcsv)"));
  }
}

// A logger's own dropout, "gap,T_S,LOST,KIND" (shutterlab record writes one per gap): a `gap`
// warning with its time and count; a line that does not parse is a `format` warning (a header key
// the reader does not need never makes a file unreadable).
LogWarning GapLineWarning(long n, const std::vector<std::string_view>& fields) {
  const auto t_s = fields.size() >= 3 ? ParseDouble(fields[1]) : std::nullopt;
  const auto lost = fields.size() >= 3 ? ParseInt(fields[2]) : std::nullopt;
  if (!t_s || !lost || *lost < 0) {
    return {"format", "line " + std::to_string(n) + ": gap line is not 'gap,T_S,LOST[,KIND]'",
            std::nullopt, std::nullopt};
  }
  const std::string kind = fields.size() >= 4 ? std::string(fields[3]) : "gap";
  LogWarning w{"gap",
               "the logger recorded a " + kind + " at " + FormatNumber("%.6f", *t_s) +
                   " s: " + std::to_string(*lost) + " sample(s) lost (header line " +
                   std::to_string(n) + ")",
               *t_s, static_cast<size_t>(*lost)};
  return w;
}

// One 'key,value' header line (line n): kept in log->header, and the keys the reader uses checked
// into *header (frame_readout_direction straight into the log).
void ReadHeaderLine(const std::string& path, long n, std::string_view line,
                    const std::vector<std::string_view>& fields, GcsvHeader* header, GcsvLog* log) {
  if (fields.size() < 2) {
    throw IoError(
        IoMessage(path, n, "header line is not 'key,value': '" + std::string(line) + "'"));
  }
  const std::string key = ToLower(fields[0]);
  const std::string value = ValueAfterKey(line);
  log->header.emplace_back(std::string(fields[0]), value);
  auto positive = [&](const char* name) {
    const auto v = ParseDouble(value);
    if (!v || !(*v > 0.0)) {
      throw IoError(IoMessage(
          path, n, std::string(name) + " must be a positive number, found '" + value + "'"));
    }
    return *v;
  };
  if (key == "tscale") {
    header->tscale = positive("tscale");
  } else if (key == "gscale") {
    header->gscale = positive("gscale");
  } else if (key == "orientation") {
    header->orientation = value;
    header->orientation_line = n;
  } else if (key == "frame_readout_time") {
    header->readout_ms = ParseDouble(value);
    if (!header->readout_ms) {
      throw IoError(
          IoMessage(path, n, "frame_readout_time is not a finite number: '" + value + "'"));
    }
    header->readout_line = n;
  } else if (key == "gap") {
    log->warnings.push_back(GapLineWarning(n, fields));
  } else if (key == "recording" && value.rfind("unfinished", 0) == 0) {
    // shutterlab record's file of a recording that was killed or lost power (record_output.h).
    log->warnings.push_back({"truncated", "the recording did not finish (header line " +
                                              std::to_string(n) + ": " + value +
                                              "); its rows end where the file does"});
  } else if (key == "frame_readout_direction") {
    const auto direction = GyroflowReadoutDirection(value);
    if (!direction) {
      throw IoError(IoMessage(path, n,
                              "unknown frame_readout_direction '" + value +
                                  "' (0-3, TopToBottom, BottomToTop, LeftToRight, RightToLeft)"));
    }
    log->frame_readout_direction = *direction;
  }
}

// The header lines up to and including the column line ('t,...' or 'time,...'), which must come.
GcsvHeader ReadHeader(const std::string& path, LineReader* cursor, GcsvLog* log) {
  GcsvHeader header;
  std::vector<std::string_view> fields;
  while (auto line = cursor->Next()) {
    const long n = cursor->line_number();
    SplitFields(*line, ',', &fields);
    if (fields.size() == 1 && fields[0].empty()) continue;
    const std::string key = ToLower(fields[0]);
    if (key == "t" || key == "time") {
      header.column_line = n;
      header.columns.assign(fields.begin(), fields.end());
      break;
    }
    ReadHeaderLine(path, n, *line, fields, &header, log);
  }
  if (header.column_line == 0) {
    throw IoError(IoMessage(path, cursor->line_number(),
                            "header ends before the column line 't,gx,gy,gz' (truncated file?)"));
  }
  return header;
}

// The header's scales, orientation and readout into the log, checked; returns the orientation's
// matrix from the file's axes to the output's.
Eigen::Matrix3d ApplyHeader(const std::string& path, GcsvHeader* header, GcsvLog* log) {
  const long column_line = header->column_line;
  if (!header->tscale) {
    throw IoError(IoMessage(path, column_line, "no tscale line before the column line"));
  }
  if (!header->gscale) {
    throw IoError(IoMessage(path, column_line, "no gscale line before the column line"));
  }
  log->tscale = *header->tscale;
  log->gscale = *header->gscale;
  if (header->orientation_line == 0) {
    header->orientation = "xzY";
    log->warnings.push_back(
        {"assumption", "no orientation line: assumed 'xzY', as Gyroflow's parser does", {}, {}});
  }
  Eigen::Matrix3d to_out;
  try {
    to_out = GcsvOrientationMatrix(header->orientation);
  } catch (const std::invalid_argument&) {
    throw IoError(IoMessage(path, header->orientation_line,
                            "orientation '" + header->orientation +
                                "' is not three letters of xXyYzZ naming each axis once"));
  }
  log->orientation = header->orientation;
  if (header->readout_ms) {
    // Gyroflow's legacy files encode bottom-to-top as a negative readout time.
    if (*header->readout_ms < 0) {
      log->frame_readout_direction = log->frame_readout_direction == ReadoutDirection::kBottomToTop
                                         ? ReadoutDirection::kTopToBottom
                                         : ReadoutDirection::kBottomToTop;
      log->warnings.push_back({"format",
                               "negative frame_readout_time on line " +
                                   std::to_string(header->readout_line) +
                                   ": read as the opposite readout direction",
                               {},
                               {}});
    }
    log->frame_readout_s = std::abs(*header->readout_ms) * 1e-3;
  }
  const std::vector<std::string>& columns = header->columns;
  if (columns.size() < 4 || ToLower(columns[1]) != "gx" || ToLower(columns[2]) != "gy" ||
      ToLower(columns[3]) != "gz") {
    throw IoError(IoMessage(path, column_line, "column line must start with t,gx,gy,gz"));
  }
  return to_out;
}

// One sample line (line n, already split into as many fields as columns): t scaled by tscale
// (exactly when tscale is a unit), the rates by gscale and turned into the output axes.
GyroSample ParseSample(const std::string& path, long n, const std::vector<std::string_view>& fields,
                       const GcsvHeader& header, const std::optional<TimeUnit>& exact_unit,
                       const Eigen::Matrix3d& to_out) {
  const double tscale = *header.tscale, gscale = *header.gscale;
  GyroSample s;
  std::optional<int64_t> t_ns;
  if (exact_unit) {
    t_ns = ParseTimeInUnitNs(fields[0], *exact_unit);
  } else if (const auto t = ParseDouble(fields[0]); t && std::abs(*t * tscale) < 9.2e9) {
    t_ns = SecondsToNs(*t * tscale);
  }
  if (!t_ns) {
    throw IoError(
        IoMessage(path, n, "t is not a finite number in range: '" + std::string(fields[0]) + "'"));
  }
  s.t_ns = *t_ns;
  Eigen::Vector3d in;
  for (int axis = 0; axis < 3; ++axis) {
    const auto value = ParseDouble(fields[axis + 1]);
    if (!value || !std::isfinite(*value * gscale)) {
      throw IoError(IoMessage(path, n,
                              std::string("g") + "xyz"[axis] + " is not a finite number: '" +
                                  std::string(fields[axis + 1]) + "'"));
    }
    in[axis] = *value * gscale;
  }
  s.omega_rad_s = to_out * in;
  return s;
}

// The sample lines after the column line, in non-decreasing time (at least one), a block at a
// time.
class GcsvSource : public FillingSource {
 public:
  GcsvSource(LineReader lines, const std::string& path, GcsvHeader header,
             const Eigen::Matrix3d& to_out, size_t chunk_samples)
      : FillingSource(chunk_samples),
        lines_(std::move(lines)),
        path_(path),
        header_(std::move(header)),
        to_out_(to_out),
        exact_unit_(ExactUnit(*header_.tscale)) {}

  double Fraction() const override { return lines_.Fraction(); }

 private:
  void Fill(std::vector<GyroSample>* chunk) override {
    ReserveChunk(chunk, lines_.size_bytes());
    while (chunk->size() < chunk_samples()) {
      const auto line = lines_.Next();
      if (!line) break;
      const long n = lines_.line_number();
      if (line->empty()) continue;
      try {
        chunk->push_back(ReadRow(*line, n));
      } catch (const IoError&) {
        if (!lines_.unterminated()) throw;
        LeaveOutCutLastLine(n);
      }
    }
    if (chunk->empty() && !last_t_ns())
      throw IoError(IoMessage(path_, 0, "no samples after the column line"));
  }

  // The sample of line n, after the one before.
  GyroSample ReadRow(std::string_view line, long n) {
    SplitFields(line, ',', &fields_);
    if (fields_.size() != header_.columns.size()) {
      throw IoError(IoMessage(path_, n,
                              "expected " + std::to_string(header_.columns.size()) +
                                  " columns as on line " + std::to_string(header_.column_line) +
                                  ", found " + std::to_string(fields_.size())));
    }
    const GyroSample s = ParseSample(path_, n, fields_, header_, exact_unit_, to_out_);
    TakeTimeInOrder(path_, n, s.t_ns, fields_[0]);
    return s;
  }
  LineReader lines_;
  std::string path_;
  GcsvHeader header_;
  Eigen::Matrix3d to_out_;
  std::optional<TimeUnit> exact_unit_;
  std::vector<std::string_view> fields_;
};

}  // namespace

GcsvStream OpenGcsv(TextBlocks blocks, const std::string& path, size_t chunk_samples) {
  LineReader lines(std::move(blocks));
  CheckFirstLine(path, &lines);
  GcsvStream stream;
  GcsvHeader header = ReadHeader(path, &lines, &stream.log);
  const Eigen::Matrix3d to_out = ApplyHeader(path, &header, &stream.log);
  stream.samples = std::make_unique<GcsvSource>(std::move(lines), path, std::move(header), to_out,
                                                chunk_samples);
  return stream;
}

GcsvLog ReadGcsv(const std::string& path) {
  GcsvStream stream = OpenGcsv(TextBlocks::OfFile(path), path);
  stream.log.trace = ReadAllSamples(stream.samples.get());
  for (LogWarning& w : stream.samples->Warnings()) stream.log.warnings.push_back(std::move(w));
  return std::move(stream.log);
}

void GcsvWriteOptions::Check() const {
  GcsvOrientationMatrix(orientation);
  SHUTTERLAB_CHECK(std::isfinite(gscale) && gscale >= 0.0) << "gscale must be >= 0, got " << gscale;
  SHUTTERLAB_CHECK(!frame_readout_s || (std::isfinite(*frame_readout_s) && *frame_readout_s > 0.0))
      << "frame_readout_s must be positive";
  SHUTTERLAB_CHECK(id.find_first_of(",\r\n") == std::string::npos)
      << "id must not hold ',' or a newline";
  for (const auto& [key, value] : extra_header) {
    SHUTTERLAB_CHECK(!key.empty() && key.find_first_of(",\r\n") == std::string::npos)
        << "header key '" << key << "' must be non-empty without ',' or newlines";
    SHUTTERLAB_CHECK(!IsReservedKey(key))
        << "header key '" << key << "' is written by WriteGcsv itself";
    SHUTTERLAB_CHECK(value.find_first_of("\r\n") == std::string::npos)
        << "header value of '" << key << "' must not hold a newline";
  }
}

std::string GcsvHeaderText(const GcsvWriteOptions& options) {
  options.Check();
  std::string out = "GYROFLOW IMU LOG\nversion,1.3\nid," + options.id + "\norientation," +
                    options.orientation + "\n";
  for (const auto& [key, value] : options.extra_header) out += key + "," + value + "\n";
  if (options.frame_readout_s) {
    out += "frame_readout_time,";
    AppendDouble(*options.frame_readout_s * 1e3, &out);
    out += "\nframe_readout_direction," +
           std::to_string(GyroflowReadoutCode(options.frame_readout_direction)) + "\n";
  }
  out += std::string("tscale,") + TscaleText(options.time_unit) + "\ngscale,";
  AppendDouble(options.gscale > 0 ? options.gscale : 1.0, &out);
  out += "\nt,gx,gy,gz\n";
  return out;
}

void WriteGcsv(const std::string& path, const GyroTrace& trace, const GcsvWriteOptions& options) {
  std::string out = GcsvHeaderText(options);
  // The reader applies M (out = M * in); M is a signed permutation, so its inverse is M^T.
  const Eigen::Matrix3d in_from_out = GcsvOrientationMatrix(options.orientation).transpose();
  out.reserve(out.size() + trace.size() * 72);
  for (const GyroSample& s : trace.samples()) {
    AppendTimeInUnit(s.t_ns, options.time_unit, &out);
    const Eigen::Vector3d in = in_from_out * s.omega_rad_s;
    for (int axis = 0; axis < 3; ++axis) {
      out += ',';
      if (options.gscale > 0) {
        const double count = std::round(in[axis] / options.gscale);
        SHUTTERLAB_CHECK(std::abs(count) < 9e15)
            << "rate " << in[axis] << " rad/s is too large for gscale " << options.gscale;
        out += std::to_string(static_cast<int64_t>(count));
      } else {
        AppendDouble(in[axis], &out);
      }
    }
    out += '\n';
  }
  WriteFileAtomically(path, out);
}

}  // namespace shutterlab
