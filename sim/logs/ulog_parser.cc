#include "sim/logs/ulog_parser.h"

#include "sim/check.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <limits>

namespace shutterlab {
namespace ulog {
namespace {

// The contract's warning kind (docs/FORMATS.md "Warnings") for one of the parser's own.
std::string WarningKind(const std::string& parser_kind) {
  if (parser_kind == "truncated" || parser_kind == "corrupt") return parser_kind;
  return "format";  // appended data, format definitions, subscriptions, flag bits
}

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

// Flattens a (possibly nested) format into out; returns an error text or "". Without names, only
// the sizes: a topic the reader does not keep needs no field map (building one, a string per array
// element, was most of the cost of a subscription), yet its sizes and errors are the same.
std::string Flatten(const FormatMap& formats, const std::string& type, const std::string& prefix,
                    int depth, bool with_names, size_t* fields, size_t* offset, Layout* out) {
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
      const std::string name =
          with_names ? prefix + f.name + (f.count > 1 ? "[" + std::to_string(i) + "]" : "") : "";
      if (scalar) {
        if (*fields >= kMaxFlatFields) return "too many fields";
        // emplace keeps the first of two fields of one name, which still counts
        if (with_names) out->fields.emplace(name, FlatField{scalar->first, *offset});
        ++*fields;
        *offset += scalar->second;
      } else {
        const size_t before = *offset;
        const std::string err = Flatten(formats, f.type, with_names ? name + "." : "", depth + 1,
                                        with_names, fields, offset, out);
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

// Topics whose data the reader keeps.
bool WantedTopic(const std::string& topic) {
  static const char* kTopics[] = {
      "sensor_gyro_fifo",     "sensor_gyro",    "vehicle_angular_velocity", "sensor_combined",
      "camera_trigger",       "camera_capture", "vehicle_local_position",   "home_position",
      "vehicle_gps_position", "sensor_gps",     "vehicle_attitude"};
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

}  // namespace

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

bool IsGyroTopic(const std::string& topic) {
  return topic == "sensor_gyro_fifo" || topic == "sensor_gyro" ||
         topic == "vehicle_angular_velocity" || topic == "sensor_combined";
}

std::string ULogParser::Where(size_t offset) const {
  return IoMessage(path_, 0, "byte " + std::to_string(offset) + ": ");
}

void ULogParser::Fail(size_t offset, const std::string& problem) const {
  throw IoError(Where(offset) + problem);
}

void ULogParser::Warn(const std::string& kind, size_t offset, const std::string& text) {
  size_t& count = warning_counts_[kind];
  ++count;
  if (count <= kMaxDetailedWarnings)
    log_.warnings.push_back({WarningKind(kind), "byte " + std::to_string(offset) + ": " + text});
}

bool ULogParser::SizeCheckedAgainstFormat(std::string_view payload) const {
  const int index = SubscriptionIndex(LoadU16(payload.data()));
  return index >= 0 && subscriptions_[index].layout != nullptr;
}

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
      const int index = SubscriptionIndex(msg_id);
      // An id that was never subscribed may still be real when its 'A' was damaged; PX4 numbers
      // subscriptions from 0 upwards, so only ids near the known ones are believed.
      if (index < 0) return msg_id == pending_id || msg_id <= max_msg_id_ + kMsgIdSlack;
      const Layout* layout = subscriptions_[index].layout.get();
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
  size_t offset = 0, fields = 0;
  *error = Flatten(formats_, topic, "", 0, WantedTopic(topic), &fields, &offset, layout.get());
  if (!error->empty()) return nullptr;
  if (auto ts = layout->fields.find("timestamp"); ts != layout->fields.end())
    layout->timestamp = ts->second;
  layouts_.emplace(topic, layout);
  return layout;
}

bool ULogParser::DataSizeFits(std::string_view payload) const {
  const int index = SubscriptionIndex(LoadU16(payload.data()));
  if (index < 0) return true;  // judged by the header after it; Handle skips it
  const Subscription& sub = subscriptions_[index];
  if (!sub.layout) return true;
  const size_t bytes = payload.size() - 2;
  return bytes >= sub.layout->min_bytes && bytes <= sub.layout->max_bytes;
}

std::string ULogParser::DataMismatch(std::string_view payload) const {
  const uint16_t msg_id = LoadU16(payload.data());
  const int index = SubscriptionIndex(msg_id);
  if (index < 0) return "data message for unsubscribed msg_id " + std::to_string(msg_id);
  const Subscription& sub = subscriptions_[index];
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
      if (msg_id >= by_msg_id_.size()) by_msg_id_.resize(msg_id + 1, -1);
      by_msg_id_[msg_id] = static_cast<int>(subscriptions_.size());
      max_msg_id_ = std::max<int>(max_msg_id_, msg_id);
      subscriptions_.push_back(std::move(sub));
      return;
    }
    case 'R': {
      const uint16_t msg_id = LoadU16(payload.data());
      if (msg_id < by_msg_id_.size()) by_msg_id_[msg_id] = -1;
      return;
    }
    case 'D': {
      // The main loop has checked the size against the format (DataSizeFits).
      const uint16_t msg_id = LoadU16(payload.data());
      const int index = SubscriptionIndex(msg_id);
      if (index < 0) {
        ++log_.records_skipped;
        Warn("msg_id", offset,
             "data message for unsubscribed msg_id " + std::to_string(msg_id) + " skipped");
        return;
      }
      Subscription& sub = subscriptions_[index];
      if (!sub.layout) {
        ++log_.records_skipped;
        ++skipped_by_topic_[sub.topic];
        return;
      }
      const std::string_view data = payload.substr(2);
      // A dropout is placed at the time of the last gyro-topic message before it: these come at
      // hundreds of Hz, and a single odd timestamp in a slow topic cannot drag the time away.
      if (sub.gyro_topic && sub.layout->timestamp) {
        if (auto t_ns = ReadTimeNs(data, *sub.layout->timestamp))
          last_timestamp_us_ = static_cast<uint64_t>(*t_ns / 1000);
      }
      if (sub.wanted) {
        sub.has_data = true;
        sink_->OnData(static_cast<size_t>(index), sub, data);
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
  if (bytes_.substr(0, sizeof(kMagic)) != std::string_view(kMagic, sizeof(kMagic)))
    Fail(0, "not a ULog file (bad magic)");
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

}  // namespace ulog
}  // namespace shutterlab
