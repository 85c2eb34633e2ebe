#include "sim/logs/ulog.h"

#include "sim/check.h"
#include "sim/logs/gyro_candidates.h"
#include "sim/logs/ulog_parser.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <unordered_map>
#include <utility>

namespace shutterlab {

namespace {

using ulog::DataSink;
using ulog::FlatField;
using ulog::IsGyroTopic;
using ulog::Layout;
using ulog::ReadNumber;
using ulog::ReadTimeNs;
using ulog::Subscription;
using ulog::ULogParser;

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
  enum class Kind { kNone, kGyroFifo, kGyroRates, kCamera, kLocalPosition, kGps, kHome, kAttitude };
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
  std::array<const FlatField*, 3> velocity{};  // vx, vy, vz: NED, m/s
  const FlatField *v_xy_valid = nullptr, *v_z_valid = nullptr;
  std::vector<const FlatField*> q;  // vehicle_attitude.q: w, x, y, z, FRD body to NED
  // vehicle_gps_position / sensor_gps: vel_n_m_s, vel_e_m_s, vel_d_m_s where vel_ned_valid
  std::array<const FlatField*, 3> gps_velocity{};
  const FlatField *gps_velocity_valid = nullptr, *fix_type = nullptr;
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
    d.velocity = {f.Find("vx"), f.Find("vy"), f.Find("vz")};
    d.v_xy_valid = f.Find("v_xy_valid");
    d.v_z_valid = f.Find("v_z_valid");
  } else if (topic == "vehicle_attitude") {
    d.kind = TopicDecoder::Kind::kAttitude;
    d.q = f.Array("q", 4);
  } else if (topic == "vehicle_gps_position" || topic == "sensor_gps") {
    d.kind = TopicDecoder::Kind::kGps;
    d.t = t_plain ? t_plain : d.t;
    d.utc = f.Find("time_utc_usec");
    d.gps_velocity = {f.Find("vel_n_m_s"), f.Find("vel_e_m_s"), f.Find("vel_d_m_s")};
    d.gps_velocity_valid = f.Find("vel_ned_valid");
    d.fix_type = f.Find("fix_type");
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
  std::vector<VelocitySample> velocity;
  std::vector<VelocitySample> gps_velocity;
  std::vector<AttitudeSample> attitude;  // one every kAttitudeStepNs at most
};

// vehicle_local_position's velocity when its flags say the horizontal part is valid (the
// vertical part NaN when v_z_valid says it is not); nullopt otherwise.
std::optional<Eigen::Vector3d> LocalVelocity(const TopicDecoder& d, std::string_view data) {
  if (!d.velocity[0] || !d.velocity[1] || !d.v_xy_valid || ReadNumber(data, *d.v_xy_valid) == 0.0)
    return std::nullopt;
  Eigen::Vector3d v(ReadNumber(data, *d.velocity[0]), ReadNumber(data, *d.velocity[1]),
                    std::numeric_limits<double>::quiet_NaN());
  if (d.velocity[2] && d.v_z_valid && ReadNumber(data, *d.v_z_valid) != 0.0)
    v.z() = ReadNumber(data, *d.velocity[2]);
  // Beyond any multirotor's or plane's speed: a corrupt message.
  if (!v.head<2>().allFinite() || v.head<2>().norm() > kMaxLogSpeedMps) return std::nullopt;
  if (std::abs(v.z()) > kMaxLogSpeedMps) v.z() = std::numeric_limits<double>::quiet_NaN();
  return v;
}

// The GPS receiver's velocity of a 3-D fix (fix_type 3 and above) where vel_ned_valid; nullopt
// otherwise.
std::optional<Eigen::Vector3d> GpsVelocity(const TopicDecoder& d, std::string_view data) {
  const auto& [n, e, down] = d.gps_velocity;
  if (!n || !e || !down || !d.gps_velocity_valid || ReadNumber(data, *d.gps_velocity_valid) == 0.0)
    return std::nullopt;
  if (d.fix_type && !(ReadNumber(data, *d.fix_type) >= 3.0)) return std::nullopt;
  const Eigen::Vector3d v(ReadNumber(data, *n), ReadNumber(data, *e), ReadNumber(data, *down));
  if (!v.allFinite() || v.norm() > kMaxLogSpeedMps) return std::nullopt;
  return v;
}

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
      const auto t_ns = ReadTimeNs(data, *d.t);
      if (const auto v = GpsVelocity(d, data); v && t_ns && *t_ns > 0)
        records->gps_velocity.push_back({*t_ns, *v});
      // The log time of a message with a UTC time (time_utc_usec, 0 until the receiver knows it).
      if (!d.utc) return;
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
      const auto t_ns = ReadTimeNs(data, *d.t);
      if (const auto v = LocalVelocity(d, data); v && t_ns && *t_ns > 0)
        records->velocity.push_back({*t_ns, *v});
      return;
    }
    case TopicDecoder::Kind::kAttitude: {
      const auto t_ns = ReadTimeNs(data, *d.t);
      if (d.q.size() != 4 || !t_ns || *t_ns <= 0) return;
      if (!records->attitude.empty() && *t_ns - records->attitude.back().t_ns < kAttitudeStepNs)
        return;
      const Eigen::Vector4d wxyz(ReadNumber(data, *d.q[0]), ReadNumber(data, *d.q[1]),
                                 ReadNumber(data, *d.q[2]), ReadNumber(data, *d.q[3]));
      // A unit quaternion (PX4 normalises it; anything far off is not an attitude).
      if (!wxyz.allFinite() || std::abs(wxyz.norm() - 1.0) > 0.01) return;
      records->attitude.push_back(
          {*t_ns, Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]).normalized()});
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
  std::vector<VelocitySample> velocity;
  std::vector<VelocitySample> gps_velocity;
  std::vector<AttitudeSample> attitude;
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

// The velocity (the estimator's, else the GPS receiver's) and the attitude, in time order, with
// their sources.
void SetNavigation(DecodedTopics topics, FlightLog* log) {
  auto by_time = [](const auto& a, const auto& b) { return a.t_ns < b.t_ns; };
  if (!topics.velocity.empty()) {
    log->velocity_source = "vehicle_local_position.vx,vy,vz (where v_xy_valid)";
  } else if (!topics.gps_velocity.empty()) {
    topics.velocity = std::move(topics.gps_velocity);
    log->velocity_source = "the GPS's vel_n_m_s,vel_e_m_s,vel_d_m_s (where vel_ned_valid)";
  }
  std::stable_sort(topics.velocity.begin(), topics.velocity.end(), by_time);
  std::stable_sort(topics.attitude.begin(), topics.attitude.end(), by_time);
  if (!topics.attitude.empty()) log->attitude_source = "vehicle_attitude.q";
  log->velocity = std::move(topics.velocity);
  log->attitude = std::move(topics.attitude);
}

// The bytes both passes read: a file mapped page by page (pages handed back behind the parse; a
// pipe's copied to a temporary file first), or bytes in memory (a caller's).
struct ULogInput {
  std::string path;
  std::unique_ptr<MappedFile> file;
  std::string owned;
  std::string_view bytes;
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
  // progress (may be empty): the share of the bytes read, every few thousand messages.
  ULogSummary(const ULogInput& input, const internal::CandidateLimits& limits,
              const OpeningProgress& progress)
      : input_(input),
        limits_(limits),
        progress_(progress),
        parser_(input.bytes, input.path, this, input.file.get()) {}
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
  const OpeningProgress& progress_;
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
      // One instance of each: the first that has samples (a second estimator's is not merged in).
      if (topics.velocity.empty()) topics.velocity = std::move(r.velocity);
      if (topics.gps_velocity.empty()) topics.gps_velocity = std::move(r.gps_velocity);
      if (topics.attitude.empty()) topics.attitude = std::move(r.attitude);
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
  for (size_t messages = 1; parser_.Step(); ++messages) {
    if (progress_ && messages % kOpeningProgressMessages == 0) progress_(parser_.Fraction());
  }
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
  SetNavigation(std::move(topics), &log);
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
  if (input_->file) input_->file->CheckUnchanged();
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
                const internal::CandidateLimits& limits = {},
                const OpeningProgress& progress = {}) {
  ULogPass1 pass1 = ULogSummary(*input, limits, progress).Run();
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
  return first_bytes.size() >= sizeof(ulog::kMagic) &&
         std::memcmp(first_bytes.data(), ulog::kMagic, sizeof(ulog::kMagic)) == 0;
}

ULogStream OpenULog(const std::string& path, size_t chunk_samples) {
  return OpenULog(std::make_unique<MappedFile>(path, MappedFile::Paging::kStreamed), chunk_samples);
}

ULogStream OpenULog(std::unique_ptr<MappedFile> file, size_t chunk_samples,
                    const OpeningProgress& progress) {
  auto input = std::make_unique<ULogInput>();
  input->path = file->path();
  input->bytes = file->text();
  input->file = std::move(file);
  return Open(std::move(input), chunk_samples, {}, progress);
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
