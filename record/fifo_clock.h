#pragma once
// Sample times from FIFO counts. A FIFO sample carries no time of its own; what the host knows is
// how many samples the part had produced when it read the FIFO count, and when it read it. The
// part samples on its own oscillator, so sample k was produced at T(k) = a + b k on the host's
// clock, b the part's true period (nominal period times 1 - drift). A count read latched between
// t_before and t_after with N samples produced so far means T(N - 1) <= latch < T(N): the latch
// lies, on average, half a period after the newest sample, at T(N - 1/2).
//
// FifoClock fits that line to the reads, least squares of the reads' midpoints against N - 1/2,
// every read weighted by exp(-age / time_constant) so that the fit follows the oscillator's slow
// drift with temperature. The reader dithers its read instants (record/recorder.cc), so the
// latch falls at every phase of the period; a read period commensurate with the sample period
// would otherwise bias the line by up to half a period.

#include <cstdint>

namespace shutterlab {

class FifoClock {
 public:
  // nominal_period_ns: 1e9 / the configured rate; time_constant_ns: the fit's memory.
  FifoClock(double nominal_period_ns, int64_t time_constant_ns = 10000000000);

  // One count read: `produced` samples (read so far plus lost) when the count was latched within
  // [t_before_ns, t_after_ns].
  void AddRead(int64_t t_before_ns, int64_t t_after_ns, int64_t produced);

  // The clock time of sample k (0 = the first sample) on the current fit.
  int64_t SampleTimeNs(int64_t k) const;
  // How many samples the part had produced by clock time t_ns on the current fit: the index of
  // the first sample after t_ns. Used to count samples lost in a gap.
  int64_t ProducedBy(int64_t t_ns) const;

  bool has_reads() const { return reads_ > 0; }
  int64_t reads() const { return reads_; }
  // Samples between the oldest reads that still weigh and the newest: how far the fit reaches.
  double SpanSamples() const { return span_x_; }
  double PeriodNs() const;  // the fitted period (the nominal one until the reads span 50 periods)
  // The part's clock error, parts per million (positive: the part runs fast).
  double DriftPpm() const { return (nominal_period_ns_ / PeriodNs() - 1.0) * 1e6; }
  // RMS of the reads' midpoints about the line, ns (about period / sqrt(12) plus read jitter).
  double ResidualRmsNs() const;

 private:
  double nominal_period_ns_;
  double time_constant_ns_;
  int64_t reads_ = 0;
  // Exponentially weighted sums about the newest read (x: samples, y: ns), so they stay small.
  int64_t ref_x2_ = 0;  // 2 (N - 1/2) of the newest read, in half samples (an integer)
  int64_t ref_y_ns_ = 0;
  double s0_ = 0, sx_ = 0, sy_ = 0, sxx_ = 0, sxy_ = 0, syy_ = 0;
  double span_x_ = 0;  // samples between the oldest and newest read that still weigh
};

}  // namespace shutterlab
