// Sample times from FIFO counts: a part sampling at a known rate with a known clock error, its
// count read in batches at dithered instants, gives back its period, its drift and every sample's
// time; the fit follows a drift that changes; the first reads keep the nominal period.

#include "record/fifo_clock.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

namespace shutterlab {
namespace {

constexpr double kFifoTestNominalNs = 125000.0;    // 8 kHz
constexpr int64_t kFifoTestFirstNs = 2000000000;   // the part's first sample, host clock
constexpr int64_t kFifoTestReadLengthNs = 3000;    // a count read over SPI takes a few us
constexpr int64_t kFifoTestReadEveryNs = 1000000;  // reads every 1 ms, dithered +-50 %

// A part whose k-th sample is produced at first + k * period on the host's clock, its count read
// every millisecond (dithered) from the first sample on; the count is latched at the middle of
// each read (the fit's assumption; a 3 us read window moves it by at most 1.5 us).
class DriftingFifoPart {
 public:
  explicit DriftingFifoPart(double drift_ppm, uint64_t seed = 7)
      : period_ns_(kFifoTestNominalNs / (1.0 + drift_ppm * 1e-6)), rng_(seed) {}

  void SetDriftPpm(double drift_ppm) {
    // The part keeps sampling continuously: later samples follow the new period from now on.
    const double k = static_cast<double>(Produced(next_read_ns_));
    origin_ns_ = TrueTimeNs(k);
    origin_k_ = k;
    period_ns_ = kFifoTestNominalNs / (1.0 + drift_ppm * 1e-6);
  }
  // The true time of sample k.
  double TrueTimeNs(double k) const { return origin_ns_ + (k - origin_k_) * period_ns_; }
  // Samples produced by host time t: those with TrueTimeNs(k) <= t.
  int64_t Produced(int64_t t_ns) const {
    if (t_ns < kFifoTestFirstNs) return 0;
    return static_cast<int64_t>(std::floor((t_ns - origin_ns_) / period_ns_ + origin_k_)) + 1;
  }
  // Reads the count into clock until host time end_ns.
  void ReadUntil(int64_t end_ns, FifoClock* clock) {
    std::uniform_real_distribution<double> dither(0.5, 1.5);
    while (next_read_ns_ < end_ns) {
      const int64_t latch_ns = next_read_ns_ + kFifoTestReadLengthNs / 2;
      clock->AddRead(next_read_ns_, next_read_ns_ + kFifoTestReadLengthNs, Produced(latch_ns));
      next_read_ns_ += static_cast<int64_t>(kFifoTestReadEveryNs * dither(rng_));
    }
  }
  double period_ns() const { return period_ns_; }

 private:
  double period_ns_;
  double origin_k_ = 0.0;
  double origin_ns_ = static_cast<double>(kFifoTestFirstNs);
  int64_t next_read_ns_ = kFifoTestFirstNs;
  std::mt19937_64 rng_;
};

// A memory longer than the tests' reads: every read weighs alike.
constexpr int64_t kFifoTestLongMemoryNs = 1000000000000;

TEST(FifoClock, FitsThePartsPeriodDriftAndSampleTimes) {
  const double drift_ppm = 50.0;
  DriftingFifoPart part(drift_ppm);
  FifoClock clock(kFifoTestNominalNs, kFifoTestLongMemoryNs);
  part.ReadUntil(kFifoTestFirstNs + 20000000000, &clock);  // 20 s: about 20000 reads
  ASSERT_GT(clock.reads(), 19000);
  // Each read places the latch within one period (125 us, rms 36 us); 20000 of them over 160000
  // samples fix the slope to about 0.05 ppm (1 sigma) and the line to about 0.5 us.
  constexpr double kDriftTolPpm = 0.2;
  constexpr double kSampleTimeTolNs = 3000.0;
  EXPECT_NEAR(clock.DriftPpm(), drift_ppm, kDriftTolPpm);
  EXPECT_NEAR(clock.PeriodNs(), part.period_ns(), part.period_ns() * kDriftTolPpm * 1e-6);
  for (int64_t k : {0, 1000, 80000, 159000}) {
    EXPECT_NEAR(static_cast<double>(clock.SampleTimeNs(k)), part.TrueTimeNs(k), kSampleTimeTolNs)
        << "sample " << k;
  }
  // A quarter period after sample k, k + 1 samples had been produced; a quarter before, k.
  for (int64_t k : {500, 100000}) {
    const double t_ns = part.TrueTimeNs(k);
    EXPECT_EQ(clock.ProducedBy(static_cast<int64_t>(t_ns + part.period_ns() / 4)), k + 1);
    EXPECT_EQ(clock.ProducedBy(static_cast<int64_t>(t_ns - part.period_ns() / 4)), k);
  }
  // The latch is uniform over one period: rms period / sqrt(12) about the line.
  constexpr double kRmsTolFraction = 0.02;  // the rms of 20000 uniform draws, to 0.4 % (1 sigma)
  EXPECT_NEAR(clock.ResidualRmsNs(), part.period_ns() / std::sqrt(12.0),
              kRmsTolFraction * part.period_ns() / std::sqrt(12.0));
}

TEST(FifoClock, ANegativeDriftIsASlowPart) {
  DriftingFifoPart part(-120.0);
  FifoClock clock(kFifoTestNominalNs, kFifoTestLongMemoryNs);
  part.ReadUntil(kFifoTestFirstNs + 20000000000, &clock);
  constexpr double kDriftTolPpm = 0.2;  // 20 s of reads: about 0.05 ppm (1 sigma)
  EXPECT_NEAR(clock.DriftPpm(), -120.0, kDriftTolPpm);
  EXPECT_GT(clock.PeriodNs(), kFifoTestNominalNs);
}

TEST(FifoClock, KeepsTheNominalPeriodUntilTheReadsSpanFiftyPeriods) {
  DriftingFifoPart part(300.0);
  FifoClock clock(kFifoTestNominalNs);
  EXPECT_FALSE(clock.has_reads());
  part.ReadUntil(kFifoTestFirstNs + 4000000, &clock);  // 4 ms: 32 samples
  ASSERT_GE(clock.reads(), 3);
  EXPECT_LT(clock.SpanSamples(), 50.0);
  EXPECT_EQ(clock.PeriodNs(), kFifoTestNominalNs);
  EXPECT_EQ(clock.DriftPpm(), 0.0);
  part.ReadUntil(kFifoTestFirstNs + 200000000, &clock);  // 200 ms: 1600 samples
  EXPECT_GT(clock.SpanSamples(), 1500.0);
  EXPECT_NE(clock.PeriodNs(), kFifoTestNominalNs);
}

TEST(FifoClock, AShortMemoryFollowsADriftThatChanges) {
  // The part warms up: +50 ppm for 4 s, then -30 ppm for 10 s. A 1 s memory has forgotten the
  // first drift by the end (weight e^-10); one that never forgets still mixes the two.
  DriftingFifoPart part_short(50.0), part_long(50.0);
  FifoClock short_memory(kFifoTestNominalNs, 1000000000);
  FifoClock long_memory(kFifoTestNominalNs, kFifoTestLongMemoryNs);
  part_short.ReadUntil(kFifoTestFirstNs + 4000000000, &short_memory);
  part_long.ReadUntil(kFifoTestFirstNs + 4000000000, &long_memory);
  part_short.SetDriftPpm(-30.0);
  part_long.SetDriftPpm(-30.0);
  const int64_t end_ns = kFifoTestFirstNs + 14000000000;
  part_short.ReadUntil(end_ns, &short_memory);
  part_long.ReadUntil(end_ns, &long_memory);
  // About 1000 e-weighted reads over 8000 samples fix the slope to about 1 ppm (1 sigma).
  constexpr double kFollowTolPpm = 4.0;
  EXPECT_NEAR(short_memory.DriftPpm(), -30.0, kFollowTolPpm);
  EXPECT_GT(long_memory.DriftPpm(), -30.0 + 10.0);  // still pulled towards +50
  // The newest samples' times follow the new drift too.
  const int64_t k = part_short.Produced(end_ns) - 1;
  constexpr double kNewestTolNs = 10000.0;  // a tenth of a period
  EXPECT_NEAR(static_cast<double>(short_memory.SampleTimeNs(k)), part_short.TrueTimeNs(k),
              kNewestTolNs);
}

}  // namespace
}  // namespace shutterlab
