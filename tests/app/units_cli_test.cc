// Every length, time and rate on the command line carries its unit: a bare number is refused in
// one line with what it probably meant, on every command that takes one (issue 43: `analyze
// --limit 5` used to read 5 as metres and flag nothing). Also the command line's other first-hour
// traps: a mistyped command, a parser error in two lines, --every 0, a ULog without --t0.

#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::RunShutterlab;

// r was refused with exit code 2 and one line on stderr, "error: ..." holding `expected`, and
// printed nothing else.
void ExpectOneLineRefusal(const test::CommandResult& r, const std::string& expected,
                          const std::string& args) {
  EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
  EXPECT_EQ(test::LineCount(r.err), 1u) << args << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
  EXPECT_TRUE(r.out.empty()) << args << "\n" << r.out;
}

struct BareCase {
  std::string command;  // the command and its other (valid) arguments; FILE and DIR replaced
  std::string bare;     // the option with a bare number
  std::string suggestion;
};

class BareNumberCli : public ::testing::TestWithParam<BareCase> {};

// Each command's quantity options, one bare number each: refused before anything runs, with
// the number and the unit a person most likely meant.
TEST_P(BareNumberCli, IsRefusedWithTheUnitItProbablyMeant) {
  test::TempDir dir;
  const std::string gyro = dir / "gyro.csv";
  test::WriteStillThenTurningGyroCsv(gyro);
  std::string args = GetParam().command + " " + GetParam().bare;
  for (const auto& [name, path] : {std::pair<std::string, std::string>{"FILE", gyro},
                                   {"DIR", dir.path().string()},
                                   {"OUT", (dir / "out")}}) {
    for (size_t at = args.find(name); at != std::string::npos; at = args.find(name))
      args.replace(at, name.size(), path);
  }
  ExpectOneLineRefusal(RunShutterlab(args), GetParam().suggestion, args);
  // Nothing was written.
  EXPECT_FALSE(std::filesystem::exists(dir / "out")) << args;
}

INSTANTIATE_TEST_SUITE_P(
    EveryCommand, BareNumberCli,
    ::testing::Values(
        BareCase{"demo --out OUT", "--every 4",
                 "--every '4': a duration needs a unit: did you "
                 "mean 4s? (s, ms, us, ns, min, h)"},
        BareCase{"synth still --out OUT", "--rate 400", "did you mean 400Hz?"},
        BareCase{"synth flight --out OUT", "--wobble 2", "did you mean 2deg/s?"},
        BareCase{"synth still --out OUT", "--noise-density 7e-5", "did you mean 7e-5rad/s/rtHz?"},
        BareCase{"record --device emulate:FILE --out OUT", "--rate 8000", "did you mean 8000Hz?"},
        BareCase{"record --device emulate:FILE,rate=8000 --out OUT", "",
                 "rate= '8000': a frequency needs a unit: did you mean 8000Hz?"},
        BareCase{"noise FILE", "--range 2000", "did you mean 2000deg/s?"},
        BareCase{"accuracy FILE --reference-deg 1", "--guard 0.5", "did you mean 0.5s?"},
        BareCase{"flight FILE", "--altitude 50", "did you mean 50m?"},
        BareCase{"flight FILE", "--window 10,20", "did you mean 10ms or 10s?"},
        BareCase{"scene --out OUT/s.png", "--gsd 5", "did you mean 5cm or 5m?"},
        BareCase{"render --scene FILE --camera FILE --gyro FILE --frames FILE --out OUT",
                 "--moving-patch 10", "did you mean 10m/s?"},
        BareCase{"render --scene FILE --camera FILE --gyro FILE --frames FILE --out OUT --video "
                 "--stabiliser roll",
                 "--stabiliser-window 2", "did you mean 2s?"},
        BareCase{"validate DIR", "--limit 5",
                 "--limit '5': a length needs a unit: did you mean "
                 "5cm or 5m? (m, cm, mm, km)"},
        BareCase{"correct DIR --out OUT", "--depth 40", "did you mean 40m?"},
        BareCase{"analyze FILE", "--limit 5", "did you mean 5cm or 5m?"},
        BareCase{"analyze FILE", "--readout 30",
                 "--readout '30': a duration needs a unit: did "
                 "you mean 30ms or 30s?"},
        BareCase{"analyze FILE", "--latency 40", "did you mean 40ms or 40s?"},
        BareCase{"analyze FILE", "--limit 5in", "unknown unit 'in' for a length"},
        BareCase{"analyze FILE", "--readout 30m",
                 "m is a unit of length, --readout takes a "
                 "duration"}),
    [](const ::testing::TestParamInfo<BareCase>& info) {
      std::string name = info.param.command.substr(0, info.param.command.find(' ')) + "_" +
                         std::to_string(info.index);
      return name;
    });

// A stabiliser re-renders a clip: asked for on stills, refused in one line before anything runs.
TEST(UnitsCli, AStabiliserNeedsAVideo) {
  test::TempDir dir;
  const std::string gyro = dir / "gyro.csv";
  test::WriteStillThenTurningGyroCsv(gyro);
  const std::string args = "render --scene " + gyro + " --camera " + gyro + " --gyro " + gyro +
                           " --frames " + gyro + " --out " + (dir / "out") +
                           " --stabiliser roll-lock";
  ExpectOneLineRefusal(RunShutterlab(args), "--stabiliser needs --video", args);
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

// An option read only beside another is refused without it, in one line naming both, not silently
// ignored (a given value would look used).
TEST(UnitsCli, AnOptionWithoutTheOneItBelongsToIsRefused) {
  test::TempDir dir;
  const std::string gyro = dir / "gyro.csv";
  test::WriteStillThenTurningGyroCsv(gyro);
  const std::string render = "render --scene " + gyro + " --camera " + gyro + " --gyro " + gyro +
                             " --frames " + gyro + " --out " + (dir / "out") + " --video";
  const std::pair<std::string, std::string> cases[] = {
      {render + " --stabiliser-window 1s", "--stabiliser"},
      {"analyze " + gyro + " --speed 5m/s", "--photos"},
      {"analyze " + gyro + " --ground-elevation 12m", "--photos"},
      {"analyze " + gyro + " --photo-utc-offset +08:00", "--photos"},
      {"analyze " + gyro + " --recursive", "--photos"},
      {"analyze " + gyro + " --out " + (dir / "out") + " --export odm", "--photos"}};
  for (const auto& [args, needed] : cases) {
    ExpectOneLineRefusal(RunShutterlab(args), needed, args);
    EXPECT_FALSE(std::filesystem::exists(dir / "out")) << args;
  }
}

TEST(UnitsCli, QuantitiesWithUnitsAreAccepted) {
  test::TempDir dir;
  const std::string gyro = dir / "gyro.csv";
  test::WriteStillThenTurningGyroCsv(gyro);
  const auto cm = RunShutterlab("flight " + gyro +
                                " --altitude 5000cm --limit 50mm,0.1m "
                                "--window 10000us,0.02s --bias 0:5000ms --json");
  ASSERT_EQ(cm.exit_code, 0) << cm.output;
  const auto m = RunShutterlab("flight " + gyro + " --json");
  ASSERT_EQ(m.exit_code, 0) << m.output;
  // The same defaults, typed in other units; only what is said as assumed differs (they were
  // given).
  nlohmann::json typed = nlohmann::json::parse(cm.out), defaults = nlohmann::json::parse(m.out);
  EXPECT_TRUE(typed["assumptions"].empty());
  EXPECT_EQ(defaults["assumptions"].size(), 3u);
  typed.erase("assumptions");
  defaults.erase("assumptions");
  EXPECT_EQ(typed, defaults);
}

TEST(UnitsCli, AMistypedCommandGetsTheClosestOneAndTheList) {
  const auto r = RunShutterlab("anlyze log.ulg");
  ExpectOneLineRefusal(
      r, "error: unknown command 'anlyze': did you mean 'analyze'? (commands: ", "anlyze");
  EXPECT_NE(r.err.find("flight"), std::string::npos) << r.err;
  ExpectOneLineRefusal(RunShutterlab("zzzzzzzzzz"),
                       "unknown command 'zzzzzzzzzz' (commands: ", "zzzzzzzzzz");
}

TEST(UnitsCli, ParserErrorsAreOneLineNamingTheHelp) {
  ExpectOneLineRefusal(RunShutterlab("flight"), "(shutterlab flight --help)", "flight");
  ExpectOneLineRefusal(RunShutterlab("flight /etc/hostname --no-such-option"),
                       "not expected: --no-such-option (shutterlab flight --help)",
                       "flight --no-such-option");
  ExpectOneLineRefusal(RunShutterlab(""), "(shutterlab --help)", "(nothing)");
}

TEST(UnitsCli, EveryZeroIsRefusedForItWouldJudgeNothing) {
  test::TempDir dir;
  const std::string gyro = dir / "gyro.csv";
  test::WriteStillThenTurningGyroCsv(gyro);
  ExpectOneLineRefusal(RunShutterlab("analyze " + gyro + " --every 0"),
                       "--every 0s would judge no image: give a cadence above 0 s, e.g. 2s",
                       "--every 0");
  ExpectOneLineRefusal(RunShutterlab("demo --out " + (dir / "d") + " --every 0s"),
                       "--every must be positive", "demo --every 0s");
}

// The README's ULog example: without --t0 a ULog starts a second in (its clock never reads 0).
TEST(UnitsCli, SynthUlogNeedsNoT0) {
  test::TempDir dir;
  const std::string ulog = dir / "f.ulg";
  const auto r = RunShutterlab("synth flight --out " + ulog +
                               " --format ulog --trigger-every 2s --altitude 50m");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto flight = RunShutterlab("analyze " + ulog + " --json");
  ASSERT_EQ(flight.exit_code, 0) << flight.output;
  EXPECT_NE(flight.out.find("\"t\": 1"), std::string::npos) << flight.out.substr(0, 2000);
}

}  // namespace
}  // namespace shutterlab
