// Camera trigger edges: the polarity names, the filter's debounce (an edge within the debounce of
// the last one that counted is bounce, whichever its direction; one exactly at it is not) and
// polarity, the emulated line's pulses and contact bounce in virtual time, and the pulse cadence.

#include "record/trigger_source.h"

#include "record/clock.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kTriggerMs = 1000000;

// Rising at 0, its bounce at 1 and 2 ms, falling at 5 ms (exactly the debounce later), a bounce of
// that at 9 ms, rising again at 10 ms.
std::vector<TriggerEdge> BouncyTriggerEdges() {
  return {{0, true},
          {1 * kTriggerMs, false},
          {2 * kTriggerMs, true},
          {5 * kTriggerMs, false},
          {9 * kTriggerMs, true},
          {10 * kTriggerMs, true}};
}

// The edges a filter accepts, by time.
std::vector<int64_t> AcceptedTriggerTimes(TriggerFilter* filter,
                                          const std::vector<TriggerEdge>& edges) {
  std::vector<int64_t> accepted;
  for (const TriggerEdge& edge : edges) {
    if (filter->Accept(edge)) accepted.push_back(edge.t_ns);
  }
  return accepted;
}

// Every edge the line gives until deadline_ns, waiting on clock as the recorder's trigger thread
// does.
std::vector<TriggerEdge> CollectTriggerEdges(EmulatedTriggerLine* line, Clock* clock,
                                             int64_t deadline_ns) {
  std::vector<TriggerEdge> edges;
  while (clock->NowNs() < deadline_ns) line->WaitEdges(deadline_ns, &edges);
  return edges;
}

TEST(TriggerSource, PolarityNamesRoundTripAndOthersAreRefused) {
  for (TriggerPolarity p :
       {TriggerPolarity::kRising, TriggerPolarity::kFalling, TriggerPolarity::kBoth}) {
    EXPECT_EQ(ParseTriggerPolarity(TriggerPolarityName(p)), p);
  }
  EXPECT_EQ(ParseTriggerPolarity("falling"), TriggerPolarity::kFalling);
  for (const char* bad : {"", "up", "rise", "Rising "}) {
    EXPECT_THROW(ParseTriggerPolarity(bad), std::invalid_argument) << bad;
  }
}

TEST(TriggerFilter, IgnoresBounceWithinTheDebounceWhicheverItsDirection) {
  TriggerFilter filter(TriggerPolarity::kRising, 5 * kTriggerMs);
  EXPECT_EQ(AcceptedTriggerTimes(&filter, BouncyTriggerEdges()),
            (std::vector<int64_t>{0, 10 * kTriggerMs}));
  EXPECT_EQ(filter.bounces(), 3u);         // 1 and 2 ms after the first edge, 4 ms after 5 ms
  EXPECT_EQ(filter.other_polarity(), 1u);  // the falling edge at 5 ms: not bounce, not wanted
}

TEST(TriggerFilter, FallingAndBothCountTheirEdgesOnly) {
  TriggerFilter falling(TriggerPolarity::kFalling, 5 * kTriggerMs);
  EXPECT_EQ(AcceptedTriggerTimes(&falling, BouncyTriggerEdges()),
            (std::vector<int64_t>{5 * kTriggerMs}));
  EXPECT_EQ(falling.other_polarity(), 2u);
  TriggerFilter both(TriggerPolarity::kBoth, 5 * kTriggerMs);
  EXPECT_EQ(AcceptedTriggerTimes(&both, BouncyTriggerEdges()),
            (std::vector<int64_t>{0, 5 * kTriggerMs, 10 * kTriggerMs}));
  EXPECT_EQ(both.other_polarity(), 0u);
  EXPECT_EQ(both.bounces(), 3u);
}

TEST(TriggerFilter, WithoutDebounceEveryRisingEdgeCounts) {
  TriggerFilter filter(TriggerPolarity::kRising, 0);
  EXPECT_EQ(AcceptedTriggerTimes(&filter, BouncyTriggerEdges()).size(), 4u);
  EXPECT_EQ(filter.bounces(), 0u);
  EXPECT_THROW(TriggerFilter(TriggerPolarity::kRising, -1), std::invalid_argument);
}

TEST(EmulatedTriggerLine, WaitsForTheFirstEdgeAndGivesItsOwnTime) {
  VirtualClock clock(0);
  const int64_t origin_ns = 7 * kTriggerMs;
  EmulatedTriggerLine line(
      {100 * kTriggerMs, 300 * kTriggerMs}, 5 * kTriggerMs, 0,
      [&] { return std::optional<int64_t>(origin_ns); }, &clock);
  std::vector<TriggerEdge> edges;
  line.WaitEdges(origin_ns + 1000 * kTriggerMs, &edges);  // returns at the first edge
  EXPECT_EQ(clock.NowNs(), origin_ns + 100 * kTriggerMs);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_EQ(edges[0].t_ns, origin_ns + 100 * kTriggerMs);
  EXPECT_TRUE(edges[0].rising);
  line.WaitEdges(origin_ns + 200 * kTriggerMs, &edges);  // the falling edge 5 ms later
  ASSERT_EQ(edges.size(), 2u);
  EXPECT_EQ(edges[1].t_ns, origin_ns + 105 * kTriggerMs);
  EXPECT_FALSE(edges[1].rising);
  line.WaitEdges(origin_ns + 200 * kTriggerMs, &edges);  // nothing more before the deadline
  EXPECT_EQ(edges.size(), 2u);
  EXPECT_EQ(clock.NowNs(), origin_ns + 200 * kTriggerMs);
}

TEST(EmulatedTriggerLine, NothingHappensUntilTheOriginIsKnown) {
  VirtualClock clock(0);
  std::optional<int64_t> origin;
  EmulatedTriggerLine line(
      {10 * kTriggerMs}, 5 * kTriggerMs, 0, [&] { return origin; }, &clock);
  std::vector<TriggerEdge> edges;
  line.WaitEdges(50 * kTriggerMs, &edges);
  EXPECT_TRUE(edges.empty());
  EXPECT_EQ(clock.NowNs(), 50 * kTriggerMs);
  origin = 20 * kTriggerMs;  // known now: both edges are already past, and come at once
  line.WaitEdges(60 * kTriggerMs, &edges);
  ASSERT_EQ(edges.size(), 2u);
  EXPECT_EQ(edges[0].t_ns, 30 * kTriggerMs);
  EXPECT_EQ(edges[1].t_ns, 35 * kTriggerMs);
}

TEST(EmulatedTriggerLine, BouncyPulsesFilterToOneTriggerEach) {
  VirtualClock clock(0);
  const int64_t origin_ns = 2 * kTriggerMs;
  const std::vector<int64_t> pulses = {100 * kTriggerMs, 300 * kTriggerMs, 312 * kTriggerMs};
  const int bounce = 3;
  EmulatedTriggerLine line(
      pulses, 5 * kTriggerMs, bounce, [&] { return std::optional<int64_t>(origin_ns); }, &clock);
  const std::vector<TriggerEdge> edges = CollectTriggerEdges(&line, &clock, kTriggerMs * 1000);
  // Each pulse: a rising and a falling edge, each followed by `bounce` pairs of edges.
  ASSERT_EQ(edges.size(), pulses.size() * 2 * (1 + 2 * bounce));
  TriggerFilter filter(TriggerPolarity::kRising, kTriggerMs);
  std::vector<int64_t> expected;
  for (int64_t p : pulses) expected.push_back(origin_ns + p);
  EXPECT_EQ(AcceptedTriggerTimes(&filter, edges), expected);
  EXPECT_EQ(filter.bounces(), pulses.size() * 2 * 2 * bounce);
  EXPECT_EQ(filter.other_polarity(), pulses.size());  // each pulse's falling edge
}

TEST(EmulatedTriggerLine, BounceFollowsItsEdgeWithin200Microseconds) {
  // Every bounce edge lies after the edge it follows, within 200 us, up to the 99 bounces
  // `record --trigger` allows (from 10 on, the first pair's opposite edge once came before its
  // edge, and a debounced rising filter then triggered a pulse width late).
  for (int bounce : {1, 4, 9, 10, 99}) {
    VirtualClock clock(0);
    const int64_t pulse_ns = 50 * kTriggerMs, width_ns = 5 * kTriggerMs;
    EmulatedTriggerLine line(
        {pulse_ns}, width_ns, bounce, [] { return std::optional<int64_t>(0); }, &clock);
    const std::vector<TriggerEdge> edges = CollectTriggerEdges(&line, &clock, 100 * kTriggerMs);
    ASSERT_EQ(edges.size(), 2u * (1 + 2 * bounce)) << bounce;
    EXPECT_EQ(edges.front().t_ns, pulse_ns) << bounce;  // the pulse's own edge comes first
    EXPECT_TRUE(edges.front().rising) << bounce;
    for (const TriggerEdge& e : edges) {
      const int64_t edge_ns = e.t_ns < pulse_ns + width_ns ? pulse_ns : pulse_ns + width_ns;
      EXPECT_GE(e.t_ns, edge_ns) << "bounce " << bounce;
      EXPECT_LE(e.t_ns, edge_ns + 200000) << "bounce " << bounce;
    }
    TriggerFilter filter(TriggerPolarity::kRising, kTriggerMs);
    EXPECT_EQ(AcceptedTriggerTimes(&filter, edges), std::vector<int64_t>{pulse_ns}) << bounce;
  }
}

TEST(TriggerSource, PulsesEveryGivesMultiplesUpToTheDuration) {
  EXPECT_EQ(PulsesEvery(2.0, 7.0), (std::vector<int64_t>{2000000000, 4000000000, 6000000000}));
  // 3 x 0.1 s is 0.30000000000000004 s in doubles: still within a 0.3 s duration.
  EXPECT_EQ(PulsesEvery(0.1, 0.3), (std::vector<int64_t>{100000000, 200000000, 300000000}));
  EXPECT_TRUE(PulsesEvery(5.0, 4.9).empty());
  EXPECT_THROW(PulsesEvery(0.0, 10.0), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
