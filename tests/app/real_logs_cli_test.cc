// Every real log in the shared data folder that holds a gyro, whole and cut at 60 % of its bytes,
// read by every command that takes a log (what scripts/real_logs.py tabulates in
// docs/real-logs.md): each command answers or refuses in one line, never crashes, and says what
// the reader lost on stderr and in its --json, the same list in both.

#include "sim/log_warning.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iterator>
#include <ostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

struct RealLog {
  const char* name;      // the test's name
  const char* relative;  // under the data folder
  const char* flags;     // what every command needs to read it
  bool truncated_whole;  // the file as shared ends inside a message
};

// Names the parameter in gtest's and ctest's output (instead of its bytes).
void PrintTo(const RealLog& log, std::ostream* out) { *out << log.relative; }

// scripts/real_logs.py's list: keep the two the same.
const RealLog kRealLogs[] = {
    {"Btfl001", "gyro/betaflight_blackbox/btfl_001.bbl", "", false},
    {"Btfl002", "gyro/betaflight_blackbox/btfl_002.bbl", "", false},
    {"Log00037", "gyro/betaflight_blackbox/LOG00037.BFL", "", false},
    {"SampleUlog", "gyro/px4_ulog/sample.ulg", "", false},
    {"SampleLogSmallUlog", "gyro/px4_ulog/sample_log_small.ulg", "", false},
    {"Log171", "incoming/ardupilot_log171/log171.bin", "", false},
    {"Isb80k", "incoming/ardupilot_isb_80k/backend_log_80k.bin", "", true},
    {"PymavlinkTest", "incoming/ardupilot_pymavlink_test/test.BIN", "", true},
    {"Karma", "rs/gopro_karma/karma.mp4", "", false},
    {"MaxHeromode", "incoming_rs/gopro_max_heromode/max-heromode.mp4", "", false},
    {"PhoneGyroTxt", "rs/phone_gyro_video_20200109_145447/gyro.txt", "--columns 4,1,2,3", false},
    {"PhoneGyroDump", "rs/phone_gyro_video_20200109_145447/gyro_dump.txt", "", false},
};

const char* const kCommands[] = {"flight --json", "noise --json",
                                 "accuracy --json --reference-deg 1", "analyze --json --every 2s"};

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// One command on one log: exit 0 with a JSON document whose warnings are the stderr's, or exit 2
// with one "error: PATH: ..." line after the warnings; nothing else on stderr. Returns the
// warning and error lines.
std::vector<std::string> ExpectAnswerOrOneLineRefusal(const std::string& command,
                                                      const std::string& path,
                                                      const std::string& flags) {
  const std::string args = command + " " + flags + " '" + path + "'";
  const test::CommandResult r = test::RunShutterlab(args);
  EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 2) << args << " exit " << r.exit_code << "\n"
                                                    << r.err;
  const std::vector<std::string> lines = Lines(r.err);
  std::vector<std::string> warnings;
  size_t errors = 0;
  for (const std::string& line : lines) {
    if (line.rfind("warning: " + path + ": ", 0) == 0) {
      warnings.push_back(line.substr(("warning: " + path + ": ").size()));
    } else if (line.rfind("error: " + path + ": ", 0) == 0) {
      ++errors;
      EXPECT_EQ(&line, &lines.back()) << args << ": the error is the last line\n" << r.err;
      // What a user reads, never an internal tag such as "[flight.cc:240 check failed (n >= 2)]".
      EXPECT_EQ(line.find("check failed"), std::string::npos) << args << "\n" << line;
      EXPECT_EQ(line.find(".cc:"), std::string::npos) << args << "\n" << line;
    } else {
      ADD_FAILURE() << args << ": a stderr line that is neither a warning nor the error about "
                    << path << ":\n"
                    << line;
    }
  }
  EXPECT_EQ(errors, r.exit_code == 2 ? 1u : 0u) << args << "\n" << r.err;
  if (r.exit_code == 0) {
    const nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
    EXPECT_TRUE(j.is_object()) << args << ": stdout is no JSON document";
    if (!j.is_object()) return lines;
    std::vector<std::string> from_json;
    for (const nlohmann::json& w : j.at("warnings"))
      from_json.push_back(
          WarningLine({w.at("kind").get<std::string>(), w.at("message").get<std::string>()}));
    EXPECT_EQ(from_json, warnings) << args << ": --json and stderr must give the same warnings";
    if (command.rfind("flight", 0) == 0) {
      EXPECT_EQ(j.at("rows").size(), 4u) << args;
      for (const nlohmann::json& row : j.at("rows")) {
        if (row.at("too_few_samples").get<bool>()) {
          EXPECT_TRUE(row.at("flagged_percent").is_null()) << args << ": never 0 % unmeasured";
        } else {
          EXPECT_GT(row.at("windows").get<size_t>(), 0u) << args;
          const double percent = row.at("flagged_percent").get<double>();
          EXPECT_TRUE(percent >= 0.0 && percent <= 100.0) << args << ": " << percent;
        }
      }
    }
  }
  return lines;
}

bool SaysTruncated(const std::vector<std::string>& lines, const std::string& path) {
  return std::any_of(lines.begin(), lines.end(), [&](const std::string& line) {
    return line.rfind("warning: " + path + ": truncated: ", 0) == 0 ||
           (line.rfind("error: " + path + ": ", 0) == 0 &&
            line.find("truncated") != std::string::npos);
  });
}

class RealLogsCli : public ::testing::TestWithParam<RealLog> {};

TEST_P(RealLogsCli, EveryCommandAnswersOrRefusesAndSaysWhatWasLost) {
  const RealLog& log = GetParam();
  SHUTTERLAB_REAL_DATA(path, log.relative);
  for (const char* command : kCommands) {
    const std::vector<std::string> lines = ExpectAnswerOrOneLineRefusal(command, path, log.flags);
    EXPECT_EQ(SaysTruncated(lines, path), log.truncated_whole) << command << " " << path;
  }
}

// Cut at 60 % of its bytes, inside a record as a cut at random would be: every
// command still says the file was cut, whether it answers (up to the last whole record) or refuses
// (a GoPro clip keeps its sample tables at the end).
TEST_P(RealLogsCli, EveryCommandSaysACopyCutAt60PercentIsTruncated) {
  const RealLog& log = GetParam();
  SHUTTERLAB_REAL_DATA(path, log.relative);
  const std::string bytes = ReadFileToString(path);
  const size_t size = test::CutInsideARecord(bytes, 0.6);
  test::TempDir dir;
  const std::string cut = dir / ("cut_" + std::filesystem::path(path).filename().string());
  WriteFileAtomically(cut, bytes.substr(0, size));
  for (const char* command : kCommands) {
    const std::vector<std::string> lines = ExpectAnswerOrOneLineRefusal(command, cut, log.flags);
    EXPECT_TRUE(SaysTruncated(lines, cut)) << command << " " << cut;
  }
}

INSTANTIATE_TEST_SUITE_P(SharedData, RealLogsCli, ::testing::ValuesIn(kRealLogs),
                         [](const ::testing::TestParamInfo<RealLog>& info) {
                           return std::string(info.param.name);
                         });

// The list above is every file under the data folder that holds a gyro: a log added there and not
// here fails, rather than going untested.
TEST(RealLogsCli, TheListHoldsEveryGyroLogInTheDataFolder) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::set<std::string> log_extensions = {".bbl", ".bfl", ".ulg", ".bin", ".mp4"};
  std::set<std::string> listed;
  for (const RealLog& log : kRealLogs) listed.insert(log.relative);
  const std::filesystem::path root = test::RealDataDir();
  size_t found = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    std::string extension = entry.path().extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const std::string filename = entry.path().filename().string();
    const bool text_log = filename.rfind("gyro", 0) == 0 &&
                          (extension == ".txt" || extension == ".csv" || extension == ".gcsv");
    if (!log_extensions.count(extension) && !text_log) continue;
    ++found;
    EXPECT_TRUE(listed.count(std::filesystem::relative(entry.path(), root).string()))
        << entry.path() << " holds a gyro and is not in kRealLogs (nor scripts/real_logs.py)";
  }
  EXPECT_EQ(found, std::size(kRealLogs));
}

// log171 (ArduCopter 3.3, TimeMS, 50 Hz) gives its flight table: the default 10 and 20 ms windows
// hold at most two samples and are refused with the window that would do; that window is analysed
// over the whole flight, and the clipped flip is said.
TEST(RealLogsCli, Log171GivesItsFlightTableAtTheWindowsItsRateAllows) {
  SHUTTERLAB_REAL_DATA(log171, "incoming/ardupilot_log171/log171.bin");
  const test::CommandResult refused = test::RunShutterlab("flight --json '" + log171 + "'");
  ASSERT_EQ(refused.exit_code, 0) << refused.output;
  const nlohmann::json r = nlohmann::json::parse(refused.out);
  for (const nlohmann::json& row : r.at("rows"))
    EXPECT_TRUE(row.at("too_few_samples").get<bool>()) << row;
  const std::string hint = "give flight --window 50ms or longer, or log above 200 Hz for 10 ms";
  EXPECT_NE(refused.err.find(hint), std::string::npos) << refused.err;

  const test::CommandResult table =
      test::RunShutterlab("flight --window 50ms,100ms '" + log171 + "'");
  ASSERT_EQ(table.exit_code, 0) << table.output;
  EXPECT_EQ(table.out.find("too few samples"), std::string::npos) << table.out;
  EXPECT_NE(table.err.find("saturated: axis y"), std::string::npos) << table.err;
  const test::CommandResult json =
      test::RunShutterlab("flight --json --window 50ms,100ms '" + log171 + "'");
  const nlohmann::json j = nlohmann::json::parse(json.out);
  ASSERT_EQ(j.at("rows").size(), 4u);
  for (const nlohmann::json& row : j.at("rows")) {
    EXPECT_FALSE(row.at("too_few_samples").get<bool>()) << row;
    // 242.6 s at 50 Hz after a 5 s bias segment: over 11,000 windows each, a real flight's share.
    EXPECT_GT(row.at("windows").get<size_t>(), 11000u) << row;
    EXPECT_GT(row.at("flagged_percent").get<double>(), 0.0) << row;
    EXPECT_LT(row.at("flagged_percent").get<double>(), 100.0) << row;
  }
}

}  // namespace
}  // namespace shutterlab
