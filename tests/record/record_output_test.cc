// The recorder's files, read back by the project's own readers: rows of raw counts at ns from t0,
// the .gcsv header of sensor i of a recording (its part, setting, time base, figures and only its
// own gaps) through ReadGcsv, the .gcsv appearing whole or not at all with no temporary file left,
// and the triggers file through ReadTriggerFile.

#include "record/record_output.h"

#include "sim/check.h"
#include "sim/logs/gcsv.h"
#include "sim/logs/trigger_file.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/test_util.h"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kOutputT0Ns = 123456789000;  // clock time of t = 0 in the files

RecordedSample OutputSample(int64_t t_ns, int16_t x, int16_t y, int16_t z) {
  RecordedSample s;
  s.t_ns = t_ns;
  s.counts = {x, y, z};
  return s;
}

// A finished two-sensor recording: an MPU-9250 at 8 kHz +-250 deg/s and an ICM-42688-P at 32 kHz
// +-2000 deg/s, a gap on each.
RecordSummary OutputSummary() {
  RecordSummary summary;
  summary.t0_clock_ns = kOutputT0Ns;
  summary.max_writer_stall_s = 0.3;
  for (const auto& [part, rate, range] : {std::make_tuple(GyroPart::kMpu9250, 8000.0, 250),
                                          std::make_tuple(GyroPart::kIcm42688p, 32000.0, 2000)}) {
    SensorSummary s;
    SensorConfig config;
    config.rate_hz = rate;
    config.range_dps = range;
    s.setting = ResolvePartSetting(part, config);
    s.device = part == GyroPart::kMpu9250 ? "/dev/spidev0.0" : "emulate:t.csv,part=icm42688p";
    s.samples = 3;
    s.rate_hz = rate;
    s.drift_ppm = -12.5;
    s.ring_high_water = 2400;
    s.ring_capacity = 65536;
    s.still_span_s = 5.0;
    s.still_bias_rad_s = Eigen::Vector3d(0.001, -0.002, 0.0005);
    summary.sensors.push_back(s);
  }
  summary.gaps = {{0, 1.5, 315, "fifo_overflow"}, {1, 2.25, 40, "part_reset"}};
  return summary;
}

TEST(RecordOutput, RowsAreNanosecondsFromT0AndRawCounts) {
  std::string rows;
  AppendRecordedRow(OutputSample(kOutputT0Ns + 125000, -32768, 0, 32767), kOutputT0Ns, &rows);
  AppendRecordedRow(OutputSample(kOutputT0Ns - 5, 1, -1, 12), kOutputT0Ns, &rows);
  EXPECT_EQ(rows, "125000,-32768,0,32767\n-5,1,-1,12\n");
}

// The power-cut bound: rows appended every 5 ms with a 0.1 s sync interval; after every append,
// the oldest row not yet synced (what a power cut would lose) is at most the interval plus one
// append old (and scheduling: 40 ms), and the synced part always ends on a whole row.
TEST(RecordOutput, APowerCutLosesAtMostTheRowsOfOneSyncInterval) {
  test::TempDir dir;
  const RecordSummary summary = OutputSummary();
  RecorderOptions options;
  options.sync_interval_s = 0.1;
  RowFile rows(dir / "cut.gcsv", RecordingGcsvHeader(summary, 0, options), options.sync_interval_s);
  const off_t header_bytes = rows.synced_bytes();
  std::vector<std::pair<off_t, std::chrono::steady_clock::time_point>> appended;  // end, when
  double worst_age_s = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; std::chrono::steady_clock::now() - start < std::chrono::milliseconds(1200); ++k) {
    std::string text;
    AppendRecordedRow(OutputSample(kOutputT0Ns + k * 125000, k, -k, 1), kOutputT0Ns, &text);
    rows.Append(text);
    const auto now = std::chrono::steady_clock::now();
    appended.push_back({(appended.empty() ? header_bytes : appended.back().first) +
                            static_cast<off_t>(text.size()),
                        now});
    bool on_a_row = rows.synced_bytes() == header_bytes;
    for (const auto& [end, when] : appended) {
      on_a_row = on_a_row || end == rows.synced_bytes();
      if (end > rows.synced_bytes()) {  // the oldest row a power cut would lose
        worst_age_s = std::max(worst_age_s, std::chrono::duration<double>(now - when).count());
        break;
      }
    }
    EXPECT_TRUE(on_a_row) << "synced to the middle of a row";
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::printf("a power cut would have lost rows at most %.1f ms old (sync interval 100 ms)\n",
              worst_age_s * 1e3);
  EXPECT_GT(rows.synced_bytes(), header_bytes + 1000);  // it did sync, many times
  EXPECT_LT(worst_age_s, 0.1 + 0.005 + 0.04);
}

TEST(RecordOutput, TheGcsvOfSensorTwoReadsBackWithItsHeaderRowsAndGaps) {
  test::TempDir dir;
  const RecordSummary summary = OutputSummary();
  RecorderOptions options;
  options.note = "bench test";
  const std::string path = dir / "b.gcsv";
  {
    RowFile rows(path, RecordingGcsvHeader(summary, 1, options), options.sync_interval_s);
    std::string text;
    AppendRecordedRow(OutputSample(kOutputT0Ns, 100, -200, 300), kOutputT0Ns, &text);
    rows.Append(text);
    text.clear();
    AppendRecordedRow(OutputSample(kOutputT0Ns + 31250, 101, -201, 301), kOutputT0Ns, &text);
    AppendRecordedRow(OutputSample(kOutputT0Ns + 62500, -32768, 32767, 0), kOutputT0Ns, &text);
    rows.Append(text);
    EXPECT_FALSE(std::filesystem::exists(path));  // not before Finish
    // Meanwhile the partial file reads as it is, its rows so far, saying it did not finish.
    const GcsvLog partial = ReadGcsv(path + ".partial");
    ASSERT_EQ(partial.trace.size(), 3u);
    EXPECT_EQ(partial.trace[2].t_ns, 62500);
    ASSERT_EQ(partial.warnings.size(), 1u) << test::JoinedWarnings(partial.warnings);
    EXPECT_EQ(partial.warnings[0].kind, "truncated");
    EXPECT_TRUE(test::AnyWarningContains(partial.warnings, "the recording did not finish"));
    EXPECT_TRUE(test::AnyWarningContains(partial.warnings, "a power cut those of the last 520 ms"))
        << test::JoinedWarnings(partial.warnings);
    rows.Finish(RecordedGcsvHeader(summary, 1, options));
  }
  const GcsvLog log = ReadGcsv(path);
  // Times: ns from t0; rates: counts times gscale, which is one count of +-2000 deg/s in rad/s.
  const double rad_s_per_count = kPi / 180.0 / 16.4;
  EXPECT_NEAR(log.gscale, rad_s_per_count, 1e-15);
  EXPECT_DOUBLE_EQ(log.tscale, 1e-9);
  ASSERT_EQ(log.trace.size(), 3u);
  EXPECT_EQ(log.trace[1].t_ns, 31250);
  EXPECT_EQ(log.trace[2].t_ns, 62500);
  constexpr double kRateTol = 1e-12;  // a count times gscale, in doubles
  EXPECT_NEAR(log.trace[1].omega_rad_s.x(), 101 * rad_s_per_count, kRateTol);
  EXPECT_NEAR(log.trace[2].omega_rad_s.x(), -32768 * rad_s_per_count, kRateTol);
  EXPECT_NEAR(log.trace[2].omega_rad_s.y(), 32767 * rad_s_per_count, kRateTol);
  EXPECT_EQ(log.orientation, "XYZ");
  auto value = [&](const std::string& key) {
    for (const auto& [k, v] : log.header) {
      if (k == key) return v;
    }
    return std::string("(missing)");
  };
  EXPECT_EQ(value("id"), "shutterlab record");
  EXPECT_EQ(value("note"), "bench test");
  EXPECT_EQ(value("part"), "ICM-42688-P");
  EXPECT_EQ(value("who_am_i"), "0x47");
  EXPECT_EQ(value("device"), "emulate:t.csv,part=icm42688p");  // the commas survive
  EXPECT_EQ(value("sensor"), "2 of 2");
  EXPECT_EQ(value("odr_hz"), "32000");
  EXPECT_EQ(value("range_dps"), "2000");
  EXPECT_EQ(value("t0_clock_ns"), std::to_string(kOutputT0Ns));
  EXPECT_EQ(value("samples"), "3");
  EXPECT_EQ(value("drift_ppm"), "-12.500");
  EXPECT_EQ(value("ring_high_water"), "2400 of 65536");
  EXPECT_EQ(value("max_writer_stall_ms"), "300.000");
  EXPECT_EQ(value("filter"), summary.sensors[1].setting.Describe());
  // The still bias: three numbers that read back as written.
  const std::string bias = value("still_bias_rad_s");
  Eigen::Vector3d read_bias;
  ASSERT_EQ(std::sscanf(bias.c_str(), "%lf;%lf;%lf", &read_bias[0], &read_bias[1], &read_bias[2]),
            3)
      << bias;
  EXPECT_EQ(read_bias, summary.sensors[1].still_bias_rad_s);
  // Only this sensor's gap, reported by the reader as a gap warning.
  ASSERT_EQ(log.warnings.size(), 1u) << test::JoinedWarnings(log.warnings);
  EXPECT_EQ(log.warnings[0].kind, "gap");
  EXPECT_EQ(log.warnings[0].t_s, 2.25);
  EXPECT_EQ(log.warnings[0].count, 40u);
  EXPECT_TRUE(test::AnyWarningContains(log.warnings, "part_reset"));
  // Nothing but the .gcsv is left in the folder.
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "b.gcsv");
  }
  EXPECT_EQ(files, 1u);
}

// Not finished (killed, power lost, a failure): the partial file stays when it holds rows, and is
// never overwritten by the next recording; without rows it goes.
TEST(RecordOutput, ARowFileNotFinishedKeepsItsRowsAndIsNeverOverwritten) {
  test::TempDir dir;
  const std::string header = RecordingGcsvHeader(OutputSummary(), 0, RecorderOptions{});
  { RowFile rows(dir / "empty.gcsv", header, 0.5); }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
  {
    RowFile rows(dir / "cut.gcsv", header, 0.5);
    rows.Append("0,1,2,3\n");
  }
  EXPECT_EQ(ReadGcsv(dir / "cut.gcsv.partial").trace.size(), 1u);
  EXPECT_FALSE(std::filesystem::exists(dir / "cut.gcsv"));
  try {
    RowFile again(dir / "cut.gcsv", header, 0.5);
    FAIL() << "a recording's partial file was taken over";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(dir / "cut.gcsv.partial: exists: a recording before", 0),
              0u)
        << e.what();
  }
  EXPECT_EQ(ReadGcsv(dir / "cut.gcsv.partial").trace.size(), 1u);
}

TEST(RecordOutput, AFinishThatCannotRenameLeavesNoTemporaryFile) {
  test::TempDir dir;
  const std::string blocked = dir / "taken.gcsv";
  std::filesystem::create_directories(std::filesystem::path(blocked) / "inside");  // a folder
  {
    RowFile rows(blocked, RecordingGcsvHeader(OutputSummary(), 0, RecorderOptions{}), 0.5);
    rows.Append("0,1,2,3\n");
    EXPECT_THROW(rows.Finish(RecordedGcsvHeader(OutputSummary(), 0, RecorderOptions{})), IoError);
  }
  std::set<std::string> entries;  // the rows stay in the partial file, nothing else is left
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    entries.insert(entry.path().filename().string());
  EXPECT_EQ(entries, (std::set<std::string>{"taken.gcsv", "taken.gcsv.partial"}));
}

TEST(RecordOutput, ARowFileInAMissingFolderIsAnIoErrorNamingTheOutput) {
  test::TempDir dir;
  const std::string path = dir / "no/such/folder/rec.gcsv";
  try {
    RowFile rows(path, RecordingGcsvHeader(OutputSummary(), 0, RecorderOptions{}), 0.5);
    FAIL() << "created rows for " << path;
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

// A trigger source for the triggers file's "# source" line.
class OutputTestTrigger : public TriggerSource {
 public:
  void WaitEdges(int64_t, std::vector<TriggerEdge>*) override {}
  std::string Name() const override { return "gpiochip0:17"; }
};

TEST(RecordOutput, TheTriggersFileReadsBackAsImagesAndTimes) {
  test::TempDir dir;
  RecordSummary summary = OutputSummary();
  summary.trigger_t_s = {0.5, 1.234567891, 3.0};
  summary.triggers = 3;
  summary.trigger_edges = 10;
  summary.trigger_bounces = 4;
  summary.trigger_other_polarity = 3;
  OutputTestTrigger trigger;
  RecorderOptions options;
  options.trigger = &trigger;
  options.polarity = TriggerPolarity::kFalling;
  options.debounce_s = 0.002;
  const std::string path = dir / "triggers.csv";
  WriteTriggersFile(path, summary, options);
  const TriggerFile file = ReadTriggerFile(path);
  EXPECT_EQ(file.format, "csv");
  EXPECT_EQ(file.clock, TriggerClock::kLog);
  ASSERT_EQ(file.events.size(), 3u);
  const char* names[] = {"IMG_0001", "IMG_0002", "IMG_0003"};
  const int64_t times_ns[] = {500000000, 1234567891, 3000000000};
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(file.events[i].name, names[i]);
    EXPECT_EQ(file.events[i].t_ns, times_ns[i]);  // %.9f: exact to the ns
  }
  const std::string text = ReadFileToString(path);
  EXPECT_NE(text.find("# source: gpiochip0:17\n"), std::string::npos) << text;
  EXPECT_NE(text.find("falling, debounce 0.002 s; 10 edge(s) seen, 4 bounce(s) ignored, 3 of "),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("# t0_clock_ns: " + std::to_string(kOutputT0Ns) + "\n"), std::string::npos)
      << text;
}

}  // namespace
}  // namespace shutterlab
