#include "sim/logs/ulog.h"

#include "sim/check.h"
#include "sim/logs/gyro_candidates.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <unordered_map>
#include <utility>

namespace shutterlab {

// ---------------------------------------------------------------------------------------------
namespace {

// The contract's warning kind (docs/FORMATS.md "Warnings") for one of the parser's own.
std::string WarningKind(const std::string& parser_kind) {
  if (parser_kind == "truncated" || parser_kind == "corrupt") return parser_kind;
  return "format";  // appended data, format definitions, subscriptions, flag bits
}

constexpr char kMagic[7] = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35};
constexpr size_t kFileHeaderBytes = 16;
constexpr size_t kMessageHeaderBytes = 3;
constexpr int kMaxNestingDepth = 16;            // PX4 nests two or three deep
constexpr size_t kMaxFlatFields = 1 << 16;      // guards against absurd nested arrays
constexpr size_t kMaxMessageBytes = 65535 + 3;  // uint16 size + header
constexpr int kResyncChain = 4;                 // consecutive plausible messages to trust a resync
constexpr size_t kMaxPlausibleNonDataBytes = 8192;  // formats, infos, log text are far smaller
constexpr int kMsgIdSlack = 16;             // unsubscribed msg_ids believed above the largest seen
constexpr size_t kMaxDetailedWarnings = 8;  // per kind; the rest are summed up

// Little-endian loads, independent of the host's byte order.
uint64_t LoadLE(const char* p, size_t bytes) {
  uint64_t v = 0;
  for (size_t i = 0; i < bytes; ++i)
    v |= static_cast<uint64_t>(static_cast<uint8_t>(p[i])) << (8 * i);
  return v;
}
uint16_t LoadU16(const char* p) { return static_cast<uint16_t>(LoadLE(p, 2)); }

enum class Scalar : uint8_t {
  kInt8,
  kUInt8,
  kInt16,
  kUInt16,
  kInt32,
  kUInt32,
  kInt64,
  kUInt64,
  kFloat,
  kDouble,
  kBool,
  kChar
};

std::optional<std::pair<Scalar, size_t>> ScalarFromName(std::string_view name) {
  static const std::pair<const char*, std::pair<Scalar, size_t>> kTable[] = {
      {"int8_t", {Scalar::kInt8, 1}},   {"uint8_t", {Scalar::kUInt8, 1}},
      {"int16_t", {Scalar::kInt16, 2}}, {"uint16_t", {Scalar::kUInt16, 2}},
      {"int32_t", {Scalar::kInt32, 4}}, {"uint32_t", {Scalar::kUInt32, 4}},
      {"int64_t", {Scalar::kInt64, 8}}, {"uint64_t", {Scalar::kUInt64, 8}},
      {"float", {Scalar::kFloat, 4}},   {"double", {Scalar::kDouble, 8}},
      {"bool", {Scalar::kBool, 1}},     {"char", {Scalar::kChar, 1}}};
  for (const auto& [n, v] : kTable) {
    if (name == n) return v;
  }
  return std::nullopt;
}

size_t ScalarBytes(Scalar s) {
  switch (s) {
    case Scalar::kInt8:
    case Scalar::kUInt8:
    case Scalar::kBool:
    case Scalar::kChar:
      return 1;
    case Scalar::kInt16:
    case Scalar::kUInt16:
      return 2;
    case Scalar::kInt32:
    case Scalar::kUInt32:
    case Scalar::kFloat:
      return 4;
    default:
      return 8;
  }
}

struct FieldDef {
  std::string type;  // scalar type name or a nested format name
  size_t count = 1;  // array length; 1 for a scalar
  std::string name;
};

struct FlatField {
  Scalar type;
  size_t offset;
};

// A topic's flattened layout: "a.b[2]" style names to byte offsets within the data payload (the
// bytes after msg_id).
struct Layout {
  std::unordered_map<std::string, FlatField> fields;
  size_t min_bytes = 0;  // up to the end of the last field that is not trailing _padding
  size_t max_bytes = 0;  // with trailing padding
};

// Reads a field as a double; NaN when it lies outside data.
double ReadNumber(std::string_view data, const FlatField& f) {
  const size_t bytes = ScalarBytes(f.type);
  if (f.offset + bytes > data.size()) return std::numeric_limits<double>::quiet_NaN();
  const uint64_t raw = LoadLE(data.data() + f.offset, bytes);
  switch (f.type) {
    case Scalar::kInt8:
      return static_cast<int8_t>(raw);
    case Scalar::kUInt8:
    case Scalar::kBool:
    case Scalar::kChar:
      return static_cast<uint8_t>(raw);
    case Scalar::kInt16:
      return static_cast<int16_t>(raw);
    case Scalar::kUInt16:
      return static_cast<uint16_t>(raw);
    case Scalar::kInt32:
      return static_cast<int32_t>(raw);
    case Scalar::kUInt32:
      return static_cast<uint32_t>(raw);
    case Scalar::kInt64:
      return static_cast<double>(static_cast<int64_t>(raw));
    case Scalar::kUInt64:
      return static_cast<double>(raw);
    case Scalar::kFloat: {
      const uint32_t bits = static_cast<uint32_t>(raw);
      float v;
      std::memcpy(&v, &bits, 4);
      return v;
    }
    case Scalar::kDouble: {
      double v;
      std::memcpy(&v, &raw, 8);
      return v;
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// Reads an integer microsecond time as ns; nullopt for a non-integer field, out of range, or
// outside data.
std::optional<int64_t> ReadTimeNs(std::string_view data, const FlatField& f) {
  if (f.type == Scalar::kFloat || f.type == Scalar::kDouble) return std::nullopt;
  const size_t bytes = ScalarBytes(f.type);
  if (f.offset + bytes > data.size()) return std::nullopt;
  const uint64_t us = LoadLE(data.data() + f.offset, bytes);
  if (us > static_cast<uint64_t>(std::numeric_limits<int64_t>::max() / 1000)) return std::nullopt;
  return static_cast<int64_t>(us) * 1000;
}

// Parses "name:type name;type[n] name;..." ('F' payload). nullopt when malformed.
std::optional<std::pair<std::string, std::vector<FieldDef>>> ParseFormat(std::string_view text) {
  const size_t colon = text.find(':');
  if (colon == std::string_view::npos || colon == 0) return std::nullopt;
  std::string name(text.substr(0, colon));
  std::vector<FieldDef> fields;
  std::string_view rest = text.substr(colon + 1);
  while (!rest.empty()) {
    const size_t semi = rest.find(';');
    std::string_view item = rest.substr(0, semi);
    rest = semi == std::string_view::npos ? std::string_view() : rest.substr(semi + 1);
    while (!item.empty() && (item.front() == ' ' || item.front() == '\0')) item.remove_prefix(1);
    while (!item.empty() && (item.back() == ' ' || item.back() == '\0')) item.remove_suffix(1);
    if (item.empty()) continue;
    const size_t space = item.find(' ');
    if (space == std::string_view::npos) return std::nullopt;
    std::string_view type = item.substr(0, space);
    std::string_view field_name = item.substr(space + 1);
    if (field_name.empty() || field_name.find(' ') != std::string_view::npos) return std::nullopt;
    FieldDef def;
    def.name = std::string(field_name);
    const size_t bracket = type.find('[');
    if (bracket != std::string_view::npos) {
      if (type.back() != ']' || bracket == 0) return std::nullopt;
      const auto count = ParseInt(type.substr(bracket + 1, type.size() - bracket - 2));
      if (!count || *count < 1 || *count > 65535) return std::nullopt;
      def.count = static_cast<size_t>(*count);
      type = type.substr(0, bracket);
    }
    def.type = std::string(type);
    fields.push_back(std::move(def));
  }
  return std::make_pair(std::move(name), std::move(fields));
}

using FormatMap = std::unordered_map<std::string, std::vector<FieldDef>>;

// Flattens a (possibly nested) format into out; returns an error text or "".
std::string Flatten(const FormatMap& formats, const std::string& type, const std::string& prefix,
                    int depth, size_t* offset, Layout* out) {
  if (depth > kMaxNestingDepth) return "nesting deeper than " + std::to_string(kMaxNestingDepth);
  auto it = formats.find(type);
  if (it == formats.end()) return "no format definition for type '" + type + "'";
  for (const FieldDef& f : it->second) {
    const bool top_level = depth == 0;
    const bool padding = f.name.rfind("_padding", 0) == 0;
    const auto scalar = ScalarFromName(f.type);
    if (scalar && *offset + f.count * scalar->second > kMaxMessageBytes) {
      return "message larger than a ULog message can be";
    }
    if (scalar && padding) {
      *offset += f.count * scalar->second;
      continue;  // padding is not a field, and never ends the part a data message must carry
    }
    for (size_t i = 0; i < f.count; ++i) {
      const std::string name = prefix + f.name + (f.count > 1 ? "[" + std::to_string(i) + "]" : "");
      if (scalar) {
        if (out->fields.size() >= kMaxFlatFields) return "too many fields";
        out->fields.emplace(name, FlatField{scalar->first, *offset});
        *offset += scalar->second;
      } else {
        const size_t before = *offset;
        const std::string err = Flatten(formats, f.type, name + ".", depth + 1, offset, out);
        if (!err.empty()) return err;
        // An empty nested type would let a large array spin without growing the message.
        if (*offset == before) return "nested type '" + f.type + "' has no bytes";
      }
      if (*offset > kMaxMessageBytes) return "message larger than a ULog message can be";
    }
    if (top_level && !padding) out->min_bytes = *offset;
  }
  if (depth == 0) out->max_bytes = *offset;
  return "";
}

struct Subscription {
  std::string topic;
  int multi_id = 0;
  std::shared_ptr<const Layout> layout;  // null when the format could not be resolved
  bool has_data = false;                 // a data message of a wanted topic came (with a layout)
  bool gyro_topic = false;  // IsGyroTopic(topic), cached: tested for every data message
  bool wanted = false;      // WantedTopic(topic), cached
};

bool IsGyroTopic(const std::string& topic) {
  return topic == "sensor_gyro_fifo" || topic == "sensor_gyro" ||
         topic == "vehicle_angular_velocity" || topic == "sensor_combined";
}

// Topics whose data the reader keeps.
bool WantedTopic(const std::string& topic) {
  static const char* kTopics[] = {
      "sensor_gyro_fifo",     "sensor_gyro",    "vehicle_angular_velocity", "sensor_combined",
      "camera_trigger",       "camera_capture", "vehicle_local_position",   "home_position",
      "vehicle_gps_position", "sensor_gps"};
  for (const char* t : kTopics) {
    if (topic == t) return true;
  }
  return false;
}

size_t MinPayload(uint8_t type) {
  switch (type) {
    case 'B':
      return 40;
    case 'F':
      return 2;
    case 'I':
      return 2;
    case 'M':
      return 3;
    case 'P':
      return 2;
    case 'Q':
      return 3;
    case 'A':
      return 4;
    case 'R':
      return 2;
    case 'D':
      return 2;
    case 'L':
      return 10;
    case 'C':
      return 12;
    case 'S':
      return 8;
    case 'O':
      return 2;
    default:
      return 0;  // unknown type
  }
}

class ULogParser;

// Where the parse loop hands each data message of a wanted topic (with a resolved format): pass 1
// decodes every one, pass 2 the gyro stream it chose.
class DataSink {
 public:
  virtual ~DataSink() = default;
  // data: the payload after msg_id; sub_index: the subscription's place in the file's order of
  // 'A' messages (the same in every pass over the same bytes).
  virtual void OnData(size_t sub_index, const Subscription& sub, std::string_view data) = 0;
};

// The one parse loop over a ULog's messages: format definitions, subscriptions, dropouts, corrupt
// stretches (resynchronisation) and appended-data segments. Every pass over a file is a fresh
// parser over the same bytes, so that each sees the same subscriptions and data in the same order.
class ULogParser {
 public:
  // release (may be null): the mapping under bytes, whose pages behind the parse position are
  // handed back as it moves on.
  ULogParser(std::string_view bytes, const std::string& path, DataSink* sink,
             MappedFile* release = nullptr)
      : bytes_(bytes), path_(path), sink_(sink), release_(release) {}

  // Checks the file header and reads the flag bits (throws IoError when the file is not ULog or
  // sets an unknown incompatible flag); then Step reads the messages one at a time.
  void Start();
  // Reads the next message (handing data to the sink); false at the end of the file.
  bool Step();
  double Fraction() const {
    return bytes_.empty() ? 1.0 : static_cast<double>(at_) / static_cast<double>(bytes_.size());
  }
  // What the loop read: format "ulog", its warnings and records_skipped (the summary warnings come
  // with SummariseWarnings, once every data message has been decoded).
  FlightLog& log() { return log_; }
  const std::vector<Subscription>& subscriptions() const { return subscriptions_; }
  // Data messages of topic that could not be decoded (counted with the parser's own).
  void SkipData(const std::string& topic, size_t count) {
    log_.records_skipped += count;
    skipped_by_topic_[topic] += count;
  }
  // Appends the warnings that sum up what was skipped (after the reader's others).
  void SummariseWarnings();

 private:
  std::string Where(size_t offset) const {
    return IoMessage(path_, 0, "byte " + std::to_string(offset) + ": ");
  }
  [[noreturn]] void Fail(size_t offset, const std::string& problem) const {
    throw IoError(Where(offset) + problem);
  }
  void Warn(const std::string& kind, size_t offset, const std::string& text) {
    size_t& count = warning_counts_[kind];
    ++count;
    if (count <= kMaxDetailedWarnings)
      log_.warnings.push_back({WarningKind(kind), "byte " + std::to_string(offset) + ": " + text});
  }

  // A message header at q with a known type, a size that fits, and for 'D' a subscribed msg_id
  // (or pending_id, the id of an 'A' just before it that is not handled yet; -1 for none).
  bool Plausible(size_t q, size_t end, int pending_id = -1) const;
  // True when a message may start at q: the segment ends there, too few bytes are left for a
  // header (the loop reports that), a plausible header follows, or one that runs past the end of
  // the segment (cut off there).
  bool NextHeaderOk(size_t q, size_t end, int pending_id) const;
  size_t Resync(size_t from, size_t end);
  void ReadFlagBits(std::string_view payload, size_t offset);
  void Handle(uint8_t type, std::string_view payload, size_t offset);
  // For a 'D' payload: false only when its topic's format is known and its size does not fit it
  // (an unsubscribed msg_id or an unresolved format cannot be judged by size).
  bool DataSizeFits(std::string_view payload) const;
  // For a 'D' payload: its topic's layout is known, so DataSizeFits was a real check.
  bool SizeCheckedAgainstFormat(std::string_view payload) const {
    auto it = by_msg_id_.find(LoadU16(payload.data()));
    return it != by_msg_id_.end() && subscriptions_[it->second].layout != nullptr;
  }
  std::string DataMismatch(std::string_view payload) const;
  std::shared_ptr<const Layout> LayoutFor(const std::string& topic, std::string* error);
  // Start's steps: the flag bits when they come first (returns where the messages start), the
  // segments of the file between appended-data offsets. Step's: one message (false: stop reading
  // this segment).
  size_t ReadLeadingFlagBits(size_t pos);
  std::vector<std::pair<size_t, size_t>> Segments(size_t pos);
  bool ReadMessage(size_t* at, size_t end, bool last_segment);

  std::string_view bytes_;
  std::string path_;
  DataSink* sink_;
  MappedFile* release_;
  size_t released_ = 0;  // bytes before this handed back to release_
  std::vector<std::pair<size_t, size_t>> segments_;
  size_t segment_ = 0;  // the segment Step reads
  size_t at_ = 0;       // where the next message starts
  FlightLog log_;
  FormatMap formats_;
  std::unordered_map<std::string, std::shared_ptr<const Layout>> layouts_;
  std::vector<Subscription> subscriptions_;
  std::unordered_map<uint16_t, size_t> by_msg_id_;
  std::vector<uint64_t> appended_offsets_;
  int max_msg_id_ = -1;  // largest msg_id subscribed so far
  std::map<std::string, size_t> warning_counts_;
  std::map<std::string, size_t> skipped_by_topic_;
  std::vector<std::pair<uint64_t, uint16_t>>
      dropouts_;  // (gyro-topic timestamp before it, us; duration ms)
  uint64_t last_timestamp_us_ = 0;
  size_t skipped_bytes_ = 0;
};

bool ULogParser::Plausible(size_t q, size_t end, int pending_id) const {
  if (end - q < kMessageHeaderBytes) return false;
  const uint16_t size = LoadU16(bytes_.data() + q);
  const uint8_t type = static_cast<uint8_t>(bytes_[q + 2]);
  const size_t min = MinPayload(type);
  if (min == 0 || size < min || size > end - q - kMessageHeaderBytes) return false;
  // Payload bytes can look like a header by chance; what each type must contain rules most of
  // those out, which keeps resynchronisation from locking onto the middle of a message.
  const std::string_view p = bytes_.substr(q + kMessageHeaderBytes, size);
  // 'I', 'P', 'M', 'Q' carry a key "type name": printable, with a space.
  auto key_fits = [&](size_t at) {
    if (at >= p.size()) return false;
    const size_t len = static_cast<uint8_t>(p[at]);
    if (len < 3 || at + 1 + len > p.size()) return false;
    const std::string_view key = p.substr(at + 1, len);
    return key.find(' ') != std::string_view::npos &&
           std::all_of(key.begin(), key.end(), [](char c) { return c >= 0x20 && c < 0x7f; });
  };
  if (type != 'D' && size > kMaxPlausibleNonDataBytes) return false;
  switch (type) {
    case 'D': {
      const uint16_t msg_id = LoadU16(p.data());
      auto it = by_msg_id_.find(msg_id);
      // An id that was never subscribed may still be real when its 'A' was damaged; PX4 numbers
      // subscriptions from 0 upwards, so only ids near the known ones are believed.
      if (it == by_msg_id_.end())
        return msg_id == pending_id || msg_id <= max_msg_id_ + kMsgIdSlack;
      const Layout* layout = subscriptions_[it->second].layout.get();
      return !layout || (size - 2u >= layout->min_bytes && size - 2u <= layout->max_bytes);
    }
    case 'O':
    case 'R':
      return size == 2;
    case 'S':
      return size == 8;
    case 'I':
    case 'P':
      return key_fits(0);
    case 'M':
    case 'Q':
      return key_fits(1);
    case 'L':
    case 'C':
      return p[0] >= '0' && p[0] <= '7';
    case 'F':
      return p.find(':') != std::string_view::npos;
    case 'A':
      return size <= 3 + 255;  // a topic name, not a long text
    default:
      return true;
  }
}

bool ULogParser::NextHeaderOk(size_t q, size_t end, int pending_id) const {
  if (q >= end || end - q < kMessageHeaderBytes) return true;
  if (Plausible(q, end, pending_id)) return true;
  // A header whose message runs past the end of the segment: the file (or the part before
  // appended data) was cut inside it. The loop deals with it.
  const uint8_t type = static_cast<uint8_t>(bytes_[q + 2]);
  const size_t min = MinPayload(type);
  const size_t size = LoadU16(bytes_.data() + q);
  return min != 0 && size >= min && size > end - q - kMessageHeaderBytes;
}

// Finds the next offset after `from` where kResyncChain plausible messages follow each other (or
// run exactly to the end). Returns end when there is none. Linear in the bytes scanned.
size_t ULogParser::Resync(size_t from, size_t end) {
  for (size_t q = from; q < end; ++q) {
    size_t p = q;
    int chain = 0;
    int pending_id = -1;
    while (chain < kResyncChain && p < end && Plausible(p, end, pending_id)) {
      pending_id = bytes_[p + 2] == 'A' ? LoadU16(bytes_.data() + p + 4) : -1;
      p += kMessageHeaderBytes + LoadU16(bytes_.data() + p);
      ++chain;
    }
    if (chain == kResyncChain || (chain > 0 && p == end)) return q;
  }
  return end;
}

void ULogParser::ReadFlagBits(std::string_view payload, size_t offset) {
  const uint8_t* flags = reinterpret_cast<const uint8_t*>(payload.data());
  // incompat_flags[0] bit 0 is DATA_APPENDED; any other incompatible bit means a layout we
  // cannot read (the spec says a parser must refuse such a file).
  const uint8_t* incompat = flags + 8;
  if ((incompat[0] & ~1u) != 0)
    Fail(offset, "unknown incompatible ULog flag set in incompat_flags[0]; cannot parse");
  for (int i = 1; i < 8; ++i) {
    if (incompat[i] != 0)
      Fail(offset, "unknown incompatible ULog flag set in incompat_flags[" + std::to_string(i) +
                       "]; cannot parse");
  }
  if ((incompat[0] & 1u) == 0) return;
  for (int i = 0; i < 3; ++i) {
    const uint64_t at = LoadLE(payload.data() + 16 + 8 * i, 8);
    if (at == 0) continue;
    if (at >= bytes_.size()) {
      Warn("appended", offset,
           "appended data offset " + std::to_string(at) +
               " lies beyond the end of the file (truncated?); ignored");
      continue;
    }
    if (!appended_offsets_.empty() && at <= appended_offsets_.back()) {
      Warn("appended", offset,
           "appended data offsets not increasing; " + std::to_string(at) + " ignored");
      continue;
    }
    appended_offsets_.push_back(at);
  }
}

std::shared_ptr<const Layout> ULogParser::LayoutFor(const std::string& topic, std::string* error) {
  auto it = layouts_.find(topic);
  if (it != layouts_.end()) return it->second;
  auto layout = std::make_shared<Layout>();
  size_t offset = 0;
  *error = Flatten(formats_, topic, "", 0, &offset, layout.get());
  if (!error->empty()) return nullptr;
  layouts_.emplace(topic, layout);
  return layout;
}

bool ULogParser::DataSizeFits(std::string_view payload) const {
  auto it = by_msg_id_.find(LoadU16(payload.data()));
  if (it == by_msg_id_.end()) return true;  // judged by the header after it; Handle skips it
  const Subscription& sub = subscriptions_[it->second];
  if (!sub.layout) return true;
  const size_t bytes = payload.size() - 2;
  return bytes >= sub.layout->min_bytes && bytes <= sub.layout->max_bytes;
}

std::string ULogParser::DataMismatch(std::string_view payload) const {
  const uint16_t msg_id = LoadU16(payload.data());
  auto it = by_msg_id_.find(msg_id);
  if (it == by_msg_id_.end())
    return "data message for unsubscribed msg_id " + std::to_string(msg_id);
  const Subscription& sub = subscriptions_[it->second];
  return "data message of '" + sub.topic + "' has " + std::to_string(payload.size() - 2) +
         " bytes, its format " + std::to_string(sub.layout->min_bytes) + ".." +
         std::to_string(sub.layout->max_bytes);
}

void ULogParser::Handle(uint8_t type, std::string_view payload, size_t offset) {
  switch (type) {
    case 'F': {
      auto parsed = ParseFormat(payload);
      if (!parsed) {
        ++log_.records_skipped;
        Warn("format", offset, "malformed format definition skipped");
        return;
      }
      formats_[parsed->first] = std::move(parsed->second);
      layouts_.clear();  // a (re)definition can change any cached layout that nests it
      return;
    }
    case 'A': {
      Subscription sub;
      sub.multi_id = static_cast<uint8_t>(payload[0]);
      const uint16_t msg_id = LoadU16(payload.data() + 1);
      sub.topic = std::string(payload.substr(3));
      while (!sub.topic.empty() && sub.topic.back() == '\0') sub.topic.pop_back();
      sub.gyro_topic = IsGyroTopic(sub.topic);
      sub.wanted = WantedTopic(sub.topic);
      std::string error;
      sub.layout = LayoutFor(sub.topic, &error);
      if (!sub.layout) {
        ++log_.records_skipped;
        Warn("subscription", offset,
             "topic '" + sub.topic + "': " + error + "; its data is skipped");
      }
      by_msg_id_[msg_id] = subscriptions_.size();
      max_msg_id_ = std::max<int>(max_msg_id_, msg_id);
      subscriptions_.push_back(std::move(sub));
      return;
    }
    case 'R': {
      by_msg_id_.erase(LoadU16(payload.data()));
      return;
    }
    case 'D': {
      // The main loop has checked the size against the format (DataSizeFits).
      const uint16_t msg_id = LoadU16(payload.data());
      auto it = by_msg_id_.find(msg_id);
      if (it == by_msg_id_.end()) {
        ++log_.records_skipped;
        Warn("msg_id", offset,
             "data message for unsubscribed msg_id " + std::to_string(msg_id) + " skipped");
        return;
      }
      Subscription& sub = subscriptions_[it->second];
      if (!sub.layout) {
        ++log_.records_skipped;
        ++skipped_by_topic_[sub.topic];
        return;
      }
      const std::string_view data = payload.substr(2);
      // A dropout is placed at the time of the last gyro-topic message before it: these come at
      // hundreds of Hz, and a single odd timestamp in a slow topic cannot drag the time away.
      if (sub.gyro_topic) {
        auto ts = sub.layout->fields.find("timestamp");
        if (ts != sub.layout->fields.end()) {
          if (auto t_ns = ReadTimeNs(data, ts->second))
            last_timestamp_us_ = static_cast<uint64_t>(*t_ns / 1000);
        }
      }
      if (sub.wanted) {
        sub.has_data = true;
        sink_->OnData(it->second, sub, data);
      }
      return;
    }
    case 'O': {
      dropouts_.emplace_back(last_timestamp_us_, LoadU16(payload.data()));
      return;
    }
    case 'B':
      Warn("flags", offset, "flag-bits message not at the start of the file; ignored");
      return;
    default:
      return;  // I, M, P, Q, L, C, S: nothing the gyro analysis needs
  }
}

size_t ULogParser::ReadLeadingFlagBits(size_t pos) {
  const size_t n = bytes_.size();
  // 'B' must be the first message; it decides how the rest is read.
  if (n - pos >= kMessageHeaderBytes && bytes_[pos + 2] == 'B') {
    const uint16_t size = LoadU16(bytes_.data() + pos);
    if (size >= MinPayload('B') && size <= n - pos - kMessageHeaderBytes) {
      ReadFlagBits(bytes_.substr(pos + kMessageHeaderBytes, size), pos);
      pos += kMessageHeaderBytes + size;
    }
  }
  return pos;
}

// Segments: [pos, appended[0]), [appended[0], appended[1]), ..., [last, n). A message that
// straddles a segment end was cut off when the logger moved on to appended data.
std::vector<std::pair<size_t, size_t>> ULogParser::Segments(size_t pos) {
  std::vector<std::pair<size_t, size_t>> segments;
  size_t start = pos;
  for (uint64_t at : appended_offsets_) {
    if (at <= start) {
      Warn("appended", pos,
           "appended data offset " + std::to_string(at) + " lies inside the header; ignored");
      continue;
    }
    segments.emplace_back(start, static_cast<size_t>(at));
    start = static_cast<size_t>(at);
  }
  segments.emplace_back(start, bytes_.size());
  return segments;
}

bool ULogParser::ReadMessage(size_t* at, size_t end, bool last_segment) {
  size_t& pos = *at;
  if (end - pos < kMessageHeaderBytes) {
    if (last_segment) Warn("truncated", pos, "file ends inside a message header (truncated?)");
    return false;
  }
  const uint16_t size = LoadU16(bytes_.data() + pos);
  const uint8_t type = static_cast<uint8_t>(bytes_[pos + 2]);
  const size_t min = MinPayload(type);
  if (min == 0 || size < min) {
    const size_t next = Resync(pos + 1, end);
    skipped_bytes_ += next - pos;
    ++log_.records_skipped;
    Warn("corrupt", pos,
         std::string("corrupt message header (type ") + std::to_string(type) + ", size " +
             std::to_string(size) + "); skipped " + std::to_string(next - pos) + " bytes");
    pos = next;
    return true;
  }
  if (size > end - pos - kMessageHeaderBytes) {
    if (!last_segment) return false;  // cut off at the start of appended data
    // Either the file was cut here, or this size field is corrupt: try to read on.
    const size_t next = Resync(pos + 1, end);
    if (next == end) {
      Warn("truncated", pos,
           "file ends inside a message of " + std::to_string(size) + " bytes (truncated?)");
      return false;
    }
    skipped_bytes_ += next - pos;
    ++log_.records_skipped;
    Warn("corrupt", pos,
         "message size " + std::to_string(size) + " runs past the end; skipped " +
             std::to_string(next - pos) + " bytes");
    pos = next;
    return true;
  }
  const std::string_view payload = bytes_.substr(pos + kMessageHeaderBytes, size);
  const size_t after = pos + kMessageHeaderBytes + size;
  const bool data_fits = type != 'D' || DataSizeFits(payload);
  const int pending_id = type == 'A' ? LoadU16(payload.data() + 1) : -1;
  // A data message whose size matches its topic's format is trusted as it is; any other
  // message must be followed by a plausible header, or its size field may be corrupt.
  const bool size_verified = type == 'D' && data_fits && SizeCheckedAgainstFormat(payload);
  if (!data_fits || (!size_verified && !NextHeaderOk(after, end, pending_id))) {
    // A data message whose msg_id is unknown or whose size contradicts its format, or any
    // message not followed by a plausible header, most likely has a corrupt size or type;
    // skipping `size` bytes would silently throw away the good messages after it.
    const size_t next = Resync(pos + 1, end);
    if (data_fits && next >= after) {
      // No valid message starts inside this one: only what follows it is damaged, and the
      // next pass of the loop skips that.
      Handle(type, payload, pos);
      pos = after;
      return true;
    }
    skipped_bytes_ += next - pos;
    ++log_.records_skipped;
    Warn("corrupt", pos,
         (data_fits ? std::string("message (type ") + std::to_string(type) + ", size " +
                          std::to_string(size) + ") not followed by a valid message"
                    : DataMismatch(payload)) +
             "; skipped " + std::to_string(next - pos) + " bytes");
    pos = next;
    return true;
  }
  Handle(type, payload, pos);
  pos += kMessageHeaderBytes + size;
  return true;
}

void ULogParser::SummariseWarnings() {
  for (const auto& [kind, count] : warning_counts_) {
    if (count > kMaxDetailedWarnings) {
      log_.warnings.push_back({WarningKind(kind),
                               std::to_string(count - kMaxDetailedWarnings) +
                                   " more warnings of kind '" + kind + "' not listed",
                               std::nullopt, count - kMaxDetailedWarnings});
    }
  }
  for (const auto& [topic, count] : skipped_by_topic_) {
    log_.warnings.push_back(
        {"corrupt", "topic '" + topic + "': " + std::to_string(count) + " data messages skipped",
         std::nullopt, count});
  }
  if (skipped_bytes_ > 0)
    log_.warnings.push_back(
        {"corrupt", std::to_string(skipped_bytes_) + " corrupt bytes skipped in total"});
  if (dropouts_.empty()) return;
  uint64_t total_ms = 0;
  std::string where;
  for (size_t i = 0; i < dropouts_.size(); ++i) {
    total_ms += dropouts_[i].second;
    if (i < kMaxDetailedWarnings) {
      char buf[64];
      if (dropouts_[i].first == 0) {
        std::snprintf(buf, sizeof(buf), "%s%u ms before the first gyro message", i ? ", " : "",
                      dropouts_[i].second);
      } else {
        std::snprintf(buf, sizeof(buf), "%s%u ms at %.3f s", i ? ", " : "", dropouts_[i].second,
                      dropouts_[i].first * 1e-6);
      }
      where += buf;
    }
  }
  std::optional<double> first_s;
  if (dropouts_.front().first != 0) first_s = dropouts_.front().first * 1e-6;
  log_.warnings.push_back({"gap",
                           std::to_string(dropouts_.size()) + " logging dropouts totalling " +
                               std::to_string(total_ms) + " ms (" + where +
                               (dropouts_.size() > kMaxDetailedWarnings ? ", ..." : "") + ")",
                           first_s, dropouts_.size()});
}

void ULogParser::Start() {
  log_.format = "ulog";
  if (bytes_.size() < kFileHeaderBytes)
    Fail(0, "file too short for a ULog header (" + std::to_string(bytes_.size()) + " bytes)");
  if (!LooksLikeULog(bytes_)) Fail(0, "not a ULog file (bad magic)");
  const int version = static_cast<uint8_t>(bytes_[7]);
  if (version > 1)
    log_.warnings.push_back({"format", "ULog file version " + std::to_string(version) +
                                           " is newer than 1; read as version 1"});
  const size_t pos = ReadLeadingFlagBits(kFileHeaderBytes);
  segments_ = Segments(pos);
  segment_ = 0;
  at_ = segments_.front().first;
}

bool ULogParser::Step() {
  // Pages this far behind are handed back in steps of this size (a resync looks forward only).
  constexpr size_t kReleaseStepBytes = 4 << 20;
  while (segment_ < segments_.size()) {
    const bool last_segment = segment_ + 1 == segments_.size();
    const size_t end = segments_[segment_].second;
    if (at_ < end && ReadMessage(&at_, end, last_segment)) {
      if (release_ && at_ >= released_ + kReleaseStepBytes) {
        release_->ReleaseBefore(at_);
        released_ = at_;
      }
      return true;
    }
    if (++segment_ < segments_.size()) at_ = segments_[segment_].first;
  }
  at_ = bytes_.size();
  return false;
}

// Looks up fields of one layout once, then reads them per message.
struct Fields {
  const Layout& layout;
  const FlatField* Find(const std::string& name) const {
    auto it = layout.fields.find(name);
    return it == layout.fields.end() ? nullptr : &it->second;
  }
  // name[0], name[1], ... as far as they exist.
  std::vector<const FlatField*> Array(const std::string& name, size_t max) const {
    std::vector<const FlatField*> out;
    for (size_t i = 0; i < max; ++i) {
      const FlatField* f = Find(name + "[" + std::to_string(i) + "]");
      if (!f) break;
      out.push_back(f);
    }
    return out;
  }
};

std::string CandidateName(const std::string& topic, int multi_id, const std::string& field) {
  return topic + (multi_id ? "/" + std::to_string(multi_id) : "") + "." + field;
}

// How the data messages of one subscription are read: its fields, looked up once in its layout.
struct TopicDecoder {
  enum class Kind { kNone, kGyroFifo, kGyroRates, kCamera, kLocalPosition, kGps, kHome };
  Kind kind = Kind::kNone;       // kNone: no time field, or a topic the reader does not decode
  const FlatField* t = nullptr;  // the message's time
  // Gyro topics: the candidate's name and rank (set even when the sample fields are missing: the
  // last subscription of a topic instance names its candidate) and whether those fields exist.
  std::string candidate_name;
  int preference = 0;
  bool gyro_fields = false;
  // sensor_gyro_fifo
  const FlatField *dt = nullptr, *scale = nullptr, *count = nullptr;
  std::vector<const FlatField*> x, y, z;
  size_t max_n = 0;
  // sensor_gyro, vehicle_angular_velocity, sensor_combined
  std::array<const FlatField*, 3> axes{};
  const FlatField* seq = nullptr;  // camera events
  const FlatField* utc = nullptr;  // GPS time
  // vehicle_local_position (home_position: z_m alone)
  const FlatField *dist = nullptr, *dist_valid = nullptr, *z_m = nullptr, *z_valid = nullptr;
  bool gyro() const { return kind == Kind::kGyroFifo || kind == Kind::kGyroRates; }
};

// The gyro topics' candidates: sensor_gyro_fifo (preference 0, int16 * scale, up to 256 samples a
// message), sensor_gyro (1), vehicle_angular_velocity (2), sensor_combined (3, at timestamp).
void SetGyroDecoder(const std::string& topic, int multi_id, const Fields& f,
                    const FlatField* t_plain, TopicDecoder* d) {
  if (topic == "sensor_gyro_fifo") {
    d->kind = TopicDecoder::Kind::kGyroFifo;
    d->candidate_name = CandidateName(topic, multi_id, "x,y,z");
    d->preference = 0;
    d->dt = f.Find("dt");
    d->scale = f.Find("scale");
    d->count = f.Find("samples");
    d->x = f.Array("x", 256);
    d->y = f.Array("y", 256);
    d->z = f.Array("z", 256);
    d->max_n = std::min({d->x.size(), d->y.size(), d->z.size()});
    d->gyro_fields = d->dt && d->scale && d->count && d->max_n > 0;
    return;
  }
  d->kind = TopicDecoder::Kind::kGyroRates;
  if (topic == "sensor_gyro") {
    d->candidate_name = CandidateName(topic, multi_id, "x,y,z");
    d->preference = 1;
    d->axes = {f.Find("x"), f.Find("y"), f.Find("z")};
  } else if (topic == "vehicle_angular_velocity") {
    d->candidate_name = CandidateName(topic, multi_id, "xyz");
    d->preference = 2;
    d->axes = {f.Find("xyz[0]"), f.Find("xyz[1]"), f.Find("xyz[2]")};
  } else {
    // sensor_combined.timestamp is the gyro sample's time (the accelerometer's is relative).
    d->t = t_plain;
    d->preference = 3;
    const std::string field = f.Find("gyro_rad[0]") ? "gyro_rad" : "gyro_rad_s";
    d->candidate_name = CandidateName(topic, multi_id, field);
    d->axes = {f.Find(field + "[0]"), f.Find(field + "[1]"), f.Find(field + "[2]")};
  }
  d->gyro_fields = d->t && d->axes[0] && d->axes[1] && d->axes[2];
}

TopicDecoder MakeTopicDecoder(const std::string& topic, int multi_id, const Layout& layout) {
  TopicDecoder d;
  const Fields f{layout};
  const FlatField* t_sample = f.Find("timestamp_sample");
  const FlatField* t_plain = f.Find("timestamp");
  d.t = t_sample ? t_sample : t_plain;
  if (!d.t) return d;  // a topic instance without a time: nothing of it is read
  if (IsGyroTopic(topic)) {
    SetGyroDecoder(topic, multi_id, f, t_plain, &d);
  } else if (topic == "camera_trigger" || topic == "camera_capture") {
    d.kind = TopicDecoder::Kind::kCamera;
    d.t = t_plain ? t_plain : d.t;
    d.seq = f.Find("seq");
  } else if (topic == "vehicle_local_position") {
    d.kind = TopicDecoder::Kind::kLocalPosition;
    d.dist = f.Find("dist_bottom");
    d.dist_valid = f.Find("dist_bottom_valid");
    d.z_m = f.Find("z");
    d.z_valid = f.Find("z_valid");
  } else if (topic == "vehicle_gps_position" || topic == "sensor_gps") {
    d.kind = TopicDecoder::Kind::kGps;
    d.t = t_plain ? t_plain : d.t;
    d.utc = f.Find("time_utc_usec");
  } else if (topic == "home_position") {
    d.kind = TopicDecoder::Kind::kHome;
    d.z_m = f.Find("z");
  }
  return d;
}

// Hands the gyro samples of one data message to emit(t_ns or nullopt when unreadable, rate), in
// log order. False when a sensor_gyro_fifo message is skipped (no time, or a dt, scale or count
// out of range).
template <class Emit>
bool DecodeGyro(const TopicDecoder& d, std::string_view data, const Emit& emit) {
  if (!d.gyro_fields) return true;
  if (d.kind == TopicDecoder::Kind::kGyroRates) {
    emit(ReadTimeNs(data, *d.t),
         Eigen::Vector3d(ReadNumber(data, *d.axes[0]), ReadNumber(data, *d.axes[1]),
                         ReadNumber(data, *d.axes[2])));
    return true;
  }
  const auto t_ns = ReadTimeNs(data, *d.t);
  const double dt_us = ReadNumber(data, *d.dt);
  const double sc = ReadNumber(data, *d.scale);
  const double k = ReadNumber(data, *d.count);
  if (!t_ns || !(dt_us > 0.0 && dt_us < 1e6) || !std::isfinite(sc) || !(k >= 0)) return false;
  const size_t nk = static_cast<size_t>(std::min(k, static_cast<double>(d.max_n)));
  for (size_t i = 0; i < nk; ++i) {
    // timestamp_sample is the newest sample's time; older ones are dt apart before it.
    const int64_t back_ns = std::llround(static_cast<double>(nk - 1 - i) * dt_us * 1e3);
    emit(std::optional<int64_t>(*t_ns - back_ns),
         Eigen::Vector3d(ReadNumber(data, *d.x[i]) * sc, ReadNumber(data, *d.y[i]) * sc,
                         ReadNumber(data, *d.z[i]) * sc));
  }
  return true;
}

// What pass 1 keeps of a subscription that is not a gyro topic (tens of messages a second).
struct TopicRecords {
  std::vector<CameraEvent> events;
  std::vector<UtcFix> utc_fixes;
  std::vector<double> dist_bottom_m;  // valid distances to the ground
  std::vector<double> local_z_m;      // valid local z values
  std::optional<double> last_z_m;     // home_position.z of its last message (may be NaN)
};

// Decodes one data message of a topic other than a gyro one into records.
void DecodeRecord(const std::string& topic, const TopicDecoder& d, std::string_view data,
                  TopicRecords* records) {
  switch (d.kind) {
    case TopicDecoder::Kind::kCamera: {
      // One event a message with a positive time.
      const auto t_ns = ReadTimeNs(data, *d.t);
      if (!t_ns || *t_ns <= 0) return;
      CameraEvent e;
      e.t_ns = *t_ns;
      e.kind = topic;
      if (d.seq) {
        const double v = ReadNumber(data, *d.seq);
        if (std::isfinite(v) && std::abs(v) < 9.0e15) e.sequence = static_cast<int64_t>(v);
      }
      records->events.push_back(e);
      return;
    }
    case TopicDecoder::Kind::kGps: {
      // The log time of a message with a UTC time (time_utc_usec, 0 until the receiver knows it).
      if (!d.utc) return;
      const auto t_ns = ReadTimeNs(data, *d.t);
      const double utc_us = ReadNumber(data, *d.utc);
      // After 2000-01-01 and before 2200: a set clock, not a count from zero.
      if (!t_ns || *t_ns <= 0 || !(utc_us > 946684800e6 && utc_us < 7258118400e6)) return;
      records->utc_fixes.push_back({*t_ns, static_cast<int64_t>(utc_us) * 1000});
      return;
    }
    case TopicDecoder::Kind::kLocalPosition: {
      if (d.dist && d.dist_valid && ReadNumber(data, *d.dist_valid) != 0.0) {
        const double v = ReadNumber(data, *d.dist);
        if (std::isfinite(v)) records->dist_bottom_m.push_back(v);
      }
      if (d.z_m && (!d.z_valid || ReadNumber(data, *d.z_valid) != 0.0)) {
        const double v = ReadNumber(data, *d.z_m);
        if (std::isfinite(v)) records->local_z_m.push_back(v);
      }
      return;
    }
    case TopicDecoder::Kind::kHome:
      if (d.z_m) records->last_z_m = ReadNumber(data, *d.z_m);
      return;
    default:
      return;
  }
}

// What pass 1 gathers from the data messages before choosing the gyro source.
struct DecodedTopics {
  std::vector<CameraEvent> events;
  std::vector<UtcFix> utc_fixes;
  std::vector<double> dist_bottom_m;
  std::vector<double> local_z_m;
  std::optional<double> home_z_m;
};

// The altitude above ground: the airborne median of dist_bottom, else of the height above home
// (or above the first local z); with the warning that says which.
void SetAltitudeAboveGround(const DecodedTopics& topics, FlightLog* log) {
  auto airborne_median = [](const std::vector<double>& heights) {
    std::vector<double> up;
    for (double h : heights) {
      if (h > kAirborneAltitudeM) up.push_back(h);
    }
    return up.empty() ? std::nullopt : std::optional<double>(Median(std::move(up)));
  };
  if (auto m = airborne_median(topics.dist_bottom_m)) {
    log->altitude_above_ground_m = m;
    log->altitude_source = "median vehicle_local_position.dist_bottom (valid, above 1 m)";
  } else if (!topics.local_z_m.empty()) {
    const double z_home = topics.home_z_m.value_or(topics.local_z_m.front());
    std::vector<double> heights;
    for (double z : topics.local_z_m) heights.push_back(-(z - z_home));
    if (auto h = airborne_median(heights)) {
      log->altitude_above_ground_m = h;
      log->altitude_source = std::string("median -(vehicle_local_position.z - ") +
                             (topics.home_z_m ? "home_position.z" : "first local z") +
                             ") above 1 m (height above home, not a ground-distance measurement)";
    }
  }
}

// The bytes both passes read: a file mapped page by page (pages handed back behind the parse), or
// bytes in memory (a pipe's, taken whole; a caller's).
struct ULogInput {
  std::string path;
  std::unique_ptr<MappedFile> file;
  std::string owned;
  std::string_view bytes;
  // A regular file's size when opened: pass 2 refuses a file that has changed since.
  std::optional<uintmax_t> file_size;
};

// The passes over the bytes that give a topic instance's gyro samples in the order they are
// cleaned in, each sweep reading some of its subscriptions: all of them in one sweep when their
// data come one subscription after another in the file (as a topic removed and added again
// leaves it), else one sweep per subscription.
using Sweeps = std::vector<std::vector<size_t>>;

// Pass over the bytes that hands the gyro samples of some subscriptions to emit, in log order
// (pass 2, and pass 1 again for a topic instance that needs it).
class GyroSweep final : public DataSink {
 public:
  using Emit = std::function<void(const std::optional<int64_t>&, const Eigen::Vector3d&)>;
  GyroSweep(const ULogInput& input, std::vector<size_t> subs, Emit emit)
      : parser_(input.bytes, input.path, this, input.file.get()),
        subs_(std::move(subs)),
        decoders_(subs_.size()),
        emit_(std::move(emit)) {
    parser_.Start();
  }
  GyroSweep(const GyroSweep&) = delete;  // its parser hands data to this object
  GyroSweep& operator=(const GyroSweep&) = delete;
  // Reads the next message; false at the end.
  bool Step() { return parser_.Step(); }
  void RunToEnd() {
    while (parser_.Step()) continue;
  }
  double Fraction() const { return parser_.Fraction(); }
  void OnData(size_t sub_index, const Subscription& sub, std::string_view data) override {
    const auto it = std::find(subs_.begin(), subs_.end(), sub_index);
    if (it == subs_.end()) return;
    std::optional<TopicDecoder>& decoder = decoders_[it - subs_.begin()];
    if (!decoder) decoder = MakeTopicDecoder(sub.topic, sub.multi_id, *sub.layout);
    DecodeGyro(*decoder, data, emit_);
  }

 private:
  ULogParser parser_;
  std::vector<size_t> subs_;
  std::vector<std::optional<TopicDecoder>> decoders_;  // each subscription's, from its layout
  Emit emit_;
};

// What pass 1 hands to pass 2: the log without samples, and how to read and clean them.
struct ULogPass1 {
  FlightLog log;
  Sweeps sweeps;  // that read the chosen topic instance's samples
  std::optional<internal::CandidateSummary> chosen;
};

// Pass 1: the parse with every data message decoded, each gyro stream (topic instance) fed to the
// summary of its candidate, then the choice.
class ULogSummary final : public DataSink {
 public:
  ULogSummary(const ULogInput& input, const internal::CandidateLimits& limits)
      : input_(input), limits_(limits), parser_(input.bytes, input.path, this, input.file.get()) {}
  ULogSummary(const ULogSummary&) = delete;  // its parser hands data to this object
  ULogSummary& operator=(const ULogSummary&) = delete;
  // Throws IoError as ReadULog does.
  ULogPass1 Run();
  void OnData(size_t sub_index, const Subscription& sub, std::string_view data) override;

 private:
  // One topic instance's gyro candidate, fed in log order.
  struct GyroStream {
    std::optional<internal::CandidateSummary> summary;  // from its first sample on
    size_t last_sub = 0;                                // the subscription that fed it last
    bool interleaved = false;  // an earlier subscription fed it after a later one
  };
  struct SubState {
    bool resolved = false;
    TopicDecoder decoder;
    TopicRecords records;
    GyroStream* gyro = nullptr;  // a gyro topic's stream (std::map nodes stay put)
  };
  // A gyro topic instance as the choice sees it.
  struct Candidate {
    internal::CandidateSummary summary;
    Sweeps sweeps;
  };
  SubState& State(size_t sub_index, const Subscription& sub);
  // The stream's summary made again from its sweeps, named as its last subscription names it.
  internal::CandidateSummary Refeed(const Sweeps& sweeps, const TopicDecoder& last,
                                    const internal::CandidateLimits& limits) const;
  // The finished, exact summary of a stream; a disorder too deep for the limits makes it again
  // without (bounded: the summary that was not exact, for the warning).
  internal::CandidateSummary Finish(const Sweeps& sweeps, const TopicDecoder& last,
                                    GyroStream* stream,
                                    std::vector<internal::CandidateSummary>* bounded) const;
  // Everything but the gyro samples, gathered per topic instance in topic order, and the gyro
  // candidates in that order.
  DecodedTopics Gather(std::vector<Candidate>* candidates,
                       std::vector<internal::CandidateSummary>* bounded);

  const ULogInput& input_;
  internal::CandidateLimits limits_;
  ULogParser parser_;
  std::vector<SubState> subs_;  // by subscription index
  std::map<std::pair<std::string, int>, GyroStream> gyro_;
};

ULogSummary::SubState& ULogSummary::State(size_t sub_index, const Subscription& sub) {
  if (sub_index >= subs_.size()) subs_.resize(sub_index + 1);
  SubState& state = subs_[sub_index];
  if (!state.resolved) {
    state.resolved = true;
    state.decoder = MakeTopicDecoder(sub.topic, sub.multi_id, *sub.layout);
    if (state.decoder.gyro()) state.gyro = &gyro_[{sub.topic, sub.multi_id}];
  }
  return state;
}

void ULogSummary::OnData(size_t sub_index, const Subscription& sub, std::string_view data) {
  SubState& state = State(sub_index, sub);
  const TopicDecoder& d = state.decoder;
  if (!d.gyro()) {
    DecodeRecord(sub.topic, d, data, &state.records);
    return;
  }
  GyroStream& stream = *state.gyro;
  bool fed = false;
  const bool read =
      DecodeGyro(d, data, [&](const std::optional<int64_t>& t_ns, const Eigen::Vector3d& w) {
        if (!stream.summary) stream.summary.emplace(d.candidate_name, d.preference, limits_);
        stream.summary->Add(t_ns, w);
        fed = true;
      });
  if (!read) parser_.SkipData(sub.topic, 1);
  if (fed) {
    if (sub_index < stream.last_sub) stream.interleaved = true;
    stream.last_sub = sub_index;
  }
}

internal::CandidateSummary ULogSummary::Refeed(const Sweeps& sweeps, const TopicDecoder& last,
                                               const internal::CandidateLimits& limits) const {
  internal::CandidateSummary summary(last.candidate_name, last.preference, limits);
  for (const std::vector<size_t>& subs : sweeps) {
    GyroSweep(input_, subs, [&](const std::optional<int64_t>& t_ns, const Eigen::Vector3d& w) {
      summary.Add(t_ns, w);
    }).RunToEnd();
  }
  return summary;
}

internal::CandidateSummary ULogSummary::Finish(
    const Sweeps& sweeps, const TopicDecoder& last, GyroStream* stream,
    std::vector<internal::CandidateSummary>* bounded) const {
  // Fed in file order, which is the subscriptions' order unless their data interleave; named by
  // the first subscription that fed it, which is the last one's name unless a format changed.
  internal::CandidateSummary summary = stream->interleaved ||
                                               stream->summary->name() != last.candidate_name ||
                                               stream->summary->preference() != last.preference
                                           ? Refeed(sweeps, last, limits_)
                                           : std::move(*stream->summary);
  stream->summary.reset();
  summary.Finish();
  if (summary.exact()) return summary;
  bounded->push_back(std::move(summary));
  internal::CandidateSummary whole = Refeed(sweeps, last, internal::CandidateLimits::Unbounded());
  whole.Finish();
  return whole;
}

DecodedTopics ULogSummary::Gather(std::vector<Candidate>* candidates,
                                  std::vector<internal::CandidateSummary>* bounded) {
  DecodedTopics topics;
  // Subscriptions of the same topic and instance (a topic removed and added again) share one
  // stream.
  std::map<std::pair<std::string, int>, std::vector<size_t>> streams;
  const std::vector<Subscription>& subscriptions = parser_.subscriptions();
  for (size_t i = 0; i < subscriptions.size(); ++i) {
    const Subscription& sub = subscriptions[i];
    if (sub.layout && sub.has_data) streams[{sub.topic, sub.multi_id}].push_back(i);
  }
  for (const auto& [key, indices] : streams) {
    GyroStream* gyro = nullptr;
    const TopicDecoder* last_gyro = nullptr;
    std::vector<size_t> gyro_subs;
    for (size_t i : indices) {
      SubState& state = subs_[i];
      if (state.decoder.gyro()) {
        gyro = state.gyro;
        last_gyro = &state.decoder;
        gyro_subs.push_back(i);
        continue;
      }
      TopicRecords& r = state.records;
      topics.events.insert(topics.events.end(), r.events.begin(), r.events.end());
      topics.utc_fixes.insert(topics.utc_fixes.end(), r.utc_fixes.begin(), r.utc_fixes.end());
      topics.dist_bottom_m.insert(topics.dist_bottom_m.end(), r.dist_bottom_m.begin(),
                                  r.dist_bottom_m.end());
      topics.local_z_m.insert(topics.local_z_m.end(), r.local_z_m.begin(), r.local_z_m.end());
      if (r.last_z_m && std::isfinite(*r.last_z_m)) topics.home_z_m = r.last_z_m;
      r = TopicRecords();
    }
    // A stream none of whose messages gave a sample with a readable time is no candidate.
    if (!gyro || !gyro->summary) continue;
    Sweeps sweeps;
    if (gyro->interleaved) {
      for (size_t i : gyro_subs) sweeps.push_back({i});
    } else {
      sweeps.push_back(gyro_subs);
    }
    internal::CandidateSummary summary = Finish(sweeps, *last_gyro, gyro, bounded);
    candidates->push_back({std::move(summary), std::move(sweeps)});
  }
  return topics;
}

ULogPass1 ULogSummary::Run() {
  parser_.Start();
  while (parser_.Step()) continue;
  std::vector<Candidate> candidates;
  std::vector<internal::CandidateSummary> bounded;
  DecodedTopics topics = Gather(&candidates, &bounded);
  ULogPass1 out;
  FlightLog& log = parser_.log();
  std::stable_sort(topics.events.begin(), topics.events.end(),
                   [](const CameraEvent& a, const CameraEvent& b) { return a.t_ns < b.t_ns; });
  log.camera_events = std::move(topics.events);
  std::stable_sort(topics.utc_fixes.begin(), topics.utc_fixes.end(),
                   [](const UtcFix& a, const UtcFix& b) { return a.t_ns < b.t_ns; });
  log.utc_fixes = std::move(topics.utc_fixes);
  KeepOneCameraEventKind(&log);
  SetAltitudeAboveGround(topics, &log);
  std::vector<internal::CandidateSummary> summaries;
  for (Candidate& c : candidates) summaries.push_back(std::move(c.summary));
  const std::optional<size_t> chosen = internal::ChooseGyroSummary(summaries, &log);
  if (!chosen) {
    throw IoError(IoMessage(input_.path, 0,
                            "no usable gyro data (looked for sensor_gyro_fifo, sensor_gyro, "
                            "vehicle_angular_velocity, sensor_combined)"));
  }
  if (!bounded.empty()) log.warnings.push_back(internal::ReadInMemoryWarning(bounded));
  parser_.SummariseWarnings();
  out.log = std::move(log);
  out.sweeps = std::move(candidates[*chosen].sweeps);
  out.chosen = std::move(summaries[*chosen]);
  return out;
}

// Pass 2: the chosen stream's samples read again (its sweeps, in order) and cleaned, handed on in
// chunks.
class ULogGyroSource final : public FillingSource {
 public:
  ULogGyroSource(std::unique_ptr<ULogInput> input, ULogPass1* pass1, size_t chunk_samples)
      : FillingSource(chunk_samples),
        input_(std::move(input)),
        sweeps_(std::move(pass1->sweeps)),
        cleaner_(*pass1->chosen) {}
  double Fraction() const override {
    if (finished_ || sweeps_.empty()) return 1.0;
    const double done = sweep_ ? static_cast<double>(next_sweep_ - 1) + sweep_->Fraction()
                               : static_cast<double>(next_sweep_);
    return done / static_cast<double>(sweeps_.size());
  }

 protected:
  void Fill(std::vector<GyroSample>* chunk) override;

 private:
  // Refuses a file that is not the one pass 1 read (a log still being recorded).
  void CheckUnchanged() const;

  std::unique_ptr<ULogInput> input_;
  Sweeps sweeps_;
  internal::CandidateCleaner cleaner_;
  std::optional<GyroSweep> sweep_;
  size_t next_sweep_ = 0;
  bool finished_ = false;
  std::vector<GyroSample> ready_;  // cleaned samples from ready_begin_ on, not handed on yet
  size_t ready_begin_ = 0;
};

void ULogGyroSource::CheckUnchanged() const {
  if (!input_->file_size) return;
  std::error_code error;
  const uintmax_t now = std::filesystem::file_size(input_->path, error);
  if (error || now == *input_->file_size) return;
  throw IoError(
      IoMessage(input_->path, 0,
                "changed while it was read in passes (" + std::to_string(*input_->file_size) +
                    " bytes, now " + std::to_string(now) +
                    "): is it still being recorded? Analyse a copy, or the finished log"));
}

void ULogGyroSource::Fill(std::vector<GyroSample>* chunk) {
  CheckUnchanged();
  const size_t want = chunk_samples();
  while (ready_.size() - ready_begin_ < want && !finished_) {
    if (!sweep_) {
      if (next_sweep_ == sweeps_.size()) {
        finished_ = true;
        if (!cleaner_.Finish(&ready_)) {
          throw IoError(IoMessage(input_->path, 0,
                                  "its gyro samples read differently the second time: is it "
                                  "still being recorded? Analyse a copy, or the finished log"));
        }
        break;
      }
      sweep_.emplace(*input_, sweeps_[next_sweep_++],
                     [this](const std::optional<int64_t>& t_ns, const Eigen::Vector3d& w) {
                       cleaner_.Add(t_ns, w, &ready_);
                     });
    }
    if (!sweep_->Step()) sweep_.reset();
  }
  const size_t n = std::min(want, ready_.size() - ready_begin_);
  chunk->insert(chunk->end(), ready_.begin() + ready_begin_, ready_.begin() + ready_begin_ + n);
  ready_begin_ += n;
  if (ready_begin_ > want || ready_begin_ == ready_.size()) {
    ready_.erase(ready_.begin(), ready_.begin() + ready_begin_);
    ready_begin_ = 0;
  }
}

ULogStream Open(std::unique_ptr<ULogInput> input, size_t chunk_samples,
                const internal::CandidateLimits& limits = {}) {
  ULogPass1 pass1 = ULogSummary(*input, limits).Run();
  ULogStream stream;
  stream.gyro = std::make_unique<ULogGyroSource>(std::move(input), &pass1, chunk_samples);
  stream.log = std::move(pass1.log);
  return stream;
}

FlightLog ReadWhole(ULogStream stream) {
  FlightLog log = std::move(stream.log);
  log.gyro = ReadAllSamples(stream.gyro.get());
  for (LogWarning& warning : stream.gyro->Warnings()) log.warnings.push_back(std::move(warning));
  return log;
}

}  // namespace

bool LooksLikeULog(std::string_view first_bytes) {
  return first_bytes.size() >= sizeof(kMagic) &&
         std::memcmp(first_bytes.data(), kMagic, sizeof(kMagic)) == 0;
}

ULogStream OpenULog(const std::string& path, size_t chunk_samples) {
  auto input = std::make_unique<ULogInput>();
  input->path = path;
  input->file = std::make_unique<MappedFile>(path, MappedFile::Paging::kStreamed);
  input->bytes = input->file->text();
  std::error_code error;
  if (std::filesystem::is_regular_file(path, error)) input->file_size = input->bytes.size();
  return Open(std::move(input), chunk_samples);
}

ULogStream OpenULogBytes(std::string bytes, const std::string& path, size_t chunk_samples) {
  return internal::OpenULogBytes(std::move(bytes), path, chunk_samples, {});
}

namespace internal {
ULogStream OpenULogBytes(std::string bytes, const std::string& path, size_t chunk_samples,
                         const CandidateLimits& limits) {
  auto input = std::make_unique<ULogInput>();
  input->path = path;
  input->owned = std::move(bytes);
  input->bytes = input->owned;
  return Open(std::move(input), chunk_samples, limits);
}
}  // namespace internal

FlightLog ParseULog(std::string_view bytes, const std::string& path) {
  auto input = std::make_unique<ULogInput>();
  input->path = path;
  input->bytes = bytes;  // read whole within this call
  return ReadWhole(Open(std::move(input), FillingSource::kDefaultChunkSamples));
}

FlightLog ReadULog(const std::string& path) { return ReadWhole(OpenULog(path)); }

}  // namespace shutterlab
