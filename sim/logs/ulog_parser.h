#pragma once
// The message layer of the PX4 ULog reader (sim/logs/ulog.h): the file header and flag bits,
// format definitions flattened into field layouts, subscriptions, appended-data segments, dropouts,
// and the resynchronisation past corrupt stretches. One parse loop, message by message, that hands
// each data message of a topic the reader decodes to a DataSink; every pass over a file is a fresh
// parser over the same bytes. Internal to the reader.

#include "sim/logs/flight_log.h"
#include "sim/text_file.h"

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace shutterlab {
namespace ulog {

// A ULog file's first seven bytes: "ULog" 0x01 0x12 0x35.
inline constexpr char kMagic[7] = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35};

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
  // fields' "timestamp", looked up once: a gyro topic's every data message reads it, and the lookup
  // by name was a tenth of a 10 MB log's parse.
  std::optional<FlatField> timestamp;
  size_t min_bytes = 0;  // up to the end of the last field that is not trailing _padding
  size_t max_bytes = 0;  // with trailing padding
};

using FormatMap = std::unordered_map<std::string, std::vector<FieldDef>>;

// Reads a field as a double; NaN when it lies outside data.
double ReadNumber(std::string_view data, const FlatField& f);
// Reads an integer microsecond time as ns; nullopt for a non-integer field, out of range, or
// outside data.
std::optional<int64_t> ReadTimeNs(std::string_view data, const FlatField& f);

struct Subscription {
  std::string topic;
  int multi_id = 0;
  std::shared_ptr<const Layout> layout;  // null when the format could not be resolved
  bool has_data = false;                 // a data message of a wanted topic came (with a layout)
  bool gyro_topic = false;  // IsGyroTopic(topic), cached: tested for every data message
  bool wanted = false;      // WantedTopic(topic), cached
};

// The four topics the gyro may come from (sensor_gyro_fifo, sensor_gyro, vehicle_angular_velocity,
// sensor_combined).
bool IsGyroTopic(const std::string& topic);

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
  std::string Where(size_t offset) const;
  [[noreturn]] void Fail(size_t offset, const std::string& problem) const;
  // A warning of the parser's own kind (appended, flags, msg_id, ...): the first few of each kind
  // in full, the rest counted (SummariseWarnings).
  void Warn(const std::string& kind, size_t offset, const std::string& text);

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
  // The subscription of msg_id, index into subscriptions_; -1 when none.
  int SubscriptionIndex(uint16_t msg_id) const {
    return msg_id < by_msg_id_.size() ? by_msg_id_[msg_id] : -1;
  }
  // For a 'D' payload: its topic's layout is known, so DataSizeFits was a real check.
  bool SizeCheckedAgainstFormat(std::string_view payload) const;
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
  // subscriptions_'s index by msg_id (-1: none), up to the largest subscribed: looked up for every
  // data message, twice (a hash map's lookup was a tenth of a 10 MB log's parse).
  std::vector<int> by_msg_id_;
  std::vector<uint64_t> appended_offsets_;
  int max_msg_id_ = -1;  // largest msg_id subscribed so far
  std::map<std::string, size_t> warning_counts_;
  std::map<std::string, size_t> skipped_by_topic_;
  std::vector<std::pair<uint64_t, uint16_t>>
      dropouts_;  // (gyro-topic timestamp before it, us; duration ms)
  uint64_t last_timestamp_us_ = 0;
  size_t skipped_bytes_ = 0;
};

}  // namespace ulog
}  // namespace shutterlab
