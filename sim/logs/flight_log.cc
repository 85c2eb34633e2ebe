#include "sim/logs/flight_log.h"

#include <algorithm>
#include <map>

namespace shutterlab {

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
