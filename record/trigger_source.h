#pragma once
// Camera trigger edges (hot-shoe, flash sync, an autopilot's trigger output) on the recorder's
// clock. A TriggerSource hands over edges with the time they happened, stamped where they happened
// (the kernel's GPIO interrupt for a real line), so the time a thread takes to collect them does
// not enter. The GPIO backend is record/gpio_trigger.h; tests and `record --trigger emulate:`
// use EmulatedTriggerLine.

#include "record/clock.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct TriggerEdge {
  int64_t t_ns = 0;  // on the recorder's clock
  bool rising = true;
};

class TriggerSource {
 public:
  virtual ~TriggerSource() = default;
  // Waits until deadline_ns (the recorder's clock) at most, and appends the edges that happened
  // by then, oldest first. May return early with edges.
  virtual void WaitEdges(int64_t deadline_ns, std::vector<TriggerEdge>* edges) = 0;
  virtual std::string Name() const = 0;
};

enum class TriggerPolarity { kRising, kFalling, kBoth };
// "rising", "falling", "both"; throws std::invalid_argument otherwise.
TriggerPolarity ParseTriggerPolarity(const std::string& text);
const char* TriggerPolarityName(TriggerPolarity polarity);

// Which edges become triggers. Debounce: after an accepted edge, every edge within debounce_ns
// is contact bounce and ignored, whichever its direction; then only edges of the polarity count.
class TriggerFilter {
 public:
  TriggerFilter(TriggerPolarity polarity, int64_t debounce_ns);
  // True when the edge is a trigger.
  bool Accept(const TriggerEdge& edge);
  size_t bounces() const { return bounces_; }                // edges ignored as bounce
  size_t other_polarity() const { return other_polarity_; }  // edges of the other direction

 private:
  TriggerPolarity polarity_;
  int64_t debounce_ns_;
  std::optional<int64_t> last_edge_ns_;
  size_t bounces_ = 0, other_polarity_ = 0;
};

// A line that replays pulses: a rising edge at origin + t, a falling edge width_ns later, and
// `bounce` extra edge pairs in the first 200 us after each edge, as a mechanical contact gives.
// origin() gives the clock time that pulse times count from once it is known (the emulated
// sensor's play origin, so that the pulses sit where the trace's camera triggers were);
// nothing happens before it is.
class EmulatedTriggerLine : public TriggerSource {
 public:
  EmulatedTriggerLine(std::vector<int64_t> pulse_times_ns, int64_t width_ns, int bounce,
                      std::function<std::optional<int64_t>()> origin, Clock* clock);
  void WaitEdges(int64_t deadline_ns, std::vector<TriggerEdge>* edges) override;
  std::string Name() const override { return "emulated trigger line"; }

 private:
  std::vector<TriggerEdge> relative_edges_;  // sorted, times relative to the origin
  size_t next_ = 0;
  std::function<std::optional<int64_t>()> origin_;
  Clock* clock_;
};

// Pulse times every every_s seconds, from every_s up to duration_s (ns, relative to the origin).
std::vector<int64_t> PulsesEvery(double every_s, double duration_s);

}  // namespace shutterlab
