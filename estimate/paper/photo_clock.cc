#include "estimate/paper/photo_clock.h"

#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/log_clock.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numeric>
#include <unordered_map>

namespace shutterlab {
namespace {

constexpr int64_t kVoteBinNs = 500'000'000;          // offset votes, 0.5 s bins
constexpr int64_t kQuarterHourNs = 900'000'000'000;  // time zones are whole quarter hours
constexpr size_t kMaxVotePairs = 4'000'000;          // photo x event pairs that vote

struct Event {
  std::optional<int64_t> log_ns, utc_ns;
  int64_t sequence = -1;
  std::string name;
};

struct Events {
  std::vector<Event> list;
  std::string text;       // where they came from
  bool numbered = false;  // the sequence is the photo's number (an .MRK)
};

// The time line capture times are matched on: UTC where the events have it (the offset is then the
// camera clock's zone and error), else the log's own clock (the offset is then the camera clock
// against the log's boot time: any number, one per flight).
enum class Base { kUtc, kLog };

std::optional<int64_t> EventNs(const Event& e, Base base) {
  return base == Base::kUtc ? e.utc_ns : e.log_ns;
}

// The camera clock's offset to a time base: capture time - offset = the exposure on that base.
struct Offset {
  int64_t ns = 0;
  Base base = Base::kUtc;
};

int64_t FloorDiv(int64_t a, int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

std::string Stem(const std::string& name) {
  return ToLower(std::filesystem::path(name).stem().string());
}

Events CollectEvents(const FlightLog& log, const TriggerFile* triggers,
                     const std::optional<LogUtcClock>& clock) {
  Events events;
  if (triggers) {
    events.text =
        "trigger file (" + triggers->format + ", " + TriggerClockName(triggers->clock) + ")";
    events.numbered = triggers->format == "mrk";
    for (const TriggerEvent& t : triggers->events) {
      Event e;
      e.sequence = t.sequence;
      e.name = t.name;
      if (triggers->clock == TriggerClock::kLog) e.log_ns = t.t_ns;
      if (triggers->clock == TriggerClock::kUtc) e.utc_ns = t.t_ns;
      if (triggers->clock == TriggerClock::kGps) e.utc_ns = UtcFromGpsNs(t.t_ns);
      events.list.push_back(std::move(e));
    }
  } else if (!log.camera_events.empty()) {
    // As analyze does: the most frequent kind (PX4 may log camera_trigger and camera_capture).
    std::map<std::string, size_t> kinds;
    for (const CameraEvent& c : log.camera_events) ++kinds[c.kind];
    const std::string kind = std::max_element(kinds.begin(), kinds.end(), [](auto& a, auto& b) {
                               return a.second < b.second;
                             })->first;
    events.text = "the log's camera events (" + kind + ")";
    for (const CameraEvent& c : log.camera_events) {
      if (c.kind != kind) continue;
      Event e;
      e.log_ns = c.t_ns;
      e.sequence = c.sequence;
      events.list.push_back(std::move(e));
    }
  }
  for (Event& e : events.list) {
    if (!clock) continue;
    if (e.log_ns && !e.utc_ns) e.utc_ns = clock->UtcNsFromLog(*e.log_ns);
    if (e.utc_ns && !e.log_ns) e.log_ns = clock->LogNsFromUtc(*e.utc_ns);
  }
  return events;
}

std::optional<int64_t> FaceNs(const PhotoRecord& r) {
  if (!r.ok() || !r.metadata.capture_time) return std::nullopt;
  return r.metadata.capture_time->face_ns;
}

double ToleranceS(const PhotoRecord& r) {
  return 0.5 * r.metadata.capture_time->resolution_s + 0.5;
}

using Pairs = std::vector<int>;  // event index per photo, -1: none

Pairs PairByName(const PhotoSet& set, const Events& events) {
  Pairs pairs(set.photos.size(), -1);
  std::map<std::string, int> by_stem;
  for (size_t j = 0; j < events.list.size(); ++j) {
    if (!events.list[j].name.empty())
      by_stem.emplace(Stem(events.list[j].name), static_cast<int>(j));
  }
  if (by_stem.empty()) return {};
  for (size_t i = 0; i < set.photos.size(); ++i) {
    const auto it = by_stem.find(Stem(set.photos[i].name));
    if (it != by_stem.end()) pairs[i] = it->second;
  }
  return pairs;
}

Pairs PairByNumber(const PhotoSet& set, const Events& events) {
  if (!events.numbered) return {};
  Pairs pairs(set.photos.size(), -1);
  std::map<int64_t, int> by_number;
  for (size_t j = 0; j < events.list.size(); ++j)
    by_number.emplace(events.list[j].sequence, static_cast<int>(j));
  for (size_t i = 0; i < set.photos.size(); ++i) {
    if (!set.photos[i].number) continue;
    const auto it = by_number.find(*set.photos[i].number);
    if (it != by_number.end()) pairs[i] = it->second;
  }
  return pairs;
}

// Each timed photo to the nearest event (by UTC) within its tolerance at camera offset offset_ns;
// one photo per event, the closer one kept.
Pairs MatchAtOffset(const PhotoSet& set, const Events& events, const std::vector<int>& by_time,
                    Offset offset) {
  Pairs pairs(set.photos.size(), -1);
  std::vector<int64_t> best_residual(events.list.size(), INT64_MAX);
  std::vector<int> owner(events.list.size(), -1);
  for (size_t i = 0; i < set.photos.size(); ++i) {
    const auto face = FaceNs(set.photos[i]);
    if (!face) continue;
    const int64_t target = *face - offset.ns;
    auto it = std::lower_bound(by_time.begin(), by_time.end(), target, [&](int j, int64_t t) {
      return *EventNs(events.list[j], offset.base) < t;
    });
    int best = -1;
    int64_t best_abs = INT64_MAX;
    for (auto c = it == by_time.begin() ? it : it - 1; c != by_time.end() && c <= it; ++c) {
      const int64_t r = std::llabs(target - *EventNs(events.list[*c], offset.base));
      if (r < best_abs) best_abs = r, best = *c;
    }
    if (best < 0 || best_abs > static_cast<int64_t>(ToleranceS(set.photos[i]) * 1e9)) continue;
    if (best_abs < best_residual[best]) {
      if (owner[best] >= 0) pairs[owner[best]] = -1;
      owner[best] = static_cast<int>(i);
      best_residual[best] = best_abs;
      pairs[i] = best;
    }
  }
  return pairs;
}

// The median of capture time - event time over the pairs with both; nullopt when none has.
std::optional<int64_t> MedianOffset(const PhotoSet& set, const Events& events, const Pairs& pairs,
                                    Base base) {
  // Relative to the first pair's, so that the doubles hold small numbers: exact to 1 ns.
  std::vector<double> d;
  std::optional<int64_t> first;
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (pairs[i] < 0 || !FaceNs(set.photos[i])) continue;
    const auto event_ns = EventNs(events.list[pairs[i]], base);
    if (!event_ns) continue;
    const int64_t offset = *FaceNs(set.photos[i]) - *event_ns;
    if (!first) first = offset;
    d.push_back(static_cast<double>(offset - *first));
  }
  if (!first) return std::nullopt;
  return *first + std::llround(Median(std::move(d)));
}

// Distance of an offset from the nearest whole quarter hour (a time zone), ns.
int64_t FromQuarterHour(int64_t offset_ns) {
  const int64_t r = ((offset_ns % kQuarterHourNs) + kQuarterHourNs) % kQuarterHourNs;
  return std::min(r, kQuarterHourNs - r);
}

Pairs PairByTime(const PhotoSet& set, const Events& events, Base base, int64_t* offset_ns) {
  std::vector<int> by_time;
  for (size_t j = 0; j < events.list.size(); ++j) {
    if (EventNs(events.list[j], base)) by_time.push_back(static_cast<int>(j));
  }
  std::vector<size_t> timed;
  for (size_t i = 0; i < set.photos.size(); ++i) {
    if (FaceNs(set.photos[i])) timed.push_back(i);
  }
  if (by_time.empty() || timed.empty()) return {};
  std::sort(by_time.begin(), by_time.end(), [&](int a, int b) {
    return *EventNs(events.list[a], base) < *EventNs(events.list[b], base);
  });
  // Votes: every photo x event difference, in bins (photos thinned for very large sets).
  const size_t stride = std::max<size_t>(1, timed.size() * by_time.size() / kMaxVotePairs);
  std::unordered_map<int64_t, int> votes;
  for (size_t k = 0; k < timed.size(); k += stride) {
    const int64_t face = *FaceNs(set.photos[timed[k]]);
    for (int j : by_time) ++votes[FloorDiv(face - *EventNs(events.list[j], base), kVoteBinNs)];
  }
  auto count_at = [&votes](int64_t bin) {
    const auto it = votes.find(bin);
    return it == votes.end() ? 0 : it->second;
  };
  int64_t best_bin = 0;
  int best_score = -1;
  for (const auto& vote : votes) {
    const int64_t bin = vote.first;
    const int score = count_at(bin - 1) + vote.second + count_at(bin + 1);
    // Ties: nearer a whole quarter hour (a time zone, against UTC), then the smaller offset.
    const int64_t zone_gap = base == Base::kUtc ? FromQuarterHour(bin * kVoteBinNs) : 0;
    const int64_t best_gap = base == Base::kUtc ? FromQuarterHour(best_bin * kVoteBinNs) : 0;
    const bool better =
        score > best_score ||
        (score == best_score && (zone_gap < best_gap || (zone_gap == best_gap && bin < best_bin)));
    if (better) best_score = score, best_bin = bin;
  }
  Pairs pairs = MatchAtOffset(set, events, by_time, {best_bin * kVoteBinNs + kVoteBinNs / 2, base});
  *offset_ns = MedianOffset(set, events, pairs, base).value_or(0);
  pairs = MatchAtOffset(set, events, by_time, {*offset_ns, base});
  *offset_ns = MedianOffset(set, events, pairs, base).value_or(0);
  return pairs;
}

size_t Count(const Pairs& pairs) {
  return static_cast<size_t>(
      std::count_if(pairs.begin(), pairs.end(), [](int j) { return j >= 0; }));
}

// The camera zone when nothing else gives it: the one quarter hour that puts every timed photo
// inside the log's GPS span (1 min of margin). nullopt with *problem when none or several do.
std::optional<int64_t> SearchZone(const PhotoSet& set, const LogUtcClock& clock,
                                  std::string* problem) {
  const int64_t first_utc = clock.UtcNsFromLog(clock.first_t_ns) - 60 * kNsPerSecond;
  const int64_t last_utc = clock.UtcNsFromLog(clock.last_t_ns) + 60 * kNsPerSecond;
  std::vector<int64_t> fits;
  for (int64_t k = -48; k <= 56; ++k) {  // UTC-12:00 .. UTC+14:00
    bool all = true, any = false;
    for (const PhotoRecord& r : set.photos) {
      const auto face = FaceNs(r);
      if (!face) continue;
      any = true;
      const int64_t utc = *face - k * kQuarterHourNs;
      all = all && utc >= first_utc && utc <= last_utc;
    }
    if (any && all) fits.push_back(k * kQuarterHourNs);
  }
  if (fits.size() == 1) return fits[0];
  *problem = fits.empty() ? "no time zone puts the capture times inside the log's GPS time"
                          : std::to_string(fits.size()) +
                                " time zones put the capture times inside the log: give "
                                "--photo-utc-offset";
  return std::nullopt;
}

std::string OffsetText(int64_t offset_ns) {
  const int64_t zone = (offset_ns + (offset_ns >= 0 ? kQuarterHourNs / 2 : -kQuarterHourNs / 2)) /
                       kQuarterHourNs * kQuarterHourNs;
  return UtcOffsetText(static_cast<int>(zone / kNsPerSecond)) +
         FormatNumber(" %+.3f s", (offset_ns - zone) * 1e-9);
}

// The pairing: the first rule that pairs any photo; *offset is the camera clock's offset where any
// pair has both times: to UTC when the events have it, else to the log's clock (an offset free
// to be anything, found by the same vote: the pattern of the capture times against the events').
Pairs PairPhotos(const PhotoSet& set, const Events& events, std::string* rule,
                 std::optional<Offset>* offset) {
  const Base base =
      std::any_of(events.list.begin(), events.list.end(), [](const Event& e) { return e.utc_ns; })
          ? Base::kUtc
          : Base::kLog;
  Pairs pairs;
  if (!events.list.empty()) {
    int64_t o = 0;
    if (Count(pairs = PairByName(set, events)) > 0) {
      *rule = "by name";
    } else if (Count(pairs = PairByNumber(set, events)) > 0) {
      *rule = "by photo number";
    } else if (Count(pairs = PairByTime(set, events, base, &o)) > 0) {
      *rule = base == Base::kUtc ? "by capture time" : "by capture time on the log's clock";
      *offset = Offset{o, base};
    } else if (events.list.size() == set.photos.size()) {
      pairs.resize(set.photos.size());
      std::iota(pairs.begin(), pairs.end(), 0);
      *rule = "in order (as many photos as events)";
    } else {
      pairs.clear();
    }
  }
  pairs.resize(set.photos.size(), -1);
  if (!*offset) {
    if (const auto o = MedianOffset(set, events, pairs, base)) *offset = Offset{*o, base};
  }
  return pairs;
}

// Paired photos take their event's time; the residual of their capture time where both are known.
void PlacePaired(const PhotoSet& set, const Events& events, const Pairs& pairs,
                 const std::string& rule, const std::optional<Offset>& offset, PhotoClock* out,
                 std::vector<double>* residuals) {
  for (size_t i = 0; i < set.photos.size(); ++i) {
    PhotoPlacement& p = out->placements[i];
    if (pairs[i] < 0) continue;
    const Event& e = events.list[pairs[i]];
    const std::string id =
        e.name.empty() ? (e.sequence >= 0 ? " #" + std::to_string(e.sequence) : "") : " " + e.name;
    if (!e.log_ns) {
      p.problem =
          "its event (" + events.text + id + ") is not on the log's clock: the log has no GPS time";
      continue;
    }
    p.t_ns = e.log_ns;
    p.method = events.text + id + ", " + rule;
    ++out->paired;
    if (offset && FaceNs(set.photos[i]) && EventNs(e, offset->base)) {
      p.residual_s = (*FaceNs(set.photos[i]) - offset->ns - *EventNs(e, offset->base)) * 1e-9;
      residuals->push_back(*p.residual_s);
    }
  }
}

// The camera clock's zone for photos placed by capture time alone, decided once.
struct Zone {
  std::optional<int64_t> log_offset_ns;  // camera clock - log clock, fitted: no GPS time needed
  std::optional<int64_t> ns;             // given: the fitted offset or --photo-utc-offset
  std::string text;
  std::optional<int64_t> found;  // searched, for photos without OffsetTimeOriginal
  std::string found_text, problem;
  bool searched = false;
};

// The photos left: capture time -> UTC (by the zone) -> the log's clock.
void PlaceByCaptureTime(const PhotoSet& set, const Events& events,
                        const std::optional<LogUtcClock>& clock, Zone zone, PhotoClock* out) {
  for (size_t i = 0; i < set.photos.size(); ++i) {
    PhotoPlacement& p = out->placements[i];
    if (p.t_ns || !p.problem.empty()) continue;
    const PhotoRecord& r = set.photos[i];
    if (!r.ok()) {
      p.problem = "unreadable";
      continue;
    }
    if (!FaceNs(r)) {
      p.problem = "no event and no capture time";
      continue;
    }
    if (zone.log_offset_ns) {
      p.t_ns = *FaceNs(r) - *zone.log_offset_ns;
      p.method =
          FormatNumber("capture time (+-%g s)", 0.5 * r.metadata.capture_time->resolution_s) +
          " through the camera clock's fitted offset to the log's clock";
      continue;
    }
    if (!clock) {
      p.problem = std::string(events.list.empty() ? "no event" : "no matching event") +
                  ", and the log has no GPS time for the capture time";
      continue;
    }
    std::optional<int64_t> utc;
    std::string how;
    if (zone.ns) {
      utc = *FaceNs(r) - *zone.ns;
      how = zone.text;
    } else if (const auto own = r.metadata.capture_time->UtcNs()) {
      utc = own;
      how = "EXIF OffsetTimeOriginal";
    } else {
      if (!zone.searched) {
        zone.searched = true;
        if ((zone.found = SearchZone(set, *clock, &zone.problem))) {
          zone.found_text = "camera zone UTC" +
                            UtcOffsetText(static_cast<int>(*zone.found / kNsPerSecond)) +
                            " (the only one that puts every photo inside the log)";
        }
      }
      if (zone.found) {
        utc = *FaceNs(r) - *zone.found;
        how = zone.found_text;
      }
    }
    if (!utc) {
      p.problem = zone.problem;
      continue;
    }
    p.t_ns = clock->LogNsFromUtc(*utc);
    p.method = FormatNumber("capture time (+-%g s)", 0.5 * r.metadata.capture_time->resolution_s) +
               " through the log's GPS time, " + how;
  }
}

std::string MethodText(const PhotoClock& out, const Events& events, const std::string& rule,
                       const std::optional<Offset>& offset,
                       const std::optional<LogUtcClock>& clock) {
  std::string method;
  if (out.paired > 0)
    method = std::to_string(out.paired) + " paired with " + events.text + " " + rule;
  if (out.placed > out.paired) {
    method += (method.empty() ? "" : "; ") + std::to_string(out.placed - out.paired) +
              (offset && offset->base == Base::kLog
                   ? " by capture time through the camera clock's offset to the log's clock"
                   : " by capture time through the log's GPS time");
  }
  if (method.empty()) {
    method = events.list.empty() ? "no camera events" : "no photo matched " + events.text;
    if (!clock) method += ", and the log has no GPS time";
  }
  if (offset && offset->base == Base::kUtc) method += "; camera clock UTC" + OffsetText(offset->ns);
  if (offset && offset->base == Base::kLog)
    method += FormatNumber("; camera clock - log clock %.3f s", offset->ns * 1e-9);
  if (clock) {
    method +=
        FormatNumber("; log clock to UTC from %.0f GPS fixes", static_cast<double>(clock->fixes)) +
        FormatNumber(" (rms %.1f ms)", clock->rms_residual_s * 1e3);
  }
  return method;
}

}  // namespace

void PhotoClockOptions::Check() const {
  SHUTTERLAB_CHECK(!camera_utc_offset_s || std::abs(*camera_utc_offset_s) <= 14 * 3600)
      << "camera UTC offset must be within -14:00..+14:00";
}

PhotoClock PlacePhotos(const PhotoSet& set, const FlightLog& log, const TriggerFile* triggers,
                       const PhotoClockOptions& options) {
  options.Check();
  const std::optional<LogUtcClock> clock = FitLogUtcClock(log.utc_fixes);
  const Events events = CollectEvents(log, triggers, clock);
  PhotoClock out;
  out.placements.resize(set.photos.size());
  std::string rule;
  std::optional<Offset> offset;
  const Pairs pairs = PairPhotos(set, events, &rule, &offset);
  std::vector<double> residuals;
  PlacePaired(set, events, pairs, rule, offset, &out, &residuals);

  // The zone for the rest: the fitted offset, else --photo-utc-offset, else each photo's own
  // OffsetTimeOriginal, else the search.
  Zone zone;
  if (offset && offset->base == Base::kLog) {
    zone.log_offset_ns = offset->ns;
  } else if (offset) {
    zone.ns = offset->ns;
    zone.text = "the fitted camera clock offset";
  } else if (options.camera_utc_offset_s) {
    zone.ns = *options.camera_utc_offset_s * kNsPerSecond;
    zone.text = "--photo-utc-offset";
  }
  PlaceByCaptureTime(set, events, clock, zone, &out);

  for (const PhotoPlacement& p : out.placements) out.placed += p.t_ns.has_value();
  if (offset) {
    out.clock_offset_s = offset->ns * 1e-9;
    out.clock_offset_to = offset->base == Base::kUtc ? "UTC" : "log clock";
  }
  if (!residuals.empty()) {
    double sum_sq = 0, max_abs = 0;
    for (double r : residuals) sum_sq += r * r, max_abs = std::max(max_abs, std::abs(r));
    out.residual_rms_s = std::sqrt(sum_sq / residuals.size());
    out.residual_max_s = max_abs;
  }
  out.method = MethodText(out, events, rule, offset, clock);
  return out;
}

}  // namespace shutterlab
