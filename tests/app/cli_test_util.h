#pragma once
// Running the shutterlab executable from the command-line tests.

#include "sim/gyro_trace.h"
#include "sim/logs/gyro_io.h"
#include "tests/test_util.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <iostream>
#include <random>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace shutterlab::test {

struct CommandResult {
  int exit_code;
  std::string output;  // stdout, then stderr
  std::string out;     // stdout alone (e.g. the --json document)
  std::string err;     // stderr alone (warnings, progress, errors)
};

// The number of newline-ended lines in text: an output's last line must end with one too.
inline size_t LineCount(const std::string& text) {
  return static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
}

// Runs the shutterlab executable with the given argument string (shell syntax); stdin_file, when
// given, is piped to its standard input by `cat` (so /dev/stdin is a pipe, readable once only);
// env, when given, is set for the command alone ("TMPDIR=/some/folder").
inline CommandResult RunShutterlab(const std::string& args, const std::string& stdin_file = "",
                                   const std::string& env = "") {
  CommandResult result{-1, "", "", ""};
  char err_path[] = "/tmp/shutterlab_stderr_XXXXXX";
  const int fd = ::mkstemp(err_path);
  if (fd < 0) return result;
  ::close(fd);
  const std::string command = (stdin_file.empty() ? "" : "cat '" + stdin_file + "' | ") +
                              (env.empty() ? "" : "env '" + env + "' ") +
                              std::string(SHUTTERLAB_BINARY) + " " + args + " 2>" + err_path;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe) {
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) result.out.append(buffer, n);
    const int status = ::pclose(pipe);
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  if (FILE* err = std::fopen(err_path, "rb")) {
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof(buffer), err)) > 0) result.err.append(buffer, n);
    std::fclose(err);
  }
  std::remove(err_path);
  result.output = result.out + result.err;
  return result;
}

// The gyro.csv at trace_path as a flight controller beside it would log the same motion: at half
// the rate, each sample the mean of two (a flight controller logs its filtered gyro; taking every
// second sample instead would fold a multirotor's vibration down to slow motion that the other
// gyro does not show), stamped at their middle, on axes turned 2 rad about (1, 2, 3)
// (kFcFromBodyAngleRad), on a clock kFcClockAheadS ahead; written as gyro.csv to fc_path.
inline constexpr double kFcFromBodyAngleRad = 2.0;
inline constexpr double kFcClockAheadS = 123.456;
inline void WriteAsFlightControllerLog(const std::string& trace_path, const std::string& fc_path) {
  const GyroTrace trace = ReadGyroCsv(trace_path);
  const Eigen::Matrix3d fc_from_body =
      Eigen::AngleAxisd(kFcFromBodyAngleRad, Eigen::Vector3d(1, 2, 3).normalized())
          .toRotationMatrix();
  std::vector<GyroSample> fc;
  for (size_t i = 0; i + 1 < trace.size(); i += 2) {
    const int64_t t_ns = trace[i].t_ns + (trace[i + 1].t_ns - trace[i].t_ns) / 2;
    fc.push_back({t_ns + SecondsToNs(kFcClockAheadS),
                  fc_from_body * (0.5 * (trace[i].omega_rad_s + trace[i + 1].omega_rad_s))});
  }
  WriteGyroCsv(fc_path, GyroTrace(fc));
}

// Starts the shutterlab executable with `args` (no shell), its output to /dev/null, and returns
// its pid, for a test that kills it or waits for it; -1 when fork fails.
inline pid_t SpawnShutterlab(const std::vector<std::string>& args) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  const int null = ::open("/dev/null", O_WRONLY);
  ::dup2(null, 1);
  ::dup2(null, 2);
  std::vector<char*> argv = {const_cast<char*>(SHUTTERLAB_BINARY)};
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  ::execv(SHUTTERLAB_BINARY, argv.data());
  ::_exit(127);
}

// Opens a page the tool wrote in headless Chromium (scripts/check_report.sh): it must draw every
// chart it holds (`charts`, counted from its data blocks) with no script error. The screenshot goes
// to $SHUTTERLAB_SCREENSHOT_DIR/NAME.png when that is set (how docs/*.png are made), else beside
// the page. Without /usr/bin/chromium (scripts/test.sh installs it) the page is not opened, and
// the test says so in one line, or fails under CI=true.
inline void ExpectDrawsInChromium(const std::string& page, size_t charts, const std::string& name) {
  if (::access("/usr/bin/chromium", X_OK) != 0) {
    if (RealDataRequired()) {
      ADD_FAILURE() << "chromium is missing (CI=true needs it: scripts/test.sh installs it)";
    } else {
      std::cout << "note: " << page << " not opened: /usr/bin/chromium is missing "
                << "(apt-get install chromium, or run scripts/test.sh)\n";
    }
    return;
  }
  const char* dir = std::getenv("SHUTTERLAB_SCREENSHOT_DIR");
  const std::string shot = dir != nullptr && *dir != '\0'
                               ? std::string(dir) + "/" + name + ".png"
                               : page.substr(0, page.rfind('.')) + ".png";
  const std::string command =
      SourcePath("scripts/check_report.sh") + " '" + page + "' '" + shot + "' 2>&1";
  std::string output;
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) output.append(buffer, n);
  const int status = ::pclose(pipe);
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 0) << output;
  EXPECT_NE(output.find("check_report: ok (" + std::to_string(charts) + " charts drawn"),
            std::string::npos)
      << output;
}

// r is a command refused, in one line naming /dev/stdin and the folder, because the log on its
// standard input could not be copied to `folder` ($TMPDIR): proof that the pipe is copied.
inline void ExpectPipeCopyRefused(const CommandResult& r, const std::string& folder) {
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("/dev/stdin: cannot copy it to a temporary file in " + folder),
            std::string::npos)
      << r.err;
}

// A gyro.csv of 12 s at 1 kHz: still for 5 s (a small bias), then turning about x and y.
inline void WriteStillThenTurningGyroCsv(const std::string& path) {
  std::vector<GyroSample> samples;
  for (int i = 0; i < 12000; ++i) {
    const double t = i * 1e-3;
    const double turning = t < 5.0 ? 0.0 : 0.4 * std::sin(3.0 * t);
    samples.push_back({static_cast<int64_t>(i) * 1000000,
                       Eigen::Vector3d(0.01 + turning, 0.5 * turning, 0.002 * std::cos(50 * t))});
  }
  WriteGyroCsv(path, GyroTrace(std::move(samples)));
}

// 12 s at 1 kHz, still for 5 s, then turning about every axis, with a bias of 0.01 rad/s on x and
// seeded noise: motion a sensor pair's mounting can be fitted from, after a still stretch.
inline GyroTrace StillThenTurningTrace() {
  std::mt19937 rng(15);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<GyroSample> samples;
  for (int i = 0; i < 12000; ++i) {
    const double t = i * 1e-3;
    const double turning = t < 5.0 ? 0.0 : 1.0;
    samples.push_back({static_cast<int64_t>(i) * 1000000,
                       turning * Eigen::Vector3d(0.4 * std::sin(3.0 * t), 0.3 * std::cos(5.0 * t),
                                                 0.3 * std::sin(2.0 * t)) +
                           Eigen::Vector3d(0.01 + noise(rng), noise(rng), noise(rng))});
  }
  return GyroTrace(std::move(samples));
}

// A second gyro beside the first: the first's rates seen through b_from_a, 0.3 ms later, with its
// own noise (seeded), every other sample, written as DIR/a.csv and DIR/b.csv.
inline void WriteSensorPair(const GyroTrace& a, const Eigen::Matrix3d& b_from_a,
                            const std::string& dir) {
  std::mt19937 rng(18);
  std::normal_distribution<double> noise(0.0, 0.003);
  std::vector<GyroSample> b;
  for (size_t k = 0; k < a.size(); k += 2) {
    b.push_back({a[k].t_ns + 300'000, b_from_a * a[k].omega_rad_s +
                                          Eigen::Vector3d(noise(rng), noise(rng), noise(rng))});
  }
  WriteGyroCsv(dir + "/a.csv", a);
  WriteGyroCsv(dir + "/b.csv", GyroTrace(std::move(b)));
}

}  // namespace shutterlab::test
