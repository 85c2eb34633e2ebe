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

// karma.mp4's HERO5 writes no global settings, no orientation keys and no CORI / IORI.
TEST(GoproTelemetry, KarmaStatesNoSettings) {
  SHUTTERLAB_REAL_DATA(karma, "rs/gopro_karma/karma.mp4");
  const GoproTelemetry t = ReadGoproTelemetry(karma);
  EXPECT_FALSE(t.settings.present);
  EXPECT_TRUE(t.settings.unreadable.empty());
  EXPECT_TRUE(t.gyro_orin.empty());
  EXPECT_TRUE(t.image_orientation.empty());
  // The gimbal holds the camera level: z up (the importer's inference).
  ASSERT_TRUE(t.accel_mean_mps2.has_value());
  EXPECT_NEAR(t.accel_mean_mps2->z(), 9.7, 0.2);
}

// max-heromode.mp4 (GoPro MAX, HERO mode; PROVENANCE.md lists what it holds): the global settings,
// the gyro on the camera's own axes by ORIN / ORIO / MTRX, CORI and IORI per frame.
TEST(GoproTelemetry, MaxStatesItsReadoutAxesAndStabiliser) {
  SHUTTERLAB_REAL_DATA(max, "incoming_rs/gopro_max_heromode/max-heromode.mp4");
  const GoproTelemetry t = ReadGoproTelemetry(max);
  const GoproSettings& s = t.settings;
  ASSERT_TRUE(s.present);
  EXPECT_EQ(s.model, "GoPro Max");
  EXPECT_EQ(s.firmware, "H19.03.01.30.00");
  ASSERT_TRUE(s.readout_s.has_value());
  EXPECT_NEAR(*s.readout_s, 0.0206008, 1e-6);
  EXPECT_NEAR(*s.diagonal_fov_deg, 137.388, 1e-3);
  EXPECT_EQ(s.fov, "W");
  EXPECT_TRUE(s.StabilizerOn());
  EXPECT_EQ(s.stabilizer_mode, "HS HLevel");
  EXPECT_EQ(s.projection, "GPRO");
  EXPECT_EQ(t.gyro_orin, "XzY");
  EXPECT_EQ(t.gyro_orio, "ZXY");
  EXPECT_EQ(t.gyro_mtrx, (std::vector<double>{0, -1, 0, 1, 0, 0, 0, 0, 1}));
  EXPECT_EQ(t.axis_order_source, "ORIN 'XzY', ORIO 'ZXY', MTRX agrees");
  EXPECT_EQ(t.gyro.size(), 2082u);
  // Hand-held upright: gravity's reaction on the camera's Z (GoPro's "up").
  ASSERT_TRUE(t.accel_mean_mps2.has_value());
  EXPECT_NEAR(t.accel_mean_mps2->z(), 9.7, 0.2);
  EXPECT_LT(std::abs(t.accel_mean_mps2->x()), 1.0);
  // Sample by sample: X = stored 0, Y = stored 2, Z = -stored 1.
  Mp4File mp4(max);
  const GpmfTrackStream stored = ReadGpmfTrackStream(mp4, *mp4.FindTrack("meta", "gpmd"), "GYRO");
  for (size_t i = 0; i < t.gyro.size(); i += 101) {
    const Eigen::Vector3d& w = t.gyro.samples()[i].omega_rad_s;
    EXPECT_EQ(w.x(), stored.values[3 * i]);
    EXPECT_EQ(w.y(), stored.values[3 * i + 2]);
    EXPECT_EQ(w.z(), -stored.values[3 * i + 1]);
  }
  // One CORI and one IORI per frame; IORI's largest turn is 19.4 degrees (PROVENANCE.md).
  ASSERT_EQ(t.image_orientation.t_s.size(), 316u);
  ASSERT_EQ(t.camera_orientation.t_s.size(), 316u);
  double largest_deg = 0.0;
  for (const auto& q : t.image_orientation.wxyz) {
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    EXPECT_NEAR(norm, 1.0, 1e-3);
    largest_deg = std::max(largest_deg, 2 * std::acos(std::min(1.0, std::abs(q[0]) / norm)));
  }
  EXPECT_NEAR(largest_deg * 180 / M_PI, 19.4, 0.1);
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
