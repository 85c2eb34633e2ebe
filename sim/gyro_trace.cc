#include "sim/gyro_trace.h"

#include "sim/check.h"
#include "sim/interval_histogram.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {

GyroTrace::GyroTrace(std::vector<GyroSample> samples) : samples_(std::move(samples)) {
  const size_t n = samples_.size();
  IntervalHistogram intervals;
  for (size_t i = 0; i < n; ++i) {
    SHUTTERLAB_CHECK(samples_[i].omega_rad_s.allFinite())
        << "gyro sample " << i << " has a non-finite rate";
    if (i == 0) continue;
    const int64_t dt = samples_[i].t_ns - samples_[i - 1].t_ns;
    SHUTTERLAB_CHECK(dt >= 0) << "gyro sample " << i << " goes back in time by " << -dt * 1e-9
                              << " s";
    if (dt == 0) ++sampling_.duplicate_timestamps;
    intervals.Add(dt);
  }
  if (n < 2) return;
  sampling_.median_interval_ns = intervals.Median();
  sampling_.nominal_interval_ns =
      NominalIntervalNs(sampling_.median_interval_ns, n, t_end_ns() - t_begin_ns());
  const double gap_ns = SamplingReport::kGapFactor *
                        static_cast<double>(NominalIntervalNs(sampling_.median_interval_ns,
                                                              n - sampling_.duplicate_timestamps,
                                                              t_end_ns() - t_begin_ns()));
  for (size_t k = 0; k + 1 < n; ++k) {
    if (static_cast<double>(samples_[k + 1].t_ns - samples_[k].t_ns) > gap_ns) {
      sampling_.gap_indices.push_back(k);
    }
  }
}

int64_t NominalIntervalNs(int64_t median_interval_ns, size_t samples, int64_t span_ns) {
  if (median_interval_ns > 0) return median_interval_ns;
  if (samples < 2 || span_ns <= 0) return 0;
  return span_ns / static_cast<int64_t>(samples - 1);
}

size_t GyroTrace::LowerBound(int64_t t_ns) const {
  return std::lower_bound(samples_.begin(), samples_.end(), t_ns,
                          [](const GyroSample& s, int64_t t) { return s.t_ns < t; }) -
         samples_.begin();
}

int64_t SecondsToNs(double t_s) {
  SHUTTERLAB_CHECK(std::isfinite(t_s) && std::abs(t_s) < 9.2e9)
      << "time " << t_s << " s out of range";
  return std::llround(t_s * 1e9);
}

GyroTrace GyroAround(const GyroTrace& gyro, int64_t begin_ns, int64_t end_ns) {
  const std::vector<GyroSample>& s = gyro.samples();
  const auto first = std::upper_bound(s.begin(), s.end(), begin_ns,
                                      [](int64_t t, const GyroSample& x) { return t < x.t_ns; });
  const auto last = std::lower_bound(s.begin(), s.end(), end_ns,
                                     [](const GyroSample& x, int64_t t) { return x.t_ns < t; });
  const auto from = first == s.begin() ? first : first - 1;
  const auto to = last == s.end() ? last : last + 1;
  return GyroTrace(std::vector<GyroSample>(from, std::max(from, to)));
}

}  // namespace shutterlab
