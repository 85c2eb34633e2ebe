// ReadPhotoInput on hand-written photos (metadata only: nothing here decodes pixels): the photos'
// own camera, the photos a correction would get wrong skipped with the reason, and what cannot be
// known said.

#include "estimate/correct/photo_input.h"

#include "io/photo_set.h"
#include "sim/check.h"
#include "sim/gyro_trace.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/io/photo_fixtures.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace shutterlab {
namespace {

bool AnyContains(const std::vector<std::string>& lines, const std::string& text) {
  return std::any_of(lines.begin(), lines.end(),
                     [&](const std::string& line) { return line.find(text) != std::string::npos; });
}

TEST(ReadPhotoInput, TheirOwnCameraAndWhatCannotBeCorrected) {
  // Four 640x480 photos at 24 mm (35 mm equivalent), one of them zoomed to 48 mm, one 320x240,
  // and one that no trigger names; the first from a gimbal (DJI XMP).
  test::TempDir dir;
  const std::string photos = dir / "photos";
  std::filesystem::create_directories(photos);
  const auto write = [&](const std::string& name, int width, uint16_t focal_35mm,
                         const std::string& xmp = "") {
    test::FixturePhoto p;
    p.width = width;
    p.height = width * 3 / 4;
    p.focal_length_35mm = focal_35mm;
    p.xmp = xmp;
    WriteFileAtomically(photos + "/" + name, test::JpegWithMetadata(p));
  };
  write("A.JPG", 640, 24,
        test::DjiXmp({{"GimbalPitchDegree", "-90.0"},
                      {"GimbalYawDegree", "10.0"},
                      {"GimbalRollDegree", "0.0"},
                      {"AbsoluteAltitude", "142.0"}},
                     false));
  write("B.JPG", 640, 24);
  write("C.JPG", 640, 48);
  write("D.JPG", 320, 24);
  write("E.JPG", 640, 24);
  // A still gyro with a bias of 1e-3 rad/s about x.
  WriteGyroCsv(dir / "log.csv", test::ConstantRateTrace(Eigen::Vector3d(1e-3, 0, 0), 0.0, 10.0));
  WriteFileAtomically(dir / "triggers.csv", "image,t\nA.JPG,2\nB.JPG,3\nC.JPG,4\nD.JPG,5\n");
  PhotoInputOptions options;
  options.log_path = dir / "log.csv";
  options.triggers_path = dir / "triggers.csv";
  options.readout_s = 0.02;
  options.trigger_latency_s = -0.001;
  const PhotoInput input = ReadPhotoInput(photos, options);

  const RigModel& rig = input.dataset.declared;
  EXPECT_EQ(rig.camera.width, 640);
  EXPECT_NEAR(rig.camera.fx, FocalPxFrom35mm(24, 640, 480), 1e-9);
  EXPECT_EQ(rig.shutter.readout_s, 0.02);
  EXPECT_FALSE(input.dataset.video);
  ASSERT_EQ(input.dataset.frames.size(), 2u);
  EXPECT_EQ(input.dataset.frames[0].image, "A.JPG");
  EXPECT_EQ(input.dataset.frames[0].frame, 0);
  EXPECT_EQ(input.dataset.frames[0].t_first_row_ns, SecondsToNs(1.999)) << "event + latency";
  EXPECT_EQ(input.dataset.frames[1].image, "B.JPG");
  ASSERT_EQ(input.skipped.size(), 3u);
  EXPECT_EQ(input.skipped[0].first, 2);
  EXPECT_NE(input.skipped[0].second.find("C.JPG: focal length"), std::string::npos)
      << input.skipped[0].second;
  EXPECT_NE(input.skipped[1].second.find("D.JPG: is 320x240, the camera 640x480"),
            std::string::npos)
      << input.skipped[1].second;
  EXPECT_NE(input.skipped[2].second.find("E.JPG: not placed on the log"), std::string::npos)
      << input.skipped[2].second;
  EXPECT_TRUE(AnyContains(input.notes, "mounting unknown")) << "no --camera";
  EXPECT_TRUE(AnyContains(input.notes, "1 of 5 photos were taken from a gimbal: a stabilised"));
  ASSERT_TRUE(input.still_bias_rad_s) << input.still_bias_source;
  EXPECT_NEAR((*input.still_bias_rad_s - Eigen::Vector3d(1e-3, 0, 0)).norm(), 0.0, 1e-12);

  // camera.json declares the gyro's mounting on the camera: no warning that the gyro is the
  // airframe's, but the gimbal still said.
  PhotoInputOptions declared = options;
  declared.camera = rig;
  declared.camera_path = "camera.json";
  const PhotoInput on_camera = ReadPhotoInput(photos, declared);
  EXPECT_FALSE(AnyContains(on_camera.notes, "a stabilised camera")) << "camera.json given";
  EXPECT_TRUE(AnyContains(on_camera.notes,
                          "1 of 5 photos were taken from a gimbal: camera.json "
                          "declares the gyro's mounting on the camera"));

  // A given focal length is every photo's: the zoomed one is corrected with it too.
  options.focal_px = 500.0;
  const PhotoInput given = ReadPhotoInput(photos, options);
  EXPECT_EQ(given.dataset.declared.camera.fx, 500.0);
  EXPECT_EQ(given.dataset.frames.size(), 3u);
  // A's absolute altitude, with no height above take-off, gives no ground plane; with the
  // ground's elevation it does (the photos' median: A's alone).
  EXPECT_NE(given.altitude_source.find("assumed 50 m"), std::string::npos) << given.altitude_source;
  options.ground_elevation_m = 100.0;
  const PhotoInput derived = ReadPhotoInput(photos, options);
  EXPECT_DOUBLE_EQ(derived.dataset.declared.altitude_m, 42.0) << derived.altitude_source;
  options.ground_elevation_m.reset();
  // No photo placed: one line naming the folder.
  options.triggers_path.clear();
  EXPECT_THROW(ReadPhotoInput(photos, options), IoError) << "the log has no camera events";
}

// A photo's velocity: its own recorded speed, else the log's, else the one differentiated from
// the photos' GPS positions; each turned into the camera's axes by the same gimbal.
TEST(VelocityOfPhoto, ThePhotosSpeedThenTheLogsThenThePositions) {
  PhotoRecord recorded;
  recorded.metadata.gimbal = AttitudeDeg{0.0, -90.0, 30.0};
  recorded.metadata.speed_m_s = Eigen::Vector3d(0.0, 5.0, 0.0);  // east
  recorded.metadata.flight_state_source = "XMP drone-dji";
  PhotoRecord from_positions;
  from_positions.metadata.gimbal = recorded.metadata.gimbal;
  from_positions.ground_speed_m_s = 5.0;
  from_positions.course_deg = 90.0;
  from_positions.speed_source = "the GPS positions of A.JPG and C.JPG: 20.0 m in 4.00 s";
  from_positions.speed_from_positions = true;
  FlightLog no_navigation;
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const PhotoVelocity own = VelocityOfPhoto(recorded, no_navigation, 0, identity, "");
  const PhotoVelocity derived = VelocityOfPhoto(from_positions, no_navigation, 0, identity, "");
  ASSERT_TRUE(own.velocity_mps && derived.velocity_mps) << derived.source;
  EXPECT_NEAR((*derived.velocity_mps - *own.velocity_mps).norm(), 0.0, 1e-12);
  EXPECT_NEAR(own.velocity_mps->norm(), 5.0, 1e-12);
  EXPECT_EQ(derived.source,
            "5.00 m/s toward 90 deg from the GPS positions of A.JPG and C.JPG: 20.0 m in 4.00 s, "
            "turned by the photo's gimbal's yaw 30.0 deg and pitch -90.0 deg");
  // A log's velocity at the photo's time is better than positions a few seconds apart.
  FlightLog navigation;
  navigation.velocity = {{0, Eigen::Vector3d(5.0, 0.0, 0.0)},
                         {SecondsToNs(0.5), Eigen::Vector3d(5.0, 0.0, 0.0)}};
  navigation.velocity_source = "vehicle_local_position.vx,vy,vz";
  const PhotoVelocity logged =
      VelocityOfPhoto(from_positions, navigation, SecondsToNs(0.25), identity, "");
  EXPECT_NE(logged.source.find("toward 0 deg from the log's"), std::string::npos) << logged.source;
  // Nothing: said.
  PhotoRecord nothing;
  nothing.metadata.gimbal = recorded.metadata.gimbal;
  EXPECT_FALSE(VelocityOfPhoto(nothing, no_navigation, 0, identity, "").velocity_mps);
}

}  // namespace
}  // namespace shutterlab
