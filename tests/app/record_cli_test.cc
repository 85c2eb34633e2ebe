// CLI tests of `shutterlab record`: an emulated 8 kHz MPU-9250 recorded through writer stalls and
// read back by flight and analyze with its triggers, two sensors fused by noise --second, a clean
// stop on SIGINT, and bad devices refused with one line and exit code 2.

#include "sim/logs/flight_log_io.h"
#include "sim/logs/gcsv.h"
#include "sim/logs/gyro_io.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <fcntl.h>
#include <filesystem>
#include <random>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace shutterlab {
namespace {

using test::RunShutterlab;

// A synthetic trace written as gyro.csv in the test itself (a process start less per test).
void WriteTrace(const std::string& path, MotionProfile profile, double rate_hz, double duration_s,
                uint64_t seed, const std::string& second_path = "") {
  SynthOptions synth;
  synth.profile = profile;
  synth.rate_hz = rate_hz;
  synth.duration_s = duration_s;
  synth.seed = seed;
  WriteGyroCsv(path, SynthesizeTrace(synth, 0));
  if (!second_path.empty()) WriteGyroCsv(second_path, SynthesizeTrace(synth, 1));
}

// `record` of the trace through the emulated MPU-9250 at `rate` for `duration`, on the virtual
// clock, with the extra options, into out.
test::CommandResult RecordEmulated(const std::string& trace, const std::string& rate,
                                   const std::string& duration, const std::string& extra,
                                   const std::string& out) {
  return RunShutterlab("record --device emulate:" + trace + ",rate=" + rate + " --duration " +
                       duration + " --clock virtual " + extra + " --out " + out);
}

TEST(RecordCli, EmulatedRecordingGoesThroughFlightAndAnalyzeWithItsTriggers) {
  test::TempDir dir;
  const std::string trace = dir / "flight.csv", rec = dir / "rec.gcsv";
  ASSERT_EQ(
      RunShutterlab("synth flight --rate 8000Hz --duration 4s --seed 2 --out " + trace).exit_code,
      0);
  const auto record = RunShutterlab(
      "record --device emulate:" + trace + ",ppm=40 --duration 3.5s --clock virtual " +
      "--stall-writer 300ms@1s --trigger emulate:every=1s,bounce=2 --out " + rec);
  ASSERT_EQ(record.exit_code, 0) << record.output;
  EXPECT_NE(record.out.find("gaps        0, 0 sample(s) lost"), std::string::npos) << record.out;
  EXPECT_NE(record.out.find("triggers: 3"), std::string::npos) << record.out;
  const GcsvLog log = ReadGcsv(rec);
  EXPECT_NEAR(log.trace.size(), 28000.0, 100.0);
  const auto analyze =
      RunShutterlab("analyze " + rec + " --triggers " + (dir / "rec.triggers.csv") + " --json");
  ASSERT_EQ(analyze.exit_code, 0) << analyze.output;
  const auto analysis = nlohmann::json::parse(analyze.out);
  EXPECT_GT(analysis["flight"]["windows_total"].get<int>(), 10000);  // the flight table read it all
  const auto images = analysis["images"];
  ASSERT_EQ(images.size(), 3u);
  for (const auto& image : images) EXPECT_TRUE(image["in_trace"].get<bool>()) << image.dump();
}

// The recorder's triggers are on its own clock; a flight controller's log of the same flight is
// on another (WriteAsFlightControllerLog: 123.456 s ahead, its axes turned, 500 Hz). analyze
// --triggers-clock puts the triggers on the log's clock by aligning the two gyros: each image lands
// where the recorder's own analysis of the same trigger puts it, shifted by the clocks' difference.
TEST(RecordCli, TriggersOnTheRecordersClockGoOntoAFlightLogByTheMotion) {
  test::TempDir dir;
  const std::string trace = dir / "flight.csv", rec = dir / "rec.gcsv", fc = dir / "fc.csv";
  WriteTrace(trace, MotionProfile::kFlight, 1000.0, 30.0, 4);
  const auto record = RecordEmulated(trace, "1000Hz", "25s", "--trigger emulate:every=2s", rec);
  ASSERT_EQ(record.exit_code, 0) << record.output;
  test::WriteAsFlightControllerLog(trace, fc);

  const std::string triggers = " --triggers " + (dir / "rec.triggers.csv");
  const auto own = RunShutterlab("analyze " + rec + triggers + " --json");
  ASSERT_EQ(own.exit_code, 0) << own.output;
  // Without --triggers-clock the recorder's times fall before the log's first sample.
  const auto moved =
      RunShutterlab("analyze " + fc + triggers + " --triggers-clock " + rec + " --json");
  ASSERT_EQ(moved.exit_code, 0) << moved.output;
  EXPECT_NE(moved.err.find("triggers: on rec.gcsv's clock"), std::string::npos) << moved.err;
  const auto own_images = nlohmann::json::parse(own.out)["images"];
  const auto moved_images = nlohmann::json::parse(moved.out)["images"];
  ASSERT_EQ(own_images.size(), 12u);
  ASSERT_EQ(moved_images.size(), own_images.size());
  // The emulator plays the trace's first sample as the part's first (sensor_emulator.h), which
  // the recorder stamps its filter's delay earlier (the motion's time): a recorder time t is trace
  // time t - (first + delay), which the log reads + 123.456 s.
  const GcsvLog recorded = ReadGcsv(rec);
  const double first_s = recorded.trace.t_begin_ns() * 1e-9;
  double delay_ms = 0;
  for (const auto& [key, value] : recorded.header) {
    if (key == "filter_delay_ms") delay_ms = std::stod(value);
  }
  EXPECT_EQ(delay_ms, 2.9);  // 1 kHz: DLPF_CFG 1
  const double truth_s =
      ReadGyroCsv(trace).t_begin_ns() * 1e-9 - (first_s + delay_ms * 1e-3) + test::kFcClockAheadS;
  for (size_t k = 0; k < own_images.size(); ++k) {
    EXPECT_NEAR(moved_images[k]["t"].get<double>() - own_images[k]["t"].get<double>(), truth_s,
                2e-4)
        << k;
    EXPECT_TRUE(moved_images[k]["in_trace"].get<bool>());
  }
  // Triggers on GPS time are not on a gyro's clock: refused in one line.
  WriteFileAtomically(dir / "utc.csv", "image,utc_usec\nA.jpg,1700000000000000\n");
  const auto refused = RunShutterlab("analyze " + fc + " --triggers " + (dir / "utc.csv") +
                                     " --triggers-clock " + rec);
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_EQ(test::LineCount(refused.output), 1u) << refused.output;
  EXPECT_NE(refused.output.find("on UTC already"), std::string::npos) << refused.output;
}

// record --also: the same rows as gyro.csv (on the .gcsv's orientation, as its reader turns them)
// and as the source paper's raw counts (the part's own axes), each read back by its reader: the
// same samples, times to the nanosecond, rates to rounding.
TEST(RecordCli, AlsoWritesGyroCsvAndRawCountsOfTheSameRows) {
  test::TempDir dir;
  const std::string trace = dir / "flight.csv", rec = dir / "rec.gcsv";
  WriteTrace(trace, MotionProfile::kFlight, 2000.0, 3.0, 5);
  const auto record =
      RecordEmulated(trace, "2000Hz", "2s", "--orientation yXz --also gyro.csv,raw", rec);
  ASSERT_EQ(record.exit_code, 0) << record.output;
  const GyroTrace gcsv = ReadGcsv(rec).trace;
  const GyroTrace csv = ReadGyroCsv(dir / "rec.gyro.csv");
  FlightLogReadOptions raw_options;
  raw_options.format = LogFormat::kRaw;
  raw_options.raw.range_dps = 250;
  const GyroTrace raw = ReadFlightLog(dir / "rec.raw.csv", raw_options).gyro;
  ASSERT_GT(gcsv.size(), 3900u);
  ASSERT_EQ(csv.size(), gcsv.size());
  ASSERT_EQ(raw.size(), gcsv.size());
  const Eigen::Matrix3d orientation = GcsvOrientationMatrix("yXz");
  for (size_t i = 0; i < gcsv.size(); ++i) {
    EXPECT_EQ(csv[i].t_ns, gcsv[i].t_ns) << i;
    EXPECT_EQ(raw[i].t_ns, gcsv[i].t_ns) << i;
    EXPECT_LT((csv[i].omega_rad_s - gcsv[i].omega_rad_s).norm(), 1e-12) << i;
    EXPECT_LT((orientation * raw[i].omega_rad_s - gcsv[i].omega_rad_s).norm(), 1e-12) << i;
    if (HasFailure()) break;
  }
  // Refused in one line: a format it does not write.
  const auto bad =
      RunShutterlab("record --device emulate:" + trace +
                    " --duration 1s --clock virtual --also ulog --out " + (dir / "bad.gcsv"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("'ulog' is not a format (gyro.csv, raw)"), std::string::npos)
      << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.gcsv"));
}

TEST(RecordCli, TwoSensorsAreFusedByNoiseWithTheGainShown) {
  test::TempDir dir;
  const std::string a = dir / "a.csv", b = dir / "b.csv", rec = dir / "pair.gcsv";
  ASSERT_EQ(
      RunShutterlab("synth still --rate 8000Hz --duration 21s --seed 3 --out " + a + " --out2 " + b)
          .exit_code,
      0);
  const auto record = RunShutterlab("record --device emulate:" + a + " --device emulate:" + b +
                                    ",ppm=-30 --duration 20s --clock virtual --json --out " + rec);
  ASSERT_EQ(record.exit_code, 0) << record.output;
  const auto summary = nlohmann::json::parse(record.out);
  ASSERT_EQ(summary["sensors"].size(), 2u);
  EXPECT_NEAR(summary["sensors"][1]["drift_ppm"].get<double>(), -30.0, 2.0);
  EXPECT_EQ(summary["gaps"].size(), 0u);
  const auto noise =
      RunShutterlab("noise " + rec + " --second " + (dir / "pair.2.gcsv") + " --json");
  ASSERT_EQ(noise.exit_code, 0) << noise.output;
  const auto pair = nlohmann::json::parse(noise.out)["pair"];
  EXPECT_FALSE(pair["mounting_fitted"].get<bool>());
  for (int axis = 0; axis < 3; ++axis) {
    // Two equal independent sensors: the white noise falls by sqrt(2). The parts' 250 Hz filter
    // leaves the shortest averages of the Allan deviation off its white line, so the ARW comes
    // from longer ones, fewer; over 20 s it scatters by a few percent (over 6.5 s, up to 12 %).
    EXPECT_NEAR(pair["gain"]["arw_vs_first"][axis].get<double>(), std::sqrt(2.0), 0.1)
        << pair.dump();
  }
}

TEST(RecordCli, SigintStopsTheRecordingWithTheFileWhole) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv", rec = dir / "rec.gcsv";
  WriteTrace(trace, MotionProfile::kStill, 1000, 2.0, 4);
  // No duration: SIGINT once the recording runs (its partial file exists), however slowly the
  // process started; the shell's status is record's own. The virtual clock runs as fast as the
  // machine, so there are samples to write.
  const std::string command = "bash -c '" + std::string(SHUTTERLAB_BINARY) +
                              " record --device emulate:" + trace +
                              ",rate=1000Hz --clock virtual --out " + rec +
                              " >/dev/null 2>&1 & pid=$!; for i in $(seq 200); do "
                              "ls -a " +
                              dir.path().string() +
                              " | grep -q partial && break; sleep 0.05; done; "
                              "sleep 0.2; kill -INT $pid; wait $pid'";
  EXPECT_EQ(std::system(command.c_str()), 0);
  const GcsvLog log = ReadGcsv(rec);  // whole: header, column line, rows
  EXPECT_GT(log.trace.size(), 100u);
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().filename().string().find(".rec.gcsv."), std::string::npos)
        << "a temporary file was left: " << entry.path();
    EXPECT_NE(entry.path().extension(), ".partial") << "the partial file was left";
  }
}

// SIGKILL at 100 random moments (30 under the sanitizers) of a real-time recording: every file
// left is the recording's .partial, read as it is with its header and a `truncated` warning, and
// what it lost (the kill's time on the recorder's clock less its last row's) stays under the
// writer's interval plus scheduling. Each loss is printed; the worst is docs/raspberry-pi.md's.
// The moments are drawn within phases the test sees on disk, not in wall time from the start, so a
// loaded machine that starts the process late still has most kills land among the rows: one in
// four soon after the start (maybe before the files), one in four after the header appears (maybe
// before the first rows, which the emulated part's start-up holds back by about 0.3 s), half after
// the first rows are on disk.
TEST(RecordCli, KilledAtRandomMomentsLeavesAReadableFileLosingOnlyTheLastReads) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv";
  WriteTrace(trace, MotionProfile::kStill, 1000, 4.0, 6);
  std::mt19937 random(11);
  std::uniform_int_distribution<int> wait_ms(0, 400);
  const int kills = test::kAsan ? 30 : 100;
  const std::string column_line = "\nt,gx,gy,gz\n";
  const auto rows_written = [&](const std::string& partial) {
    const std::string text = std::filesystem::exists(partial) ? ReadFileToString(partial) : "";
    const size_t columns_at = text.find(column_line);
    return columns_at != std::string::npos && text.size() > columns_at + column_line.size();
  };
  // Polls every 5 ms for up to 20 s; false when it never came.
  const auto wait_for = [](const auto& condition) {
    for (int i = 0; i < 4000; ++i) {
      if (condition()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  };
  int before_start = 0, without_rows = 0;
  double worst_loss_ms = 0;
  for (int k = 0; k < kills; ++k) {
    const std::string rec = dir / ("k" + std::to_string(k) + ".gcsv");
    const std::string partial = rec + ".partial";
    const std::string device = "emulate:" + trace + ",rate=1000Hz";
    const pid_t pid =
        test::SpawnShutterlab({"record", "--device", device, "--out", rec, "--still", "0s"});
    ASSERT_GE(pid, 0);
    const int phase = k % 4;  // 0: from the start; 1: from the header; 2, 3: from the first rows
    if (phase == 1) {
      ASSERT_TRUE(wait_for([&] { return std::filesystem::exists(partial); })) << "run " << k;
    } else if (phase >= 2) {
      ASSERT_TRUE(wait_for([&] { return rows_written(partial); })) << "run " << k;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(wait_ms(random) / (phase == 0 ? 4 : 1)));
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    ::kill(pid, SIGKILL);
    const int64_t kill_ns = int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "run " << k << " ended before its kill";
    EXPECT_FALSE(std::filesystem::exists(rec)) << "run " << k;
    if (!std::filesystem::exists(partial)) {
      EXPECT_EQ(phase, 0) << "run " << k << ": the partial file went away";
      ++before_start;  // killed before its files: nothing was read yet
      continue;
    }
    const std::string text = ReadFileToString(partial);
    ASSERT_EQ(text.rfind("GYROFLOW IMU LOG\n", 0), 0u) << "run " << k << ": the header first";
    const size_t t0_at = text.find("\nt0_clock_ns,");
    ASSERT_NE(t0_at, std::string::npos);
    const int64_t t0_ns = std::stoll(text.substr(t0_at + 13));
    if (!rows_written(partial)) {
      EXPECT_LT(phase, 2) << "run " << k << ": the rows on disk went away";
      ++without_rows;  // killed before the part's first samples were written
      EXPECT_LT((kill_ns - t0_ns) * 1e-6, 2000.0) << "run " << k << " wrote no row for so long";
      continue;
    }
    const GcsvLog log = ReadGcsv(partial);
    ASSERT_FALSE(log.trace.empty());
    EXPECT_TRUE(test::AnyWarningContains(log.warnings, "the recording did not finish"))
        << test::JoinedWarnings(log.warnings);
    const double loss_ms = (kill_ns - t0_ns - log.trace[log.trace.size() - 1].t_ns) * 1e-6;
    EXPECT_GT(loss_ms, -1.0) << "run " << k << ": a row after the kill";
    worst_loss_ms = std::max(worst_loss_ms, loss_ms);
  }
  std::printf(
      "record killed %d times: %d before its files, %d before its first rows; the worst "
      "loss %.1f ms\n",
      kills, before_start, without_rows, worst_loss_ms);
  EXPECT_GT(before_start + without_rows, 0) << "no kill came before the rows";
  EXPECT_LT(worst_loss_ms, 250.0) << "a kill lost more than the writer's interval and scheduling";
}

// A full disk mid-recording: a file size limit (RLIMIT_FSIZE with SIGXFSZ ignored) fails the
// writes as a full disk does (EFBIG where a disk says ENOSPC). The recording stops at once with one
// line and exit code 2, and the partial file keeps whole rows only, read as it is.
TEST(RecordCli, AFullDiskStopsTheRecordingWithItsWholeRowsKept) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv", rec = dir / "rec.gcsv";
  WriteTrace(trace, MotionProfile::kStill, 1000, 10.0, 7);
  const std::string command = "bash -c \"trap '' XFSZ; ulimit -f 64; exec " +
                              std::string(SHUTTERLAB_BINARY) + " record --device emulate:" + trace +
                              ",rate=8kHz --duration 8s --still 0s --out " + rec + "\" 2> " +
                              dir / "err.txt";
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5))
      << "it went on after the disk was full";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string err = ReadFileToString(dir / "err.txt");
  EXPECT_EQ(test::LineCount(err), 1u) << err;
  EXPECT_NE(err.find(rec + ".partial: write failed: File too large"), std::string::npos) << err;
  EXPECT_NE(err.find("the recording stopped: its rows until then are in " + rec + ".partial"),
            std::string::npos)
      << err;
  EXPECT_FALSE(std::filesystem::exists(rec));
  const std::string text = ReadFileToString(rec + ".partial");
  EXPECT_LE(text.size(), 64u * 1024u);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n') << "a row cut by the full disk was kept";
  const GcsvLog log = ReadGcsv(rec + ".partial");
  EXPECT_GT(log.trace.size(), 1000u);
  ASSERT_EQ(log.warnings.size(), 1u) << test::JoinedWarnings(log.warnings);
  EXPECT_TRUE(test::AnyWarningContains(log.warnings, "disk full"));
}

TEST(RecordCli, BadDevicesAreOneLineWithExitCodeTwo) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv";
  WriteTrace(trace, MotionProfile::kStill, 1000, 1.0, 5);
  // A trace that is not there (IoError) and a part that has no such range (std::invalid_argument);
  // the device spec's other refusals are tested in tests/record.
  for (const std::string& device :
       {"emulate:" + dir / "missing.csv", "emulate:" + trace + ",range=300deg/s"}) {
    const auto result = RunShutterlab("record --device " + device +
                                      " --duration 1s --clock virtual --out " + (dir / "x.gcsv"));
    EXPECT_EQ(result.exit_code, 2) << device << "\n" << result.output;
    EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.gcsv"));
  }
}

}  // namespace
}  // namespace shutterlab
