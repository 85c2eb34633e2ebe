#include "sim/trace_audit.h"

#include "sim/text_file.h"
#include "sim/units.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// n samples every interval_ns from t0_ns, all at rate (rad/s).
std::vector<GyroSample> Regular(size_t n, int64_t interval_ns, int64_t t0_ns = 0,
                                const Eigen::Vector3d& rate = Eigen::Vector3d::Zero()) {
  std::vector<GyroSample> samples;
  for (size_t k = 0; k < n; ++k)
    samples.push_back({t0_ns + static_cast<int64_t>(k) * interval_ns, rate});
  return samples;
}

std::string Joined(const std::vector<LogWarning>& warnings) {
  std::string all;
  for (const LogWarning& w : warnings) all += WarningLine(w) + "\n";
  return all;
}

TEST(AuditTrace, CleanTraceHasNothingToSay) {
  EXPECT_TRUE(AuditTrace(GyroTrace(Regular(5000, 1'000'000))).empty());
  EXPECT_TRUE(AuditTrace(GyroTrace()).empty());
}

TEST(AuditTrace, GapsWithCountMissingTimeAndTheLongest) {
  std::vector<GyroSample> samples = Regular(1000, 1'000'000);
  // Two pauses of the logger: 50 ms after sample 199 and 300 ms after sample 599.
  for (size_t k = 200; k < samples.size(); ++k) samples[k].t_ns += 49'000'000;
  for (size_t k = 600; k < samples.size(); ++k) samples[k].t_ns += 299'000'000;
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_EQ(lines.size(), 1u) << Joined(lines);
  EXPECT_EQ(lines[0].kind, "gap");
  EXPECT_EQ(lines[0].message,
            "2 interval(s) over 3x the median 1.000 ms, 0.348 s missing in all; longest 0.300 s at "
            "0.648 s");
  EXPECT_EQ(lines[0].count, 2u);
  EXPECT_DOUBLE_EQ(*lines[0].t_s, 0.199);
}

TEST(AuditTrace, DuplicatedTimestamps) {
  std::vector<GyroSample> samples = Regular(100, 1'000'000);
  samples[50].t_ns = samples[49].t_ns;
  samples[51].t_ns = samples[49].t_ns;
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(WarningLine(lines.back()),
            "duplicate_time: 2 sample(s) share the time of the one before");
  EXPECT_DOUBLE_EQ(*lines.back().t_s, 0.049);
}

TEST(AuditTrace, SampleRateChangesAreListedWithTheirTimes) {
  // 3 s at 1 kHz, then 3 s at 250 Hz, then 2 s at 1 kHz.
  std::vector<GyroSample> samples = Regular(3000, 1'000'000);
  for (const GyroSample& s : Regular(750, 4'000'000, 3'000'000'000)) samples.push_back(s);
  for (const GyroSample& s : Regular(2000, 1'000'000, 6'000'000'000)) samples.push_back(s);
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_EQ(lines.size(), 1u) << Joined(lines);
  EXPECT_EQ(WarningLine(lines[0]),
            "rate_change: sample rate changes 2 time(s): 1000 Hz, then 250 Hz from 3.000 s, then "
            "1000 Hz from 6.000 s");
  EXPECT_DOUBLE_EQ(*lines[0].t_s, 3.0);
}

TEST(AuditTrace, BurstsStampedWithOneTimeHaveTheirRateAndChangeIt) {
  // A logger that stamps its samples in threes with one time, every 1 ms (3 kHz of samples, a
  // median interval of 0) for 4 s, then one sample every 1 ms for 3 s: the first run's rate is
  // its samples over its span, and the change to 1 kHz is the one change (each block was a
  // "change" from "0 Hz" to "0 Hz" before).
  std::vector<GyroSample> samples;
  for (size_t k = 0; k < 12000; ++k)
    samples.push_back({static_cast<int64_t>(k / 3) * 1'000'000, Eigen::Vector3d::Zero()});
  for (const GyroSample& s : Regular(3000, 1'000'000, 4'000'000'000)) samples.push_back(s);
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_EQ(lines.size(), 2u) << Joined(lines);
  EXPECT_EQ(lines[0].kind, "duplicate_time");
  EXPECT_EQ(lines[0].count, 8000u);
  EXPECT_EQ(WarningLine(lines[1]),
            "rate_change: sample rate changes 1 time(s): 3000 Hz, then 1000 Hz from 4.000 s");
  // Stamped in threes throughout: one rate, no change.
  samples.resize(12000);
  const std::vector<LogWarning> one_rate = AuditTrace(GyroTrace(samples));
  ASSERT_EQ(one_rate.size(), 1u) << Joined(one_rate);
  EXPECT_EQ(one_rate[0].kind, "duplicate_time");
}

// The streamed sampling of a burst-stamped trace (analyze's "N samples, D s at R Hz, G gaps"):
// its rate is its samples over its span and its one gap the real pause, as GyroTrace::sampling
// says of it held whole (it said 0 Hz and a gap at every 1 ms step).
TEST(TraceAuditor, BurstStampedSamplingAsTheTraceHeldWhole) {
  std::vector<GyroSample> samples;
  for (int k = 0; k < 30000; ++k) {
    const int64_t stamp_ms = k / 3 + (k >= 15000 ? 500 : 0);
    samples.push_back({stamp_ms * 1'000'000, Eigen::Vector3d::Zero()});
  }
  TraceAuditor auditor;
  for (size_t i = 0; i < samples.size(); i += 1000) auditor.Add(samples.data() + i, 1000);
  const TraceSampling sampling = auditor.Sampling();
  const SamplingReport whole = GyroTrace(samples).sampling();
  EXPECT_EQ(sampling.median_interval_ns, 0);
  EXPECT_EQ(sampling.nominal_interval_ns, whole.nominal_interval_ns);
  EXPECT_EQ(sampling.RateHz(), whole.RateHz());
  EXPECT_NEAR(sampling.RateHz(), 29999 / 10.499, 0.01);  // 29,999 intervals over 10.499 s
  EXPECT_EQ(sampling.gaps, 1u);
  EXPECT_EQ(sampling.gaps, whole.gap_indices.size());
}

TEST(AuditTrace, JitterIsNotARateChange) {
  std::vector<GyroSample> samples = Regular(8000, 1'000'000);
  for (size_t k = 0; k < samples.size(); ++k)
    samples[k].t_ns += (k * 7919 % 400) * 1000;  // +-0.2 ms
  EXPECT_TRUE(AuditTrace(GyroTrace(samples)).empty());
}

TEST(AuditTrace, SaturationAtAStatedFullScale) {
  const double full_scale = 250.0 * kRadPerDeg;
  std::vector<GyroSample> samples = Regular(1000, 1'000'000);
  for (size_t k = 400; k < 410; ++k) samples[k].omega_rad_s.z() = -full_scale;  // clipped
  samples[500].omega_rad_s.x() = 0.97 * full_scale;                             // not clipped
  TraceAuditOptions options;
  options.full_scale_rad_s = full_scale;
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples), options);
  ASSERT_EQ(lines.size(), 1u) << Joined(lines);
  EXPECT_EQ(WarningLine(lines[0]),
            "saturated: axis z, 10 sample(s) within 2 % of the +-250 deg/s full scale, peak 250 "
            "deg/s, from 0.400 s to 0.409 s: the rotation there is under-reported");
  EXPECT_EQ(lines[0].count, 10u);
  EXPECT_DOUBLE_EQ(*lines[0].t_s, 0.4);
}

TEST(AuditTrace, SaturationWhereThePeakLandsOnACommonFullScale) {
  std::vector<GyroSample> samples = Regular(1000, 20'000'000);
  samples[300].omega_rad_s = Eigen::Vector3d(1164, 2023, 1016) * kRadPerDeg;
  // The range is one for all axes: the 2023 deg/s peak says +-2000, so z's 1016 deg/s is not
  // clipped at +-1000.
  ASSERT_EQ(SaturationFullScale(GyroTrace(samples), {}), 2000.0 * kRadPerDeg);
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_EQ(lines.size(), 1u) << Joined(lines);
  EXPECT_EQ(WarningLine(lines[0]).rfind("saturated: axis y, 1 sample(s) within 2 % of the +-2000 "
                                        "deg/s full scale (where the peak lands), peak 2023 deg/s, "
                                        "from 6.000 s",
                                        0),
            0u)
      << WarningLine(lines[0]);
  // A peak between the common ranges says nothing.
  samples[300].omega_rad_s = Eigen::Vector3d(0, 1500, 0) * kRadPerDeg;
  EXPECT_FALSE(SaturationFullScale(GyroTrace(samples), {}).has_value());
  EXPECT_TRUE(AuditTrace(GyroTrace(samples)).empty());
}

// The gap and rate-change audit as first written, over a trace held whole (blocks of 1 s, a block
// of fewer than 8 intervals joining the one before, the interval into a block judged at the slower
// of the two rates): the reference for the streamed TraceAuditor. Returns (gap count, missing ns,
// longest ns, its start, first gap start, rate-run medians).
struct ReferenceAudit {
  size_t gaps = 0;
  int64_t missing_ns = 0, longest_ns = 0, longest_at_ns = 0, first_at_ns = 0;
  std::vector<int64_t> run_medians;
};
ReferenceAudit WholeTraceAudit(const std::vector<GyroSample>& t, double factor) {
  struct Block {
    size_t begin, end;
    int64_t median;
  };
  std::vector<Block> blocks;
  std::vector<int64_t> intervals;
  size_t begin = 0;
  for (size_t k = 1; k <= t.size(); ++k) {
    const bool ends = k == t.size() || t[k].t_ns - t[begin].t_ns >= 1'000'000'000;
    if (k < t.size()) intervals.push_back(t[k].t_ns - t[k - 1].t_ns);
    if (!ends) continue;
    if (intervals.size() < 8 && !blocks.empty()) {
      blocks.back().end = k;
    } else {
      blocks.push_back({begin, k, UpperMedian(intervals)});
    }
    intervals.clear();
    begin = k;
  }
  ReferenceAudit out;
  for (size_t b = 0; b < blocks.size(); ++b) {
    for (size_t k = std::max<size_t>(blocks[b].begin, 1); k < blocks[b].end; ++k) {
      const int64_t local = k == blocks[b].begin && b > 0
                                ? std::max(blocks[b].median, blocks[b - 1].median)
                                : blocks[b].median;
      const int64_t gap = t[k].t_ns - t[k - 1].t_ns;
      if (local == 0 || gap <= SamplingReport::kGapFactor * local) continue;
      if (out.gaps++ == 0) out.first_at_ns = t[k - 1].t_ns;
      out.missing_ns += gap - local;
      if (gap > out.longest_ns) {
        out.longest_ns = gap;
        out.longest_at_ns = t[k - 1].t_ns;
      }
    }
  }
  for (const Block& b : blocks) {
    if (!out.run_medians.empty()) {
      const double ratio = static_cast<double>(b.median) / out.run_medians.back();
      if (ratio < factor && ratio > 1.0 / factor) continue;
    }
    out.run_medians.push_back(b.median);
  }
  return out;
}

TEST(TraceAuditor, StreamedInAnyChunksEqualsTheWholeTraceAudit) {
  std::mt19937_64 rng(15);
  for (int trial = 0; trial < 20; ++trial) {
    // Stretches at changing rates, with jitter, pauses, repeated times and short tails.
    std::vector<GyroSample> samples;
    int64_t t = 1'000'000'000;
    const int stretches = 1 + static_cast<int>(rng() % 5);
    for (int s = 0; s < stretches; ++s) {
      const int64_t period = 250'000 * (1 + static_cast<int64_t>(rng() % 16));
      const size_t n = rng() % 4000;
      for (size_t k = 0; k < n; ++k) {
        samples.push_back({t, Eigen::Vector3d::Zero()});
        const uint64_t r = rng() % 1000;
        t += r < 3   ? period * (2 + static_cast<int64_t>(rng() % 40))  // a pause
             : r < 6 ? 0                                                // a repeated time
                     : period + static_cast<int64_t>(rng() % (period / 10 + 1));
      }
    }
    if (samples.size() < 2) continue;
    const ReferenceAudit expected = WholeTraceAudit(samples, 1.25);
    TraceAuditor auditor;
    for (size_t i = 0; i < samples.size();) {
      const size_t n = std::min<size_t>(samples.size() - i, 1 + rng() % 3000);
      auditor.Add(samples.data() + i, n);
      i += n;
    }
    const std::vector<LogWarning> lines = auditor.Finish();
    const auto find = [&](const std::string& kind) -> const LogWarning* {
      for (const LogWarning& w : lines) {
        if (w.kind == kind) return &w;
      }
      return nullptr;
    };
    const LogWarning* gap = find("gap");
    ASSERT_EQ(gap != nullptr, expected.gaps > 0) << trial << "\n" << Joined(lines);
    if (gap) {
      EXPECT_EQ(*gap->count, expected.gaps) << trial;
      EXPECT_DOUBLE_EQ(*gap->t_s, expected.first_at_ns * 1e-9) << trial;
      EXPECT_NE(gap->message.find(FormatNumber("%.3f", expected.missing_ns * 1e-9) +
                                  " s missing in all; longest " +
                                  FormatNumber("%.3f", expected.longest_ns * 1e-9) + " s at " +
                                  SecondsText(expected.longest_at_ns)),
                std::string::npos)
          << trial << ": " << gap->message;
    }
    const LogWarning* rate = find("rate_change");
    ASSERT_EQ(rate != nullptr, expected.run_medians.size() > 1) << trial << "\n" << Joined(lines);
    if (rate) {
      EXPECT_EQ(*rate->count, expected.run_medians.size() - 1) << trial;
    }
    // The streamed sampling is what the whole trace says of itself.
    const GyroTrace whole(samples);
    const TraceSampling sampling = auditor.Sampling();
    EXPECT_EQ(sampling.samples, whole.size());
    EXPECT_EQ(sampling.median_interval_ns, whole.sampling().median_interval_ns) << trial;
    EXPECT_EQ(sampling.gaps, whole.sampling().gap_indices.size()) << trial;
    EXPECT_EQ(sampling.duplicate_timestamps, whole.sampling().duplicate_timestamps) << trial;
  }
}

// The chunk-at-once audit (its times in runs, its rates' peaks over the chunk) says exactly what
// one sample at a time says, saturation included: every warning's line, time and count, and the
// sampling.
TEST(TraceAuditor, WholeChunksSayWhatOneSampleAtATimeSays) {
  std::mt19937_64 rng(18);
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<GyroSample> samples;
    int64_t t = 0;
    const int64_t period = 250'000 * (1 + static_cast<int64_t>(rng() % 8));
    for (size_t k = 0; k < 6000; ++k) {
      Eigen::Vector3d rate(std::sin(k * 0.01), std::cos(k * 0.013), 0.1);
      if (rng() % 200 == 0) rate[rng() % 3] = (rng() % 2 ? 1 : -1) * 8.6;  // 500 deg/s clipped
      samples.push_back({t, rate * (trial % 2 ? 1.0 : 2.0)});
      const uint64_t r = rng() % 1000;
      t += r < 3 ? period * 7 : r < 8 ? 0 : k > 3000 && trial % 3 == 0 ? 2 * period : period;
    }
    TraceAuditor one_by_one, chunked;
    for (const GyroSample& s : samples) one_by_one.Add(&s, 1);
    for (size_t i = 0; i < samples.size();) {
      const size_t n = std::min<size_t>(samples.size() - i, 1 + rng() % 2500);
      chunked.Add(samples.data() + i, n);
      i += n;
    }
    const std::vector<LogWarning> expected = one_by_one.Finish(), got = chunked.Finish();
    ASSERT_EQ(Joined(got), Joined(expected)) << trial;
    ASSERT_NE(Joined(got).find("saturated"), std::string::npos) << trial;
    for (size_t w = 0; w < got.size(); ++w) {
      EXPECT_EQ(got[w].t_s, expected[w].t_s) << trial;
      EXPECT_EQ(got[w].count, expected[w].count) << trial;
    }
    const TraceSampling a = chunked.Sampling(), b = one_by_one.Sampling();
    EXPECT_EQ(a.samples, b.samples);
    EXPECT_EQ(a.t_begin_ns, b.t_begin_ns);
    EXPECT_EQ(a.t_end_ns, b.t_end_ns);
    EXPECT_EQ(a.median_interval_ns, b.median_interval_ns);
    EXPECT_EQ(a.gaps, b.gaps);
    EXPECT_EQ(a.duplicate_timestamps, b.duplicate_timestamps);
  }
}

TEST(TraceAuditor, RefusesWhatGyroTraceRefuses) {
  TraceAuditor auditor;
  std::vector<GyroSample> samples = Regular(10, 1'000'000);
  samples[7].t_ns -= 3'000'000;
  auditor.Add(samples.data(), 5);
  try {
    auditor.Add(samples.data() + 5, 5);
    FAIL() << "a time going back must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("gyro sample 7 goes back in time by 0.002 s"),
              std::string::npos)
        << e.what();
  }
  TraceAuditor nan;
  samples = Regular(3, 1'000'000);
  samples[2].omega_rad_s.y() = std::nan("");
  EXPECT_THROW(nan.Add(samples), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
