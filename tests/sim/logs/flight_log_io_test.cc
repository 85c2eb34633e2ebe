#include "sim/logs/flight_log_io.h"

#include "sim/check.h"
#include "sim/logs/gopro_telemetry.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/ulog_write.h"
#include "sim/still_detect.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <memory>
#include <pthread.h>
#include <stdexcept>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

namespace shutterlab {
namespace {

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
      // A cut that falls on a record boundary cannot be told from the end of a log: move off
      // one (DataFlash records start 0xA3 0x95; the other formats' cuts here fall inside one).
      size_t size = static_cast<size_t>(fraction * bytes.size()) | 1;
      while (bytes.compare(size, 2, "\xA3\x95") == 0) size += 2;
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

// What ReadFlightLog makes of bytes that come down a pipe: readable once, of no known size, and
// not seekable, like a log given as /dev/stdin.
FlightLog ReadFromPipe(const std::string& bytes, const FlightLogReadOptions& options = {}) {
  int fds[2];
  SHUTTERLAB_CHECK(::pipe(fds) == 0) << "pipe";
  std::thread writer([&bytes, fd = fds[1]] {
    // A reader that stops early closes the pipe: the writer's write() then fails with EPIPE
    // instead of raising SIGPIPE, which is sent to the writing thread and blocked in it alone.
    sigset_t pipe_signal;
    sigemptyset(&pipe_signal);
    sigaddset(&pipe_signal, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_signal, nullptr);
    for (size_t done = 0; done < bytes.size();) {
      const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
      if (n <= 0) break;
      done += static_cast<size_t>(n);
    }
    ::close(fd);
  });
  struct Cleanup {
    std::thread& writer;
    int read_fd;
    ~Cleanup() {
      ::close(read_fd);  // before the join: a writer still writing then stops
      writer.join();
    }
  } cleanup{writer, fds[0]};
  return ReadFlightLog("/proc/self/fd/" + std::to_string(fds[0]), options);
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

// A log still being recorded grows between the passes of a reading in several: the pass after the
// change is refused in one line that names the file and says what to do, never read as another log.
TEST(ReopenFlightLog, ALogThatGrowsBetweenPassesIsRefused) {
  test::TempDir dir;
  const std::string path = dir / "gyro.csv";
  std::string text = "t,gx,gy,gz\n";
  for (int i = 0; i < 4000; ++i) text += std::to_string(i * 0.002) + ",0.001,-0.002,0.003\n";
  WriteFileAtomically(path, text);
  const LogStamp stamp = LogStamp::Of(path);
  EXPECT_EQ(stamp.size_bytes, text.size());
  EXPECT_NO_THROW(stamp.CheckUnchanged());
  // The still search reads the log in passes through ReopenFlightLog; the recorder appends after
  // the first.
  const std::string appended = "8.0,0.001,-0.002,0.003\n";
  int passes = 0;
  const auto open = [&]() -> std::unique_ptr<GyroSource> {
    if (passes++ == 1) std::ofstream(path, std::ios::app) << appended;
    return ReopenFlightLog(stamp).gyro;
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
  EXPECT_THROW(stamp.CheckUnchanged(), IoError);
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

}  // namespace
}  // namespace shutterlab
