#include "model/truth_model.h"

#include "model/effect_io.h"
#include "model/effects.h"
#include "sim/so3.h"
#include "tests/model/model_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

namespace shutterlab {
namespace {

using nlohmann::json;

// Rotations of a constant-rate trace: trapezoid integration of a constant is exact up to rounding.
constexpr double kRotationTolRad = 1e-12;

TrueModel BareModel() {
  TrueModel model;
  model.rig = test::SmallRig(64, 48);
  return model;
}

TEST(ApplyInjection, EveryEffectOfTheTableIsKnown) {
  const std::vector<std::pair<std::string, json>> cases = {
      {"time_offset=5ms", 0.005},
      {"readout_time=21ms", 0.021},
      {"gyro_to_camera=0,-1,0,1,0,0,0,0,1", json::parse("[[0,-1,0],[1,0,0],[0,0,1]]")},
      {"gyro_scale=[1.01,0.99,1.0]", json::parse("[1.01,0.99,1.0]")},
      {"gyro_bias=0.001rad/s,-0.002rad/s,0.003rad/s", json::parse("[0.001,-0.002,0.003]")},
      {"velocity=5m/s,0,0", json::parse("[5.0,0.0,0.0]")},
      {"lens_distortion=-0.1,0.02", json::parse(R"({"k1":-0.1,"k2":0.02})")},
      {"lens_distortion={\"k1\":-0.1}", json::parse(R"({"k1":-0.1,"k2":0.0})")},
      {"readout_direction=bottom_to_top", "bottom_to_top"},
      {"clock_rate=-35ppm", -35.0},
  };
  std::set<std::string> names;
  for (const auto& [text, recorded] : cases) {
    TrueModel model = BareModel();
    EXPECT_EQ(EffectValueToJson(ApplyInjection(text, &model).value), recorded) << text;
    names.insert(text.substr(0, text.find('=')));
  }
  EXPECT_EQ(names.size(), AllEffects().size());
}

TEST(ApplyInjection, ChangesOnlyItsOwnField) {
  TrueModel model = BareModel();
  ApplyInjection("time_offset=5ms", &model);
  EXPECT_EQ(model.rig.time_offset_s, 0.005);
  ApplyInjection("readout_direction=bottom_to_top", &model);
  EXPECT_EQ(model.rig.shutter.direction, ReadoutDirection::kBottomToTop);
  ApplyInjection("gyro_bias=0.001rad/s,-0.002rad/s,0.003rad/s", &model);
  EXPECT_EQ(model.gyro_bias_rad_s, Eigen::Vector3d(0.001, -0.002, 0.003));
  ApplyInjection("lens_distortion=-0.1,0.02", &model);
  EXPECT_TRUE(model.rig.camera.distortion == LensDistortion(BrownConrady{{-0.1, 0.02, 0, 0, 0}}));
  EXPECT_EQ(model.rig.time_offset_s, 0.005);
  EXPECT_EQ(model.rig.shutter.readout_s, BareModel().rig.shutter.readout_s);
  EXPECT_EQ(model.gyro_scale, Eigen::Vector3d::Ones());
}

TEST(ApplyInjection, RejectsBadNamesAndValues) {
  for (const char* bad :
       {"time_offset", "warp_speed=9", "time_offset=soon", "readout_time=-10ms", "gyro_scale=1,1",
        "gyro_scale=0,1,1", "gyro_to_camera=1,0,0,0,1,0,0,0,2", "gyro_to_camera=1,0,0,0,1,0,0,0,-1",
        "readout_direction=sideways", "lens_distortion={\"k9\":1}", "velocity=1m/s,2m/s,nan",
        "clock_rate=[1,2]"}) {
    TrueModel model = BareModel();
    EXPECT_THROW(ApplyInjection(bad, &model), std::invalid_argument) << bad;
  }
}

TEST(TrueModel, CamRateAppliesBiasThenScaleThenAxes) {
  TrueModel model = BareModel();
  model.gyro_bias_rad_s = Eigen::Vector3d(0.1, 0.2, 0.3);
  model.gyro_scale = Eigen::Vector3d(2, 3, 4);
  model.rig.cam_from_gyro << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  // true_G = s * (logged - b) = (2*0.9, 3*0.8, 4*0.7); then R_CG maps (x, y, z) -> (-y, x, z).
  const Eigen::Vector3d w = model.CamRate(Eigen::Vector3d(1, 1, 1));
  EXPECT_NEAR(w.x(), -2.4, 1e-15);
  EXPECT_NEAR(w.y(), 1.8, 1e-15);
  EXPECT_NEAR(w.z(), 2.8, 1e-15);
}

TEST(TrueModel, RowGyroTimeFollowsClockRateAndOffset) {
  TrueModel model = BareModel();  // 48 rows, 20 ms readout
  model.rig.time_offset_s = 0.003;
  model.clock_rate_ppm = 100;
  const int64_t t_first_ns = 10'000'000'000;  // 10 s
  // gyro = camera * (1 + 1e-4) + 0.003, camera = 10 s + 24 * 0.020 / 48.
  const double camera_s = 10.0 + 24 * 0.020 / 48;
  EXPECT_NEAR(model.RowGyroOffsetS(t_first_ns, 24), camera_s * (1 + 1e-4) + 0.003 - 10.0, 1e-15);
}

TEST(CameraMotion, FramesAreAnchoredAtRowZero) {
  // Constant rate w: world_from_cam(row v) = Exp(w (t_v - t_0)), identity at row 0, whatever the
  // frame's time in the flight.
  TrueModel model = BareModel();
  const Eigen::Vector3d w(0.3, -0.2, 0.5);
  const CameraMotion motion(test::ConstantRateTrace(w, 0.0, 3.0), model);
  for (double t_s : {0.1, 1.7, 2.5}) {
    const FrameMotion frame = motion.Frame(SecondsToNs(t_s));
    ASSERT_EQ(frame.world_from_cam.size(), 48u);
    test::ExpectRotationNear(Eigen::Quaterniond(frame.world_from_cam[0]),
                             Eigen::Quaterniond::Identity(), kRotationTolRad);
    const double dt_s = 47 * 0.020 / 48;
    test::ExpectRotationNear(Eigen::Quaterniond(frame.world_from_cam[47]), ExpSO3(w * dt_s),
                             kRotationTolRad);
    EXPECT_FALSE(frame.HasTranslation());
  }
}

TEST(CameraMotion, FrameAtRowsFillsTheRowsItIsGivenAsFrameDoes) {
  const CameraMotion motion(test::ConstantRateTrace(Eigen::Vector3d(0.4, -0.6, 0.9), 0.0, 3.0),
                            BareModel());
  std::vector<bool> rows(48, false);
  rows[17] = rows[18] = true;  // the first and last rows come always
  const FrameMotion all = motion.Frame(SecondsToNs(0.5));
  const FrameMotion some = motion.FrameAtRows(SecondsToNs(0.5), rows);
  for (int v = 0; v < 48; ++v) {
    if (rows[v] || v == 0 || v == 47) {
      EXPECT_EQ(some.world_from_cam[v], all.world_from_cam[v]) << v;
      EXPECT_EQ(some.cam_center_m[v], all.cam_center_m[v]) << v;
    } else {
      EXPECT_EQ(some.world_from_cam[v], Eigen::Matrix3d::Identity()) << v;
    }
  }
  EXPECT_FALSE(all.world_from_cam[17].isIdentity()) << "a row that turned";
  EXPECT_EQ(some.world_from_ref, all.world_from_ref);
  EXPECT_THROW(motion.FrameAtRows(SecondsToNs(0.5), std::vector<bool>(3, true)),
               std::invalid_argument);
  // A readout running past the trace's end throws though no row near the end is asked for.
  EXPECT_THROW(motion.FrameAtRows(SecondsToNs(2.99), rows), std::out_of_range);
}

// A model that differs in readout and offset only shares another's integrated rates and gets
// exactly the frames it would integrate itself; one whose mounting, gyro scale or bias differs is
// refused.
TEST(CameraMotion, AModelWithTheSameRatesSharesTheIntegratedTrace) {
  const GyroTrace gyro = test::ConstantRateTrace(Eigen::Vector3d(0.4, -0.6, 0.9), 0.0, 3.0);
  const CameraMotion motion(gyro, BareModel());
  TrueModel other = BareModel();
  other.rig.shutter.readout_s = 0.027;
  other.rig.time_offset_s = 0.004;
  const FrameMotion shared = CameraMotion(other, motion).Frame(SecondsToNs(0.5));
  const FrameMotion own = CameraMotion(gyro, other).Frame(SecondsToNs(0.5));
  for (int v = 0; v < 48; ++v) EXPECT_EQ(shared.world_from_cam[v], own.world_from_cam[v]) << v;
  EXPECT_EQ(shared.world_from_ref, own.world_from_ref);
  EXPECT_NE(shared.world_from_cam[47], motion.Frame(SecondsToNs(0.5)).world_from_cam[47])
      << "the other readout turns the last row by another angle";
  TrueModel scaled = BareModel();
  scaled.gyro_scale.z() = 1.01;
  EXPECT_THROW(CameraMotion(scaled, motion), std::invalid_argument);
  TrueModel biased = BareModel();
  biased.gyro_bias_rad_s.x() = 1e-4;
  EXPECT_THROW(CameraMotion(biased, motion), std::invalid_argument);
  TrueModel turned = BareModel();
  turned.rig.cam_from_gyro = ExpSO3(Eigen::Vector3d(0.0, 0.0, 0.01)).toRotationMatrix();
  EXPECT_THROW(CameraMotion(turned, motion), std::invalid_argument);
}

TEST(CameraMotion, BottomToTopAnchorsAtTheTopRowToo) {
  TrueModel model = BareModel();
  model.rig.shutter.direction = ReadoutDirection::kBottomToTop;
  const Eigen::Vector3d w(0.3, -0.2, 0.5);
  const CameraMotion motion(test::ConstantRateTrace(w, 0.0, 3.0), model);
  const FrameMotion frame = motion.Frame(SecondsToNs(1.0));
  // Row 0 is read LAST; the reference is its (true) time, so the bottom row, read first, is
  // 47 row intervals earlier.
  test::ExpectRotationNear(Eigen::Quaterniond(frame.world_from_cam[0]),
                           Eigen::Quaterniond::Identity(), kRotationTolRad);
  test::ExpectRotationNear(Eigen::Quaterniond(frame.world_from_cam[47]),
                           ExpSO3(-w * (47 * 0.020 / 48)), kRotationTolRad);
}

TEST(CameraMotion, FramesOutsideTheGyroTraceThrow) {
  const CameraMotion motion(test::ConstantRateTrace(Eigen::Vector3d::Zero(), 1.0, 1.0),
                            BareModel());
  EXPECT_THROW(motion.Frame(SecondsToNs(0.5)), std::out_of_range);
  EXPECT_THROW(motion.Frame(SecondsToNs(1.99)), std::out_of_range);  // readout runs past the end
  EXPECT_NO_THROW(motion.Frame(SecondsToNs(1.5)));
}

}  // namespace
}  // namespace shutterlab
