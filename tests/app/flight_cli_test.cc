#include "estimate/paper/flight.h"
#include "estimate/report/analysis_json.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/ulog_write.h"
#include "sim/sensor_pair.h"
#include "sim/still_detect.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::RunShutterlab;
using test::StillThenTurningTrace;
using test::TempDir;
using test::WriteSensorPair;

// 1 kHz; 5 s still (the default bias segment), then 2 s at a constant y rate that turns 300" in the
// 9 ms a 10 ms window spans: over the 5 cm threshold (226"), under the 10 cm one (433").
std::string WriteTrace(const TempDir& dir) {
  const double rate = 300.0 / (180.0 * 3600.0 / M_PI) / 0.009;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 7000; ++i) {
    samples.push_back(
        {static_cast<int64_t>(i) * 1000000, Eigen::Vector3d(0.0, i < 5000 ? 0.0 : rate, 0.0)});
  }
  const std::string path = dir / "gyro.csv";
  WriteGyroCsv(path, GyroTrace(std::move(samples)));
  return path;
}

// Lines of text (newline-terminated).
size_t CountLines(const std::string& text) { return std::count(text.begin(), text.end(), '\n'); }

TEST(FlightCli, JsonFollowsFormats) {
  TempDir dir;
  const std::string trace = WriteTrace(dir);
  const auto r = RunShutterlab("flight " + trace +
                               " --altitude 50m --limit 5cm,0.10m --window 10ms,0.02s --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("altitude_m"), 50.0);
  EXPECT_EQ(j.at("noise_allowance_arcsec"), 20.0);
  EXPECT_EQ(j.at("windows_total"), 2000 - 10);
  ASSERT_EQ(j.at("rows").size(), 4u);
  EXPECT_EQ(j["rows"][0]["limit_m"], 0.05);
  EXPECT_EQ(j["rows"][0]["window_s"], 0.010);
  EXPECT_EQ(j["rows"][0]["flagged_percent"], 100.0);  // 300" > 226"
  EXPECT_EQ(j["rows"][0]["flagged_percent_vector"], 100.0);
  EXPECT_EQ(j["rows"][2]["flagged_percent"], 0.0);    // 10 cm, 10 ms: 300" < 433"
  EXPECT_EQ(j["rows"][3]["flagged_percent"], 100.0);  // 10 cm, 20 ms: 633" > 433"
}

// "-" names the standard input: a ULog on a pipe is copied to a temporary file and read in its two
// passes, with the same output as the file, and no copy left in $TMPDIR.
TEST(FlightCli, ADashReadsALogOnThePipe) {
  test::TempDir dir;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 8000; ++i) {
    const double t_s = i * 1e-3;
    samples.push_back({static_cast<int64_t>(i + 1) * 1000000,
                       Eigen::Vector3d(0.3 * std::sin(7 * t_s), 0.01, -0.2 * std::cos(3 * t_s))});
  }
  const std::string path = dir / "log.ulg";
  WriteFileAtomically(path, SerializeULog(GyroTrace(std::move(samples)), {}));
  std::filesystem::create_directories(dir / "tmp");
  const auto file = RunShutterlab("flight " + path + " --json");
  ASSERT_EQ(file.exit_code, 0) << file.output;
  // The copy goes to $TMPDIR: none is left there; a folder that is not there is named in one line.
  const auto piped = RunShutterlab("flight - --json", path, "TMPDIR=" + (dir / "tmp"));
  ASSERT_EQ(piped.exit_code, 0) << piped.output;
  EXPECT_EQ(piped.out, file.out);
  const auto missing = RunShutterlab("flight - --json", path, "TMPDIR=" + (dir / "missing"));
  ExpectPipeCopyRefused(missing, dir / "missing");
  EXPECT_TRUE(std::filesystem::is_empty(dir / "tmp"));
}

TEST(FlightCli, WarningsGoToStderrAndIntoTheJson) {
  // A 1 kHz trace with a 0.5 s pause of the logger and one sample clipped at +-250 deg/s.
  TempDir dir;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 7000; ++i) {
    const int64_t t_ns = static_cast<int64_t>(i) * 1'000'000 + (i >= 6000 ? 500'000'000 : 0);
    samples.push_back({t_ns, Eigen::Vector3d(i == 6500 ? -250.0 * M_PI / 180.0 : 0.0, 0.0, 0.0)});
  }
  const std::string trace = dir / "gyro.csv";
  WriteGyroCsv(trace, GyroTrace(std::move(samples)));
  const auto r = RunShutterlab("flight " + trace + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // stderr names the file and each loss.
  EXPECT_NE(r.err.find("warning: " + trace + ": gap: 1 interval(s)"), std::string::npos)
      << r.output;
  EXPECT_NE(r.err.find("warning: " + trace + ": saturated: axis x, 1 sample(s)"), std::string::npos)
      << r.output;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j.at("warnings").size(), 2u) << j.dump(2);
  EXPECT_EQ(j["warnings"][0]["kind"], "gap");
  EXPECT_EQ(j["warnings"][0]["count"], 1);
  EXPECT_NEAR(j["warnings"][0]["t_s"].get<double>(), 5.999, 1e-9);
  EXPECT_EQ(j["warnings"][1]["kind"], "saturated");
  EXPECT_NEAR(j["warnings"][1]["t_s"].get<double>(), 7.0, 1e-9);

  // A clean trace carries an empty list.
  const auto clean = RunShutterlab("flight " + WriteTrace(dir) + " --json");
  ASSERT_EQ(clean.exit_code, 0) << clean.output;
  EXPECT_TRUE(nlohmann::json::parse(clean.out).at("warnings").empty());
}

TEST(FlightCli, LowRateLogRowsSayTooFewSamples) {
  TempDir dir;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 1000; ++i)
    samples.push_back({i * int64_t{20'000'000}, Eigen::Vector3d::Zero()});
  const std::string trace = dir / "gyro50.csv";
  WriteGyroCsv(trace, GyroTrace(std::move(samples)));
  const auto r = RunShutterlab("flight " + trace + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.out);
  for (const auto& row : j.at("rows")) {
    EXPECT_TRUE(row.at("too_few_samples").get<bool>());
    EXPECT_TRUE(row.at("flagged_percent").is_null());
  }
  EXPECT_EQ(j["warnings"][0]["kind"], "too_few_samples");
  const auto table = RunShutterlab("flight " + trace);
  EXPECT_NE(table.output.find("too few samples"), std::string::npos) << table.output;
  EXPECT_EQ(table.output.find(" 0.00 "), std::string::npos) << "no 0 % for a row not measured";
}

TEST(FlightCli, TableAndSeries) {
  TempDir dir;
  const std::string trace = WriteTrace(dir);
  const std::string series = dir / "series.csv";
  const auto r = RunShutterlab("flight " + trace + " --series " + series);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("per-axis %"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("criteria:"), std::string::npos) << r.output;
  const std::string csv = ReadFileToString(series);
  EXPECT_EQ(csv.rfind("t,range_x,range_y,range_z,vector\n", 0), 0u);
  EXPECT_EQ(CountLines(csv), 1u + 2000u - 10u);
}

// What flight, noise and accuracy took as defaults is said, with how to give it, in the table and
// the JSON; what was given is not.
TEST(FlightCli, SaysWhatItAssumedAndHowToGiveIt) {
  TempDir dir;
  const std::string trace = WriteTrace(dir);
  const auto bare = RunShutterlab("flight " + trace);
  ASSERT_EQ(bare.exit_code, 0) << bare.output;
  for (const std::string line :
       {"\nassumed: altitude 50 m; give --altitude\n",
        "\nassumed: readout 10 ms, 20 ms (the paper's windows); give --window with your camera's "
        "readout\n",
        "\nassumed: bias the mean over 0:5s after the first sample (the camera taken as still "
        "then); give --bias A:B over a still part, --auto-bias, or --zero-bias\n"}) {
    EXPECT_NE(bare.out.find(line), std::string::npos) << line << bare.out;
  }
  const auto json = RunShutterlab("flight " + trace + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const nlohmann::json assumed = nlohmann::json::parse(json.out)["assumptions"];
  ASSERT_EQ(assumed.size(), 3u) << assumed.dump();
  EXPECT_EQ(assumed[0]["what"], "altitude");
  EXPECT_EQ(assumed[2]["give"], "--bias A:B over a still part, --auto-bias, or --zero-bias");
  const auto given =
      RunShutterlab("flight " + trace + " --altitude 40m --window 30ms --bias 0:1s --json");
  ASSERT_EQ(given.exit_code, 0) << given.output;
  EXPECT_TRUE(nlohmann::json::parse(given.out)["assumptions"].empty()) << given.out;
  const auto noise = RunShutterlab("noise " + trace + " --json");
  ASSERT_EQ(noise.exit_code, 0) << noise.output;
  ASSERT_EQ(nlohmann::json::parse(noise.out)["assumptions"].size(), 1u) << noise.out;
  EXPECT_TRUE(nlohmann::json::parse(
                  RunShutterlab("noise " + trace + " --zero-bias --json").out)["assumptions"]
                  .empty());
}

// --auto-bias streams the log (the still search reads it in passes of its own, in bounded memory)
// and must give what the analysis of the whole trace gives: the same segment, bias and counts.
TEST(FlightCli, AutoBiasStreamedEqualsTheWholeTrace) {
  TempDir dir;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<GyroSample> samples;
  for (int i = 0; i < 9000; ++i) {  // 1 kHz: moving, still from 3 s to 6 s, moving again
    const double t = i * 1e-3;
    const bool still = t >= 3.0 && t < 6.0;
    const Eigen::Vector3d motion =
        still ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0.3 * std::sin(4 * t), 0.2, 0.05);
    samples.push_back({static_cast<int64_t>(i) * 1000000,
                       motion + Eigen::Vector3d(0.01 + noise(rng), noise(rng), noise(rng))});
  }
  const GyroTrace trace(std::move(samples));
  const std::string path = dir / "gyro.csv";
  WriteGyroCsv(path, trace);
  const auto r = RunShutterlab("flight " + path + " --auto-bias --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.err.find("auto-bias: still segment 3.0"), std::string::npos) << r.err;
  FlightOptions options;
  options.bias = DetectStillSegment(ReadGyroCsv(path)).segment;
  const nlohmann::json whole = FlightToJson(Flight(ReadGyroCsv(path), options));
  nlohmann::json streamed = nlohmann::json::parse(r.out);
  streamed.erase("warnings");
  streamed.erase("assumptions");  // the command's, not the analysis's
  EXPECT_EQ(streamed, whole) << streamed.dump(1) << "\n" << whole.dump(1);
  // A log on a pipe can be read once only: it is copied to a temporary file in $TMPDIR (none is
  // left there), whose passes give the same result; a folder that is not there is named.
  std::filesystem::create_directories(dir / "tmp");
  const auto piped =
      RunShutterlab("flight /dev/stdin --auto-bias --json", path, "TMPDIR=" + (dir / "tmp"));
  ASSERT_EQ(piped.exit_code, 0) << piped.output;
  EXPECT_NE(piped.err.find("auto-bias: still segment 3.0"), std::string::npos) << piped.err;
  nlohmann::json from_pipe = nlohmann::json::parse(piped.out);
  from_pipe.erase("warnings");
  from_pipe.erase("assumptions");
  EXPECT_EQ(from_pipe, whole);
  EXPECT_TRUE(std::filesystem::is_empty(dir / "tmp"));
  const auto missing =
      RunShutterlab("flight - --auto-bias --json", path, "TMPDIR=" + (dir / "missing"));
  ExpectPipeCopyRefused(missing, dir / "missing");
}

// A log with no still stretch: --auto-bias is refused in one line that names the log, from a file
// and from a pipe alike, by flight, noise and accuracy (which before the log pipeline said it
// without the log's name).
TEST(FlightCli, AutoBiasWithoutAStillStretchNamesTheLog) {
  TempDir dir;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 6000; ++i) {
    const double t = i * 1e-3;
    samples.push_back({static_cast<int64_t>(i) * 1000000,
                       Eigen::Vector3d(0.3 * std::sin(4 * t), 0.2 * std::cos(3 * t), 0.05)});
  }
  const std::string path = dir / "moving.csv";
  WriteGyroCsv(path, GyroTrace(std::move(samples)));
  for (const bool piped : {false, true}) {
    const auto r = piped ? RunShutterlab("flight - --auto-bias", path)
                         : RunShutterlab("flight " + path + " --auto-bias");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    const std::string named = piped ? "/dev/stdin" : path;
    EXPECT_EQ(r.err.rfind("error: " + named + ": no still segment found: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  // noise and accuracy read the log whole, and name it the same way.
  for (const std::string command : {"noise", "accuracy --reference-deg 1"}) {
    const auto r = RunShutterlab(command + " " + path + " --auto-bias");
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.output;
    EXPECT_EQ(r.err.rfind("error: " + path + ": no still segment found: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  // A bad flag is refused before a log on a pipe is copied (no folder to copy it to here), and is
  // not named by the log.
  const auto bad_flag =
      RunShutterlab("flight - --auto-bias --format bogus", path, "TMPDIR=" + (dir / "missing"));
  EXPECT_EQ(bad_flag.exit_code, 2) << bad_flag.output;
  EXPECT_EQ(bad_flag.err.rfind("error: unknown log format 'bogus'", 0), 0u) << bad_flag.err;
}

// `flight A --second B` on regular files fits the pair in passes and analyses the fused samples as
// they are made, in bounded memory: the same table as the pair fused whole (FuseSensorPair) and
// analysed (Flight), with --bias and with --auto-bias; with B on a pipe (copied to a temporary
// file that the passes read), the same.
TEST(FlightCli, ASensorPairStreamedEqualsTheWholeFusion) {
  TempDir dir;
  const Eigen::Matrix3d b_from_a =
      Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  WriteSensorPair(StillThenTurningTrace(), b_from_a, dir.path());
  const GyroTrace a = ReadGyroCsv(dir / "a.csv"), b = ReadGyroCsv(dir / "b.csv");
  for (const std::string bias : {"--bias 0:4s", "--auto-bias"}) {
    SensorPairOptions pair_options;
    pair_options.still =
        bias == "--auto-bias" ? DetectStillSegment(a).segment : BiasSegment{0.0, 4.0};
    const SensorPair fused = FuseSensorPair(a, b, pair_options);
    FlightOptions options;
    options.bias = *pair_options.still;
    nlohmann::json whole = FlightToJson(Flight(fused.fused, options));
    whole["pair"] = SensorPairToJson(fused, dir / "b.csv");
    const auto r = RunShutterlab("flight " + (dir / "a.csv") + " --second " + (dir / "b.csv") +
                                 " " + bias + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    nlohmann::json streamed = nlohmann::json::parse(r.out);
    streamed.erase("warnings");
    streamed.erase("assumptions");  // the command's, not the analysis's
    EXPECT_EQ(streamed, whole) << bias << "\n" << streamed.dump(1) << "\n" << whole.dump(1);
    EXPECT_TRUE(streamed["pair"]["mounting_fitted"].get<bool>()) << bias;
    const auto piped = RunShutterlab(
        "flight " + (dir / "a.csv") + " --second /dev/stdin --format gyro.csv " + bias + " --json",
        dir / "b.csv");
    ASSERT_EQ(piped.exit_code, 0) << piped.output;
    nlohmann::json from_pipe = nlohmann::json::parse(piped.out);
    from_pipe.erase("warnings");
    from_pipe.erase("assumptions");
    from_pipe["pair"]["second_log"] = dir / "b.csv";  // named as given: /dev/stdin
    EXPECT_EQ(from_pipe, whole) << bias;
  }
}

// A file name that is not UTF-8 goes into --json as U+FFFD, never stops the command (it stopped
// with an internal error on the second log's name).
TEST(FlightCli, AFileNameThatIsNotUtf8IsPrintedReplaced) {
  TempDir dir;
  const std::string path = dir / "gyro\xff.csv";
  WriteSensorPair(StillThenTurningTrace(), Eigen::Matrix3d::Identity(), dir.path());
  std::filesystem::rename(dir / "b.csv", path);
  const auto r = RunShutterlab("flight " + (dir / "a.csv") + " --second '" + path + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["pair"]["second_log"].get<std::string>(), dir / "gyro\xEF\xBF\xBD.csv");
}

TEST(FlightCli, BadInputExitsTwoWithOneLine) {
  TempDir dir;
  const std::string trace = WriteTrace(dir);
  const std::string series = dir / "series.csv";
  for (const std::string args :
       {"--window 3s", "--limit 5in", "--bias 0:0.005s", "--altitude -1m", "--bias 0:100s"}) {
    const auto r = RunShutterlab("flight " + trace + " " + args + " --series " + series);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_EQ(CountLines(r.output), 1u) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("error: ", 0), 0u) << r.output;
    EXPECT_FALSE(std::filesystem::exists(series)) << "partial output for " << args;
    if (args == "--window 3s") {
      EXPECT_NE(r.output.find("longer than"), std::string::npos) << r.output;
      EXPECT_NE(r.output.find(trace), std::string::npos)
          << "error must name the file: " << r.output;
    }
  }
}

}  // namespace
}  // namespace shutterlab
