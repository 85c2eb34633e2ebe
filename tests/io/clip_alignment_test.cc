#include "io/clip_alignment.h"

#include "io/image_io.h"
#include "sim/check.h"
#include "sim/so3.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

constexpr double kF = 500.0;

RigModel GlobalShutterCamera() {
  RigModel rig;
  rig.camera.width = 640;
  rig.camera.height = 480;
  rig.camera.fx = rig.camera.fy = kF;
  rig.camera.cx = 319.5;
  rig.camera.cy = 239.5;
  rig.shutter.readout_s = 0.0;  // every row at once: a pure-rotation homography is exact
  return rig;
}

// Blurred noise: corners everywhere, seen through any rotation of a few degrees.
cv::Mat Texture(int width, int height) {
  cv::Mat noise(height, width, CV_8U);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::Mat texture;
  cv::GaussianBlur(noise, texture, cv::Size(0, 0), 2.0);
  cv::normalize(texture, texture, 0, 255, cv::NORM_MINMAX);
  return texture;
}

// Known answer: frames of a camera turning at known rates, each the first frame seen through the
// camera's rotation since then (x_k = R_k^T x_0, pixels by H = K R_k^T K^-1), give those rates.
TEST(ClipRotationRates, AGlobalShutterCameraTurningAtKnownRatesGivesThem) {
  test::TempDir dir;
  const RigModel rig = GlobalShutterCamera();
  const Eigen::Matrix3d k = rig.camera.K();
  // A wide texture seen by a camera 4x as wide: the frames never run off its edge.
  const cv::Mat world = Texture(4 * 640, 4 * 480);
  Eigen::Matrix3d k_world = k;
  k_world(0, 2) += 1.5 * 640;
  k_world(1, 2) += 1.5 * 480;
  const std::vector<Eigen::Vector3d> rates = {
      {0.3, -0.2, 0.5}, {-0.4, 0.1, 0.0}, {0.0, 0.6, -0.3}, {0.2, 0.2, 0.2}};
  const double dt_s = 1.0 / 30;
  std::vector<FrameEntry> frames;
  Eigen::Quaterniond world_from_cam = Eigen::Quaterniond::Identity();
  for (size_t i = 0; i <= rates.size(); ++i) {
    // The camera's pixel p sees world pixel K_w R K^-1 p.
    const Eigen::Matrix3d h = k_world * world_from_cam.toRotationMatrix() * k.inverse();
    cv::Mat h_cv(3, 3, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) h_cv.at<double>(r, c) = h(r, c);
    cv::Mat frame;
    cv::warpPerspective(world, frame, h_cv, cv::Size(640, 480),
                        cv::INTER_CUBIC | cv::WARP_INVERSE_MAP);
    FrameEntry entry;
    entry.frame = static_cast<int64_t>(i);
    entry.t_first_row_ns = SecondsToNs(10.0 + i * dt_s);
    entry.image = "f" + std::to_string(i) + ".png";
    WriteImage(dir / entry.image, frame);
    frames.push_back(entry);
    if (i < rates.size()) world_from_cam = world_from_cam * ExpSO3(rates[i] * dt_s);
  }
  const ClipRotation found = ClipRotationRates(frames, dir.path().string(), rig, cv::Mat());
  EXPECT_EQ(found.pairs, rates.size());
  ASSERT_EQ(found.rates.size(), rates.size());
  EXPECT_GE(found.median_inliers, 200u);
  for (size_t i = 0; i < rates.size(); ++i) {
    // Timed at the pair's middle (no readout).
    EXPECT_NEAR(found.rates[i].t_ns * 1e-9, 10.0 + (i + 0.5) * dt_s, 1e-9);
    // 0.005 rad/s is 0.08 px over a frame interval at f = 500 px: the tracker's precision.
    EXPECT_LT((found.rates[i].omega_rad_s - rates[i]).norm(), 0.005)
        << i << ": " << found.rates[i].omega_rad_s.transpose();
  }
}

TEST(ClipRotationRates, AMaskedOutFrameGivesNoRate) {
  test::TempDir dir;
  const RigModel rig = GlobalShutterCamera();
  const cv::Mat image = Texture(640, 480);
  std::vector<FrameEntry> frames;
  for (int i = 0; i < 3; ++i) {
    frames.push_back({i, SecondsToNs(i / 30.0), "", "f" + std::to_string(i) + ".png"});
    WriteImage(dir / frames.back().image, image);
  }
  const cv::Mat none = cv::Mat::zeros(480, 640, CV_8U);
  const ClipRotation found = ClipRotationRates(frames, dir.path().string(), rig, none);
  EXPECT_EQ(found.pairs, 2u);
  EXPECT_EQ(found.rates.size(), 0u);  // nothing may be tracked
  const ClipRotation still = ClipRotationRates(frames, dir.path().string(), rig, cv::Mat());
  ASSERT_EQ(still.rates.size(), 2u);
  EXPECT_LT(still.rates[0].omega_rad_s.norm(), 1e-3);
}

// A rich motion about every axis that never repeats: rates (rad/s) on the body's axes at time
// t_s in [0, 300), linear between random knots 0.1 s apart.
Eigen::Vector3d BodyRate(double t_s) {
  static const std::vector<Eigen::Vector3d> knots = [] {
    std::mt19937 rng(11);
    std::normal_distribution<double> rate(0.0, 0.5);
    std::vector<Eigen::Vector3d> out(3001);
    for (Eigen::Vector3d& k : out) k = Eigen::Vector3d(rate(rng), rate(rng), rate(rng));
    return out;
  }();
  const double x = t_s / 0.1;
  const size_t i = static_cast<size_t>(x);
  return knots[i] + (x - i) * (knots[i + 1] - knots[i]);
}

// sensor_from_body w_body, sampled every interval_s over [from_s, to_s) of body time, stamped on
// a clock that reads body time + clock_s, with white noise.
GyroTrace Sensor(const Eigen::Matrix3d& sensor_from_body, double from_s, double to_s,
                 double interval_s, double clock_s, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::vector<GyroSample> out;
  for (double t = from_s; t < to_s; t += interval_s) {
    const Eigen::Vector3d w = sensor_from_body * BodyRate(t);
    out.push_back(
        {SecondsToNs(t + clock_s), w + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))});
  }
  return GyroTrace(std::move(out));
}

// A clip with a gyro of its own (200 Hz, its own axes and clock) and a flight controller's log
// (1 kHz, other axes, a clock 83.2 s ahead, longer than the clip): the log goes onto the camera's
// axes and the frames' clock. Over 10 seeds of the sensors' noise the offset lies within 2
// standard errors in at least 8 (9.5 expected) and within 4 in all.
TEST(AlignGyroLog, ByTheClipsOwnGyroFindsTheOffsetAndTheMounting) {
  const Eigen::Matrix3d cam_from_body = ExpSO3(Eigen::Vector3d(0.3, -1.2, 0.4)).toRotationMatrix();
  const Eigen::Matrix3d clip_gyro_from_body =
      ExpSO3(Eigen::Vector3d(2.0, 0.1, -0.5)).toRotationMatrix();
  const Eigen::Matrix3d log_from_body = ExpSO3(Eigen::Vector3d(-0.2, 0.9, 1.1)).toRotationMatrix();
  const Eigen::Matrix3d truth = cam_from_body * log_from_body.transpose();
  std::vector<FrameEntry> frames;
  for (int i = 0; i < 600; ++i) frames.push_back({i, SecondsToNs(101.0 + i / 30.0), "", ""});
  int within_two = 0;
  for (uint32_t seed = 1; seed <= 10; ++seed) {
    // The frames' clock reads body time; the clip's gyro clock 0.012 s ahead of it (declared).
    RigModel rig = GlobalShutterCamera();
    rig.cam_from_gyro = cam_from_body * clip_gyro_from_body.transpose();
    rig.time_offset_s = 0.012;
    const GyroTrace clip_gyro = Sensor(clip_gyro_from_body, 100.0, 130.0, 0.005, 0.012, seed);
    FlightLog log;
    log.format = "gyro.csv";
    log.gyro = Sensor(log_from_body, 60.0, 200.0, 0.001, 83.2, 100 + seed);
    ImportRecord record;
    record.claims.push_back({"time_offset_s", 0.0, ClaimStatus::kGuess, "shared timeline"});
    const GyroTrace written =
        AlignGyroLog(log, "fc.csv", frames, "", cv::Mat(), &clip_gyro, &rig, &record);
    ASSERT_TRUE(record.gyro_log.has_value());
    const double stderr_s = record.gyro_log->sync.offset_stderr_s;
    EXPECT_LT(stderr_s, 2e-5) << seed;  // 20 us over 30 s at 200 Hz
    EXPECT_NEAR(rig.time_offset_s, 83.2, 4 * stderr_s) << seed;
    within_two += std::abs(rig.time_offset_s - 83.2) <= 2 * stderr_s;
    EXPECT_LT(Eigen::AngleAxisd(rig.cam_from_gyro * truth.transpose()).angle(), 0.002) << seed;
    if (seed > 1) continue;
    // gyro.csv: the log over the frames and a second each side, on the log's clock.
    EXPECT_NEAR(written.t_begin_ns() * 1e-9, 101.0 + 83.2 - kLogMarginS, 0.002);
    EXPECT_NEAR(written.t_end_ns() * 1e-9, 101.0 + 599 / 30.0 + 83.2 + kLogMarginS, 0.002);
    EXPECT_EQ(record.gyro_samples, written.size());
    // The guess is replaced, said how.
    ASSERT_EQ(record.claims.size(), 2u);
    EXPECT_EQ(record.claims[0].what, "time_offset_s");
    EXPECT_EQ(record.claims[0].status, ClaimStatus::kInferred);
    EXPECT_NE(record.claims[0].source.find("the clip's own gyro"), std::string::npos);
    EXPECT_EQ(record.claims[1].what, "gyro_to_camera");
  }
  EXPECT_GE(within_two, 8);
}

// Another flight's log (the same kind of motion at other times) is refused in one line naming it.
TEST(AlignGyroLog, AnotherFlightsLogIsRefusedNamingIt) {
  RigModel rig = GlobalShutterCamera();
  const GyroTrace clip_gyro = Sensor(Eigen::Matrix3d::Identity(), 100.0, 120.0, 0.005, 0.0, 1);
  FlightLog log;
  log.format = "gyro.csv";
  // A still log, its noise alone: nothing to correlate.
  log.gyro = Sensor(Eigen::Matrix3d::Zero(), 0.0, 60.0, 0.001, 0.0, 3);
  std::vector<FrameEntry> frames;
  for (int i = 0; i < 300; ++i) frames.push_back({i, SecondsToNs(101.0 + i / 30.0), "", ""});
  ImportRecord record;
  try {
    AlignGyroLog(log, "other.bbl", frames, "", cv::Mat(), &clip_gyro, &rig, &record);
    FAIL() << "aligned a still log";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("other.bbl: cannot put the log on the clip", 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_FALSE(record.gyro_log.has_value());
}

}  // namespace
}  // namespace shutterlab
