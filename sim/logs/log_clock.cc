#include "sim/logs/log_clock.h"

#include "sim/units.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {

int64_t LogUtcClock::UtcNsFromLog(int64_t t_ns) const {
  const double dt_s = (t_ns - t0_ns) * 1e-9;
  return t_ns + offset0_ns + std::llround(rate * dt_s * 1e9);
}

int64_t LogUtcClock::LogNsFromUtc(int64_t utc_ns) const {
  // Solve utc = t + offset0 + rate (t - t0) for t: (utc - offset0 + rate t0) / (1 + rate).
  const double shifted_s = (utc_ns - offset0_ns - t0_ns) * 1e-9;
  return t0_ns + std::llround(shifted_s / (1.0 + rate) * 1e9);
}

std::optional<LogUtcClock> FitLogUtcClock(const std::vector<UtcFix>& fixes) {
  if (fixes.empty()) return std::nullopt;
  std::vector<int64_t> offsets, times;
  for (const UtcFix& f : fixes) {
    offsets.push_back(f.utc_ns - f.t_ns);
    times.push_back(f.t_ns);
  }
  const int64_t median_offset = UpperMedian(offsets);
  LogUtcClock clock;
  clock.t0_ns = UpperMedian(times);
  clock.offset0_ns = median_offset;
  std::vector<const UtcFix*> used;
  for (const UtcFix& f : fixes) {
    if (std::llabs(f.utc_ns - f.t_ns - median_offset) < 1'000'000'000)
      used.push_back(&f);
    else
      ++clock.rejected;
  }
  // Least squares of (offset - median) against (t - t0), in seconds.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const UtcFix* f : used) {
    const double x = (f->t_ns - clock.t0_ns) * 1e-9;
    const double y = (f->utc_ns - f->t_ns - median_offset) * 1e-9;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double n = static_cast<double>(used.size());
  const double det = n * sxx - sx * sx;
  const double slope = (used.size() >= 2 && det > 1e-12 * n * n) ? (n * sxy - sx * sy) / det : 0.0;
  const double intercept = (sy - slope * sx) / n;
  clock.rate = slope;
  clock.offset0_ns = median_offset + std::llround(intercept * 1e9);
  clock.fixes = used.size();
  clock.first_t_ns = used.front()->t_ns;
  clock.last_t_ns = used.front()->t_ns;
  double sum_sq = 0;
  for (const UtcFix* f : used) {
    const double r = (f->utc_ns - clock.UtcNsFromLog(f->t_ns)) * 1e-9;
    sum_sq += r * r;
    clock.max_residual_s = std::max(clock.max_residual_s, std::abs(r));
    clock.first_t_ns = std::min(clock.first_t_ns, f->t_ns);
    clock.last_t_ns = std::max(clock.last_t_ns, f->t_ns);
  }
  clock.rms_residual_s = std::sqrt(sum_sq / n);
  return clock;
}

}  // namespace shutterlab
