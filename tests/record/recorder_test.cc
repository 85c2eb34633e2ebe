// The recorder through the register-level emulators, in virtual time: an 8 kHz trace recorded
// through 300 ms writer stalls without a gap, the source paper's pause-while-writing logger losing
// samples on the same trace, a starved reader's FIFO overflow reported as a gap, a brown-out, the
// timestamps and the clock drift against the emulator's truth, and a wrong part refused.

#include "record/recorder.h"

#include "record/gyro_driver.h"
#include "record/sensor_emulator.h"
#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gcsv.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace shutterlab {
namespace {

constexpr int64_t kStartNs = 1000000000;  // the virtual clock's start (any positive time)

// A synthetic flight at `rate_hz` (the motion makes counts differ from sample to sample, so a
// sample recorded twice or skipped shows).
GyroTrace FlightTrace(double rate_hz, double duration_s, uint64_t seed = 3) {
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = rate_hz;
  synth.duration_s = duration_s;
  synth.seed = seed;
  return SynthesizeTrace(synth);
}

struct Rig {
  Rig(GyroTrace trace, EmulatorOptions emulator_options)
      : clock(kStartNs), emulator(std::move(trace), &clock, [&] {
          emulator_options.keep_truth = true;
          return emulator_options;
        }()) {}
  VirtualClock clock;
  SensorEmulator emulator;
};

RecordSensor Sensor(SpiTransport* bus, GyroPart part, double rate_hz, const std::string& out) {
  RecordSensor sensor;
  sensor.bus = bus;
  sensor.part = part;
  sensor.config.rate_hz = rate_hz;
  sensor.device = "emulated";
  sensor.out_path = out;
  return sensor;
}

// The time of the motion FIFO sample i shows: when the emulated part made it, less its filter's
// delay (what the recorder stamps).
int64_t MotionTimeNs(const Rig& rig, size_t i) {
  return rig.emulator.FifoSampleTimeNs(i) - rig.emulator.FilterDelayNs();
}

// Every recorded sample is the emulator's FIFO sample of the same index, counts equal, and its time
// within tol_ns of the motion it shows (MotionTimeNs); the recording holds every sample produced up
// to its end but those still in the FIFO.
void ExpectEverySample(const Rig& rig, const RecordSummary& summary, const GcsvLog& log,
                       double tol_ns) {
  const auto& samples = log.trace.samples();
  const double gscale = log.gscale;
  ASSERT_LE(samples.size(), rig.emulator.fifo_samples());
  EXPECT_GE(samples.size() + 90, rig.emulator.fifo_samples());  // at most a FIFO's worth left
  double worst_ns = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const auto& counts = rig.emulator.FifoSampleCounts(i);
    for (int axis = 0; axis < 3; ++axis) {
      ASSERT_EQ(std::lround(samples[i].omega_rad_s[axis] / gscale), counts[axis]) << "sample " << i;
    }
    const double error_ns =
        std::abs(static_cast<double>(samples[i].t_ns + summary.t0_clock_ns - MotionTimeNs(rig, i)));
    worst_ns = std::max(worst_ns, error_ns);
  }
  EXPECT_LT(worst_ns, tol_ns);
}

TEST(Recorder, EverySampleOfAnEightKilohertzTraceSurvivesWriterStalls) {
  test::TempDir dir;
  EmulatorOptions emulator;
  emulator.ppm = 40.0;
  Rig rig(FlightTrace(8000.0, 4.0), emulator);
  RecorderOptions options;
  options.duration_s = 3.5;
  options.ring_s = 1.0;
  options.writer_stall = {1.0, 0.3};  // 300 ms every second: three stalls
  const RecordSummary summary = Record(
      {Sensor(&rig.emulator, GyroPart::kMpu9250, 8000, dir / "rec.gcsv")}, options, rig.clock);
  ASSERT_EQ(summary.sensors.size(), 1u);
  const SensorSummary& s = summary.sensors[0];
  EXPECT_EQ(s.gaps, 0u);
  EXPECT_EQ(s.lost, 0);
  EXPECT_EQ(rig.emulator.samples_dropped(), 0u);
  EXPECT_GE(summary.max_writer_stall_s, 0.3);  // the writer really was away that long
  EXPECT_GE(s.ring_high_water, 2400u);         // and the ring held what came meanwhile
  EXPECT_NEAR(s.drift_ppm, 40.0, 1.0);         // the part's clock error, fitted
  // Samples over their span: the part's fast clock, less what the young fit's first stamps skew.
  EXPECT_NEAR(s.rate_hz, 8000.0 * (1 + 40e-6), 0.5);
  const GcsvLog log = ReadGcsv(dir / "rec.gcsv");
  EXPECT_EQ(log.trace.size(), s.samples);
  // The fit needs a few reads to settle; after that every sample sits within 5 us of its truth.
  ExpectEverySample(rig, summary, log, 60000.0);
  EXPECT_TRUE(log.warnings.empty()) << test::JoinedWarnings(log.warnings);
}

// The MPU's 32 kHz mode (FCHOICE_B, the DLPF bypassed): its 512-byte FIFO fills in 2.7 ms, so
// the reader comes every 0.67 ms; every sample is kept, stamped with the mode's 0.064 ms delay off.
TEST(Recorder, TheMpusThirtyTwoKilohertzModeKeepsEverySample) {
  test::TempDir dir;
  Rig rig(FlightTrace(32000.0, 1.5), EmulatorOptions{});
  RecorderOptions options;
  options.duration_s = 1.2;
  const RecordSummary summary = Record(
      {Sensor(&rig.emulator, GyroPart::kMpu9250, 32000, dir / "rec.gcsv")}, options, rig.clock);
  ASSERT_EQ(summary.sensors.size(), 1u);
  EXPECT_EQ(summary.sensors[0].setting.odr_hz, 32000.0);
  EXPECT_EQ(summary.sensors[0].setting.fchoice_b, 1);
  EXPECT_EQ(summary.sensors[0].gaps, 0u);
  EXPECT_EQ(rig.emulator.samples_dropped(), 0u);
  EXPECT_EQ(rig.emulator.FilterDelayNs(), 64000);
  const GcsvLog log = ReadGcsv(dir / "rec.gcsv");
  EXPECT_GT(log.trace.size(), 30000u);
  ExpectEverySample(rig, summary, log, 60000.0);
}

TEST(Recorder, TimestampsFollowThePartsClockToMicroseconds) {
  test::TempDir dir;
  EmulatorOptions emulator;
  emulator.ppm = -120.0;
  Rig rig(FlightTrace(8000.0, 6.0), emulator);
  RecorderOptions options;
  options.duration_s = 6.0;
  const RecordSummary summary = Record(
      {Sensor(&rig.emulator, GyroPart::kMpu9250, 8000, dir / "rec.gcsv")}, options, rig.clock);
  const GcsvLog log = ReadGcsv(dir / "rec.gcsv");
  // After the first second the stamps are within 10 us of the truth (each read's latch is known
  // to a period, 125 us; the fit averages a few thousand reads): a trigger edge lands on the
  // right sample.
  const size_t settled = 8000;
  double worst_ns = 0;
  for (size_t i = settled; i < log.trace.size(); ++i) {
    worst_ns =
        std::max(worst_ns, std::abs(static_cast<double>(log.trace[i].t_ns + summary.t0_clock_ns -
                                                        MotionTimeNs(rig, i))));
  }
  EXPECT_LT(worst_ns, 10000.0);
  EXPECT_NEAR(summary.sensors[0].drift_ppm, -120.0, 1.0);
}

TEST(Recorder, ThePapersPauseWhileWritingLosesSamplesOnTheSameTrace) {
  test::TempDir dir;
  Rig rig(FlightTrace(8000.0, 5.0), EmulatorOptions{});
  RecorderOptions options;
  options.duration_s = 4.5;
  options.paper_pause = {8000, 0.3};  // a buffer of one second, then 300 ms writing it
  const RecordSummary summary = Record(
      {Sensor(&rig.emulator, GyroPart::kMpu9250, 8000, dir / "rec.gcsv")}, options, rig.clock);
  const SensorSummary& s = summary.sensors[0];
  ASSERT_EQ(s.gaps, 3u);
  // Each pause costs 300 ms of samples less the 85 the FIFO holds.
  for (const RecordGap& gap : summary.gaps) {
    EXPECT_EQ(gap.kind, "fifo_overflow");
    EXPECT_NEAR(gap.lost, 2400 - 85, 2);
  }
  EXPECT_NEAR(static_cast<double>(s.lost), static_cast<double>(rig.emulator.samples_dropped()), 3);
  // The gaps are in the log, and the readers report them.
  const FlightLog log = ReadFlightLog(dir / "rec.gcsv");
  EXPECT_TRUE(test::AnyWarningContains(log.warnings, "fifo_overflow"))
      << test::JoinedWarnings(log.warnings);
}

TEST(Recorder, AStarvedReadersFifoOverflowIsAGapWithItsTime) {
  test::TempDir dir;
  Rig rig(FlightTrace(8000.0, 3.0), EmulatorOptions{});
  RecorderOptions options;
  options.duration_s = 2.0;
  options.reader_pauses = {{1.0, 0.05}};
  const RecordSummary summary = Record(
      {Sensor(&rig.emulator, GyroPart::kMpu9250, 8000, dir / "rec.gcsv")}, options, rig.clock);
  ASSERT_EQ(summary.gaps.size(), 1u);
  const RecordGap& gap = summary.gaps[0];
  EXPECT_EQ(gap.kind, "fifo_overflow");
  EXPECT_EQ(gap.lost, static_cast<int64_t>(rig.emulator.samples_dropped()));
  EXPECT_NEAR(gap.lost, 400 - 85, 20);  // 50 ms at 8 kHz less the FIFO, give or take a read
  EXPECT_NEAR(gap.t_s, 1.0 + 85 / 8000.0, 0.003);  // the FIFO filled 10.6 ms into the pause
  // The samples after the gap carry the right times: the gap is in the trace too.
  const GcsvLog log = ReadGcsv(dir / "rec.gcsv");
  const auto& samples = log.trace.samples();
  size_t big = 0;
  for (size_t i = 1; i < samples.size(); ++i) big += samples[i].t_ns - samples[i - 1].t_ns > 200000;
  EXPECT_EQ(big, 1u);
}

// An emulated MPU-9250 at 8 kHz, with `emulator`'s faults, recorded into `path` for duration_s
// of a 4 s flight trace.
RecordSummary RecordMpuAt8kHz(const std::string& path, const EmulatorOptions& emulator,
                              double duration_s) {
  Rig rig(FlightTrace(8000.0, 4.0), emulator);
  RecorderOptions options;
  options.duration_s = duration_s;
  return Record({Sensor(&rig.emulator, GyroPart::kMpu9250, 8000, path)}, options, rig.clock);
}

TEST(Recorder, ABrownOutIsAGapAndThePartIsConfiguredAgain) {
  test::TempDir dir;
  EmulatorOptions emulator;
  emulator.brownouts = {{kStartNs + 1200000000, 30000000}};
  const RecordSummary summary = RecordMpuAt8kHz(dir / "rec.gcsv", emulator, 3.5);
  ASSERT_FALSE(summary.gaps.empty());
  int64_t lost = 0;
  bool reset = false;
  for (const RecordGap& gap : summary.gaps) {
    lost += gap.lost;
    reset |= gap.kind == "part_reset";
  }
  EXPECT_TRUE(reset);
  // The first read of the dead bus (within 2.5 ms of its start) finds bad data and the health
  // check at once; the part is declared dead after 10 ms of failed checks (noise shorter than that
  // costs only its FIFO: the test below), its reset is lost in the dead bus, the one 100 ms later
  // configures the part again, and its gyro starts 35 ms after: at least 145 ms lost, and the
  // reads' dithered passes (1 to 3 ms apart) add a few more (163.5 ms measured).
  EXPECT_GE(lost / 8000.0, 0.145);
  EXPECT_LE(lost / 8000.0, 0.175);
  EXPECT_GT(summary.sensors[0].samples, 8000u * 2);  // it kept recording after
}

// Noise on the line back from the part for 5 ms: the FIFO count read then is one the FIFO cannot
// hold, a bad_data gap at its time, the FIFO flushed and the health check run; the recording goes
// on, and the gap is in the file's header for every reader.
TEST(Recorder, AGarbledSpiReadIsABadDataGapAndTheRecordingGoesOn) {
  test::TempDir dir;
  EmulatorOptions emulator;
  constexpr int64_t kGarbledNs = kStartNs + 1500000000;
  emulator.garbled_reads = {{kGarbledNs, 5000000}};
  const RecordSummary summary = RecordMpuAt8kHz(dir / "rec.gcsv", emulator, 3.0);
  ASSERT_FALSE(summary.gaps.empty());
  const RecordGap& gap = summary.gaps.front();
  EXPECT_EQ(gap.kind, "bad_data");
  EXPECT_NEAR(gap.t_s, (kGarbledNs - summary.t0_clock_ns) * 1e-9, 0.01);
  // What the FIFO held at the flush and what came during the noise: at most the 5 ms of noise
  // and one read interval's samples (3 ms at most, dithered): under 10 ms (3.5 ms measured).
  int64_t lost = 0;
  for (const RecordGap& g : summary.gaps) lost += g.lost;
  EXPECT_GT(lost, 0);
  EXPECT_LT(lost / 8000.0, 0.010);
  EXPECT_GT(summary.sensors[0].samples, 8000u * 2);  // it kept recording after
  const GcsvLog log = ReadGcsv(dir / "rec.gcsv");
  EXPECT_TRUE(test::AnyWarningContains(log.warnings, "bad_data"))
      << test::JoinedWarnings(log.warnings);
}

TEST(Recorder, TheIcm42688pRecordsAt32Kilohertz) {
  test::TempDir dir;
  EmulatorOptions emulator;
  emulator.part = GyroPart::kIcm42688p;
  emulator.ppm = 15.0;
  Rig rig(FlightTrace(32000.0, 1.5), emulator);
  RecorderOptions options;
  options.duration_s = 1.2;
  options.writer_stall = {0.5, 0.3};
  const RecordSummary summary = Record(
      {Sensor(&rig.emulator, GyroPart::kIcm42688p, 32000, dir / "rec.gcsv")}, options, rig.clock);
  EXPECT_EQ(summary.sensors[0].setting.odr_hz, 32000.0);
  EXPECT_EQ(summary.sensors[0].gaps, 0u);
  const GcsvLog log = ReadGcsv(dir / "rec.gcsv");
  ExpectEverySample(rig, summary, log, 60000.0);
}

TEST(Recorder, AWrongWhoAmIIsRefusedBeforeAnythingIsWritten) {
  test::TempDir dir;
  EmulatorOptions emulator;
  emulator.part = GyroPart::kMpu6500;  // an MPU-6500 on the bus, configured as an MPU-9250
  Rig rig(FlightTrace(8000.0, 1.0), emulator);
  RecorderOptions options;
  options.duration_s = 0.5;
  try {
    Record({Sensor(&rig.emulator, GyroPart::kMpu9250, 8000, dir / "rec.gcsv")}, options, rig.clock);
    FAIL() << "a wrong WHO_AM_I was accepted";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("WHO_AM_I is 0x70, expected 0x71"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("MPU-6500"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(Recorder, TriggerEdgesLandOnTheirSample) {
  test::TempDir dir;
  Rig rig(FlightTrace(8000.0, 3.0), EmulatorOptions{});
  // Off the grid of the motion times the samples show (every 125 us, 0.97 ms before the part made
  // them) by 30 us or more.
  const std::vector<int64_t> pulses = {400090000, 1234567000, 2000062000};
  EmulatedTriggerLine line(
      pulses, 5000000, /*bounce=*/2, [&] { return rig.emulator.PlayOriginNs(); }, &rig.clock);
  RecorderOptions options;
  options.duration_s = 2.5;
  options.trigger = &line;
  options.triggers_path = dir / "triggers.csv";
  options.debounce_s = 0.001;
  const RecordSummary summary = Record(
      {Sensor(&rig.emulator, GyroPart::kMpu9250, 8000, dir / "rec.gcsv")}, options, rig.clock);
  ASSERT_EQ(summary.trigger_t_s.size(), pulses.size());
  EXPECT_EQ(summary.trigger_bounces, pulses.size() * 2 * 4);  // 2 bounces = 4 edges per edge
  const GcsvLog log = ReadGcsv(dir / "rec.gcsv");
  const int64_t origin_ns = *rig.emulator.PlayOriginNs();
  for (size_t p = 0; p < pulses.size(); ++p) {
    const int64_t true_ns = origin_ns + pulses[p];
    EXPECT_NEAR(summary.trigger_t_s[p], (true_ns - summary.t0_clock_ns) * 1e-9, 1e-9);
    // The sample the trigger falls on in the log is the one that shows the motion of that moment
    // (made a filter delay later).
    const int64_t t_in_log = SecondsToNs(summary.trigger_t_s[p]);
    const size_t logged = log.trace.LowerBound(t_in_log);
    size_t truth = 0;
    while (MotionTimeNs(rig, truth) < true_ns) ++truth;
    EXPECT_EQ(logged, truth) << "pulse " << p;
  }
  const std::string text = ReadFileToString(dir / "triggers.csv");
  EXPECT_NE(text.find("\nimage,t\nIMG_0001,"), std::string::npos) << text;
}

TEST(Recorder, TwoSensorsOnOneClockSeeTheSameMotionAtTheSameTime) {
  test::TempDir dir;
  VirtualClock clock(kStartNs);
  // A slow motion (3 to 11 Hz, no noise: white noise would be matched by where each filter's
  // impulse response peaks, not by its delay), sampled at 8 kHz.
  std::vector<GyroSample> motion;
  for (int64_t k = 0; k < 24000; ++k) {
    const double t = k / 8000.0;
    motion.push_back({k * 125000, Eigen::Vector3d(0.5 * std::sin(2 * kPi * 3 * t),
                                                  0.3 * std::sin(2 * kPi * 7 * t + 1),
                                                  0.2 * std::sin(2 * kPi * 11 * t))});
  }
  const GyroTrace trace(std::move(motion));
  EmulatorOptions options;
  options.shared_origin = std::make_shared<std::atomic<int64_t>>(INT64_MIN);
  SensorEmulator first(trace, &clock, options);
  options.part = GyroPart::kIcm42688p;  // another part on the second bus, configured 100 ms later
  SensorEmulator second(trace, &clock, options);
  RecorderOptions recorder;
  recorder.duration_s = 2.5;
  recorder.writer_stall = {1.0, 0.3};
  const RecordSummary summary =
      Record({Sensor(&first, GyroPart::kMpu9250, 8000, dir / "a.gcsv"),
              Sensor(&second, GyroPart::kIcm42688p, 8000, dir / "b.gcsv")},
             recorder, clock);
  ASSERT_EQ(summary.sensors.size(), 2u);
  EXPECT_EQ(summary.gaps.size(), 0u);
  EXPECT_EQ(summary.sensors[1].setting.odr_hz, 8000.0);
  const GcsvLog a = ReadGcsv(dir / "a.gcsv"), b = ReadGcsv(dir / "b.gcsv");
  // The parts filter differently (the MPU's 250 Hz DLPF, 0.97 ms; the ICM's 2 kHz UI filter): a
  // slow motion leaves them seven samples apart. Each stamp is the
  // motion's time, the part's delay taken off: the two agree best with no lag (within a sample).
  const double delay_apart_samples =
      (summary.sensors[0].setting.filter_delay_s - summary.sensors[1].setting.filter_delay_s) *
      8000.0;
  EXPECT_GT(delay_apart_samples, 5.0);
  std::vector<size_t> nearest_b(a.trace.size());  // b's sample nearest each of a's
  size_t j = 0;
  for (size_t i = 0; i < a.trace.size(); ++i) {
    while (j + 1 < b.trace.size() && std::llabs(b.trace[j + 1].t_ns - a.trace[i].t_ns) <=
                                         std::llabs(b.trace[j].t_ns - a.trace[i].t_ns)) {
      ++j;
    }
    nearest_b[i] = j;
  }
  int best_lag = 0;
  double best_msd = INFINITY;
  for (int lag = -12; lag <= 12; ++lag) {
    double sum = 0;
    size_t n = 0;
    for (size_t i = 8000; i + 8000 < a.trace.size(); ++i) {  // away from the ends
      const size_t k = static_cast<size_t>(static_cast<int64_t>(nearest_b[i]) + lag);
      sum += (a.trace[i].omega_rad_s - b.trace[k].omega_rad_s).squaredNorm();
      ++n;
    }
    ASSERT_GT(n, 1000u);
    if (sum / n < best_msd) {
      best_msd = sum / n;
      best_lag = lag;
    }
  }
  EXPECT_LE(std::abs(best_lag), 1) << "b agrees best with a " << best_lag << " samples later";
}

}  // namespace
}  // namespace shutterlab
