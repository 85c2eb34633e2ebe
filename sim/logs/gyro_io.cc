#include "sim/logs/gyro_io.h"

#include "sim/check.h"
#include "sim/logs/gyro_row_shapes.h"
#include "sim/text_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

namespace shutterlab {
namespace {

bool IsGyroCsvHeader(const std::vector<std::string_view>& fields) {
  return fields.size() >= 4 && ToLower(fields[0]) == "t" && ToLower(fields[1]) == "gx" &&
         ToLower(fields[2]) == "gy" && ToLower(fields[3]) == "gz";
}

// Parses one ordinary row "t,gx,gy,gz[,...]\n" at p in a single pass: t a plain decimal of at
// most 10 whole digits (at most 9e9 s, so that t_ns fits int64) and 9 fraction digits, rates plain
// decimals (PlainDecimalBeforeLineEnd), no spaces. The caller guarantees a '\n' at or after p
// before end, which ends every digit run, so that no byte position is compared with end. Returns
// the position after the row's '\n', or nullptr for anything else, which the caller then re-reads
// field by field for the general case and its exact error message. This path is what makes a
// 30-million-line log read at GB/s: no per-line memchr, no field vector, no bounds checks.
const char* ParseRowFast(const char* p, const char* end, GyroSample* s) {
  static constexpr int64_t kNsPerDigit[] = {1000000000, 100000000, 10000000, 1000000, 100000,
                                            10000,      1000,      100,      10,      1};
  uint64_t whole = 0;
  const char* digits = p;
  while (IsDecimalDigit(*p)) whole = whole * 10 + (*p++ - '0');
  if (p == digits || p - digits > 10 || whole > 9'000'000'000) return nullptr;
  uint64_t fraction = 0;
  size_t places = 0;
  if (*p == '.') {
    const char* first = ++p;
    while (IsDecimalDigit(*p)) fraction = fraction * 10 + (*p++ - '0');
    places = static_cast<size_t>(p - first);
    if (places > 9) return nullptr;
  }
  if (*p != ',') return nullptr;
  s->t_ns = static_cast<int64_t>(whole) * 1000000000 +
            static_cast<int64_t>(fraction) * kNsPerDigit[places];
  for (int axis = 0; axis < 3; ++axis) {
    ++p;  // the ',' before this field
    const char* next = PlainDecimalBeforeLineEnd(p, &s->omega_rad_s[axis]);
    if (!next) return nullptr;
    p = next;
    if (axis < 2 && *p != ',') return nullptr;
  }
  if (*p == ',') {  // extra columns: ignored
    p = static_cast<const char*>(std::memchr(p, '\n', end - p));
    return p + 1;
  }
  if (*p == '\r') ++p;  // a CRLF line end; a '\r' anywhere else is the general path's to refuse
  return *p == '\n' ? p + 1 : nullptr;
}

// Reads the general form of one row (spaces, '+', exponents in t, ...) or throws the error that
// names what is wrong with it.
GyroSample ParseRowGeneral(const std::string& path, long n, std::string_view line,
                           std::vector<std::string_view>* fields) {
  SplitFields(line, ',', fields);
  if (fields->size() < 4) {
    throw IoError(IoMessage(
        path, n, "expected 4 columns t,gx,gy,gz, found " + std::to_string(fields->size())));
  }
  GyroSample s;
  // Exact for plain decimals (9 digits of seconds keep every ns at any epoch).
  const auto t_ns = ParseTimeInUnitNs((*fields)[0], TimeUnit::kSeconds);
  if (!t_ns) {
    throw IoError(IoMessage(
        path, n, "t is not a finite number in range: '" + std::string((*fields)[0]) + "'"));
  }
  s.t_ns = *t_ns;
  for (int axis = 0; axis < 3; ++axis) {
    const auto value = ParseDouble((*fields)[axis + 1]);
    if (!value) {
      throw IoError(IoMessage(path, n,
                              std::string("g") + "xyz"[axis] + " is not a finite number: '" +
                                  std::string((*fields)[axis + 1]) + "'"));
    }
    s.omega_rad_s[axis] = *value;
  }
  return s;
}

// gyro.csv read block by block: the header at once, then chunks of rows (t in seconds, then gx,
// gy, gz in rad/s).
class GyroCsvSource : public FillingSource {
 public:
  GyroCsvSource(TextBlocks blocks, const std::string& path, size_t chunk_samples, GyroCsvRows rows)
      : FillingSource(chunk_samples), blocks_(std::move(blocks)), path_(path) {
    if (rows == GyroCsvRows::kByteLoop) shapes_.Disable();
    rest_ = blocks_.Next();
    const size_t header_end = std::min(rest_.find('\n'), rest_.size());
    std::string_view header = rest_.substr(0, header_end);
    if (!header.empty() && header.back() == '\r') header.remove_suffix(1);
    std::vector<std::string_view> fields;
    SplitFields(StripBom(header), ',', &fields);
    if (rest_.empty() || !IsGyroCsvHeader(fields)) {
      throw IoError(IoMessage(path, 1, "missing header 't,gx,gy,gz'"));
    }
    rest_.remove_prefix(std::min(rest_.size(), header_end + 1));
  }

  double Fraction() const override { return blocks_.Fraction(); }

 private:
  void Fill(std::vector<GyroSample>* chunk) override {
    ReserveChunk(chunk, blocks_.size_bytes());
    while (chunk->size() < chunk_samples()) {
      if (rest_.empty() && (rest_ = blocks_.Next()).empty()) break;
      ParseRows(chunk);
    }
    if (chunk->empty() && !any_) throw IoError(IoMessage(path_, 0, "no samples"));
  }

  // Rows from rest_ (whole lines) into chunk until it is full or rest_ is used up. The rows before
  // the last line break take the fast path; the input's last line when it has no line break, and
  // any row the fast path does not take, the general one.
  void ParseRows(std::vector<GyroSample>* chunk) {
    const char* p = rest_.data();
    const char* const end = p + rest_.size();
    const size_t last_break = rest_.rfind('\n');
    const char* const fast_end = last_break == std::string_view::npos ? p : p + last_break + 1;
    while (p < end && chunk->size() < chunk_samples()) {
      ++line_number_;
      // A mapped file's next page, before the parser gets there: the hardware's prefetcher stops
      // at each 4 KiB page, and rows read from memory instead of the cache cost 8 % of `flight`
      // on a 30-million-line gyro.csv (analysis_bench --flight-only, 1.35 s against 1.23 s).
      __builtin_prefetch(p + 4096);
      GyroSample s;
      // A row of a shape seen before: read without a byte loop (sim/logs/gyro_row_shapes.h).
      const char* next =
          shapes_.enabled() && end - p >= static_cast<ptrdiff_t>(GyroRowShapes::kReadBytes)
              ? shapes_.Read(p, &s)
              : nullptr;
      if (!next && p < fast_end) {
        next = ParseRowFast(p, end, &s);
        if (next) shapes_.Learn(p, next);
      }
      if (!next) {
        const char* eol = static_cast<const char*>(std::memchr(p, '\n', end - p));
        if (!eol) eol = end;
        std::string_view line(p, eol - p);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        next = eol < end ? eol + 1 : end;
        if (line.empty()) {
          p = next;
          continue;
        }
        if (eol < end) {
          s = ParseRowGeneral(path_, line_number_, line, &fields_);
        } else if (!ParseCutLastLine(line, &s)) {
          p = end;
          break;
        }
      }
      if (s.t_ns < last_t_ns_) {
        const char* comma = static_cast<const char*>(std::memchr(p, ',', end - p));
        throw IoError(IoMessage(path_, line_number_,
                                "timestamp decreases (" + std::string(p, comma ? comma - p : 0) +
                                    " after an earlier, larger one)"));
      }
      any_ = true;
      last_t_ns_ = s.t_ns;
      chunk->push_back(s);
      p = next;
    }
    rest_ = std::string_view(p, end - p);
  }

  // The input's last line, which has no line break (a block holds whole lines but for that one):
  // false when it does not read, the file cut inside it, which is left out and said.
  bool ParseCutLastLine(std::string_view line, GyroSample* s) {
    try {
      *s = ParseRowGeneral(path_, line_number_, line, &fields_);
      return true;
    } catch (const IoError&) {
      LeaveOutCutLastLine(line_number_, any_ ? std::optional<int64_t>(last_t_ns_) : std::nullopt);
      return false;
    }
  }

  TextBlocks blocks_;
  std::string path_;
  std::string_view rest_;  // whole lines of the current block not parsed yet
  long line_number_ = 1;   // the header is line 1
  bool any_ = false;
  int64_t last_t_ns_ = std::numeric_limits<int64_t>::min();  // no row yet: nothing decreases
  std::vector<std::string_view> fields_;
  GyroRowShapes shapes_;
};

}  // namespace

void GyroReadOptions::Check() const {
  SHUTTERLAB_CHECK(format == LogFormat::kAuto || IsPlainGyroFormat(format))
      << "ReadGyro reads gyro.csv, gcsv or raw counts only: a flight log is read by "
         "sim/logs/flight_log_io.h ReadFlightLog";
  raw.Check();
}

std::unique_ptr<GyroSource> OpenGyroCsv(TextBlocks blocks, const std::string& path,
                                        size_t chunk_samples, GyroCsvRows rows) {
  return std::make_unique<GyroCsvSource>(std::move(blocks), path, chunk_samples, rows);
}

GyroTrace ReadGyroCsv(const std::string& path) {
  return ReadAllSamples(OpenGyroCsv(TextBlocks::OfFile(path), path).get(), path);
}

void WriteGyroCsv(const std::string& path, const GyroTrace& trace) {
  std::string out = "t,gx,gy,gz\n";
  // A line is about 80 characters (to_chars' shortest doubles, up to 24 each): reserved for 96,
  // the text of a 120 s log at 1 kHz (10 MB) is not copied to grow halfway.
  out.reserve(trace.size() * 96 + 16);
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

LogFormat DetectGyroFormat(std::string_view text, const std::string& path) {
  LineCursor cursor(text);
  std::vector<std::string_view> fields;
  std::optional<std::string_view> first;
  while ((first = cursor.Next()) && first->empty()) {
  }
  if (!first) throw IoError(IoMessage(path, 0, "empty file"));
  const long first_line = cursor.line_number();
  SplitFields(StripBom(*first), ',', &fields);
  if (fields.size() == 1 && (fields[0] == "GYROFLOW IMU LOG" || fields[0] == "CAMERA IMU LOG")) {
    return LogFormat::kGcsv;
  }
  const bool has_header = !ParseDouble(fields[0]);
  // docs/FORMATS.md is the contract: its header means gyro.csv, whatever the values look like (an
  // ideal still trace writes every rate as "0"). Raw counts carry another header or none.
  if (has_header && IsGyroCsvHeader(fields)) return LogFormat::kGyroCsv;
  // Scan the rows of a headerless file from its first line, else from the line after the header.
  LineCursor rows(text);
  if (has_header) {
    while (rows.line_number() < first_line) rows.Next();
  }
  while (auto line = rows.Next()) {
    if (line->empty()) continue;
    SplitFields(*line, ',', &fields);
    for (size_t axis = 1; axis < 4 && axis < fields.size(); ++axis) {
      if (ParseInt(fields[axis])) continue;
      // A non-number is left to the raw reader, which names it; a fractional number is neither
      // format.
      if (!ParseDouble(fields[axis])) return LogFormat::kRaw;
      throw IoError(IoMessage(
          path, rows.line_number(),
          std::string(has_header ? "unrecognised header '" + std::string(*first) + "' and"
                                 : "no header line and") +
              " a non-integer rate '" + std::string(fields[axis]) +
              "': not raw counts (integers), and a gyro.csv needs the header 't,gx,gy,gz'; see "
              "--format"));
    }
  }
  // Every rate an integer: raw counts (whatever their header says).
  return LogFormat::kRaw;
}

GyroTrace ReadGyro(const std::string& path, const GyroReadOptions& options) {
  options.Check();
  LogFormat format = options.format;
  if (format == LogFormat::kAuto) format = DetectGyroFormat(ReadFileToString(path), path);
  switch (format) {
    case LogFormat::kAuto:
    case LogFormat::kGyroCsv:
      return ReadGyroCsv(path);
    case LogFormat::kGcsv: {
      GcsvLog log = ReadGcsv(path);
      for (const LogWarning& w : log.warnings) {
        if (w.kind == "truncated")  // as ReadGyroCsv: no warnings kept here, so refused
          throw IoError(path + ": " + w.message + " (this reader keeps no warnings)");
      }
      return std::move(log.trace);
    }
    case LogFormat::kRaw:
      return ReadRawCsv(path, options.raw.range_dps, options.raw.time_unit);
    case LogFormat::kULog:
    case LogFormat::kBlackbox:
    case LogFormat::kDataFlash:
    case LogFormat::kGoproMp4:
    case LogFormat::kGyroDump:
    case LogFormat::kColumns:
      break;  // refused by options.Check()
  }
  return ReadGyroCsv(path);
}

TimeUnit ParseTimeUnit(const std::string& name) {
  if (name == "s") return TimeUnit::kSeconds;
  if (name == "ms") return TimeUnit::kMilliseconds;
  if (name == "us") return TimeUnit::kMicroseconds;
  if (name == "ns") return TimeUnit::kNanoseconds;
  SHUTTERLAB_CHECK(false) << "unknown time unit '" << name << "' (s, ms, us, ns)";
  return TimeUnit::kSeconds;
}

}  // namespace shutterlab
