#include "sim/logs/flight_log_io.h"

#include "sim/check.h"
#include "sim/logs/gopro_telemetry.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/ulog_write.h"
#include "sim/still_detect.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/sim/logs/pipe_util.h"
#include "tests/sim/logs/same_log.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <sys/resource.h>
#include <vector>

namespace shutterlab {
namespace {

using test::ReadFromPipe;

TEST(ReadFlightLog, DetectsAndReadsEveryRealLog) {
  struct Case {
    std::string path, format;
  };
  SHUTTERLAB_REAL_DATA(gyro_dir, "gyro");
  const Case cases[] = {{"betaflight_blackbox/btfl_001.bbl", "betaflight"},
                        {"betaflight_blackbox/btfl_002.bbl", "betaflight"},
                        {"betaflight_blackbox/LOG00037.BFL", "betaflight"},
                        {"px4_ulog/sample.ulg", "ulog"},
                        {"px4_ulog/sample_log_small.ulg", "ulog"}};
  for (const Case& c : cases) {
    const FlightLog log = ReadFlightLog(gyro_dir + "/" + c.path);
    EXPECT_EQ(log.format, c.format) << c.path;
    EXPECT_GT(log.gyro.samples().size(), 1000u) << c.path;
    EXPECT_FALSE(log.gyro_source.empty()) << c.path;
  }
}

// The real PX4 and ArduPilot logs' navigation: a velocity and an attitude a flight can have. The
// velocity over the ground below 30 m/s; the attitude mostly near level (median tilt below 15 deg;
// under 10 % of it beyond 45 deg: log171 flips in ACRO and ends upside down, 6 % of its samples);
// samples at the rates the autopilots log them, in time order.
TEST(ReadFlightLog, RealLogsGiveTheirNavigation) {
  struct Case {
    std::string path;
    std::string velocity_source, attitude_source;
  };
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string& data = real_data_dir_;
  const Case cases[] = {
      {"gyro/px4_ulog/sample_log_small.ulg",
       "the GPS's vel_n_m_s,vel_e_m_s,vel_d_m_s (where vel_ned_valid)", "vehicle_attitude.q"},
      {"incoming/ardupilot_log171/log171.bin", "EKF1.VN,VE,VD", "ATT.Roll,Pitch,Yaw"},
      {"incoming/ardupilot_isb_80k/backend_log_80k.bin",
       "XKF1.VN,VE,VD (core 0), the EKF flown on (AHRS_EKF_TYPE 3)", "ATT.Roll,Pitch,Yaw"}};
  const auto span_s = [](const auto& samples) {
    return samples.size() < 2 ? 0.0 : (samples.back().t_ns - samples.front().t_ns) * 1e-9;
  };
  for (const Case& c : cases) {
    const FlightLog log = ReadFlightLog(data + "/" + c.path);
    EXPECT_EQ(log.velocity_source, c.velocity_source) << c.path;
    EXPECT_EQ(log.attitude_source, c.attitude_source) << c.path;
    double top_speed = 0.0;
    for (const VelocitySample& v : log.velocity)
      top_speed = std::max(top_speed, v.ned_mps.head<2>().norm());
    std::vector<double> tilt_deg;
    for (const AttitudeSample& a : log.attitude) {
      const double down = a.ned_from_body.toRotationMatrix()(2, 2);
      tilt_deg.push_back(std::acos(std::clamp(down, -1.0, 1.0)) * 180 / M_PI);
    }
    const double beyond_45 =
        std::count_if(tilt_deg.begin(), tilt_deg.end(), [](double t) { return t > 45.0; }) /
        static_cast<double>(std::max<size_t>(tilt_deg.size(), 1));
    std::printf(
        "  %s: %zu velocity samples over %.1f s (top %.2f m/s), %zu attitude samples "
        "over %.1f s (%.1f %% tilted beyond 45 deg)\n",
        c.path.c_str(), log.velocity.size(), span_s(log.velocity), top_speed, log.attitude.size(),
        span_s(log.attitude), 100 * beyond_45);
    ASSERT_GE(log.velocity.size(), 5u) << c.path;  // the 80 kB log's first seconds hold 5
    ASSERT_GE(log.attitude.size(), 5u) << c.path;
    EXPECT_LT(top_speed, 30.0) << c.path;
    EXPECT_LT(Median(tilt_deg), 15.0) << c.path;
    EXPECT_LT(beyond_45, 0.10) << c.path;
    // At 1 Hz or more (GPS 5-10 Hz, the estimators 10-100 Hz); the attitude at 50 Hz at most.
    EXPECT_GT(log.velocity.size() / span_s(log.velocity), 1.0) << c.path;
    EXPECT_LE(log.attitude.size() / span_s(log.attitude), 50.5) << c.path;
    for (size_t k = 1; k < log.velocity.size(); ++k)
      ASSERT_GT(log.velocity[k].t_ns, log.velocity[k - 1].t_ns) << c.path << " " << k;
  }
}

// A GoPro clip's GPMF gyro is a log like any other: detected by its first box, read on the
// camera's axes as import reads it.
TEST(ReadFlightLog, ReadsAGoproClipsGyro) {
  SHUTTERLAB_REAL_DATA(karma, "rs/gopro_karma/karma.mp4");
  const FlightLog log = ReadFlightLog(karma);
  EXPECT_EQ(log.format, "gopro");
  EXPECT_NE(log.gyro_source.find("GPMF GYRO"), std::string::npos) << log.gyro_source;
  const GoproTelemetry telemetry = ReadGoproTelemetry(karma);
  ASSERT_EQ(log.gyro.size(), telemetry.gyro.size());
  EXPECT_EQ(log.gyro[100].t_ns, telemetry.gyro[100].t_ns);
  EXPECT_EQ(log.gyro[100].omega_rad_s, telemetry.gyro[100].omega_rad_s);
  EXPECT_TRUE(log.camera_events.empty());
  // An MP4 without GoPro telemetry is refused with what it lacks.
  test::TempDir dir;
  const std::string bytes = ReadFileToString(karma);
  WriteFileAtomically(dir / "cut.mp4", bytes.substr(0, 4096));
  try {
    ReadFlightLog(dir / "cut.mp4");
    ADD_FAILURE() << "a cut MP4 was read";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(dir / "cut.mp4"), std::string::npos) << e.what();
  }
}

TEST(ReadFlightLog, RealArduPilotLogsSayWhatTheyLost) {
  // ArduCopter 3.3 (2015): TimeMS, IMU/IMU2/IMU3 at 50 Hz, one sample clipped at +-2000 deg/s.
  SHUTTERLAB_REAL_DATA(log171, "incoming/ardupilot_log171/log171.bin");
  const FlightLog old = ReadFlightLog(log171);
  EXPECT_EQ(old.gyro_source, "IMU");
  EXPECT_EQ(old.gyro.size(), 11'916u);
  EXPECT_NEAR(old.gyro.DurationS(), 242.6, 0.1);
  EXPECT_NEAR(old.gyro.sampling().RateHz(), 50.0, 0.5);
  EXPECT_EQ(old.gyro_sources_available.size(), 3u);
  EXPECT_TRUE(test::AnyWarningContains(old.warnings,
                                       "saturated: axis y, 1 sample(s) within 2 % of the "
                                       "+-2000 deg/s full scale"))
      << test::JoinedWarnings(old.warnings);
  EXPECT_FALSE(test::AnyWarningContains(old.warnings, "axis x"))
      << test::JoinedWarnings(old.warnings);
  EXPECT_FALSE(test::AnyWarningContains(old.warnings, "axis z"))
      << test::JoinedWarnings(old.warnings);

  // ArduCopter 4.6, cut at 80 KiB: its one gyro batch holds 576 of 1024 samples.
  SHUTTERLAB_REAL_DATA(isb, "incoming/ardupilot_isb_80k/backend_log_80k.bin");
  const FlightLog batch = ReadFlightLog(isb);
  EXPECT_EQ(batch.gyro_source, "ISBD");
  EXPECT_EQ(batch.gyro.size(), 576u);
  EXPECT_TRUE(test::AnyWarningContains(batch.warnings, "576 of the 1024 samples"))
      << test::JoinedWarnings(batch.warnings);
  EXPECT_TRUE(test::AnyWarningContains(batch.warnings, "truncated"))
      << test::JoinedWarnings(batch.warnings);

  SHUTTERLAB_REAL_DATA(pymavlink, "incoming/ardupilot_pymavlink_test/test.BIN");
  const FlightLog cut = ReadFlightLog(pymavlink);
  EXPECT_TRUE(test::AnyWarningContains(cut.warnings, "truncated"))
      << test::JoinedWarnings(cut.warnings);
}

// A log cut off anywhere is read up to its last whole record and says it was cut: never silently.
TEST(ReadFlightLog, TruncatedCopiesOfEveryRealLogSaySo) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string logs[] = {"gyro/betaflight_blackbox/btfl_001.bbl",
                              "gyro/betaflight_blackbox/btfl_002.bbl",
                              "gyro/betaflight_blackbox/LOG00037.BFL",
                              "gyro/px4_ulog/sample.ulg",
                              "gyro/px4_ulog/sample_log_small.ulg",
                              "incoming/ardupilot_log171/log171.bin",
                              "incoming/ardupilot_isb_80k/backend_log_80k.bin",
                              "incoming/ardupilot_pymavlink_test/test.BIN"};
  test::TempDir dir;
  size_t read = 0;
  for (const std::string& name : logs) {
    const std::string bytes = ReadFileToString(test::RealDataPath(name));
    for (const double fraction : {0.35, 0.5, 0.65, 0.8, 0.95}) {
      const size_t size = test::CutInsideARecord(bytes, fraction);
      const std::string path = dir / ("cut_" + std::to_string(size) + "_" +
                                      std::filesystem::path(name).filename().string());
      WriteFileAtomically(path, bytes.substr(0, size));
      try {
        const FlightLog log = ReadFlightLog(path);
        EXPECT_TRUE(test::AnyWarningContains(log.warnings, "truncated: "))
            << name << " cut at " << size << ":\n"
            << test::JoinedWarnings(log.warnings);
        ++read;
      } catch (const IoError& e) {
        // Only a cut before any gyro data may be refused, and then with the path.
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("no "), std::string::npos) << e.what();
      }
    }
  }
  EXPECT_GE(read, 35u) << "most cuts still hold gyro data";
}

TEST(ReadFlightLog, WrapsGyroCsv) {
  test::TempDir dir;
  std::ofstream(dir / "gyro.csv") << "t,gx,gy,gz\n0.0,0.1,0.2,0.3\n0.001,0.1,0.2,0.3\n";
  const FlightLog log = ReadFlightLog(dir / "gyro.csv");
  EXPECT_EQ(log.format, "gyro.csv");
  EXPECT_EQ(log.gyro.samples().size(), 2u);
  EXPECT_TRUE(log.camera_events.empty());
  EXPECT_FALSE(log.altitude_above_ground_m.has_value());
}

// A log on a pipe is detected by a look at its start and read through the same opening: the
// format is not needed, and the result is the file's.
TEST(ReadFlightLog, ALogOnAPipeIsDetectedAndReadOnce) {
  test::TempDir dir;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 20000; ++i)  // larger than a look at the start (16 KiB) as text and ULog
    samples.push_back(
        {static_cast<int64_t>(i + 1) * 500000, Eigen::Vector3d(0.01 * i, -0.25, 1e-3 * (i % 7))});
  const GyroTrace trace(std::move(samples));
  WriteGyroCsv(dir / "gyro.csv", trace);
  const std::string ulog = SerializeULog(trace, {});
  WriteFileAtomically(dir / "log.ulg", ulog);
  for (const auto& [name, bytes] :
       {std::pair<std::string, std::string>{"gyro.csv", ReadFileToString(dir / "gyro.csv")},
        {"log.ulg", ulog}}) {
    const FlightLog from_file = ReadFlightLog(dir / name);
    const FlightLog from_pipe = ReadFromPipe(bytes);
    EXPECT_EQ(from_pipe.format, from_file.format) << name;
    EXPECT_EQ(from_pipe.gyro_source, from_file.gyro_source) << name;
    ASSERT_EQ(from_pipe.gyro.samples().size(), trace.samples().size()) << name;
    for (size_t i = 0; i < trace.samples().size(); ++i) {
      ASSERT_EQ(from_pipe.gyro.samples()[i].t_ns, from_file.gyro.samples()[i].t_ns) << name << i;
      ASSERT_EQ(from_pipe.gyro.samples()[i].omega_rad_s, from_file.gyro.samples()[i].omega_rad_s)
          << name << i;
    }
  }
  // A format named is read from a pipe too; a GoPro clip cannot be (its tables may follow its
  // samples), and says so.
  FlightLogReadOptions ulog_named;
  ulog_named.format = LogFormat::kULog;
  EXPECT_EQ(ReadFromPipe(ulog, ulog_named).gyro.samples().size(), trace.samples().size());
  try {
    ReadFromPipe(std::string("\0\0\0\x10"
                             "ftypmp42\0\0\0\0",
                             16) +
                 std::string(100, 'x'));
    FAIL() << "an MP4 on a pipe was read";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be read from a pipe"), std::string::npos)
        << e.what();
  }
}

// A binary log on a pipe is copied to a temporary file and read in the same two passes as the file
// (MappedFile::Copied): the same log in every field, and a log cut inside a message (a pipe closed
// early, a copy still being recorded) says it was truncated, as the file does.
TEST(ReadFlightLog, EveryBinaryFormatOnAPipeIsReadAsItsFile) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  for (const char* relative :
       {"gyro/px4_ulog/sample_log_small.ulg", "gyro/betaflight_blackbox/LOG00037.BFL",
        "incoming/ardupilot_pymavlink_test/test.BIN"}) {
    const std::string bytes = ReadFileToString(test::RealDataPath(relative));
    // Whole, and cut at 60 % (inside a message: these formats' messages are not aligned to it).
    for (const size_t size : {bytes.size(), bytes.size() * 6 / 10}) {
      const std::string what = std::string(relative) + " (" + std::to_string(size) + " bytes)";
      const std::string path = dir / "log";
      WriteFileAtomically(path, bytes.substr(0, size));
      const FlightLog from_file = ReadFlightLog(path);
      const FlightLog from_pipe = ReadFromPipe(bytes.substr(0, size));
      test::ExpectSameLog(from_pipe, from_file, what);
      EXPECT_GE(from_pipe.gyro.size(), 2u) << what;
      if (size < bytes.size()) {
        EXPECT_TRUE(std::any_of(from_pipe.warnings.begin(), from_pipe.warnings.end(),
                                [](const LogWarning& w) { return w.kind == "truncated"; }))
            << what << ": " << test::JoinedWarnings(from_pipe.warnings);
      }
    }
  }
}

// Sets an environment variable for as long as it lives.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// A folder of its own for pipes' copies ($TMPDIR names it for as long as this lives), in a
// temporary folder that the test may use too.
struct CopyFolder {
  test::TempDir dir;
  std::string folder = dir / "tmp";
  bool made = std::filesystem::create_directories(folder);
  ScopedEnv tmpdir{"TMPDIR", folder};
};

// The copy lives in $TMPDIR unlinked from the start: nothing is left there while the log is read,
// nor after. A copy that cannot be written (a full disk; here a file-size limit) is refused in one
// line naming the input and the folder.
TEST(ReadFlightLog, APipesCopyLeavesNoFileAndAFailedCopySaysWhere) {
  const CopyFolder copies;
  const test::TempDir& dir = copies.dir;
  const std::string& folder = copies.folder;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 20000; ++i)
    samples.push_back({static_cast<int64_t>(i + 1) * 500000, Eigen::Vector3d(0.01 * i, -0.25, 0)});
  const std::string ulog = SerializeULog(GyroTrace(std::move(samples)), {});
  ASSERT_GT(ulog.size(), size_t{256} << 10);
  const size_t read = test::ReadThroughPipe(ulog, [&](const std::string& path) {
    FlightLogStream stream = OpenFlightLog(path);
    EXPECT_TRUE(std::filesystem::is_empty(folder)) << "a copy left a name in " << folder;
    return ReadAllSamples(stream.gyro.get()).size();
  });
  EXPECT_EQ(read, 20000u);
  EXPECT_TRUE(std::filesystem::is_empty(folder));

  const auto expect_refused = [&](const std::string& in_folder, const std::string& reason) {
    try {
      ReadFromPipe(ulog);
      FAIL() << "a copy that failed was read";
    } catch (const IoError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind("/proc/self/fd/", 0), 0u) << message;  // the input, first
      EXPECT_NE(message.find("cannot copy it to a temporary file in " + in_folder + ": " + reason),
                std::string::npos)
          << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  };
  // A disk that fills up: writes past a limit fail (EFBIG, as ENOSPC would), the signal that
  // limit raises ignored as the shell's default would not.
  struct rlimit old_limit {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  struct rlimit small = old_limit;
  small.rlim_cur = 64 << 10;
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  expect_refused(folder, std::strerror(EFBIG));
  ::setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_TRUE(std::filesystem::is_empty(folder));
  // A folder that is not there.
  const ScopedEnv missing("TMPDIR", dir / "missing");
  expect_refused(dir / "missing", std::strerror(ENOENT));
}

// A reading in passes (the still search, a sensor pair's fit, analyze) of a log on a pipe: the
// pipe is copied once, when the log is opened for passes, to a file in $TMPDIR unlinked at once;
// every pass then reads that copy, each the same log as the file gives, a text log and a binary one
// alike, and nothing is left in $TMPDIR.
TEST(OpenFlightLog, EveryPassOverALogOnAPipeReadsItsOneCopy) {
  const CopyFolder copies;
  const test::TempDir& dir = copies.dir;
  const std::string& folder = copies.folder;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 6000; ++i) {
    samples.push_back({static_cast<int64_t>(i + 1) * 500000,
                       Eigen::Vector3d(0.001 * i, -0.25, 0.5 * std::sin(0.01 * i))});
  }
  const GyroTrace trace(std::move(samples));
  WriteGyroCsv(dir / "gyro.csv", trace);
  const std::string csv = ReadFileToString(dir / "gyro.csv");
  for (const std::string& bytes : {csv, SerializeULog(trace, {})}) {
    const std::string path = dir / "log";
    WriteFileAtomically(path, bytes);
    const FlightLog from_file = ReadFlightLog(path);
    const std::vector<FlightLog> passes =
        test::ReadThroughPipe(bytes, [&](const std::string& pipe) {
          const ReopenableFile file(pipe);
          EXPECT_EQ(file.path(), pipe);
          std::vector<FlightLog> logs;
          for (int pass = 0; pass < 3; ++pass) {
            FlightLogStream stream = OpenFlightLog(file);
            FlightLog log = std::move(stream.log);
            log.gyro = ReadAllSamples(stream.gyro.get());
            for (LogWarning& w : stream.gyro->Warnings()) log.warnings.push_back(std::move(w));
            for (LogWarning& w : AuditTrace(log.gyro, stream.audit))
              log.warnings.push_back(std::move(w));
            logs.push_back(std::move(log));
            EXPECT_TRUE(std::filesystem::is_empty(folder)) << "the copy left a name in " << folder;
          }
          EXPECT_NO_THROW(file.CheckUnchanged());
          return logs;
        });
    ASSERT_EQ(passes.size(), 3u);
    EXPECT_EQ(passes[0].gyro.size(), 6000u) << from_file.format;
    for (const FlightLog& log : passes) test::ExpectSameLog(log, from_file, from_file.format);
  }
  EXPECT_TRUE(std::filesystem::is_empty(folder));
  // A file that cannot be opened is named in one line, as OpenFlightLog names it.
  try {
    ReopenableFile missing(dir / "missing.csv");
    FAIL() << "a missing file was opened";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(dir / "missing.csv" + ": cannot open", 0), 0u)
        << e.what();
  }
}

// Every binary reader checks the file between its passes against the stamp taken when it was
// mapped (MappedFile::CheckUnchanged): a log rewritten in place at the same size, whose second
// pass would read other bytes than the first, is refused in one line naming it.
TEST(OpenFlightLog, ALogRewrittenAtTheSameSizeBetweenThePassesIsRefused) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  for (const char* relative :
       {"gyro/px4_ulog/sample_log_small.ulg", "gyro/betaflight_blackbox/LOG00037.BFL",
        "incoming/ardupilot_pymavlink_test/test.BIN"}) {
    const std::string path = dir / std::filesystem::path(relative).filename().string();
    std::string bytes = ReadFileToString(test::RealDataPath(relative));
    WriteFileAtomically(path, bytes);
    FlightLogStream stream = OpenFlightLog(path);  // pass 1
    // Rewritten in place (the same inode, the same size), a second later than it was.
    const auto modified = std::filesystem::last_write_time(path);
    std::reverse(bytes.begin() + bytes.size() / 2, bytes.end());
    {
      std::fstream out(path, std::ios::in | std::ios::out | std::ios::binary);
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    }
    std::filesystem::last_write_time(path, modified + std::chrono::seconds(1));
    ASSERT_EQ(std::filesystem::file_size(path), bytes.size());
    try {
      ReadAllSamples(stream.gyro.get());  // pass 2
      FAIL() << relative << ": a rewritten log was read";
    } catch (const IoError& e) {
      EXPECT_EQ(std::string(e.what()),
                path + ": changed while it was read in passes (rewritten, still " +
                    std::to_string(bytes.size()) +
                    " bytes): is it still being recorded? Analyse a copy, or the finished log")
          << relative;
    }
  }
}

// The opening's pass 1 tells how far it has read: never backwards, from 0 to exactly 1, with
// shares between on a log of many messages; the log read is the same as without.
TEST(OpenFlightLog, TheOpeningPassTellsItsProgressUpToOne) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  // Three logs in one blackbox file (5.6 MB): its decoder tells its share every 4 MiB.
  const std::string blackbox =
      ReadFileToString(test::RealDataPath("gyro/betaflight_blackbox/btfl_002.bbl"));
  WriteFileAtomically(dir / "three.bbl", blackbox + blackbox + blackbox);
  for (const std::string& path :
       {test::RealDataPath("gyro/px4_ulog/sample.ulg"),
        test::RealDataPath("incoming/ardupilot_log171/log171.bin"), dir / "three.bbl"}) {
    std::vector<double> told;
    FlightLogReadOptions options;
    options.opening_progress = [&told](double fraction) { told.push_back(fraction); };
    FlightLogStream stream = OpenFlightLog(path, options);
    ASSERT_FALSE(told.empty()) << path;
    EXPECT_GE(told.front(), 0.0) << path;
    EXPECT_EQ(told.back(), 1.0) << path;
    EXPECT_TRUE(std::is_sorted(told.begin(), told.end())) << path;
    EXPECT_TRUE(std::any_of(told.begin(), told.end(), [](double f) { return f > 0 && f < 1; }))
        << path << ": " << told.size() << " shares told";
    const size_t told_opening = told.size();
    FlightLog log = std::move(stream.log);
    log.gyro = ReadAllSamples(stream.gyro.get());
    for (LogWarning& warning : stream.gyro->Warnings()) log.warnings.push_back(std::move(warning));
    EXPECT_EQ(told.size(), told_opening) << path << ": told after the opening";
    FlightLog whole = ReadFlightLog(path);
    whole.warnings.resize(log.warnings.size());  // without the trace audit's, which come last
    test::ExpectSameLog(log, whole, path);
  }
  // A text log has no opening pass.
  WriteFileAtomically(dir / "gyro.csv", "t,gx,gy,gz\n0,0,0,0\n0.001,0,0,0\n");
  FlightLogReadOptions options;
  options.opening_progress = [](double) { ADD_FAILURE() << "a text log told an opening pass"; };
  EXPECT_EQ(ReadFlightLog(dir / "gyro.csv", options).gyro.size(), 2u);
}

// A log still being recorded grows between the passes of a reading in several: the pass after the
// change is refused in one line that names the file and says what to do, never read as another log.
TEST(OpenFlightLog, ALogThatGrowsBetweenPassesIsRefused) {
  test::TempDir dir;
  const std::string path = dir / "gyro.csv";
  std::string text = "t,gx,gy,gz\n";
  for (int i = 0; i < 4000; ++i) text += std::to_string(i * 0.002) + ",0.001,-0.002,0.003\n";
  WriteFileAtomically(path, text);
  const ReopenableFile file(path);
  EXPECT_NO_THROW(file.CheckUnchanged());
  // The still search reads the log in passes, each opening it again; the recorder appends after
  // the first.
  const std::string appended = "8.0,0.001,-0.002,0.003\n";
  int passes = 0;
  const auto open = [&]() -> std::unique_ptr<GyroSource> {
    if (passes++ == 1) std::ofstream(path, std::ios::app) << appended;
    return OpenFlightLog(file).gyro;
  };
  try {
    DetectStillSegment(open);
    FAIL() << "a log that grew between passes was read";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path, 0), 0u) << message;
    EXPECT_NE(message.find("changed while it was read in passes (" + std::to_string(text.size()) +
                           " bytes, now " + std::to_string(text.size() + appended.size()) + ")"),
              std::string::npos)
        << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_EQ(passes, 2);
  EXPECT_THROW(file.CheckUnchanged(), IoError);
}

TEST(ReadFlightLog, HonoursTheLogIndex) {
  // btfl_001.bbl holds two logs of different lengths.
  SHUTTERLAB_REAL_DATA(bbl, "gyro/betaflight_blackbox/btfl_001.bbl");
  FlightLogReadOptions first, second;
  first.log_index = 0;
  second.log_index = 1;
  EXPECT_NE(ReadFlightLog(bbl, first).gyro.samples().size(),
            ReadFlightLog(bbl, second).gyro.samples().size());
}

// A format told by its magic bytes is what it says: a cut GoPro MP4's error is the reader's alone.
// A text detected from its content may be another kind of file, and its error says how it was
// read and that --format chooses.
TEST(ReadFlightLog, OnlyATextLogsErrorSaysWhatDetectionConcluded) {
  SHUTTERLAB_NEED_REAL_DATA();
  test::TempDir dir;
  const std::string mp4 = ReadFileToString(test::RealDataPath("rs/gopro_karma/karma.mp4"));
  WriteFileAtomically(dir / "cut.mp4", mp4.substr(0, mp4.size() * 6 / 10));
  try {
    ReadFlightLog(dir / "cut.mp4");
    FAIL() << "a GoPro MP4 cut before its sample tables";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("runs past the end of the file"), std::string::npos);
    EXPECT_EQ(std::string(e.what()).find("read as"), std::string::npos) << e.what();
  }
  WriteFileAtomically(dir / "gyro.csv", "t,gx,gy,gz\n0,1,2,3\n1,1,2\n");
  try {
    ReadFlightLog(dir / "gyro.csv");
    FAIL() << "a row of three fields";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("(read as gyro.csv: not ULog, DataFlash"),
              std::string::npos)
        << e.what();
  }
}

TEST(ReadFlightLog, UnknownFileIsAClearIoError) {
  test::TempDir dir;
  std::ofstream(dir / "photo.jpg", std::ios::binary)
      << std::string("\xff\xd8\xff\xe0\0\x10JFIF", 10);
  std::ofstream(dir / "notes.txt") << "hello world\n";
  for (const std::string name : {"photo.jpg", "notes.txt"}) {
    try {
      ReadFlightLog(dir / name);
      FAIL() << name;
    } catch (const IoError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(name), std::string::npos) << message;
      EXPECT_NE(message.find("not ULog, DataFlash"), std::string::npos) << message;
    }
  }
  EXPECT_THROW(ReadFlightLog(dir / "missing.bin"), IoError);
}

TEST(ReadFlightLog, FormatOverrideAndNames) {
  test::TempDir dir;
  std::ofstream(dir / "gyro.csv") << "t,gx,gy,gz\n0.0,0.1,0.2,0.3\n0.001,0.1,0.2,0.3\n";
  FlightLogReadOptions options;
  options.format = ParseLogFormat("ulog");
  EXPECT_THROW(ReadFlightLog(dir / "gyro.csv", options), IoError);
  EXPECT_EQ(ParseLogFormat("Blackbox"), LogFormat::kBlackbox);
  EXPECT_STREQ(LogFormatName(LogFormat::kDataFlash), "dataflash");
  EXPECT_THROW(ParseLogFormat("jpeg"), std::invalid_argument);
}

TEST(ReaderTable, NamesRoundTripThroughBothParsers) {
  for (LogFormat f : {LogFormat::kAuto, LogFormat::kGyroCsv, LogFormat::kGcsv, LogFormat::kRaw,
                      LogFormat::kULog, LogFormat::kBlackbox, LogFormat::kDataFlash,
                      LogFormat::kGoproMp4, LogFormat::kGyroDump, LogFormat::kColumns}) {
    EXPECT_EQ(ParseLogFormat(LogFormatName(f)), f) << LogFormatName(f);
    if (f == LogFormat::kAuto || IsPlainGyroFormat(f)) {
      EXPECT_EQ(ParseGyroFormat(LogFormatName(f)), f) << LogFormatName(f);
    } else {
      EXPECT_THROW(ParseGyroFormat(LogFormatName(f)), std::invalid_argument) << LogFormatName(f);
    }
  }
  EXPECT_EQ(ParseLogFormat("CSV"), LogFormat::kGyroCsv);
  EXPECT_EQ(ParseLogFormat("px4"), LogFormat::kULog);
  EXPECT_EQ(ParseLogFormat("bin"), LogFormat::kDataFlash);
  EXPECT_EQ(ParseLogFormat("MP4"), LogFormat::kGoproMp4);
  EXPECT_EQ(ParseLogFormat("dump"), LogFormat::kGyroDump);
}

TEST(ReaderTable, UnknownNamesAreNamedWithTheChoices) {
  try {
    ParseLogFormat("jpeg");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("unknown log format 'jpeg' (auto, ulog, dataflash, "
                                          "blackbox, gopro, gyro.csv, gcsv, raw, gyro_dump, "
                                          "columns)",
                                          0),
              0u)
        << e.what();
  }
  try {
    ParseGyroFormat("ulog");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("unknown gyro format 'ulog' (auto, csv, gcsv, raw)", 0),
              0u)
        << e.what();
  }
}

// The reader table is the one list of formats: every format but kAuto has one reader, with names
// of its own; what dispatch, --format and the messages say comes from it.
TEST(ReaderTable, EveryFormatHasOneReaderWithNamesOfItsOwn) {
  std::set<std::string> names;
  for (LogFormat f : {LogFormat::kGyroCsv, LogFormat::kGcsv, LogFormat::kRaw, LogFormat::kULog,
                      LogFormat::kBlackbox, LogFormat::kDataFlash, LogFormat::kGoproMp4,
                      LogFormat::kGyroDump, LogFormat::kColumns}) {
    const auto count = std::count_if(LogReaders().begin(), LogReaders().end(),
                                     [f](const LogReader& r) { return r.format == f; });
    EXPECT_EQ(count, 1) << LogFormatName(f);
  }
  EXPECT_EQ(LogReaders().size(), 9u);
  for (const LogReader& reader : LogReaders()) {
    for (const char* name : reader.names) {
      if (name != nullptr) {
        EXPECT_TRUE(names.insert(name).second) << name;
      }
    }
    EXPECT_EQ(&ReaderOf(reader.format), &reader);
    // A first pass that tells its progress: the flight-controller logs, read in two passes.
    const bool flight_controller = reader.format == LogFormat::kULog ||
                                   reader.format == LogFormat::kDataFlash ||
                                   reader.format == LogFormat::kBlackbox;
    EXPECT_EQ(reader.opening_pass, flight_controller) << reader.display_name;
  }
  std::vector<std::string> listed = LogFormatNames();
  ASSERT_EQ(listed.size(), LogReaders().size() + 1);
  EXPECT_EQ(listed.front(), "auto");
}

// Each reader is fuzzed by its own target, and docs/FORMATS.md names its reader's header; a format
// that may carry camera events says which, one that may not says so or says nothing of them.
TEST(ReaderTable, FuzzTargetsAndDocsFollowTheTable) {
  const std::string root = SHUTTERLAB_SOURCE_DIR;
  const std::string docs = ReadFileToString(root + "/docs/FORMATS.md");
  for (const LogReader& reader : LogReaders()) {
    const std::string target = root + "/fuzz/" + reader.fuzz_target + "_fuzz.cc";
    EXPECT_TRUE(std::filesystem::exists(target)) << target;
    const std::string header = std::string("`") + reader.reader_header + "`";
    const size_t at = docs.find(header);
    ASSERT_NE(at, std::string::npos) << reader.display_name << ": " << header;
    const size_t row_begin = docs.rfind('\n', at) + 1;
    const std::string row = docs.substr(row_begin, docs.find('\n', at) - row_begin);
    if (row.rfind("|", 0) != 0) continue;  // named in prose, not in the table
    const bool says_events = row.find("camera events") != std::string::npos &&
                             row.find("no camera events") == std::string::npos;
    EXPECT_EQ(says_events, reader.camera_events) << reader.display_name << ": " << row;
  }
}

// Detection and its refusal name the formats in the table's order.
TEST(ReaderTable, DetectionRefusesUnknownBytesNamingEveryDetectedFormat) {
  try {
    DetectFlightLogFormat(std::string("\x01\x02\0binary", 9), "x.bin");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(
        std::string(e.what()).find("not ULog, DataFlash, blackbox, GoPro MP4, gyro.csv, .gcsv, "
                                   "raw counts or a gyro dump (binary content)"),
        std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace shutterlab
