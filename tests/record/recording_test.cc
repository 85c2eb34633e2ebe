// A recording's settings and reports: RecorderOptions::Check refusing each bad field by name (and
// taking the edges of what is allowed), the status line's rates, gaps, ring fill and drift per
// sensor, and the summary's figures for a person (the still bias in deg/s, the gaps, the notes, the
// triggers only when there were any).

#include "record/recording.h"

#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

class RecordingTestTrigger : public TriggerSource {
 public:
  void WaitEdges(int64_t, std::vector<TriggerEdge>*) override {}
  std::string Name() const override { return "test trigger"; }
};

RecorderOptions RecordingGoodOptions() {
  RecorderOptions options;
  options.duration_s = 1.0;
  return options;
}

// True when text contains part; says where it looked otherwise.
::testing::AssertionResult RecordingTextHas(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << part << "' not in:\n" << text;
}

TEST(RecorderOptions, CheckRefusesEachBadFieldByName) {
  RecordingTestTrigger trigger;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    const char* field;  // a word the message must hold
    std::function<void(RecorderOptions&)> spoil;
  };
  const std::vector<Case> cases = {
      {"duration", [](RecorderOptions& o) { o.duration_s = -1; }},
      {"still", [&](RecorderOptions& o) { o.still_s = nan; }},
      {"ring", [](RecorderOptions& o) { o.ring_s = 0.04; }},
      {"read interval", [](RecorderOptions& o) { o.read_interval_s = 0.11; }},
      {"writer interval", [](RecorderOptions& o) { o.writer_interval_s = 0; }},
      {"writer interval", [](RecorderOptions& o) { o.writer_interval_s = 1.5; }},
      {"health check", [](RecorderOptions& o) { o.health_check_s = 0; }},
      {"writer stall",
       [](RecorderOptions& o) {
         o.writer_stall = {-1.0, 0.1};
       }},
      {"writer stall",
       [](RecorderOptions& o) {
         o.writer_stall = {0.3, 0.3};
       }},
      {"paper pause",
       [](RecorderOptions& o) {
         o.paper_pause = {8000, -0.1};
       }},
      {"reader pause",
       [](RecorderOptions& o) {
         o.reader_pauses = {{1.0, 0.1}, {-2.0, 0.1}};
       }},
      {"debounce", [](RecorderOptions& o) { o.debounce_s = -0.001; }},
      {"priority", [](RecorderOptions& o) { o.reader_priority = 100; }},
      {"priority", [](RecorderOptions& o) { o.reader_priority = -1; }},
      {"triggers file", [&](RecorderOptions& o) { o.trigger = &trigger; }},
      {"duration or a stop flag", [](RecorderOptions& o) { o.duration_s = 0; }},
      {"orientation", [](RecorderOptions& o) { o.orientation = "XXY"; }},
      {"note", [](RecorderOptions& o) { o.note = "two\nlines"; }},
  };
  EXPECT_NO_THROW(RecordingGoodOptions().Check());
  for (const Case& c : cases) {
    RecorderOptions options = RecordingGoodOptions();
    c.spoil(options);
    try {
      options.Check();
      ADD_FAILURE() << "a bad " << c.field << " was accepted";
    } catch (const std::invalid_argument& e) {
      const std::string message = e.what();
      EXPECT_NE(ToLower(message).find(c.field), std::string::npos) << c.field << ": " << message;
    }
  }
}

TEST(RecorderOptions, CheckTakesTheEdgesOfWhatIsAllowed) {
  RecordingTestTrigger trigger;
  const std::atomic<bool> stop{false};
  std::vector<std::function<void(RecorderOptions&)>> edges = {
      [](RecorderOptions& o) { o.read_interval_s = 0.1; },
      [](RecorderOptions& o) { o.ring_s = 0.05; },
      [](RecorderOptions& o) { o.writer_interval_s = 1.0; },
      [](RecorderOptions& o) {
        o.writer_stall = {0.0, 0.3};
      },  // every 0: off
      [](RecorderOptions& o) { o.reader_priority = 99; },
      [](RecorderOptions& o) { o.debounce_s = 0; },
      [](RecorderOptions& o) { o.orientation = "yXz"; },
      [&](RecorderOptions& o) { o.duration_s = 0, o.stop = &stop; },  // until stopped
      [&](RecorderOptions& o) { o.trigger = &trigger, o.triggers_path = "t.csv"; },
  };
  for (size_t i = 0; i < edges.size(); ++i) {
    RecorderOptions options = RecordingGoodOptions();
    edges[i](options);
    EXPECT_NO_THROW(options.Check()) << "case " << i;
  }
}

TEST(RecordStatusLine, ShowsEachSensorsRateGapsRingFillAndDrift) {
  RecordStatus status;
  status.elapsed_s = 12.04;
  RecordStatus::Sensor first;
  first.rate_hz = 8000.26;
  first.gaps = 2;
  first.lost = 15;
  first.ring_high_water = 3000;  // of 8192: 36.6 %
  first.ring_capacity = 8192;
  first.drift_ppm = -12.34;
  RecordStatus::Sensor second;
  second.rate_hz = 1000.0;
  second.drift_ppm = 3.0;  // no ring yet: capacity 0 reads 0 %
  status.sensors = {first, second};
  status.triggers = 5;
  status.max_writer_stall_s = 0.25;
  const std::string line = RecordStatusLine(status);
  EXPECT_TRUE(RecordingTextHas(line, "12.0 s"));
  EXPECT_TRUE(RecordingTextHas(line, "8000.3 Hz  2 gap(s) (15 lost)  ring 37%  -12.3 ppm"));
  EXPECT_TRUE(RecordingTextHas(line, "  |  1000.0 Hz  0 gap(s)  ring 0%  +3.0 ppm"));
  EXPECT_EQ(line.find("(0 lost)"), std::string::npos) << line;
  EXPECT_LT(line.find("8000.3 Hz"), line.find("1000.0 Hz"));
  EXPECT_TRUE(RecordingTextHas(line, "5 trigger(s)"));
  EXPECT_TRUE(RecordingTextHas(line, "writer stall 250 ms"));
  EXPECT_EQ(line.find('\n'), std::string::npos);
}

RecordSummary RecordingTestSummary() {
  RecordSummary summary;
  summary.duration_s = 10.5;
  summary.stopped = true;
  SensorSummary s;
  s.device = "emulate:t.csv";
  s.out_path = "a.gcsv";
  s.setting = ResolvePartSetting(GyroPart::kMpu9250, SensorConfig{});
  s.samples = 84000;
  s.rate_hz = 8000.123;
  s.drift_ppm = 15.4;
  s.timestamp_rms_us = 12.3;
  s.gaps = 1;
  s.lost = 315;
  s.ring_high_water = 2400;
  s.ring_capacity = 65536;
  s.max_read_interval_s = 0.0025;
  s.still_span_s = 5.0;
  s.still_bias_rad_s = Eigen::Vector3d(0.5, -0.25, 0.0) * kPi / 180.0;  // deg/s to rad/s
  s.still_std_rad_s = Eigen::Vector3d(0.01, 0.02, 0.03) * kPi / 180.0;
  summary.sensors = {s};
  summary.gaps = {{0, 1.010625, 315, "fifo_overflow"}};
  summary.notes = {"real-time priority refused"};
  summary.max_writer_stall_s = 0.3;
  return summary;
}

TEST(RecordSummaryText, GivesEachSensorsFiguresTheBiasInDegreesAndTheGaps) {
  const std::string text = RecordSummaryText(RecordingTestSummary());
  EXPECT_EQ(text.rfind("recorded 10.500 s (stopped by signal)\n", 0), 0u) << text;
  EXPECT_TRUE(RecordingTextHas(text, "sensor 1: MPU-9250 on emulate:t.csv -> a.gcsv\n"));
  EXPECT_TRUE(RecordingTextHas(text, "achieved 8000.123 Hz (the part's clock +15.40 ppm"));
  EXPECT_TRUE(RecordingTextHas(text, "1, 315 sample(s) lost"));
  EXPECT_TRUE(RecordingTextHas(text, "ring high-water 2400 of 65536 samples"));
  EXPECT_TRUE(RecordingTextHas(text, "longest between FIFO reads 2.50 ms"));
  EXPECT_TRUE(RecordingTextHas(text, "over the first 5.00 s: +0.5000 -0.2500 +0.0000 deg/s"));
  EXPECT_TRUE(RecordingTextHas(text, "(std 0.0100 0.0200 0.0300 deg/s)"));
  EXPECT_TRUE(RecordingTextHas(text, "gap: sensor 1 fifo_overflow at 1.010625 s, 315 sample(s)"));
  EXPECT_TRUE(RecordingTextHas(text, "note: real-time priority refused\n"));
  EXPECT_TRUE(RecordingTextHas(text, "longest away from the rings 300.0 ms"));
  EXPECT_EQ(text.find("triggers:"), std::string::npos) << text;  // none were set up
}

TEST(RecordSummaryText, ReportsTriggersWhenThereWereEdges) {
  RecordSummary summary = RecordingTestSummary();
  summary.stopped = false;
  summary.triggers = 3;
  summary.trigger_edges = 14;
  summary.trigger_bounces = 8;
  const std::string text = RecordSummaryText(summary);
  EXPECT_TRUE(RecordingTextHas(text, "triggers: 3 (14 edge(s), 8 bounce(s) ignored)"));
  EXPECT_EQ(text.find("stopped by signal"), std::string::npos) << text;
}

}  // namespace
}  // namespace shutterlab
