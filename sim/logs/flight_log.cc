#include "sim/logs/flight_log.h"

#include <algorithm>
#include <map>
#include <utility>

namespace shutterlab {

namespace {

// The samples around t_ns (i before, i + 1 after) and the fraction of the way between them; a
// time within kNavigationGapNs outside the samples takes the nearest (fraction 0 or 1, i == i + 1).
template <class Sample>
std::optional<std::pair<size_t, double>> Bracket(const std::vector<Sample>& samples, int64_t t_ns) {
  if (samples.empty()) return std::nullopt;
  const auto after = std::lower_bound(samples.begin(), samples.end(), t_ns,
                                      [](const Sample& s, int64_t t) { return s.t_ns < t; });
  if (after == samples.begin()) {
    if (samples.front().t_ns - t_ns > kNavigationGapNs) return std::nullopt;
    return std::make_pair(size_t{0}, 0.0);
  }
  if (after == samples.end()) {
    if (t_ns - samples.back().t_ns > kNavigationGapNs) return std::nullopt;
    return std::make_pair(samples.size() - 1, 0.0);
  }
  const size_t i = static_cast<size_t>(after - samples.begin()) - 1;
  const int64_t gap_ns = samples[i + 1].t_ns - samples[i].t_ns;
  if (gap_ns > kNavigationGapNs) return std::nullopt;
  return std::make_pair(i, gap_ns > 0 ? static_cast<double>(t_ns - samples[i].t_ns) / gap_ns : 0.0);
}

}  // namespace

std::optional<Eigen::Vector3d> VelocityAt(const std::vector<VelocitySample>& samples,
                                          int64_t t_ns) {
  const auto b = Bracket(samples, t_ns);
  if (!b) return std::nullopt;
  const auto [i, f] = *b;
  if (f == 0.0) return samples[i].ned_mps;
  return (1.0 - f) * samples[i].ned_mps + f * samples[i + 1].ned_mps;
}

std::optional<Eigen::Quaterniond> AttitudeAt(const std::vector<AttitudeSample>& samples,
                                             int64_t t_ns) {
  const auto b = Bracket(samples, t_ns);
  if (!b) return std::nullopt;
  const auto [i, f] = *b;
  if (f == 0.0) return samples[i].ned_from_body;
  return samples[i].ned_from_body.slerp(f, samples[i + 1].ned_from_body);
}

void KeepOneCameraEventKind(FlightLog* log) {
  std::map<std::string, size_t> counts;
  for (const CameraEvent& event : log->camera_events) ++counts[event.kind];
  if (counts.size() < 2) return;
  std::string kept;
  for (const char* kind : {"camera_capture", "CAM", "camera_trigger", "TRIG"}) {
    if (counts.count(kind)) {
      kept = kind;
      break;
    }
  }
  if (kept.empty()) {
    kept = std::max_element(counts.begin(), counts.end(), [](const auto& a, const auto& b) {
             return a.second < b.second;
           })->first;
  }
  std::string others;
  size_t dropped = 0;
  for (const auto& [kind, count] : counts) {
    if (kind == kept) continue;
    others += (others.empty() ? "" : ", ") + std::to_string(count) + " " + kind;
    dropped += count;
  }
  auto& events = log->camera_events;
  events.erase(std::remove_if(events.begin(), events.end(),
                              [&](const CameraEvent& e) { return e.kind != kept; }),
               events.end());
  log->warnings.push_back({"unused_source",
                           "camera events: used the " + std::to_string(counts[kept]) + " " + kept +
                               " events; " + others +
                               " not used (a picture may be recorded by both kinds)",
                           std::nullopt, dropped});
}

}  // namespace shutterlab
