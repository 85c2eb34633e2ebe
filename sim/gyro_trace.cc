#include "sim/gyro_trace.h"

#include <algorithm>
#include <cmath>

#include "sim/check.h"

namespace shutterlab {

GyroTrace::GyroTrace(std::vector<GyroSample> samples) : samples_(std::move(samples)) {
  std::vector<int64_t> intervals;
  intervals.reserve(samples_.empty() ? 0 : samples_.size() - 1);
  for (size_t i = 0; i < samples_.size(); ++i) {
    SHUTTERLAB_CHECK(samples_[i].omega_rad_s.allFinite())
        << "gyro sample " << i << " has a non-finite rate";
    if (i == 0) continue;
    const int64_t dt = samples_[i].t_ns - samples_[i - 1].t_ns;
    SHUTTERLAB_CHECK(dt >= 0) << "gyro sample " << i << " goes back in time by " << -dt * 1e-9
                              << " s";
    if (dt == 0) ++sampling_.duplicate_timestamps;
    intervals.push_back(dt);
  }
  if (intervals.empty()) return;
  std::vector<int64_t> sorted = intervals;
  auto mid = sorted.begin() + sorted.size() / 2;
  std::nth_element(sorted.begin(), mid, sorted.end());
  sampling_.median_interval_ns = *mid;
  const double gap_ns = SamplingReport::kGapFactor * static_cast<double>(*mid);
  for (size_t k = 0; k < intervals.size(); ++k) {
    if (static_cast<double>(intervals[k]) > gap_ns) sampling_.gap_indices.push_back(k);
  }
}

size_t GyroTrace::LowerBound(int64_t t_ns) const {
  return std::lower_bound(samples_.begin(), samples_.end(), t_ns,
                          [](const GyroSample& s, int64_t t) { return s.t_ns < t; }) -
         samples_.begin();
}

int64_t SecondsToNs(double t_s) {
  SHUTTERLAB_CHECK(std::isfinite(t_s) && std::abs(t_s) < 9.2e9) << "time " << t_s << " s out of range";
  return std::llround(t_s * 1e9);
}

}  // namespace shutterlab
