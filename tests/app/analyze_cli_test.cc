#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/estimate/report/report_test_util.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::RunShutterlab;
using test::SourcePath;
using test::StillThenTurningTrace;
using test::WriteSensorPair;

std::string Bbl() { return test::RealDataPath("gyro/betaflight_blackbox/btfl_001.bbl"); }

TEST(AnalyzeCli, BlackboxEveryTwoSecondsJsonAndOutputs) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  const auto r =
      RunShutterlab("analyze " + Bbl() + " --every 2s --readout 20ms --altitude 40m --json --out " +
                    (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["source"]["format"], "betaflight");
  EXPECT_EQ(json["source"]["gyro"], "gyroADC");
  const double duration_s = json["source"]["duration_s"];
  ASSERT_EQ(json["images"].size(), static_cast<size_t>(duration_s / 2.0));
  EXPECT_DOUBLE_EQ(json["flight"]["altitude_m"].get<double>(), 40.0);
  EXPECT_DOUBLE_EQ(json["flight"]["rows"][0]["window_s"].get<double>(), 0.020);
  for (const auto& image : json["images"]) {
    EXPECT_TRUE(image["D_paper_m"].is_number());
    EXPECT_TRUE(image["flagged"]["0.05"].is_boolean());
  }
  const std::string csv = ReadFileToString(dir / "out/images.csv");
  EXPECT_EQ(test::LineCount(csv), json["images"].size() + 1);
  EXPECT_TRUE(std::filesystem::exists(dir / "out/exclude.txt"));
  // Said on stderr (stdout is the JSON document).
  EXPECT_NE(r.err.find("wrote " + (dir / "out") + "/: report.html, images.csv, exclude.txt\n"),
            std::string::npos)
      << r.err;
}

TEST(AnalyzeCli, ReportWithSceneIsSelfContainedAndMatchesTheTable) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  const auto r = RunShutterlab("analyze " + Bbl() + " --every 4s --out " + (dir / "out") +
                               " --scene " + test::GroundScenePath(1) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json json = nlohmann::json::parse(r.out);
  const std::string html = ReadFileToString(dir / "out/report.html");
  EXPECT_TRUE(test::SelfContained(html));
  EXPECT_NE(html.find("var uPlot="), std::string::npos);
  EXPECT_EQ(html.rfind("</html>\n"), html.size() - 8);  // written whole
  const auto charts = test::ChartBlocks(html);
  ASSERT_EQ(charts.size(), 5u);
  // The per-image chart holds the JSON's images and values.
  const auto& d = charts[2]["data"];
  ASSERT_EQ(d[0].size(), json["images"].size());
  for (size_t i = 0; i < d[0].size(); ++i) {
    EXPECT_NEAR(d[1][i].get<double>(), json["images"][i]["D_paper_m"].get<double>() * 100, 1e-9);
    EXPECT_NEAR(d[2][i].get<double>(), json["images"][i]["D_full_m"].get<double>() * 100, 1e-9);
  }
  // 3 worst images over the scene; the rate chart's 25k samples enveloped to at most 8000 points.
  size_t pictures = 0;
  for (size_t at = html.find("data:image/png;base64,"); at != std::string::npos;
       at = html.find("data:image/png;base64,", at + 1)) {
    ++pictures;
  }
  EXPECT_EQ(pictures, 3u);
  EXPECT_NE(html.find("blended over " +
                      std::filesystem::path(test::GroundScenePath(1)).filename().string()),
            std::string::npos);
  EXPECT_LE(charts[0]["data"][0].size(), 8000u);
  EXPECT_LT(html.size(), 6u << 20);
  // The log has no still time: its Allan coefficients are marked, not offered as the gyro's noise.
  EXPECT_NE(html.find("<td>not meaningful, at most "), std::string::npos);
  test::ExpectDrawsInChromium(dir / "out/report.html", charts.size(), "report_btfl");
}

TEST(AnalyzeCli, ReportOfSamplesStampedInBurstsSaysWhyItHasNoAllan) {
  // Samples stamped in threes with one time (a median interval of 0): the report is written, its
  // Allan section says why it has no deviation (`analyze --out` stopped in that section before).
  test::TempDir dir;
  std::vector<GyroSample> samples(20 * 3000);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.002);
  for (size_t k = 0; k < samples.size(); ++k) {
    samples[k].t_ns = static_cast<int64_t>(k / 3) * 1'000'000;
    samples[k].omega_rad_s = Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  }
  WriteGyroCsv(dir / "bursts.csv", GyroTrace(std::move(samples)));
  const auto r =
      RunShutterlab("analyze " + (dir / "bursts.csv") + " --every 2s --out " + (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string html = ReadFileToString(dir / "out/report.html");
  EXPECT_NE(html.find("Allan deviation: not computed on"), std::string::npos);
  EXPECT_NE(html.find("the median sample interval is 0"), std::string::npos);
  // The sampling line: the samples' rate, and no gap (it said "0.0 Hz, 19999 gaps": 59,999
  // intervals over 19.999 s).
  EXPECT_NE(r.out.find(" at 3000.1 Hz, 0 gaps"), std::string::npos) << r.out;
}

TEST(AnalyzeCli, SceneWithoutOutIsExitTwo) {
  SHUTTERLAB_NEED_REAL_DATA();
  const auto r =
      RunShutterlab("analyze " + Bbl() + " --every 4s --scene " + test::GroundScenePath(1));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--out"), std::string::npos) << r.output;
}

TEST(AnalyzeCli, EveryTakesPrecedenceAndOneImageIsSingular) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  const auto r = RunShutterlab("analyze " + Bbl() + " --every 40s");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("triggers: every 40 s"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("verdict: 1 image,"), std::string::npos) << r.output;
}

// `analyze LOG` reads a regular file as a stream, several times; a log on a pipe can be read once
// only, so it is copied once to a temporary file in $TMPDIR that the passes read (none is left
// there): the same images, flight table and report either way.
TEST(AnalyzeCli, ALogOnAPipeIsCopiedOnceWithTheSameResult) {
  test::TempDir dir;
  const std::string path = dir / "gyro.csv";
  test::WriteStillThenTurningGyroCsv(path);
  const std::string args = " --every 1s --size 320x240 --focal-px 280 --json --out ";
  const auto from_file = RunShutterlab("analyze " + path + args + (dir / "file"));
  ASSERT_EQ(from_file.exit_code, 0) << from_file.output;
  std::filesystem::create_directories(dir / "tmp");
  const auto from_pipe = RunShutterlab("analyze /dev/stdin" + args + (dir / "pipe"), path,
                                       "TMPDIR=" + (dir / "tmp"));  // format found
  ASSERT_EQ(from_pipe.exit_code, 0) << from_pipe.output;
  EXPECT_TRUE(std::filesystem::is_empty(dir / "tmp"));
  const auto missing = RunShutterlab("analyze - --json", path, "TMPDIR=" + (dir / "missing"));
  ExpectPipeCopyRefused(missing, dir / "missing");
  for (const char* name : {"images.csv", "exclude.txt"})
    EXPECT_EQ(ReadFileToString(dir / ("pipe/" + std::string(name))),
              ReadFileToString(dir / ("file/" + std::string(name))))
        << name;
  // The report's charts and pictures (its title names the log: "gyro.csv", "stdin").
  const std::string file_page = ReadFileToString(dir / "file/report.html");
  const std::string pipe_page = ReadFileToString(dir / "pipe/report.html");
  ASSERT_EQ(test::ChartBlocks(file_page).size(), 5u);
  EXPECT_EQ(test::ChartBlocks(pipe_page), test::ChartBlocks(file_page));
  const auto pictures = [](const std::string& page) {
    std::vector<std::string> found;
    for (size_t at = page.find("data:image/png"); at != std::string::npos;
         at = page.find("data:image/png", at + 1))
      found.push_back(page.substr(at, page.find('"', at) - at));
    return found;
  };
  EXPECT_EQ(pictures(pipe_page).size(), 3u);
  EXPECT_EQ(pictures(pipe_page), pictures(file_page));
  const nlohmann::json file_json = nlohmann::json::parse(from_file.out);
  const nlohmann::json pipe_json = nlohmann::json::parse(from_pipe.out);
  ASSERT_EQ(file_json["images"].size(), 11u);  // at 1, 2, ... 11 s of the 12 s log
  EXPECT_EQ(pipe_json["images"], file_json["images"]);
  EXPECT_EQ(pipe_json["flight"], file_json["flight"]);
}

TEST(AnalyzeCli, TableHasVerdict) {
  SHUTTERLAB_NEED_REAL_DATA();
  const auto r = RunShutterlab("analyze " + Bbl() + " --every 5s --limit 5cm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("verdict: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("with a 10 ms readout"), std::string::npos) << r.output;
}

TEST(AnalyzeCli, BadTriggersCsvIsOneLineExitTwoAndNoOutput) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  std::ofstream(dir / "times.csv") << "image,t\nIMG_1,1.0\nIMG_2,abc\n";
  const auto r = RunShutterlab("analyze " + Bbl() + " --triggers " + (dir / "times.csv") +
                               " --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(test::LineCount(r.output), 1u) << r.output;
  EXPECT_NE(r.output.find("times.csv:3:"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/images.csv"));
}

// A trigger file cut inside its last line: the rest is analysed, and what was lost is said on
// stderr and in the JSON's warnings, named by the file.
TEST(AnalyzeCli, ACutTriggerFileIsAWarningInTheJson) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  std::ofstream(dir / "times.csv") << "image,t\nIMG_1,1.0\nIMG_2,";
  const auto r =
      RunShutterlab("analyze " + Bbl() + " --triggers " + (dir / "times.csv") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["images"].size(), 1u);
  bool said = false;
  for (const auto& w : json["warnings"]) {
    said |= w["kind"] == "truncated" &&
            w["message"].get<std::string>().rfind("trigger file times.csv: line 3:", 0) == 0;
  }
  EXPECT_TRUE(said) << json["warnings"];
  EXPECT_NE(r.err.find("times.csv: truncated: line 3"), std::string::npos) << r.err;
}

TEST(AnalyzeCli, UnknownLogIsOneLineExitTwo) {
  test::TempDir dir;
  std::ofstream(dir / "notes.txt") << "hello\n";
  const auto r = RunShutterlab("analyze " + (dir / "notes.txt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(test::LineCount(r.output), 1u) << r.output;
}

// A flight log the project writes itself (synth --format ulog): analyze takes its camera triggers
// and its altitude, with no option but the log.
TEST(AnalyzeCli, SyntheticULogWithItsOwnTriggersAndAltitude) {
  test::TempDir dir;
  const std::string log = dir / "flight.ulg";
  const auto synth = RunShutterlab(
      "synth flight --rate 500Hz --duration 30s --t0 1s --format ulog "
      "--trigger-every 2s --altitude 40m --out " +
      log);
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const auto r = RunShutterlab("analyze " + log + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json json = nlohmann::json::parse(r.out);
  // Triggers at 3, 5, ..., 29 s on the log's clock (every 2 s from the first sample at 1 s, the
  // last a full interval before the log ends).
  ASSERT_EQ(json["images"].size(), 14u) << r.output;
  EXPECT_NEAR(json["images"][0]["trigger_t"].get<double>(), 3.0, 1e-6);
  EXPECT_EQ(json["camera"]["altitude_m"].get<double>(), 40.0);
  EXPECT_EQ(json["triggers"].get<std::string>().rfind("camera events", 0), 0u) << json["triggers"];
}

// `analyze A --second B` fuses the pair as streams, in bounded memory, B from a file or from a
// pipe (copied to a temporary file that the passes read): the same JSON (pair, images, flight),
// and with text the same table. Returns the JSON from the files.
nlohmann::json ExpectPairOnAPipeAsOnFiles(const std::string& dir, const std::string& args,
                                          bool text) {
  const std::string files_args = "analyze " + dir + "/a.csv --second " + dir + "/b.csv" + args;
  const std::string pipe_args =
      "analyze " + dir + "/a.csv --second /dev/stdin --format gyro.csv" + args;
  if (text) {
    const auto files = RunShutterlab(files_args);
    const auto piped = RunShutterlab(pipe_args, dir + "/b.csv");
    EXPECT_EQ(files.exit_code, 0) << files.output;
    EXPECT_EQ(files.out.substr(files.out.find('\n')), piped.out.substr(piped.out.find('\n')))
        << "all but the first line, which names the second log";
  }
  const auto files = RunShutterlab(files_args + " --json");
  EXPECT_EQ(files.exit_code, 0) << files.output;
  const auto piped = RunShutterlab(pipe_args + " --json", dir + "/b.csv");
  EXPECT_EQ(piped.exit_code, 0) << piped.output;
  nlohmann::json s = nlohmann::json::parse(files.out), w = nlohmann::json::parse(piped.out);
  EXPECT_EQ(s["pair"]["second_log"], dir + "/b.csv");
  nlohmann::json s_unnamed = s;
  s_unnamed["pair"].erase("second_log");  // named as given: /dev/stdin for the pipe
  w["pair"].erase("second_log");
  EXPECT_EQ(s_unnamed, w);
  return s;
}

TEST(AnalyzeCli, ASensorPairWithTheSecondOnAPipeGivesTheFilesResult) {
  test::TempDir dir;
  const Eigen::Matrix3d b_from_a =
      Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  WriteSensorPair(StillThenTurningTrace(), b_from_a, dir.path());
  const nlohmann::json pair = ExpectPairOnAPipeAsOnFiles(dir.path(), " --every 1s", true)["pair"];
  EXPECT_TRUE(pair["mounting_fitted"].get<bool>());
  EXPECT_NEAR(pair["mounting_angle_deg"].get<double>(), 0.5 * 180 / M_PI, 0.1);
  EXPECT_TRUE(pair["weights_from_still"].get<bool>());
  EXPECT_EQ(pair["paired"], 12000)
      << "the second's nearest sample is within half its 2 ms interval";

  // A second log on another clock is refused in one line naming both logs.
  std::vector<GyroSample> far;
  for (int k = 0; k < 100; ++k)
    far.push_back({100'000'000'000 + k * 2'000'000LL, Eigen::Vector3d::Zero()});
  WriteGyroCsv(dir / "far.csv", GyroTrace(std::move(far)));
  const auto refused =
      RunShutterlab("analyze " + (dir / "a.csv") + " --second " + (dir / "far.csv"));
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_EQ(refused.err, "error: " + (dir / "a.csv") + " + " + (dir / "far.csv") +
                             ": the two sensors share only 0 sample times: are they on one clock? "
                             "(a pair is within half of the second's interval)\n");
}

// The same on real motion: a PX4 flight's gyro (its gaps included) and a second gyro made from it.
TEST(AnalyzeCli, ASensorPairOfARealFlightOnAPipeGivesTheFilesResult) {
  SHUTTERLAB_REAL_DATA(log, "gyro/px4_ulog/sample.ulg");
  test::TempDir dir;
  WriteSensorPair(ReadFlightLog(log).gyro,
                  Eigen::AngleAxisd(2.0, Eigen::Vector3d(0, 0, 1)).toRotationMatrix(), dir.path());
  ExpectPairOnAPipeAsOnFiles(dir.path(), " --every 5s", false);
}

// What neither the user nor the log gave is said as assumed, with how to give it: in the table,
// the JSON and the page; what was given is not.
TEST(AnalyzeCli, SaysWhatItAssumedAndHowToGiveIt) {
  test::TempDir dir;
  const std::string gyro = dir / "gyro.csv";
  test::WriteStillThenTurningGyroCsv(gyro);
  const auto bare = RunShutterlab("analyze " + gyro + " --every 2s --out " + (dir / "out"));
  ASSERT_EQ(bare.exit_code, 0) << bare.output;
  for (const std::string line :
       {"assumed: camera 1280 x 960 px, f 1100 px; give --camera camera.json, or --size and "
        "--focal-px\n",
        "assumed: readout 30 ms; give --readout, --camera or --lens-profile\n",
        "assumed: lens no distortion; give --lens-profile (a Gyroflow profile) or --camera\n",
        "assumed: altitude 50 m (the log has no height above ground); give --altitude\n"}) {
    EXPECT_NE(bare.out.find(line), std::string::npos) << line << bare.out;
  }
  const std::string page = ReadFileToString(dir / "out/report.html");
  EXPECT_NE(page.find("What was assumed"), std::string::npos);
  EXPECT_NE(page.find("the log has no height above ground"), std::string::npos);

  const auto given = RunShutterlab("analyze " + gyro +
                                   " --every 2s --readout 20ms --altitude 80m --size 4000x3000 "
                                   "--focal-px 3000 --json");
  ASSERT_EQ(given.exit_code, 0) << given.output;
  const nlohmann::json json = nlohmann::json::parse(given.out);
  ASSERT_EQ(json["assumptions"].size(), 1u) << json["assumptions"].dump();
  EXPECT_EQ(json["assumptions"][0]["what"], "lens");
  EXPECT_EQ(json["assumptions"][0]["give"], "--lens-profile (a Gyroflow profile) or --camera");
  // The still gyro.csv starts with 5 s still: the bias is measured, not assumed.
  EXPECT_TRUE(json["bias"]["from_still_segment"].get<bool>());

  // A flight that never stands still: the bias is taken as zero, and said so.
  const std::string moving = dir / "moving.csv";
  ASSERT_EQ(RunShutterlab("synth flight --lead 0 --duration 20s --out " + moving).exit_code, 0);
  const auto no_still = RunShutterlab("analyze " + moving + " --every 2s --json");
  ASSERT_EQ(no_still.exit_code, 0) << no_still.output;
  const nlohmann::json assumed = nlohmann::json::parse(no_still.out)["assumptions"];
  ASSERT_FALSE(assumed.empty());
  EXPECT_EQ(assumed.back()["what"], "bias") << assumed.dump();
  EXPECT_EQ(assumed.back()["taken"], "zero");
  // --zero-bias, as flight has it: given, so not assumed.
  const auto zero = RunShutterlab("analyze " + moving + " --every 2s --zero-bias --json");
  ASSERT_EQ(zero.exit_code, 0) << zero.output;
  const nlohmann::json zero_json = nlohmann::json::parse(zero.out);
  EXPECT_FALSE(zero_json["bias"]["estimated"].get<bool>());
  for (const auto& a : zero_json["assumptions"]) EXPECT_NE(a["what"], "bias") << a.dump();
}

// The bias options of flight, noise and accuracy: --bias A:B takes the bias from that segment
// instead of the search (the same bias as the search's on a log still for its first 5 s, within
// the noise of a shorter mean), --auto-bias is the default said aloud, and a segment too short
// for a bias, or two of the options together, are refused in one line.
TEST(AnalyzeCli, TheBiasOptionsOfEveryCommandThatReadsALog) {
  test::TempDir dir;
  const std::string gyro = dir / "gyro.csv";
  test::WriteStillThenTurningGyroCsv(gyro);
  const auto searched = RunShutterlab("analyze " + gyro + " --every 2s --json");
  const auto automatic = RunShutterlab("analyze " + gyro + " --every 2s --auto-bias --json");
  const auto given = RunShutterlab("analyze " + gyro + " --every 2s --bias 0:2s --json");
  ASSERT_EQ(searched.exit_code, 0) << searched.output;
  ASSERT_EQ(given.exit_code, 0) << given.output;
  EXPECT_EQ(automatic.out, searched.out);
  const nlohmann::json found = nlohmann::json::parse(searched.out)["bias"];
  const nlohmann::json segment = nlohmann::json::parse(given.out)["bias"];
  EXPECT_FALSE(found["segment_given"].get<bool>());
  EXPECT_TRUE(segment["segment_given"].get<bool>());
  EXPECT_EQ(segment["segment_s"], nlohmann::json::array({0.0, 2.0}));
  // The log's still part: 0.01 rad/s on x, 0 on y, 0.002 cos(50 t) on z (a mean near 0).
  EXPECT_NEAR(segment["rad_s"][0].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(segment["rad_s"][1].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(segment["rad_s"][2].get<double>(), found["rad_s"][2].get<double>(), 1e-4);
  EXPECT_NE(RunShutterlab("analyze " + gyro + " --every 2s --bias 0:2s")
                .out.find("bias: the segment given, 0.00:2.00 s\n"),
            std::string::npos);
  const auto short_segment = RunShutterlab("analyze " + gyro + " --every 2s --bias 0:5ms");
  EXPECT_EQ(short_segment.exit_code, 2);
  EXPECT_EQ(test::LineCount(short_segment.output), 1u) << short_segment.output;
  EXPECT_NE(short_segment.err.find("bias segment 0:0.005 s holds 5 samples (need at least 10)"),
            std::string::npos)
      << short_segment.err;
  for (const char* both :
       {"--bias 0:2s --zero-bias", "--bias 0:2s --auto-bias", "--zero-bias --auto-bias"}) {
    const auto r = RunShutterlab("analyze " + gyro + " --every 2s " + both);
    EXPECT_EQ(r.exit_code, 2) << both;
    EXPECT_NE(r.err.find("excludes"), std::string::npos) << both << ": " << r.err;
  }
  // noise and accuracy take --zero-bias as flight does: no segment, every sample analysed.
  const nlohmann::json noise =
      nlohmann::json::parse(RunShutterlab("noise " + gyro + " --zero-bias --json").out);
  EXPECT_EQ(noise["samples"], 12000);
  EXPECT_EQ(noise["axes"]["x"]["bias_rad_s"], 0.0);
  // An ideal sensor's steps: no bias to remove, so the zero bias finds the turns the segment does.
  const std::string steps = dir / "steps.csv";
  ASSERT_EQ(RunShutterlab("synth steps --ideal --out " + steps).exit_code, 0);
  const auto by_segment = RunShutterlab("accuracy " + steps + " --reference-deg 1 --json");
  const auto by_zero = RunShutterlab("accuracy " + steps + " --reference-deg 1 --zero-bias --json");
  ASSERT_EQ(by_zero.exit_code, 0) << by_zero.output;
  EXPECT_EQ(nlohmann::json::parse(by_zero.out)["rotations"].size(),
            nlohmann::json::parse(by_segment.out)["rotations"].size());
  EXPECT_GE(nlohmann::json::parse(by_zero.out)["rotations"].size(), 1u) << by_zero.out;
  for (const char* both : {"--zero-bias --auto-bias", "--zero-bias --bias 0:2s"}) {
    for (const char* command : {"noise ", "flight ", "accuracy "}) {
      const auto r = RunShutterlab(command + gyro + " " + both);
      EXPECT_EQ(r.exit_code, 2) << command << both;
      EXPECT_NE(r.err.find("excludes"), std::string::npos) << command << both << ": " << r.err;
    }
  }
}

}  // namespace
}  // namespace shutterlab
