#include "sim/logs/raw_csv.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <vector>

namespace shutterlab {
namespace {

// Decimal digits of the fraction needed to write t_ns exactly in a unit: 9, 6, 3, 0.
int FractionDigits(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::kSeconds:
      return 9;
    case TimeUnit::kMilliseconds:
      return 6;
    case TimeUnit::kMicroseconds:
      return 3;
    case TimeUnit::kNanoseconds:
      return 0;
  }
  return 0;
}

}  // namespace

void AppendTimeInUnit(int64_t t_ns, TimeUnit unit, std::string* out) {
  const int64_t per_unit = NanosecondsPerUnit(unit);
  const bool negative = t_ns < 0;
  const uint64_t magnitude = negative ? 0 - static_cast<uint64_t>(t_ns) : t_ns;
  char buffer[48];
  int n = std::snprintf(buffer, sizeof(buffer), "%s%llu", negative ? "-" : "",
                        static_cast<unsigned long long>(magnitude / per_unit));
  const uint64_t fraction = magnitude % per_unit;
  if (fraction != 0) {
    n += std::snprintf(buffer + n, sizeof(buffer) - n, ".%0*llu", FractionDigits(unit),
                       static_cast<unsigned long long>(fraction));
    while (buffer[n - 1] == '0') --n;
  }
  out->append(buffer, n);
}

std::optional<int64_t> ParseTimeInUnitNs(std::string_view field, TimeUnit unit) {
  const int64_t per_unit = NanosecondsPerUnit(unit);
  const int max_fraction_digits = FractionDigits(unit);
  std::string_view rest = field;
  const bool negative = !rest.empty() && rest.front() == '-';
  if (!rest.empty() && (rest.front() == '-' || rest.front() == '+')) rest.remove_prefix(1);
  const size_t dot = rest.find('.');
  const std::string_view whole = rest.substr(0, dot);
  const std::string_view fraction =
      dot == std::string_view::npos ? std::string_view() : rest.substr(dot + 1);
  auto all_digits = [](std::string_view s) {
    for (char c : s) {
      if (c < '0' || c > '9') return false;
    }
    return true;
  };
  if (!whole.empty() && all_digits(whole) && all_digits(fraction) &&
      fraction.size() <= static_cast<size_t>(max_fraction_digits)) {
    const auto parsed = ParseInt(whole);  // nullopt on int64 overflow
    if (!parsed || *parsed > std::numeric_limits<int64_t>::max() / per_unit - 1)
      return std::nullopt;
    const int64_t units = *parsed;
    int64_t fraction_ns = 0;
    int64_t place = per_unit;
    for (char c : fraction) {
      place /= 10;
      fraction_ns += (c - '0') * place;
    }
    const int64_t t_ns = units * per_unit + fraction_ns;
    return negative ? -t_ns : t_ns;
  }
  const auto value = ParseDouble(field);
  if (!value) return std::nullopt;
  const double t_s = *value * (per_unit * 1e-9);
  if (!(std::abs(t_s) < 9.2e9)) return std::nullopt;
  return SecondsToNs(t_s);
}

namespace {

bool IsHeader(const std::vector<std::string_view>& fields) {
  if (fields.size() < 4) return false;
  for (int i = 0; i < 4; ++i) {
    if (ParseDouble(fields[i])) return false;
  }
  return true;
}

}  // namespace

int64_t NanosecondsPerUnit(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::kSeconds:
      return 1000000000;
    case TimeUnit::kMilliseconds:
      return 1000000;
    case TimeUnit::kMicroseconds:
      return 1000;
    case TimeUnit::kNanoseconds:
      return 1;
  }
  return 1;
}

double RawSensitivityLsbPerDps(int range_dps) {
  switch (range_dps) {
    case 250:
      return 131.0;
    case 500:
      return 65.5;
    case 1000:
      return 32.8;
    case 2000:
      return 16.4;
  }
  SHUTTERLAB_CHECK(false) << "unknown gyro range " << range_dps
                          << " deg/s (expected 250, 500, 1000 or 2000)";
  return 0.0;
}

int16_t RateToCount(double omega_rad_s, double lsb_per_dps, bool* saturated) {
  const double counts = std::round(omega_rad_s / kRadPerDeg * lsb_per_dps);
  *saturated = !(counts >= -32768.0 && counts <= 32767.0);
  if (*saturated) return counts < 0 ? -32768 : 32767;  // NaN was rejected by GyroTrace already
  return static_cast<int16_t>(counts);
}

namespace {

// A raw-count log read a block at a time.
class RawCsvSource : public FillingSource {
 public:
  RawCsvSource(TextBlocks blocks, const std::string& path, int range_dps, TimeUnit time_unit,
               size_t chunk_samples)
      : FillingSource(chunk_samples),
        lines_(std::move(blocks)),
        path_(path),
        rad_s_per_count_(kRadPerDeg / RawSensitivityLsbPerDps(range_dps)),
        time_unit_(time_unit) {}

  double Fraction() const override { return lines_.Fraction(); }

 private:
  void Fill(std::vector<GyroSample>* chunk) override {
    ReserveChunk(chunk, lines_.size_bytes());
    while (chunk->size() < chunk_samples()) {
      const auto line = lines_.Next();
      if (!line) break;
      if (line->empty()) continue;
      SplitFields(*line, ',', &fields_);
      if (first_) {
        first_ = false;
        if (IsHeader(fields_)) continue;
      }
      try {
        chunk->push_back(ReadRow(lines_.line_number()));
      } catch (const IoError&) {
        if (!lines_.unterminated()) throw;
        LeaveOutCutLastLine(lines_.line_number());
      }
    }
    if (chunk->empty() && !last_t_ns()) throw IoError(IoMessage(path_, 0, "no samples"));
  }

  // The sample of line n, split into fields_, after the one before.
  GyroSample ReadRow(long n) {
    const GyroSample s = ParseRow(n);
    TakeTimeInOrder(path_, n, s.t_ns, fields_[0]);
    return s;
  }

  // The sample of line n, split into fields_.
  GyroSample ParseRow(long n) const {
    if (fields_.size() < 4) {
      throw IoError(IoMessage(
          path_, n, "expected 4 columns t,gx,gy,gz, found " + std::to_string(fields_.size())));
    }
    GyroSample s;
    const auto t_ns = ParseTimeInUnitNs(fields_[0], time_unit_);
    if (!t_ns) {
      throw IoError(IoMessage(
          path_, n, "t is not a finite number in range: '" + std::string(fields_[0]) + "'"));
    }
    s.t_ns = *t_ns;
    for (int axis = 0; axis < 3; ++axis) {
      const std::string_view field = fields_[axis + 1];
      const std::string name = std::string("g") + "xyz"[axis];
      const auto count = ParseInt(field);
      if (!count) {
        throw IoError(
            IoMessage(path_, n, name + " is not an integer count: '" + std::string(field) + "'"));
      }
      if (*count < -32768 || *count > 32767) {
        throw IoError(IoMessage(
            path_, n,
            name + " = " + std::string(field) + " is outside the int16 range of a raw count"));
      }
      s.omega_rad_s[axis] = static_cast<double>(*count) * rad_s_per_count_;
    }
    return s;
  }

  LineReader lines_;
  std::string path_;
  double rad_s_per_count_;
  TimeUnit time_unit_;
  bool first_ = true;
  std::vector<std::string_view> fields_;
};

}  // namespace

std::unique_ptr<GyroSource> OpenRawCsv(TextBlocks blocks, const std::string& path, int range_dps,
                                       TimeUnit time_unit, size_t chunk_samples) {
  return std::make_unique<RawCsvSource>(std::move(blocks), path, range_dps, time_unit,
                                        chunk_samples);
}

GyroTrace ReadRawCsv(const std::string& path, int range_dps, TimeUnit time_unit) {
  RawSensitivityLsbPerDps(range_dps);  // an unknown range before the file is opened
  return ReadAllSamples(OpenRawCsv(TextBlocks::OfFile(path), path, range_dps, time_unit).get(),
                        path);
}

size_t WriteRawCsv(const std::string& path, const GyroTrace& trace, int range_dps,
                   TimeUnit time_unit) {
  const double lsb_per_dps = RawSensitivityLsbPerDps(range_dps);
  std::string out = std::string(kRawCsvHeader) + "\n";
  out.reserve(trace.size() * 40 + 16);
  size_t saturated_count = 0;
  for (const GyroSample& s : trace.samples()) {
    AppendTimeInUnit(s.t_ns, time_unit, &out);
    for (int axis = 0; axis < 3; ++axis) {
      bool saturated = false;
      const int16_t count = RateToCount(s.omega_rad_s[axis], lsb_per_dps, &saturated);
      saturated_count += saturated;
      out += ',';
      out += std::to_string(count);
    }
    out += '\n';
  }
  WriteFileAtomically(path, out);
  return saturated_count;
}

}  // namespace shutterlab
