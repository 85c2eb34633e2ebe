#include "sim/logs/gopro_telemetry.h"

#include "sim/check.h"
#include "sim/logs/gpmf.h"
#include "sim/logs/mp4.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// SHUT values 1, 2, 3 ms written at 0, 1/30 and 2/30 s.
GoproTelemetry ThreeShutters() {
  GoproTelemetry t;
  t.shutter_s = {0.001, 0.002, 0.003};
  t.shutter_t_s = {0.0, 1.0 / 30, 2.0 / 30};
  return t;
}

TEST(GoproTelemetry, NearestShutterIsTheClosestInTimeWithinAPeriod) {
  const GoproTelemetry t = ThreeShutters();
  const double period_s = 1.0 / 30;
  EXPECT_EQ(NearestShutterS(t, 0.0, period_s), 0.001);
  EXPECT_EQ(NearestShutterS(t, 0.016, period_s), 0.001);  // 16 ms from the first, 17 from the next
  EXPECT_EQ(NearestShutterS(t, 0.017, period_s), 0.002);
  EXPECT_EQ(NearestShutterS(t, 0.045, period_s),
            0.002);                                      // 12 ms from the second, 22 from the third
  EXPECT_EQ(NearestShutterS(t, 0.09, period_s), 0.003);  // after the last, within a period
  EXPECT_EQ(NearestShutterS(t, -0.03, period_s), 0.001);        // before the first, within a period
  EXPECT_EQ(NearestShutterS(t, 0.11, period_s), std::nullopt);  // 43 ms after the last
  EXPECT_EQ(NearestShutterS(t, -0.04, period_s), std::nullopt);
  EXPECT_EQ(NearestShutterS(GoproTelemetry{}, 0.0, period_s), std::nullopt);  // no SHUT stream
}

TEST(GoproTelemetry, NotAnMp4IsAnIoErrorNamingThePath) {
  test::TempDir dir;
  std::ofstream(dir / "text.mp4") << "not a video\n";
  for (const auto& read : {+[](const std::string& p) { (void)HasGoproTelemetry(p); },
                           +[](const std::string& p) { (void)ReadGoproTelemetry(p); },
                           +[](const std::string& p) { (void)ReadVideoFrameTimesS(p); }}) {
    try {
      read(dir / "text.mp4");
      ADD_FAILURE() << "no error";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("text.mp4: offset 0"), std::string::npos) << e.what();
    }
  }
}

// karma.mp4 (HERO5 Black on a Karma drone): GYRO stored as z, x, y with SCAL 3755, SHUT per frame.
TEST(GoproTelemetry, KarmaGyroInSensorAxesAndShutter) {
  SHUTTERLAB_REAL_DATA(karma, "rs/gopro_karma/karma.mp4");
  ASSERT_TRUE(HasGoproTelemetry(karma));
  const GoproTelemetry t = ReadGoproTelemetry(karma);
  EXPECT_EQ(t.device, "Camera");
  EXPECT_EQ(t.gyro_name, "Gyroscope (z,x,y)");
  EXPECT_EQ(t.axis_order_source, "STNM 'Gyroscope (z,x,y)'");
  EXPECT_EQ(t.gyro_scale, std::vector<double>{3755});
  EXPECT_EQ(t.gyro_payload_samples.size(), 13u);
  EXPECT_NEAR(t.gyro_rate_hz, 397.18, 0.05);

  // Sample by sample against the stream as GPMF stores it: x, y, z = stored columns 1, 2, 0.
  Mp4File mp4(karma);
  const GpmfTrackStream stored = ReadGpmfTrackStream(mp4, *mp4.FindTrack("meta", "gpmd"), "GYRO");
  ASSERT_EQ(t.gyro.size(), stored.samples());
  ASSERT_EQ(t.gyro.size(), 4795u);
  for (size_t i = 0; i < t.gyro.size(); i += 97) {
    const GyroSample& s = t.gyro.samples()[i];
    EXPECT_EQ(s.t_ns, SecondsToNs(stored.TimeS(i))) << i;
    EXPECT_EQ(s.omega_rad_s.x(), stored.values[3 * i + 1]) << i;
    EXPECT_EQ(s.omega_rad_s.y(), stored.values[3 * i + 2]) << i;
    EXPECT_EQ(s.omega_rad_s.z(), stored.values[3 * i + 0]) << i;
  }

  ASSERT_EQ(t.shutter_s.size(), 361u);
  ASSERT_EQ(t.shutter_t_s.size(), 361u);
  EXPECT_NEAR(t.shutter_s.front(), 0.00487, 0.00001);
  for (size_t i = 1; i < t.shutter_t_s.size(); ++i)
    EXPECT_NEAR(t.shutter_t_s[i] - t.shutter_t_s[i - 1], 1 / 29.97, 1e-3) << i;
}

TEST(GoproTelemetry, KarmaVideoFrameTimesAreTheSampleTable) {
  SHUTTERLAB_REAL_DATA(karma, "rs/gopro_karma/karma.mp4");
  const std::vector<double> times_s = ReadVideoFrameTimesS(karma);
  ASSERT_EQ(times_s.size(), 362u);
  for (size_t i = 0; i < times_s.size(); ++i)
    EXPECT_DOUBLE_EQ(times_s[i], i * 3003 / 90000.0) << i;  // 3003 ticks of 1/90000 s a frame
}

}  // namespace
}  // namespace shutterlab
