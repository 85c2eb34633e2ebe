// What `record` writes, read back by the readers every command uses, gives the source trace's
// noise and flight tables: a synthetic 8 kHz MPU-9250 still and flight trace played by the
// register-level emulator through the recorder (virtual time, writer stalls), against the same
// samples of the source.

#include "estimate/paper/flight.h"
#include "estimate/paper/noise.h"
#include "record/recorder.h"
#include "record/sensor_emulator.h"
#include "sim/logs/flight_log_io.h"
#include "sim/synth/synth.h"
#include "sim/units.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>

namespace shutterlab {
namespace {

GyroTrace Synthetic(MotionProfile profile, uint64_t seed) {
  SynthOptions synth;
  synth.profile = profile;
  synth.rate_hz = 8000.0;
  synth.duration_s = 9.0;
  synth.seed = seed;
  return SynthesizeTrace(synth);
}

// Records `source` through the emulated MPU-9250 (ppm 0: the part samples where the trace did; its
// filter off)
// and reads the file back with ReadFlightLog. *offset receives the index of the source sample the
// recording starts with (the samples before the recorder's first FIFO read were flushed).
GyroTrace RecordAndReadBack(const GyroTrace& source, const std::string& out, size_t* offset) {
  VirtualClock clock(1000000000);
  // The part's filter off: this is the recording and the readers against the source, sample for
  // sample (docs/raspberry-pi.md shows the tables through the filter too).
  EmulatorOptions part;
  part.filter = false;
  SensorEmulator emulator(source, &clock, part);
  RecordSensor sensor;
  sensor.bus = &emulator;
  sensor.device = "emulated";
  sensor.out_path = out;
  RecorderOptions options;
  options.duration_s = 8.0;
  options.writer_stall = {2.0, 0.3};
  const RecordSummary summary = Record({sensor}, options, clock);
  EXPECT_EQ(summary.sensors[0].gaps, 0u);
  const FlightLog log = ReadFlightLog(out);
  EXPECT_EQ(log.format, "gcsv");
  // The recorded counts are the source's from some sample on.
  const double gscale = kPi / 180.0 / 131.0;
  *offset = 0;
  for (size_t j = 0; j < 100; ++j) {
    bool same = true;
    for (size_t i = 0; i < 50 && same; ++i) {
      same =
          (source[j + i].omega_rad_s - log.gyro[i].omega_rad_s).cwiseAbs().maxCoeff() < gscale / 2;
    }
    if (same) {
      *offset = j;
      return log.gyro;
    }
  }
  ADD_FAILURE() << "the recorded counts are not the source's";
  return log.gyro;
}

// The source's samples that the recording holds, on the source's own clock.
GyroTrace SameSamples(const GyroTrace& source, size_t offset, size_t n) {
  return GyroTrace(std::vector<GyroSample>(source.samples().begin() + offset,
                                           source.samples().begin() + offset + n));
}

TEST(RecordReadback, NoiseTablesAreTheSourcesWithinQuantisation) {
  test::TempDir dir;
  const GyroTrace source = Synthetic(MotionProfile::kStill, 11);
  size_t offset = 0;
  const GyroTrace recorded = RecordAndReadBack(source, dir / "still.gcsv", &offset);
  const GyroTrace expected = SameSamples(source, offset, recorded.size());
  const NoiseResult a = AnalyzeNoise(expected, NoiseOptions{});
  const NoiseResult b = AnalyzeNoise(recorded, NoiseOptions{});
  for (int axis = 0; axis < 3; ++axis) {
    // Same counts; the stamps differ by microseconds, which moves the 5 s bias boundary by a
    // sample at most: the table's 0.01" is not touched.
    EXPECT_NEAR(a.axes[axis].sigma_mean_arcsec, b.axes[axis].sigma_mean_arcsec, 0.005);
    EXPECT_NEAR(a.axes[axis].range_mean_arcsec, b.axes[axis].range_mean_arcsec, 0.005);
    EXPECT_NEAR(a.allan.axes[axis].arw_rad_s_sqrt_hz / b.allan.axes[axis].arw_rad_s_sqrt_hz, 1.0,
                1e-3);
  }
}

TEST(RecordReadback, FlightTablesAreTheSourcesWithinQuantisation) {
  test::TempDir dir;
  const GyroTrace source = Synthetic(MotionProfile::kFlight, 12);
  size_t offset = 0;
  const GyroTrace recorded = RecordAndReadBack(source, dir / "flight.gcsv", &offset);
  const GyroTrace expected = SameSamples(source, offset, recorded.size());
  FlightOptions options;
  // Windows that are not a whole number of 125 us periods: at exactly 80 periods (10 ms) the
  // window's end falls on a sample of the source's perfect grid, and a stamp a microsecond early
  // adds that sample to the window; the recorded table then reads up to 0.3 points higher.
  options.windows_s = {0.0100625, 0.0200625};
  const FlightResult a = Flight(expected, options);
  const FlightResult b = Flight(recorded, options);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  for (size_t r = 0; r < a.rows.size(); ++r) {
    EXPECT_NEAR(a.rows[r].flagged_percent, b.rows[r].flagged_percent, 0.02) << "row " << r;
    EXPECT_NEAR(a.rows[r].flagged_percent_vector, b.rows[r].flagged_percent_vector, 0.05)
        << "row " << r;
  }
}

}  // namespace
}  // namespace shutterlab
