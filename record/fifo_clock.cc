#include "record/fifo_clock.h"

#include "sim/check.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {

FifoClock::FifoClock(double nominal_period_ns, int64_t time_constant_ns)
    : nominal_period_ns_(nominal_period_ns),
      time_constant_ns_(static_cast<double>(time_constant_ns)) {
  SHUTTERLAB_CHECK(nominal_period_ns > 0 && time_constant_ns > 0)
      << "FifoClock needs a positive period and time constant";
}

void FifoClock::AddRead(int64_t t_before_ns, int64_t t_after_ns, int64_t produced) {
  SHUTTERLAB_CHECK(t_after_ns >= t_before_ns) << "a read ends before it begins";
  const int64_t x2 = 2 * produced - 1;                                // 2 (N - 1/2)
  const int64_t y_ns = t_before_ns + (t_after_ns - t_before_ns) / 2;  // the latch, on average
  if (reads_ > 0) {
    // Move the sums' origin to this read, then age them.
    const double dx = 0.5 * static_cast<double>(x2 - ref_x2_);
    const double dy = static_cast<double>(y_ns - ref_y_ns_);
    sxx_ += -2 * dx * sx_ + dx * dx * s0_;
    sxy_ += -dx * sy_ - dy * sx_ + dx * dy * s0_;
    syy_ += -2 * dy * sy_ + dy * dy * s0_;
    sx_ -= dx * s0_;
    sy_ -= dy * s0_;
    const double decay = std::exp(-std::max(dy, 0.0) / time_constant_ns_);
    s0_ *= decay, sx_ *= decay, sy_ *= decay, sxx_ *= decay, sxy_ *= decay, syy_ *= decay;
    span_x_ = span_x_ * decay + dx;
  }
  ref_x2_ = x2;
  ref_y_ns_ = y_ns;
  s0_ += 1.0;  // the new read sits at the origin: x = y = 0
  ++reads_;
}

double FifoClock::PeriodNs() const {
  if (reads_ < 3 || span_x_ < 50.0) return nominal_period_ns_;
  const double var_x = sxx_ - sx_ * sx_ / s0_;
  if (var_x <= 0) return nominal_period_ns_;
  return (sxy_ - sx_ * sy_ / s0_) / var_x;
}

int64_t FifoClock::SampleTimeNs(int64_t k) const {
  SHUTTERLAB_CHECK(reads_ > 0) << "no FIFO read yet";
  const double b = PeriodNs();
  // The line through the weighted means with slope b, evaluated at x = k - (N - 1/2).
  const double mean_x = sx_ / s0_, mean_y = sy_ / s0_;
  const double x = static_cast<double>(k) - 0.5 * static_cast<double>(ref_x2_);
  return ref_y_ns_ + static_cast<int64_t>(std::llround(mean_y + b * (x - mean_x)));
}

int64_t FifoClock::ProducedBy(int64_t t_ns) const {
  SHUTTERLAB_CHECK(reads_ > 0) << "no FIFO read yet";
  const double b = PeriodNs();
  const double mean_x = sx_ / s0_, mean_y = sy_ / s0_;
  // Sample k is produced at or before t when y(k) <= t: k <= x*, so floor(x*) + 1 of them.
  const double x = mean_x + (static_cast<double>(t_ns - ref_y_ns_) - mean_y) / b;
  return static_cast<int64_t>(std::floor(x + 0.5 * static_cast<double>(ref_x2_))) + 1;
}

double FifoClock::ResidualRmsNs() const {
  if (reads_ < 3) return 0.0;
  const double b = PeriodNs();
  const double var_y = syy_ - sy_ * sy_ / s0_;
  const double cov = sxy_ - sx_ * sy_ / s0_;
  const double var_x = sxx_ - sx_ * sx_ / s0_;
  const double residual = var_y - 2 * b * cov + b * b * var_x;
  return std::sqrt(std::max(residual, 0.0) / s0_);
}

}  // namespace shutterlab
