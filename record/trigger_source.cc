#include "record/trigger_source.h"

#include "sim/check.h"
#include "sim/gyro_trace.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {

TriggerPolarity ParseTriggerPolarity(const std::string& text) {
  if (text == "rising") return TriggerPolarity::kRising;
  if (text == "falling") return TriggerPolarity::kFalling;
  if (text == "both") return TriggerPolarity::kBoth;
  throw std::invalid_argument("edge polarity must be rising, falling or both, got '" + text + "'");
}

const char* TriggerPolarityName(TriggerPolarity polarity) {
  switch (polarity) {
    case TriggerPolarity::kRising:
      return "rising";
    case TriggerPolarity::kFalling:
      return "falling";
    case TriggerPolarity::kBoth:
      return "both";
  }
  return "rising";
}

TriggerFilter::TriggerFilter(TriggerPolarity polarity, int64_t debounce_ns)
    : polarity_(polarity), debounce_ns_(debounce_ns) {
  SHUTTERLAB_CHECK(debounce_ns >= 0) << "debounce must not be negative";
}

bool TriggerFilter::Accept(const TriggerEdge& edge) {
  if (last_edge_ns_ && edge.t_ns - *last_edge_ns_ < debounce_ns_) {
    ++bounces_;
    return false;
  }
  last_edge_ns_ = edge.t_ns;
  const bool wanted =
      polarity_ == TriggerPolarity::kBoth || (polarity_ == TriggerPolarity::kRising) == edge.rising;
  if (!wanted) ++other_polarity_;
  return wanted;
}

EmulatedTriggerLine::EmulatedTriggerLine(std::vector<int64_t> pulse_times_ns, int64_t width_ns,
                                         int bounce, std::function<std::optional<int64_t>()> origin,
                                         Clock* clock)
    : origin_(std::move(origin)), clock_(clock) {
  SHUTTERLAB_CHECK(width_ns > 0 && bounce >= 0 && clock_ != nullptr)
      << "pulse width > 0, bounce >= 0 and a clock";
  for (int64_t t : pulse_times_ns) {
    for (const bool rising : {true, false}) {
      const int64_t edge_ns = rising ? t : t + width_ns;
      relative_edges_.push_back({edge_ns, rising});
      // Bounce: the contact opens and closes again within 200 us of the edge, each opening 20 us
      // before it closes, or halfway from the last edge where bounces are closer (so that every
      // bounce follows its edge, up to the 99 `record --trigger` allows).
      const int64_t open_ns = std::min<int64_t>(20000, 200000 / (bounce + 1) / 2);
      for (int b = 1; b <= bounce; ++b) {
        const int64_t at = edge_ns + b * 200000 / (bounce + 1);
        relative_edges_.push_back({at - open_ns, !rising});
        relative_edges_.push_back({at, rising});
      }
    }
  }
  std::stable_sort(relative_edges_.begin(), relative_edges_.end(),
                   [](const TriggerEdge& a, const TriggerEdge& b) { return a.t_ns < b.t_ns; });
}

void EmulatedTriggerLine::WaitEdges(int64_t deadline_ns, std::vector<TriggerEdge>* edges) {
  const std::optional<int64_t> origin = origin_();
  int64_t wake_ns = deadline_ns;
  if (origin && next_ < relative_edges_.size()) {
    wake_ns = std::min(wake_ns, *origin + relative_edges_[next_].t_ns);
  }
  clock_->SleepUntilNs(wake_ns);
  if (!origin) return;
  const int64_t now_ns = clock_->NowNs();
  while (next_ < relative_edges_.size() && *origin + relative_edges_[next_].t_ns <= now_ns) {
    edges->push_back({*origin + relative_edges_[next_].t_ns, relative_edges_[next_].rising});
    ++next_;
  }
}

std::vector<int64_t> PulsesEvery(double every_s, double duration_s) {
  SHUTTERLAB_CHECK(every_s > 0 && std::isfinite(every_s)) << "trigger cadence must be positive";
  std::vector<int64_t> pulses;
  for (int64_t k = 1; k * every_s <= duration_s + 1e-9; ++k)
    pulses.push_back(SecondsToNs(k * every_s));
  return pulses;
}

}  // namespace shutterlab
