// The streamed candidate cleaning (CandidateSummary, ChooseGyroSummary, CandidateCleaner) against
// a reference: the whole-trace ChooseGyroSource as it was before streaming, kept here verbatim in
// substance, on random candidates with every defect the cleaning handles.

#include "sim/logs/gyro_candidates.h"
#include "sim/units.h"
#include "tests/sim/logs/same_log.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

using test::ExpectSameLog;

using internal::CandidateCleaner;
using internal::CandidateLimits;
using internal::CandidateSummary;
using internal::GyroCandidate;

// ---- The reference: ChooseGyroSource before streaming (holds every sample, sorts them whole).
struct RefCleaned {
  GyroCandidate candidate;
  double rate_hz = 0.0;
  size_t dropped_time = 0, dropped_value = 0, dropped_spike = 0, out_of_order = 0,
         dropped_outlier_end = 0;
};

int64_t RefMedianInterval(const std::vector<GyroSample>& s) {
  if (s.size() < 2) return 0;
  std::vector<int64_t> d(s.size() - 1);
  for (size_t i = 0; i + 1 < s.size(); ++i) d[i] = s[i + 1].t_ns - s[i].t_ns;
  return UpperMedian(std::move(d));
}

RefCleaned RefClean(GyroCandidate in) {
  RefCleaned out;
  std::vector<GyroSample> kept;
  for (const GyroSample& s : in.samples) {
    if (s.t_ns <= 0) {
      ++out.dropped_time;
    } else if (!s.omega_rad_s.allFinite()) {
      ++out.dropped_value;
    } else {
      kept.push_back(s);
    }
  }
  std::vector<GyroSample> despiked;
  const size_t n = kept.size();
  for (size_t i = 0; i < n; ++i) {
    const int64_t t = kept[i].t_ns;
    bool spike = false;
    if (i > 0 && i + 1 < n) {
      const int64_t a = kept[i - 1].t_ns, b = kept[i + 1].t_ns;
      spike = a <= b && (t < a || t > b);
    } else if (i == 0 && n >= 3) {
      spike = t > kept[1].t_ns && kept[1].t_ns <= kept[2].t_ns;
    } else if (i + 1 == n && n >= 3) {
      spike = t < kept[n - 2].t_ns && kept[n - 3].t_ns <= kept[n - 2].t_ns;
    }
    if (spike) {
      ++out.dropped_spike;
    } else {
      despiked.push_back(kept[i]);
    }
  }
  for (size_t i = 1; i < despiked.size(); ++i) {
    if (despiked[i].t_ns < despiked[i - 1].t_ns) ++out.out_of_order;
  }
  std::stable_sort(despiked.begin(), despiked.end(),
                   [](const GyroSample& a, const GyroSample& b) { return a.t_ns < b.t_ns; });
  constexpr int64_t kMaxEndGapNs = 60'000'000'000;
  while (despiked.size() >= 3 &&
         despiked.back().t_ns - despiked[despiked.size() - 2].t_ns > kMaxEndGapNs) {
    despiked.pop_back();
    ++out.dropped_outlier_end;
  }
  while (despiked.size() >= 3 && despiked[1].t_ns - despiked[0].t_ns > kMaxEndGapNs) {
    despiked.erase(despiked.begin());
    ++out.dropped_outlier_end;
  }
  const int64_t median = RefMedianInterval(despiked);
  out.rate_hz = median > 0 ? 1e9 / static_cast<double>(median) : 0.0;
  out.candidate = std::move(in);
  out.candidate.samples = std::move(despiked);
  return out;
}

bool RefChoose(std::vector<GyroCandidate> candidates, FlightLog* log) {
  std::vector<RefCleaned> usable;
  for (GyroCandidate& c : candidates) {
    RefCleaned cleaned = RefClean(std::move(c));
    if (cleaned.candidate.samples.size() >= 2 && cleaned.rate_hz > 0.0)
      usable.push_back(std::move(cleaned));
  }
  if (usable.empty()) return false;
  std::stable_sort(usable.begin(), usable.end(),
                   [](const RefCleaned& a, const RefCleaned& b) { return a.rate_hz > b.rate_hz; });
  const double best_rate = usable.front().rate_hz;
  size_t chosen = 0;
  for (size_t i = 1; i < usable.size(); ++i) {
    if (usable[i].rate_hz < 0.9 * best_rate) break;
    const auto& a = usable[i].candidate;
    const auto& b = usable[chosen].candidate;
    if (a.preference < b.preference ||
        (a.preference == b.preference && a.samples.size() > b.samples.size()))
      chosen = i;
  }
  std::rotate(usable.begin(), usable.begin() + chosen, usable.begin() + chosen + 1);
  log->gyro_sources_available.clear();
  for (const RefCleaned& c : usable) {
    char rate[64];
    std::snprintf(rate, sizeof(rate), "%.1f Hz", c.rate_hz);
    log->gyro_sources_available.push_back(c.candidate.name + " (" + rate + ", " +
                                          std::to_string(c.candidate.samples.size()) + " samples)");
  }
  RefCleaned& best = usable.front();
  const std::string& name = best.candidate.name;
  auto warn = [&](size_t count, const char* what) {
    if (count == 0) return;
    log->records_skipped += count;
    log->warnings.push_back(
        {"corrupt", name + ": " + std::to_string(count) + " " + what, std::nullopt, count});
  };
  warn(best.dropped_time, "samples with a zero timestamp dropped");
  warn(best.candidate.unreadable_time,
       "samples with an unreadable timestamp (beyond 292 years in nanoseconds) dropped");
  warn(best.dropped_value, "samples with a non-finite rate dropped");
  warn(best.dropped_spike, "samples with a timestamp out of line with their neighbours dropped");
  warn(best.dropped_outlier_end, "samples more than 60 s beyond the rest dropped");
  if (best.out_of_order > 0) {
    log->warnings.push_back({"time_backwards",
                             name + ": " + std::to_string(best.out_of_order) +
                                 " samples were out of time order and were sorted",
                             std::nullopt, best.out_of_order});
  }
  log->gyro_source = name;
  log->gyro = GyroTrace(std::move(best.candidate.samples));
  return true;
}

// ---- Random candidates: a stream as a reader feeds it, unreadable times included.
struct Fed {
  std::string name;
  int preference = 0;
  std::vector<std::pair<std::optional<int64_t>, Eigen::Vector3d>> samples;  // in log order
};

GyroCandidate AsCandidate(const Fed& fed) {
  GyroCandidate c;
  c.name = fed.name;
  c.preference = fed.preference;
  for (const auto& [t, rate] : fed.samples) internal::AddCandidateSample(t, rate, &c);
  return c;
}

Fed RandomStream(std::mt19937_64* rng, int index) {
  auto uniform = [&](int64_t a, int64_t b) {
    return std::uniform_int_distribution<int64_t>(a, b)(*rng);
  };
  Fed fed;
  fed.name = "S" + std::to_string(index);
  fed.preference = static_cast<int>(uniform(0, 2));
  const int64_t sizes[] = {0, 1, 2, 3, 4, 5, uniform(6, 40), uniform(40, 400)};
  const size_t n = static_cast<size_t>(sizes[uniform(0, 7)]);
  // Intervals from a few distinct values (a jittery logger), or many.
  const int64_t period = uniform(1, 4) * 1'000'000 / (uniform(0, 1) ? 1 : 3);
  const int64_t jitter = uniform(0, 3) == 0 ? period / 3 : uniform(0, 2);
  int64_t t = uniform(-2, 3) * period + 1;
  for (size_t k = 0; k < n; ++k) {
    t += period + uniform(-jitter, jitter);
    const double v = 1e-3 * static_cast<double>(k);
    fed.samples.push_back({t, {v, -v, 0.5 * v}});
  }
  const int defects = static_cast<int>(uniform(0, 6));
  for (int d = 0; d < defects && !fed.samples.empty(); ++d) {
    const size_t i = static_cast<size_t>(uniform(0, static_cast<int64_t>(fed.samples.size()) - 1));
    auto& s = fed.samples[i];
    switch (uniform(0, 9)) {
      case 0:  // a spike either way
        s.first = *s.first + (uniform(0, 1) ? 1 : -1) * uniform(1, 5) * 1'000'000'000;
        break;
      case 1: {  // a run moved back (out of order by up to 30 samples)
        const size_t len = static_cast<size_t>(uniform(1, 30));
        const int64_t back = uniform(1, 30) * period;
        for (size_t j = i; j < std::min(fed.samples.size(), i + len); ++j) {
          if (fed.samples[j].first) fed.samples[j].first = *fed.samples[j].first - back;
        }
        break;
      }
      case 2:  // equal times
        if (i + 1 < fed.samples.size()) fed.samples[i + 1].first = s.first;
        break;
      case 3:  // unreadable
        s.first = std::nullopt;
        break;
      case 4:  // not set, or before boot
        s.first = uniform(0, 1) ? 0 : -uniform(1, 1000);
        break;
      case 5:
        s.second.y() = uniform(0, 1) ? std::numeric_limits<double>::quiet_NaN() : INFINITY;
        break;
      case 6:  // far end samples (several, minutes apart)
        for (int64_t j = 0, m = uniform(1, 3); j < m; ++j) {
          const int64_t gap = uniform(61, 200) * 1'000'000'000;
          if (uniform(0, 1)) {
            const int64_t last = fed.samples.back().first.value_or(1);
            fed.samples.push_back({last + gap, {1, 1, 1}});
          } else {
            const int64_t first = fed.samples.front().first.value_or(1);
            fed.samples.insert(fed.samples.begin(), {first - gap, {2, 2, 2}});
          }
        }
        break;
      case 7:  // a pair of high times that sort to the end
        if (i + 1 < fed.samples.size()) {
          s.first = fed.samples.back().first.value_or(0) + 5'000'000'000;
          fed.samples[i + 1].first = *s.first + 1;
        }
        break;
      case 8: {  // one sample moved far back
        const size_t j = static_cast<size_t>(uniform(0, static_cast<int64_t>(i)));
        if (fed.samples[j].first) s.first = fed.samples[j].first;
        break;
      }
      default:  // the times reversed over a stretch
        std::reverse(fed.samples.begin() + static_cast<std::ptrdiff_t>(i),
                     fed.samples.begin() +
                         static_cast<std::ptrdiff_t>(std::min(fed.samples.size(), i + 20)));
        break;
    }
  }
  return fed;
}

// The streamed way, as a reader does it: pass 1 under limits (again without limits when they do
// not hold), the choice, then pass 2 over the chosen stream. read_in_memory: whether pass 1 had to
// be redone.
bool StreamedChoose(const std::vector<Fed>& feds, CandidateLimits limits, FlightLog* log,
                    bool* read_in_memory) {
  auto pass1 = [&](CandidateLimits l) {
    std::vector<CandidateSummary> summaries;
    for (const Fed& fed : feds) summaries.emplace_back(fed.name, fed.preference, l);
    // Interleaved, as in a log: one sample of each stream in turn.
    for (size_t k = 0;; ++k) {
      bool any = false;
      for (size_t c = 0; c < feds.size(); ++c) {
        if (k >= feds[c].samples.size()) continue;
        summaries[c].Add(feds[c].samples[k].first, feds[c].samples[k].second);
        any = true;
      }
      if (!any) break;
    }
    for (CandidateSummary& s : summaries) s.Finish();
    return summaries;
  };
  std::vector<CandidateSummary> summaries = pass1(limits);
  *read_in_memory = !std::all_of(summaries.begin(), summaries.end(),
                                 [](const CandidateSummary& s) { return s.exact(); });
  if (*read_in_memory) summaries = pass1(CandidateLimits::Unbounded());
  const std::optional<size_t> chosen = internal::ChooseGyroSummary(summaries, log);
  if (!chosen) return false;
  CandidateCleaner cleaner(summaries[*chosen]);
  std::vector<GyroSample> out;
  for (const auto& [t, rate] : feds[*chosen].samples) {
    cleaner.Add(t, rate, &out);
    EXPECT_LE(out.size(), feds[*chosen].samples.size());
  }
  EXPECT_TRUE(cleaner.Finish(&out));
  log->gyro = GyroTrace(std::move(out));
  return true;
}

TEST(GyroCandidatesStream, RandomCandidatesGiveTheReferenceResultEveryWay) {
  std::mt19937_64 rng(20261126);
  size_t chosen = 0, in_memory = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<Fed> feds;
    const int count = std::uniform_int_distribution<int>(0, 4)(rng);
    for (int c = 0; c < count; ++c) feds.push_back(RandomStream(&rng, c));
    std::vector<GyroCandidate> candidates;
    for (const Fed& fed : feds) candidates.push_back(AsCandidate(fed));
    FlightLog reference, whole;
    const bool ref_ok = RefChoose(candidates, &reference);
    ASSERT_EQ(internal::ChooseGyroSource(candidates, &whole), ref_ok) << "trial " << trial;
    const std::string what = "trial " + std::to_string(trial);
    if (ref_ok) ExpectSameLog(whole, reference, what + " (whole)");
    // Limits small enough to be exceeded by some (then redone without), and the defaults.
    for (CandidateLimits limits :
         {CandidateLimits{4, 6}, CandidateLimits{40, 1000}, CandidateLimits{}}) {
      FlightLog streamed;
      bool read_in_memory = false;
      ASSERT_EQ(StreamedChoose(feds, limits, &streamed, &read_in_memory), ref_ok) << what;
      in_memory += read_in_memory;
      if (ref_ok) ExpectSameLog(streamed, reference, what + " (streamed)");
      if (HasFailure()) return;
    }
    chosen += ref_ok;
  }
  // The random cases reach both ways: most choose a stream, and small limits are exceeded.
  EXPECT_GT(chosen, 1500u);
  EXPECT_GT(in_memory, 300u);
}

TEST(GyroCandidatesStream, AnInOrderStreamHoldsNothingBackInPassTwo) {
  // 10^5 samples at 1 kHz with jitter: pass 1's summary is exact under the default limits and the
  // cleaner hands each sample on as soon as its successor is known.
  CandidateSummary summary("GYR", 0);
  std::vector<GyroSample> samples;
  for (int64_t k = 0; k < 100'000; ++k)
    samples.push_back({1'000'000 + k * 1'000'000 + (k % 7) * 1000, {0.0, 0.0, 0.0}});
  for (const GyroSample& s : samples) summary.Add(s.t_ns, s.omega_rad_s);
  summary.Finish();
  ASSERT_TRUE(summary.exact());
  EXPECT_NEAR(summary.rate_hz(), 1000.0, 10.0);
  CandidateCleaner cleaner(summary);
  std::vector<GyroSample> out;
  for (size_t k = 0; k < samples.size(); ++k) {
    cleaner.Add(samples[k].t_ns, samples[k].omega_rad_s, &out);
    ASSERT_GE(out.size() + 2, k + 1) << "held back more than the despike window at " << k;
  }
  EXPECT_TRUE(cleaner.Finish(&out));
  EXPECT_EQ(out.size(), samples.size());
}

TEST(GyroCandidatesStream, ADisorderDeeperThanTheLimitIsNotExact) {
  // Two samples near the end belong 100 samples back (two, so that they are no spike): a reorder
  // limit of 50 cannot sort them.
  CandidateSummary bounded("IMU", 0, CandidateLimits{50, 1000});
  CandidateSummary deep_enough("IMU", 0, CandidateLimits{100, 1000});
  for (int64_t k = 1; k <= 200; ++k) {
    bounded.Add(k * 1000, {0, 0, 0});
    deep_enough.Add(k * 1000, {0, 0, 0});
  }
  for (CandidateSummary* s : {&bounded, &deep_enough}) {
    s->Add(100'500, {0, 0, 0});
    s->Add(100'600, {0, 0, 0});
    s->Add(201'000, {0, 0, 0});
    s->Finish();
  }
  EXPECT_FALSE(bounded.exact());
  EXPECT_TRUE(deep_enough.exact());
  EXPECT_EQ(deep_enough.samples(), 203u);
}

TEST(GyroCandidatesStream, PassTwoFedOtherSamplesSaysSo) {
  CandidateSummary summary("GYR", 0);
  for (int64_t k = 1; k <= 10; ++k) summary.Add(k * 1000, {0, 0, 0});
  summary.Finish();
  CandidateCleaner cleaner(summary);
  std::vector<GyroSample> out;
  for (int64_t k = 1; k <= 9; ++k) cleaner.Add(k * 1000, {0, 0, 0}, &out);  // one fewer
  EXPECT_FALSE(cleaner.Finish(&out));
}

}  // namespace
}  // namespace shutterlab
