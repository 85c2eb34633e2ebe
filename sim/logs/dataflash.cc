#include "sim/logs/dataflash.h"

#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/gyro_candidates.h"
#include "sim/logs/ulog.h"  // kAirborneAltitudeM
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

constexpr uint8_t kHead1 = 0xA3;
constexpr uint8_t kHead2 = 0x95;
constexpr uint8_t kFmtType = 128;
constexpr size_t kHeaderBytes = 3;
constexpr size_t kFmtLength = 89;     // 3 + type + length + name[4] + format[16] + labels[64]
constexpr size_t kBatchSamples = 32;  // int16[32] per ISBD axis ('a')
constexpr size_t kMaxDetailedWarnings = 8;

uint64_t LoadLE(const char* p, size_t bytes) {
  uint64_t v = 0;
  for (size_t i = 0; i < bytes; ++i)
    v |= static_cast<uint64_t>(static_cast<uint8_t>(p[i])) << (8 * i);
  return v;
}

// Bytes of one format character; 0 when unknown.
size_t CharBytes(char c) {
  switch (c) {
    case 'b':
    case 'B':
    case 'M':
      return 1;
    case 'h':
    case 'H':
    case 'c':
    case 'C':
    case 'g':
      return 2;
    case 'i':
    case 'I':
    case 'f':
    case 'e':
    case 'E':
    case 'L':
    case 'n':
      return 4;
    case 'd':
    case 'q':
    case 'Q':
      return 8;
    case 'N':
      return 16;
    case 'Z':
    case 'a':
      return 64;
    default:
      return 0;
  }
}

double HalfToDouble(uint16_t h) {
  const int exponent = (h >> 10) & 0x1f;
  const int mantissa = h & 0x3ff;
  const double sign = (h & 0x8000) ? -1.0 : 1.0;
  if (exponent == 0) return sign * std::ldexp(mantissa, -24);
  if (exponent == 31) return mantissa ? std::numeric_limits<double>::quiet_NaN() : sign * INFINITY;
  return sign * std::ldexp(mantissa + 1024, exponent - 25);
}

// A logged number as an integer; 0 when it is not finite or out of int range (corrupt data).
int64_t ToInt(double v) {
  return std::isfinite(v) && std::abs(v) < 9.0e15 ? static_cast<int64_t>(v) : 0;
}

struct Field {
  char type = 0;
  size_t offset = 0;  // within the payload (after the 3 header bytes)
};

// Reads a numeric field with ArduPilot's fixed multipliers applied; NaN for text fields.
double ReadNumber(std::string_view payload, const Field& f, size_t element = 0) {
  const size_t at = f.offset + (f.type == 'a' ? 2 * element : 0);
  auto raw = [&](size_t bytes) { return LoadLE(payload.data() + at, bytes); };
  switch (f.type) {
    case 'b':
      return static_cast<int8_t>(raw(1));
    case 'B':
    case 'M':
      return static_cast<uint8_t>(raw(1));
    case 'h':
    case 'a':
      return static_cast<int16_t>(raw(2));
    case 'H':
      return static_cast<uint16_t>(raw(2));
    case 'c':
      return static_cast<int16_t>(raw(2)) * 0.01;
    case 'C':
      return static_cast<uint16_t>(raw(2)) * 0.01;
    case 'i':
      return static_cast<int32_t>(raw(4));
    case 'I':
      return static_cast<uint32_t>(raw(4));
    case 'e':
      return static_cast<int32_t>(raw(4)) * 0.01;
    case 'E':
      return static_cast<uint32_t>(raw(4)) * 0.01;
    case 'L':
      return static_cast<int32_t>(raw(4)) * 1e-7;
    case 'q':
      return static_cast<double>(static_cast<int64_t>(raw(8)));
    case 'Q':
      return static_cast<double>(raw(8));
    case 'g':
      return HalfToDouble(static_cast<uint16_t>(raw(2)));
    case 'f': {
      const uint32_t bits = static_cast<uint32_t>(raw(4));
      float v;
      std::memcpy(&v, &bits, 4);
      return v;
    }
    case 'd': {
      const uint64_t bits = raw(8);
      double v;
      std::memcpy(&v, &bits, 8);
      return v;
    }
    default:
      return std::numeric_limits<double>::quiet_NaN();
  }
}

// A time field as ns (ns_per_tick: 1000 for TimeUS / SampleUS, 1e6 for the TimeMS of old logs);
// nullopt unless an integer type in range.
std::optional<int64_t> ReadTimeNs(std::string_view payload, const Field& f, int64_t ns_per_tick) {
  int64_t ticks = 0;
  switch (f.type) {
    case 'Q': {
      const uint64_t v = LoadLE(payload.data() + f.offset, 8);
      if (v > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) return std::nullopt;
      ticks = static_cast<int64_t>(v);
      break;
    }
    case 'q':
      ticks = static_cast<int64_t>(LoadLE(payload.data() + f.offset, 8));
      break;
    case 'I':
      ticks = static_cast<uint32_t>(LoadLE(payload.data() + f.offset, 4));
      break;
    case 'i':
      ticks = static_cast<int32_t>(LoadLE(payload.data() + f.offset, 4));
      break;
    default:
      return std::nullopt;
  }
  if (ticks < 0 || ticks > std::numeric_limits<int64_t>::max() / ns_per_tick) return std::nullopt;
  return ticks * ns_per_tick;
}

std::string TrimmedText(std::string_view s) {
  const size_t nul = s.find('\0');
  s = s.substr(0, nul);
  while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
  return std::string(s);
}

struct Format {
  std::string name;
  bool relevant = false;  // a message this reader decodes; most of a real log is not
  size_t length = 0;      // whole message, header included
  std::map<std::string, Field> fields;
  std::vector<std::string> labels;  // in field order, for the FMTU unit and multiplier columns
  // The boot-time column: TimeUS (µs), or TimeMS (ms) in logs before ArduPilot 3.4.
  const Field* time = nullptr;
  int64_t time_ns_per_tick = 1000;
  const Field* Find(const std::string& label) const {
    auto it = fields.find(label);
    return it == fields.end() ? nullptr : &it->second;
  }
  std::optional<int64_t> TimeNs(std::string_view payload) const {
    if (!time) return std::nullopt;
    return ReadTimeNs(payload, *time, time_ns_per_tick);
  }
};

// Builds a format from an FMT payload; an error text when it is inconsistent.
std::optional<Format> ParseFmt(std::string_view p, std::string* error) {
  Format fmt;
  fmt.length = static_cast<uint8_t>(p[1]);
  fmt.name = TrimmedText(p.substr(2, 4));
  const std::string format = TrimmedText(p.substr(6, 16));
  const std::string labels = TrimmedText(p.substr(22, 64));
  std::vector<std::string> names;
  size_t start = 0;
  while (start <= labels.size()) {
    const size_t comma = labels.find(',', start);
    names.push_back(
        labels.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (labels.empty()) names.clear();
  if (names.size() != format.size()) {
    *error = "FMT for '" + fmt.name + "' has " + std::to_string(format.size()) +
             " format characters but " + std::to_string(names.size()) + " labels";
    return std::nullopt;
  }
  size_t offset = 0;
  for (size_t i = 0; i < format.size(); ++i) {
    const size_t bytes = CharBytes(format[i]);
    if (bytes == 0) {
      *error = "FMT for '" + fmt.name + "' has unknown format character '" +
               std::string(1, format[i]) + "'";
      return std::nullopt;
    }
    fmt.fields.emplace(names[i], Field{format[i], offset});
    offset += bytes;
  }
  fmt.labels = names;
  if ((fmt.time = fmt.Find("TimeUS")) == nullptr && (fmt.time = fmt.Find("TimeMS")) != nullptr)
    fmt.time_ns_per_tick = 1'000'000;
  static const char* kRelevant[] = {"GYR", "IMU",  "IMU2", "IMU3", "ISBH", "ISBD",
                                    "CAM", "TRIG", "FMTU", "UNIT", "MULT", "GPS",
                                    "ATT", "EKF1", "NKF1", "XKF1", "PARM"};
  fmt.relevant = std::any_of(std::begin(kRelevant), std::end(kRelevant),
                             [&](const char* n) { return fmt.name == n; });
  if (offset + kHeaderBytes != fmt.length) {
    *error = "FMT for '" + fmt.name + "' declares length " + std::to_string(fmt.length) +
             " but its format '" + format + "' needs " + std::to_string(offset + kHeaderBytes);
    return std::nullopt;
  }
  return fmt;
}

struct BatchHeader {
  int instance = 0;
  int64_t sample_ns = 0;
  double rate_hz = 0.0;
  double mul = 0.0;
  size_t count = 0;     // samples the header declares
  size_t received = 0;  // samples its ISBD packets delivered
};

// The gyro streams a DataFlash log may hold, best raw first (their preference).
enum GyroKind { kGyr = 0, kIsbd = 1, kImu = 2 };
constexpr const char* kGyroKindNames[] = {"GYR", "ISBD", "IMU"};

// Where the samples go: pass 1 summarises every stream (summaries), pass 2 cleans the chosen one
// (cleaner, target) into out.
struct GyroSinks {
  internal::CandidateLimits limits;
  std::map<std::string, internal::CandidateSummary> summaries;  // by name: the candidates' order
  std::string target;
  internal::CandidateCleaner* cleaner = nullptr;
  std::vector<GyroSample>* out = nullptr;
};

class DataFlashParser {
 public:
  DataFlashParser(std::string_view bytes, const std::string& path, GyroSinks* sinks)
      : bytes_(bytes), path_(path), sinks_(sinks) {}
  // Pass 1: every message but the samples, which go to the summaries; throws IoError when the
  // bytes are not DataFlash. progress (may be empty): the share read, every few thousand messages.
  FlightLog Run(MappedFile* file, const OpeningProgress& progress = {});
  // Reads the next message (or skips a corrupt stretch); false at the end of the bytes.
  bool Step();
  size_t position() const { return pos_; }

 private:
  void Warn(const std::string& kind, size_t offset, const std::string& text) {
    size_t& count = warning_counts_[kind];
    ++count;
    if (count > kMaxDetailedWarnings) return;
    // A cut-off file: say how far into the flight the last whole message reached.
    std::optional<double> t_s;
    if (kind == "truncated" && last_t_ns_ > 0) t_s = last_t_ns_ * 1e-9;
    log_.warnings.push_back({kind, "byte " + std::to_string(offset) + ": " + text, t_s});
  }
  // Message length at q when a known message starts there, else 0.
  size_t KnownAt(size_t q) const;
  size_t Resync(size_t from) const;
  // True when q is the end of the file, too close to it for a header (the loop reports that), or
  // a known message starts there (possibly cut off by the end of the file).
  bool NextHeaderOk(size_t q) const { return q + kHeaderBytes > bytes_.size() || KnownAt(q) != 0; }
  // Decodes the known message of len bytes at pos (FMT or data).
  void Accept(size_t pos, size_t len);
  void Handle(uint8_t type, const Format& fmt, std::string_view payload);
  void HandleGyro(uint8_t type, const Format& fmt, std::string_view payload);
  void HandleBatchHeader(const Format& fmt, std::string_view payload);
  void HandleBatchData(const Format& fmt, std::string_view payload);
  void CloseBatch(int64_t key);
  void HandleCamera(const Format& fmt, std::string_view payload);
  void HandleGps(const Format& fmt, std::string_view payload);
  void HandleGpsVelocity(const Format& fmt, std::string_view payload, int64_t t_ns);
  void HandleAttitude(const Format& fmt, std::string_view payload);
  void HandleEkfVelocity(const Format& fmt, std::string_view payload);
  void HandleParameter(const Format& fmt, std::string_view payload);
  void ChooseVelocity();
  void HandleUnits(const Format& fmt, std::string_view payload);
  double GyroToRadPerS(const Format& fmt, uint8_t type, const std::string& label);
  // GyroToRadPerS for GyrX, GyrY, GyrZ of a type, worked out once and kept until a UNIT, FMTU or
  // FMT message could change it (a log holds thousands of gyro messages per second).
  const Eigen::Vector3d& GyroScale(uint8_t type, const Format& fmt);
  void Finish();
  // A sample of stream kind/instance ("NAME" for instance 0, "NAME/N" otherwise).
  void AddSample(GyroKind kind, int instance, const std::optional<int64_t>& t_ns,
                 const Eigen::Vector3d& rate) {
    Sink& sink = sink_by_stream_[kind][static_cast<uint8_t>(instance)];
    if (!sink.resolved) Resolve(kind, instance, &sink);
    if (sink.summary) {
      sink.summary->Add(t_ns, rate);
    } else if (sink.clean) {
      sinks_->cleaner->Add(t_ns, rate, sinks_->out);
    }
  }
  struct Sink {
    bool resolved = false;
    internal::CandidateSummary* summary = nullptr;  // pass 1
    bool clean = false;                             // pass 2: the chosen stream
  };
  void Resolve(GyroKind kind, int instance, Sink* sink);

  std::string_view bytes_;
  std::string path_;
  GyroSinks* sinks_;
  size_t pos_ = 0;
  FlightLog log_;
  std::array<std::optional<Format>, 256> formats_;
  std::map<std::string, size_t> warning_counts_;
  std::array<std::array<Sink, 256>, 3> sink_by_stream_;
  std::map<int64_t, BatchHeader> batches_;  // by ISBH.N
  std::vector<double> cam_rel_alt_m_;
  std::vector<VelocitySample> gps_velocity_;  // ChooseVelocity keeps one
  struct EkfVelocity {
    std::vector<VelocitySample> samples;
    std::string source;  // "XKF1.VN,VE,VD (core 0)"
  };
  std::map<std::string, EkfVelocity> ekf_velocity_;  // by message: EKF1, NKF1, XKF1
  std::string first_ekf_;                            // the first of them logged
  std::optional<double> ahrs_ekf_type_;              // PARM AHRS_EKF_TYPE, the last
  size_t skipped_bytes_ = 0;
  std::array<std::optional<Eigen::Vector3d>, 256> gyro_scale_by_type_;  // GyroScale's cache
  std::map<char, std::string> unit_labels_;        // UNIT: id -> label ("rad/s")
  std::map<uint8_t, std::string> field_unit_ids_;  // FMTU: type -> one unit id per field
  std::set<std::string> odd_gyro_units_;
  size_t partial_batches_ = 0, missing_batch_samples_ = 0;
  size_t camera_events_without_time_ = 0;
  int64_t last_t_ns_ = 0;  // the latest gyro sample time read so far
};

void DataFlashParser::Resolve(GyroKind kind, int instance, Sink* sink) {
  const std::string name =
      std::string(kGyroKindNames[kind]) + (instance ? "/" + std::to_string(instance) : "");
  sink->resolved = true;
  if (sinks_->cleaner) {
    sink->clean = name == sinks_->target;
    return;
  }
  sink->summary = &sinks_->summaries.try_emplace(name, name, static_cast<int>(kind), sinks_->limits)
                       .first->second;
}

size_t DataFlashParser::KnownAt(size_t q) const {
  if (bytes_.size() - q < kHeaderBytes) return 0;
  if (static_cast<uint8_t>(bytes_[q]) != kHead1 || static_cast<uint8_t>(bytes_[q + 1]) != kHead2)
    return 0;
  const uint8_t type = static_cast<uint8_t>(bytes_[q + 2]);
  if (type == kFmtType) return kFmtLength;
  return formats_[type] ? formats_[type]->length : 0;
}

// Next offset after `from` where a known message starts and is followed by another one (or by the
// end of the file). Linear in the bytes scanned.
size_t DataFlashParser::Resync(size_t from) const {
  const size_t n = bytes_.size();
  for (size_t q = from; q + kHeaderBytes <= n; ++q) {
    const size_t len = KnownAt(q);
    if (len == 0 || len > n - q) continue;
    if (q + len == n || KnownAt(q + len) != 0) return q;
  }
  return n;
}

void DataFlashParser::Accept(size_t pos, size_t len) {
  const std::string_view payload = bytes_.substr(pos + kHeaderBytes, len - kHeaderBytes);
  const uint8_t type = static_cast<uint8_t>(bytes_[pos + 2]);
  if (type != kFmtType) {
    Handle(type, *formats_[type], payload);
    return;
  }
  std::string error;
  auto fmt = ParseFmt(payload, &error);
  const uint8_t defined = static_cast<uint8_t>(payload[0]);
  if (!fmt) {
    ++log_.records_skipped;
    Warn("fmt", pos, error + "; skipped");
  } else if (defined == kFmtType) {
    if (fmt->length != kFmtLength)
      Warn("fmt", pos, "FMT redefines itself with another length; ignored");
  } else {
    formats_[defined] = std::move(fmt);
    gyro_scale_by_type_[defined].reset();
  }
}

void DataFlashParser::Handle(uint8_t type, const Format& fmt, std::string_view p) {
  if (!fmt.relevant) return;
  const std::string& name = fmt.name;
  if (name == "GYR" || name == "IMU" || name == "IMU2" || name == "IMU3") {
    HandleGyro(type, fmt, p);
  } else if (name == "ISBH") {
    HandleBatchHeader(fmt, p);
  } else if (name == "ISBD") {
    HandleBatchData(fmt, p);
  } else if (name == "CAM" || name == "TRIG") {
    HandleCamera(fmt, p);
  } else if (name == "GPS") {
    HandleGps(fmt, p);
  } else if (name == "ATT") {
    HandleAttitude(fmt, p);
  } else if (name == "EKF1" || name == "NKF1" || name == "XKF1") {
    HandleEkfVelocity(fmt, p);
  } else if (name == "PARM") {
    HandleParameter(fmt, p);
  } else if (name == "UNIT" || name == "FMTU") {
    HandleUnits(fmt, p);
    for (auto& scale : gyro_scale_by_type_) scale.reset();  // a unit may have changed
  }
}

// UNIT (Id, Label) names a unit; FMTU (FmtType, UnitIds) gives one unit id per field of a type.
void DataFlashParser::HandleUnits(const Format& fmt, std::string_view p) {
  if (fmt.name == "UNIT") {
    const Field* id = fmt.Find("Id");
    const Field* label = fmt.Find("Label");
    if (!id || !label || label->type != 'Z') return;
    unit_labels_[static_cast<char>(ToInt(ReadNumber(p, *id)))] =
        TrimmedText(p.substr(label->offset, 64));
    return;
  }
  const Field* type = fmt.Find("FmtType");
  const Field* units = fmt.Find("UnitIds");
  if (!type || !units || units->type != 'N') return;
  field_unit_ids_[static_cast<uint8_t>(ToInt(ReadNumber(p, *type)))] =
      TrimmedText(p.substr(units->offset, 16));
}

// The factor that turns a gyro field into rad/s: 1 unless the log's FMTU/UNIT tables say deg/s.
double DataFlashParser::GyroToRadPerS(const Format& fmt, uint8_t type, const std::string& label) {
  auto ids = field_unit_ids_.find(type);
  if (ids == field_unit_ids_.end()) return 1.0;
  const auto at = std::find(fmt.labels.begin(), fmt.labels.end(), label) - fmt.labels.begin();
  if (static_cast<size_t>(at) >= ids->second.size()) return 1.0;
  auto unit = unit_labels_.find(ids->second[at]);
  if (unit == unit_labels_.end() || unit->second == "rad/s") return 1.0;
  if (unit->second == "deg/s" || unit->second == "degs") return kRadPerDeg;
  odd_gyro_units_.insert(fmt.name + "." + label + " in '" + unit->second + "'");
  return 1.0;
}

const Eigen::Vector3d& DataFlashParser::GyroScale(uint8_t type, const Format& fmt) {
  std::optional<Eigen::Vector3d>& scale = gyro_scale_by_type_[type];
  if (!scale) {
    scale = Eigen::Vector3d(GyroToRadPerS(fmt, type, "GyrX"), GyroToRadPerS(fmt, type, "GyrY"),
                            GyroToRadPerS(fmt, type, "GyrZ"));
  }
  return *scale;
}

void DataFlashParser::HandleGyro(uint8_t type, const Format& fmt, std::string_view p) {
  const std::string& name = fmt.name;
  const Field* x = fmt.Find("GyrX");
  const Field* y = fmt.Find("GyrY");
  const Field* z = fmt.Find("GyrZ");
  if (!x || !y || !z) return;
  // GYR's SampleUS is when the sensor sampled; TimeUS is when the message was written.
  const Field* sample_us = name == "GYR" ? fmt.Find("SampleUS") : nullptr;
  const std::optional<int64_t> t_ns = sample_us ? ReadTimeNs(p, *sample_us, 1000) : fmt.TimeNs(p);
  if (!sample_us && !fmt.time) return;
  int instance = name == "IMU2" ? 1 : name == "IMU3" ? 2 : 0;
  if (const Field* i = fmt.Find("I")) instance = static_cast<int>(ToInt(ReadNumber(p, *i)) & 0xff);
  const Eigen::Vector3d& scale = GyroScale(type, fmt);
  last_t_ns_ = std::max(last_t_ns_, t_ns.value_or(0));
  AddSample(
      name == "GYR" ? kGyr : kImu, instance, t_ns,
      Eigen::Vector3d(ReadNumber(p, *x), ReadNumber(p, *y), ReadNumber(p, *z)).cwiseProduct(scale));
}

void DataFlashParser::HandleBatchHeader(const Format& fmt, std::string_view p) {
  const Field* n = fmt.Find("N");
  const Field* type = fmt.Find("type");
  const Field* mul = fmt.Find("mul");
  const Field* cnt = fmt.Find("smp_cnt");
  const Field* sus = fmt.Find("SampleUS");
  const Field* rate = fmt.Find("smp_rate");
  if (!n || !type || !mul || !cnt || !sus || !rate) return;
  const int64_t key = ToInt(ReadNumber(p, *n));
  CloseBatch(key);
  if (ReadNumber(p, *type) != 1.0) return;  // 0 accelerometer, 1 gyro
  BatchHeader h;
  if (const Field* inst = fmt.Find("instance"))
    h.instance = static_cast<int>(ToInt(ReadNumber(p, *inst)) & 0xff);
  h.mul = ReadNumber(p, *mul);
  h.rate_hz = ReadNumber(p, *rate);
  h.count = static_cast<size_t>(std::max<int64_t>(0, ToInt(ReadNumber(p, *cnt))));
  const auto t = ReadTimeNs(p, *sus, 1000);
  // Bounds that keep sample-time arithmetic far from int64 overflow on corrupt headers.
  constexpr size_t kMaxBatchSamples = 1'000'000;
  constexpr int64_t kMaxSampleNs = 4'000'000'000'000'000'000;  // 127 years of boot time
  if (!t || *t > kMaxSampleNs || !(h.mul > 0.0) || !(h.rate_hz >= 1.0 && h.rate_hz < 1e6) ||
      h.count > kMaxBatchSamples) {
    ++log_.records_skipped;
    return;
  }
  h.sample_ns = *t;
  batches_[key] = h;
}

void DataFlashParser::HandleBatchData(const Format& fmt, std::string_view p) {
  const Field* n = fmt.Find("N");
  const Field* seq = fmt.Find("seqno");
  const Field* x = fmt.Find("x");
  const Field* y = fmt.Find("y");
  const Field* z = fmt.Find("z");
  if (!n || !seq || !x || !y || !z || x->type != 'a' || y->type != 'a' || z->type != 'a') return;
  auto it = batches_.find(ToInt(ReadNumber(p, *n)));
  if (it == batches_.end()) return;  // an accelerometer batch, or its header was lost
  BatchHeader& h = it->second;
  const int64_t seqno = ToInt(ReadNumber(p, *seq));
  if (seqno < 0 || static_cast<uint64_t>(seqno) * kBatchSamples >= h.count) return;
  for (size_t k = 0; k < kBatchSamples; ++k) {
    const size_t index = static_cast<size_t>(seqno) * kBatchSamples + k;
    if (index >= h.count) break;
    const int64_t t_ns = h.sample_ns + std::llround(static_cast<double>(index) * 1e9 / h.rate_hz);
    AddSample(
        kIsbd, h.instance, t_ns,
        Eigen::Vector3d(ReadNumber(p, *x, k), ReadNumber(p, *y, k), ReadNumber(p, *z, k)) / h.mul);
    ++h.received;
    last_t_ns_ = std::max(last_t_ns_, t_ns);
  }
}

// Forgets batch `key`, first saying when it ended with fewer samples than its header declared.
void DataFlashParser::CloseBatch(int64_t key) {
  auto it = batches_.find(key);
  if (it == batches_.end()) return;
  const BatchHeader& h = it->second;
  if (h.received < h.count) {
    ++partial_batches_;
    missing_batch_samples_ += h.count - h.received;
    if (partial_batches_ <= kMaxDetailedWarnings) {
      log_.warnings.push_back({"partial_batch",
                               "gyro batch " + std::to_string(key) + " (ISBH at " +
                                   SecondsText(h.sample_ns) + "): " + std::to_string(h.received) +
                                   " of the " + std::to_string(h.count) + " samples it declares",
                               h.sample_ns * 1e-9, h.count - h.received});
    }
  }
  batches_.erase(it);
}

void DataFlashParser::HandleCamera(const Format& fmt, std::string_view p) {
  const auto t = fmt.TimeNs(p);
  if (!t || *t <= 0) {
    // Logs before ArduPilot 3.4 stamp CAM with GPS time only, which is not the gyro's clock.
    ++camera_events_without_time_;
    return;
  }
  CameraEvent e;
  e.t_ns = *t;
  e.kind = fmt.name;
  if (const Field* img = fmt.Find("Img")) e.sequence = ToInt(ReadNumber(p, *img));
  log_.camera_events.push_back(e);
  if (fmt.name == "CAM") {
    if (const Field* rel = fmt.Find("RelAlt")) {
      const double h = ReadNumber(p, *rel);
      if (std::isfinite(h)) cam_rel_alt_m_.push_back(h);
    }
  }
}

// GPS (ArduPilot 3.4 and later: TimeUS boot time, GWk GPS week, GMS ms of week, Status 3 and above
// a 3-D fix): the boot clock against UTC and the velocity, from the first GPS instance only. Older
// logs stamp GPS with GPS time alone (TimeMS is then the ms of week) and give neither.
void DataFlashParser::HandleGps(const Format& fmt, std::string_view p) {
  const Field* week = fmt.Find("GWk");
  const Field* ms = fmt.Find("GMS");
  const Field* status = fmt.Find("Status");
  if (!fmt.Find("TimeUS")) return;
  if (const Field* i = fmt.Find("I"); i && ReadNumber(p, *i) != 0.0) return;
  if (status && ReadNumber(p, *status) < 3.0) return;
  const auto t = fmt.TimeNs(p);
  if (!t || *t <= 0) return;
  HandleGpsVelocity(fmt, p, *t);
  if (!week || !ms) return;
  const double w = ReadNumber(p, *week), gms = ReadNumber(p, *ms);
  if (!(w > 0 && w < 10000) || !(gms >= 0 && gms < 604800e3)) return;
  const int64_t gps_ns =
      (static_cast<int64_t>(w) * kSecondsPerWeek * 1000 + static_cast<int64_t>(gms)) * 1'000'000;
  log_.utc_fixes.push_back({*t, UtcFromGpsNs(gps_ns)});
}

// GPS Spd (ground speed, m/s), GCrs (its course, degrees from north) and VZ (vertical speed, m/s,
// down positive: ArduPilot logs the NED velocity's z) of a 3-D fix.
void DataFlashParser::HandleGpsVelocity(const Format& fmt, std::string_view p, int64_t t_ns) {
  const Field* speed = fmt.Find("Spd");
  const Field* course = fmt.Find("GCrs");
  if (!speed || !course) return;
  const double v = ReadNumber(p, *speed), course_rad = ReadNumber(p, *course) * kRadPerDeg;
  if (!(v >= 0 && v <= kMaxLogSpeedMps) || !std::isfinite(course_rad)) return;
  Eigen::Vector3d ned(v * std::cos(course_rad), v * std::sin(course_rad),
                      std::numeric_limits<double>::quiet_NaN());
  if (const Field* vz = fmt.Find("VZ")) {
    const double down = ReadNumber(p, *vz);
    if (std::abs(down) <= kMaxLogSpeedMps) ned.z() = down;
  }
  if (!gps_velocity_.empty() && t_ns <= gps_velocity_.back().t_ns) return;  // time order
  gps_velocity_.push_back({t_ns, ned});
}

// The EKF's velocity: EKF1 (ArduPilot's first EKF), NKF1 (EKF2), XKF1 (EKF3) VN, VE, VD, m/s, of
// the first core (C 0 where the message names its core). A log may run EKF2 and EKF3 side by
// side: ChooseVelocity keeps one. The estimate fuses GPS, IMU and baro: preferred to the
// receiver's own velocity.
void DataFlashParser::HandleEkfVelocity(const Format& fmt, std::string_view p) {
  const Field* n = fmt.Find("VN");
  const Field* e = fmt.Find("VE");
  const Field* d = fmt.Find("VD");
  if (!n || !e || !d) return;
  if (const Field* core = fmt.Find("C"); core && ReadNumber(p, *core) != 0.0) return;
  const auto t = fmt.TimeNs(p);
  const Eigen::Vector3d ned(ReadNumber(p, *n), ReadNumber(p, *e), ReadNumber(p, *d));
  if (!t || *t <= 0 || !ned.allFinite() || ned.norm() > kMaxLogSpeedMps) return;
  EkfVelocity& ekf = ekf_velocity_[fmt.name];
  if (!ekf.samples.empty() && *t <= ekf.samples.back().t_ns) return;  // time order
  if (ekf.samples.empty()) ekf.source = fmt.name + ".VN,VE,VD" + (fmt.Find("C") ? " (core 0)" : "");
  ekf.samples.push_back({*t, ned});
  if (first_ekf_.empty()) first_ekf_ = fmt.name;
}

// PARM Name, Value: AHRS_EKF_TYPE says which EKF the autopilot flew on (2: EKF2, 3: EKF3).
void DataFlashParser::HandleParameter(const Format& fmt, std::string_view p) {
  const Field* name = fmt.Find("Name");
  const Field* value = fmt.Find("Value");
  if (!name || !value || name->type != 'N') return;
  if (TrimmedText(p.substr(name->offset, 16)) != "AHRS_EKF_TYPE") return;
  const double type = ReadNumber(p, *value);
  if (std::isfinite(type)) ahrs_ekf_type_ = type;
}

// The log's velocity: the EKF the autopilot flew on (AHRS_EKF_TYPE) where the log holds its
// messages, else the first EKF logged, else the GPS's.
void DataFlashParser::ChooseVelocity() {
  std::string ekf = first_ekf_, why;
  if (ahrs_ekf_type_) {
    const std::string flown = *ahrs_ekf_type_ == 2 ? "NKF1" : *ahrs_ekf_type_ == 3 ? "XKF1" : "";
    if (!flown.empty() && ekf_velocity_.count(flown) != 0) {
      ekf = flown;
      why = FormatNumber(", the EKF flown on (AHRS_EKF_TYPE %g)", *ahrs_ekf_type_);
    }
  }
  if (!ekf.empty()) {
    EkfVelocity& chosen = ekf_velocity_[ekf];
    log_.velocity = std::move(chosen.samples);
    log_.velocity_source = chosen.source + why;
  } else if (!gps_velocity_.empty()) {
    log_.velocity = std::move(gps_velocity_);
    log_.velocity_source = "GPS.Spd,GCrs,VZ (3-D fix)";
  }
}

// ATT Roll, Pitch, Yaw (degrees; centidegrees in older logs, which ReadNumber scales): Z-Y-X Euler
// angles of the FRD body in NED, one every kAttitudeStepNs at most.
void DataFlashParser::HandleAttitude(const Format& fmt, std::string_view p) {
  const Field* roll = fmt.Find("Roll");
  const Field* pitch = fmt.Find("Pitch");
  const Field* yaw = fmt.Find("Yaw");
  const auto t = fmt.TimeNs(p);  // boot time (TimeUS, or TimeMS in logs before 3.4)
  if (!roll || !pitch || !yaw || !t || *t <= 0) return;
  if (!log_.attitude.empty() && *t - log_.attitude.back().t_ns < kAttitudeStepNs) return;
  const Eigen::Vector3d rpy_rad =
      Eigen::Vector3d(ReadNumber(p, *roll), ReadNumber(p, *pitch), ReadNumber(p, *yaw)) *
      kRadPerDeg;
  if (!rpy_rad.allFinite() || rpy_rad.cwiseAbs().maxCoeff() > 2 * kPi) return;
  const Eigen::Quaterniond ned_from_body =
      Eigen::AngleAxisd(rpy_rad.z(), Eigen::Vector3d::UnitZ()) *
      Eigen::AngleAxisd(rpy_rad.y(), Eigen::Vector3d::UnitY()) *
      Eigen::AngleAxisd(rpy_rad.x(), Eigen::Vector3d::UnitX());
  log_.attitude.push_back({*t, ned_from_body});
  log_.attitude_source = "ATT.Roll,Pitch,Yaw";
}

// Everything said once the whole file has been read: what was lost, the altitude, the gyro.
void DataFlashParser::Finish() {
  while (!batches_.empty()) CloseBatch(batches_.begin()->first);
  if (partial_batches_ > 0) {
    log_.warnings.push_back({"partial_batch",
                             std::to_string(partial_batches_) + " gyro batch(es) incomplete: " +
                                 std::to_string(missing_batch_samples_) +
                                 " declared samples never logged",
                             std::nullopt, missing_batch_samples_});
  }
  if (camera_events_without_time_ > 0) {
    log_.warnings.push_back({"unused_source",
                             std::to_string(camera_events_without_time_) +
                                 " camera event(s) without a boot-time stamp (GPS time only) left "
                                 "out",
                             std::nullopt, camera_events_without_time_});
  }
  for (const std::string& unit : odd_gyro_units_)
    log_.warnings.push_back({"unit", "gyro field " + unit + " read as rad/s"});
  for (const auto& [kind, count] : warning_counts_) {
    if (count > kMaxDetailedWarnings) {
      log_.warnings.push_back({kind,
                               std::to_string(count - kMaxDetailedWarnings) +
                                   " more warnings of kind '" + kind + "' not listed",
                               std::nullopt, count - kMaxDetailedWarnings});
    }
  }
  if (skipped_bytes_ > 0)
    log_.warnings.push_back(
        {"corrupt", std::to_string(skipped_bytes_) + " corrupt bytes skipped in total"});

  ChooseVelocity();
  std::stable_sort(log_.camera_events.begin(), log_.camera_events.end(),
                   [](const CameraEvent& a, const CameraEvent& b) { return a.t_ns < b.t_ns; });
  KeepOneCameraEventKind(&log_);
  std::vector<double> airborne;
  for (double h : cam_rel_alt_m_) {
    if (h > kAirborneAltitudeM) airborne.push_back(h);
  }
  if (!airborne.empty()) {
    log_.altitude_above_ground_m = Median(std::move(airborne));
    log_.altitude_source = "median CAM.RelAlt above 1 m (height above home at each picture)";
  }
}

bool DataFlashParser::Step() {
  const size_t n = bytes_.size();
  const size_t pos = pos_;
  if (pos >= n) return false;
  if (n - pos < kHeaderBytes) {
    Warn("truncated", pos, "file ends inside a message header (truncated?)");
    pos_ = n;
    return false;
  }
  const size_t len = KnownAt(pos);
  if (len == 0) {
    const size_t next = Resync(pos + 1);
    ++log_.records_skipped;
    skipped_bytes_ += next - pos;
    Warn("corrupt", pos,
         "no known message starts here (type " +
             std::to_string(static_cast<uint8_t>(bytes_[pos + 2])) + "); skipped " +
             std::to_string(next - pos) + " bytes");
    pos_ = next;
    return true;
  }
  if (len > n - pos) {
    Warn("truncated", pos,
         "file ends inside a message of " + std::to_string(len) + " bytes (truncated?)");
    pos_ = n;
    return false;
  }
  const uint8_t type = static_cast<uint8_t>(bytes_[pos + 2]);
  const bool defines_next = type == kFmtType && pos + len + kHeaderBytes <= n &&
                            bytes_[pos + len + 2] == bytes_[pos + kHeaderBytes];
  if (!defines_next && !NextHeaderOk(pos + len)) {
    // A damaged type byte makes a message of another length: what follows no longer starts
    // with a header, and a valid message starts inside this one. Decoding it would turn
    // payload bytes into samples. (When no valid message starts inside it, only what follows
    // is damaged; the next step skips that.)
    const size_t next = Resync(pos + 1);
    if (next < pos + len) {
      ++log_.records_skipped;
      skipped_bytes_ += next - pos;
      Warn("corrupt", pos,
           "message (type " + std::to_string(static_cast<uint8_t>(bytes_[pos + 2])) +
               ") not followed by a valid message; skipped " + std::to_string(next - pos) +
               " bytes");
      pos_ = next;
      return true;
    }
  }
  Accept(pos, len);
  pos_ = pos + len;
  return true;
}

// Hands the pages already read back every few MiB, so that resident memory stays bounded.
void ReleaseBehind(MappedFile* file, size_t position, size_t* released) {
  constexpr size_t kReleaseBytes = 8 << 20;
  if (!file || position < *released + kReleaseBytes) return;
  file->ReleaseBefore(position);
  *released = position;
}

FlightLog DataFlashParser::Run(MappedFile* file, const OpeningProgress& progress) {
  log_.format = "dataflash";
  if (!LooksLikeDataFlash(bytes_)) {
    throw IoError(
        IoMessage(path_, 0, "byte 0: not an ArduPilot DataFlash log (expected 0xA3 0x95 0x80)"));
  }
  size_t released = 0;
  for (size_t messages = 1; Step(); ++messages) {
    ReleaseBehind(file, pos_, &released);
    if (progress && messages % kOpeningProgressMessages == 0)
      progress(static_cast<double>(pos_) / static_cast<double>(bytes_.size()));
  }
  Finish();
  return std::move(log_);
}

// The bytes of a log: a file mapped to be read front to back (a pipe's copied to a temporary file
// first), or the caller's bytes in memory.
struct DataFlashBytes {
  std::string path;
  std::unique_ptr<MappedFile> file;
  std::string_view bytes;
};

// Pass 2: the chosen stream's cleaned samples, parsed again from the bytes a chunk at a time.
class DataFlashSource : public FillingSource {
 public:
  DataFlashSource(std::shared_ptr<DataFlashBytes> bytes, internal::CandidateCleaner cleaner,
                  std::string target, size_t chunk_samples)
      : FillingSource(chunk_samples), bytes_(std::move(bytes)), cleaner_(std::move(cleaner)) {
    sinks_.target = std::move(target);
    sinks_.cleaner = &cleaner_;
    sinks_.out = &pending_;
    parser_ = std::make_unique<DataFlashParser>(bytes_->bytes, bytes_->path, &sinks_);
  }
  double Fraction() const override {
    return bytes_->bytes.empty() ? 1.0
                                 : static_cast<double>(parser_->position()) / bytes_->bytes.size();
  }

 protected:
  void Fill(std::vector<GyroSample>* chunk) override {
    CheckUnchanged();
    // What the last chunk left (less than a message's samples, or the cleaner's last release) moves
    // to the front, so that pending_ holds about a chunk.
    pending_.erase(pending_.begin(), pending_.begin() + taken_);
    taken_ = 0;
    while (pending_.size() < chunk_samples() && !done_) {
      if (!parser_->Step()) {
        done_ = true;
        if (!cleaner_.Finish(&pending_)) Changed();
      }
      ReleaseBehind(bytes_->file.get(), parser_->position(), &released_);
    }
    taken_ = std::min(chunk_samples(), pending_.size());
    chunk->insert(chunk->end(), pending_.begin(), pending_.begin() + taken_);
  }

 private:
  // A mapped file cut while mapped would fault on its lost pages; one that grew or was rewritten
  // is not the file pass 1 read. Either way, one line naming it.
  void CheckUnchanged() const {
    if (bytes_->file) bytes_->file->CheckUnchanged();
  }
  std::uintmax_t SizeNow() const {
    std::error_code error;
    const std::uintmax_t now = std::filesystem::file_size(bytes_->path, error);
    return error ? 0 : now;
  }
  // Also when pass 2 met other samples than pass 1 (a file rewritten at the same size).
  [[noreturn]] void Changed() const {
    throw IoError(IoMessage(bytes_->path, 0,
                            "changed while it was read in passes (" +
                                std::to_string(bytes_->bytes.size()) + " bytes, now " +
                                std::to_string(SizeNow()) +
                                "): is it still being recorded? Analyse a copy, or the finished "
                                "log"));
  }

  std::shared_ptr<DataFlashBytes> bytes_;
  internal::CandidateCleaner cleaner_;
  GyroSinks sinks_;
  std::unique_ptr<DataFlashParser> parser_;
  std::vector<GyroSample> pending_;  // cleaned samples; the first taken_ handed out already
  size_t taken_ = 0;
  size_t released_ = 0;
  bool done_ = false;
};

// Pass 1 (again without limits when a stream's disorder or intervals exceed them), the choice,
// and pass 2 handed out as the stream's samples.
DataFlashStream OpenBytes(std::shared_ptr<DataFlashBytes> bytes, size_t chunk_samples,
                          internal::CandidateLimits limits = {},
                          const OpeningProgress& progress = {}) {
  GyroSinks sinks;
  sinks.limits = limits;
  FlightLog log =
      DataFlashParser(bytes->bytes, bytes->path, &sinks).Run(bytes->file.get(), progress);
  std::vector<internal::CandidateSummary> summaries;
  auto finish = [&] {
    summaries.clear();
    summaries.reserve(sinks.summaries.size());
    for (auto& [name, summary] : sinks.summaries) {
      summary.Finish();
      summaries.push_back(std::move(summary));
    }
    return std::all_of(summaries.begin(), summaries.end(),
                       [](const internal::CandidateSummary& s) { return s.exact(); });
  };
  if (!finish()) {
    const LogWarning in_memory = internal::ReadInMemoryWarning(summaries);
    GyroSinks unbounded;
    unbounded.limits = internal::CandidateLimits::Unbounded();
    log = DataFlashParser(bytes->bytes, bytes->path, &unbounded).Run(bytes->file.get());
    sinks = std::move(unbounded);
    finish();
    log.warnings.push_back(in_memory);
  }
  const std::optional<size_t> chosen = internal::ChooseGyroSummary(summaries, &log);
  if (!chosen) {
    throw IoError(IoMessage(bytes->path, 0,
                            "no usable gyro data (looked for GYR, ISBH/ISBD gyro batches, IMU)"));
  }
  DataFlashStream stream;
  stream.log = std::move(log);
  stream.samples = std::make_unique<DataFlashSource>(std::move(bytes),
                                                     internal::CandidateCleaner(summaries[*chosen]),
                                                     summaries[*chosen].name(), chunk_samples);
  return stream;
}

FlightLog ReadWhole(DataFlashStream stream) {
  stream.log.gyro = ReadAllSamples(stream.samples.get());
  return std::move(stream.log);
}

}  // namespace

bool LooksLikeDataFlash(std::string_view first_bytes) {
  if (first_bytes.size() < 3) return false;
  const auto* b = reinterpret_cast<const uint8_t*>(first_bytes.data());
  if (b[0] != kHead1 || b[1] != kHead2 || b[2] != kFmtType) return false;
  if (first_bytes.size() >= 5 && (b[3] != kFmtType || b[4] != kFmtLength)) return false;
  return true;
}

DataFlashStream OpenDataFlash(const std::string& path, size_t chunk_samples) {
  return OpenDataFlash(std::make_unique<MappedFile>(path, MappedFile::Paging::kStreamed),
                       chunk_samples);
}

DataFlashStream OpenDataFlash(std::unique_ptr<MappedFile> file, size_t chunk_samples,
                              const OpeningProgress& progress) {
  auto bytes = std::make_shared<DataFlashBytes>();
  bytes->path = file->path();
  bytes->bytes = file->text();
  bytes->file = std::move(file);
  return OpenBytes(std::move(bytes), chunk_samples, {}, progress);
}

DataFlashStream OpenDataFlash(std::string_view bytes, const std::string& path, size_t chunk_samples,
                              internal::CandidateLimits limits) {
  auto borrowed = std::make_shared<DataFlashBytes>();
  borrowed->path = path;
  borrowed->bytes = bytes;
  return OpenBytes(std::move(borrowed), chunk_samples, limits);
}

FlightLog ParseDataFlash(std::string_view bytes, const std::string& path) {
  return ReadWhole(OpenDataFlash(bytes, path));
}

FlightLog ReadDataFlash(const std::string& path) { return ReadWhole(OpenDataFlash(path)); }

}  // namespace shutterlab
