// validate on a rig dataset that shutterlab's renderer did not make. The generator here follows
// docs/FORMATS.md only and shares no code with render/ or sim/: its own motion (analytic body
// rates, integrated with a 20 us midpoint rule), its own rolling-shutter image synthesis (cv::remap
// of a procedural ground texture through the rotation-only homography of each row), and choices our
// renderer never makes: 16-bit grey TIFF images in a subfolder, frame ids that are not 0..N-1,
// clock times near 1000 s, a jittered 1.6 kHz gyro log with an extra column, a gyro mounted with
// its axes swapped, a bottom-to-top readout, a declared non-zero time offset, and a minimal
// camera.json. The truth differs from camera.json by 3 ms of time offset; validate must find that,
// and nothing on the twin whose camera.json is right.

#include "estimate/loop/validate.h"
#include "io/codecs.h"
#include "io/image_io.h"
#include "sim/text_file.h"
#include "tests/estimate/loop/validate_fixtures.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// printf into a std::string.
template <typename... Args>
std::string Format(const char* format, Args... args) {
  std::vector<char> buffer(std::snprintf(nullptr, 0, format, args...) + 1);
  std::snprintf(buffer.data(), buffer.size(), format, args...);
  return buffer.data();
}

constexpr int kForeignWidth = 480, kForeignHeight = 360, kForeignFrames = 8;
constexpr double kForeignFocalPx = 420.0, kForeignReadoutS = 0.025;
constexpr double kDeclaredOffsetS = 0.010;  // camera.json's time_offset_s
constexpr double kGyroStartS = 1000.0, kGyroEndS = 1008.0;

// Camera-frame body rate, rad/s: slow swings plus a 7 Hz shake (what makes a clock offset visible).
Eigen::Vector3d CameraRate(double t_s) {
  const double t = t_s - kGyroStartS, two_pi = 2.0 * M_PI;
  return {0.3 * std::sin(two_pi * 1.3 * t + 0.2) + 0.3 * std::sin(two_pi * 7.0 * t),
          0.25 * std::sin(two_pi * 0.9 * t + 1.0) + 0.2 * std::sin(two_pi * 7.0 * t + 1.1),
          0.4 * std::sin(two_pi * 0.6 * t + 2.1)};
}

// Camera-to-world orientation R(t) (docs/FORMATS.md: R(t + dt) = R(t) Exp(w_C dt)), tabulated every
// 20 us from identity at kGyroStartS with the midpoint rate; between entries one more midpoint
// step.
class Orientation {
 public:
  Orientation() {
    const size_t n = static_cast<size_t>((kGyroEndS - kGyroStartS) / kStepS) + 2;
    table_.reserve(n);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    for (size_t i = 0; i < n; ++i) {
      table_.push_back(q);
      q = q * Step(kGyroStartS + (i + 0.5) * kStepS, kStepS);
      q.normalize();
    }
  }
  Eigen::Matrix3d At(double t_s) const {
    const size_t i = static_cast<size_t>((t_s - kGyroStartS) / kStepS);
    const double t_i = kGyroStartS + i * kStepS, dt = t_s - t_i;
    return (table_.at(i) * Step(t_i + 0.5 * dt, dt)).toRotationMatrix();
  }

 private:
  static Eigen::Quaterniond Step(double t_mid_s, double dt_s) {
    const Eigen::Vector3d angle = CameraRate(t_mid_s) * dt_s;
    if (angle.norm() == 0.0) return Eigen::Quaterniond::Identity();
    return Eigen::Quaterniond(Eigen::AngleAxisd(angle.norm(), angle.normalized()));
  }
  static constexpr double kStepS = 20e-6;
  std::vector<Eigen::Quaterniond> table_;
};

// gyro axes: gyro x along camera y, gyro y along camera -x (w_C = R_CG w_G).
Eigen::Matrix3d CamFromGyro() {
  Eigen::Matrix3d r;
  r << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  return r;
}

// Renders one image: every row v seen at its own orientation, through the scene convention of
// docs/FORMATS.md (scene pixel = K_scene * ray / ray.z, principal point at the scene's centre).
cv::Mat RenderGrey16(const cv::Mat& scene, const Orientation& orientation,
                     const std::vector<double>& row_time_s) {
  const Eigen::Matrix3d k = (Eigen::Matrix3d() << kForeignFocalPx, 0, 0.5 * (kForeignWidth - 1), 0,
                             kForeignFocalPx, 0.5 * (kForeignHeight - 1), 0, 0, 1)
                                .finished();
  const Eigen::Matrix3d k_scene = (Eigen::Matrix3d() << kForeignFocalPx, 0, 0.5 * (scene.cols - 1),
                                   0, kForeignFocalPx, 0.5 * (scene.rows - 1), 0, 0, 1)
                                      .finished();
  const Eigen::Matrix3d k_inv = k.inverse();
  cv::Mat map(kForeignHeight, kForeignWidth, CV_32FC2);
  for (int v = 0; v < kForeignHeight; ++v) {
    const Eigen::Matrix3d h = k_scene * orientation.At(row_time_s[v]) * k_inv;
    for (int u = 0; u < kForeignWidth; ++u) {
      const Eigen::Vector3d x = h * Eigen::Vector3d(u, v, 1.0);
      map.at<cv::Vec2f>(v, u) =
          cv::Vec2f(static_cast<float>(x.x() / x.z()), static_cast<float>(x.y() / x.z()));
    }
  }
  cv::Mat out;
  cv::remap(scene, out, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

// Writes the dataset into dir and returns it. true_offset_s: gyro clock - camera clock in truth.
std::string WriteForeignDataset(const test::TempDir& dir, double true_offset_s) {
  namespace fs = std::filesystem;
  const fs::path root = dir.path() / "foreign";
  fs::create_directories(root / "cam0");
  cv::Mat scene8 = ReadImage(test::GroundScenePath(2));
  if (scene8.channels() == 3) cv::cvtColor(scene8, scene8, cv::COLOR_RGB2GRAY);
  cv::Mat scene;
  scene8.convertTo(scene, CV_16U, 257.0);
  const Orientation orientation;

  WriteFileAtomically((root / "camera.json").string(),
                      Format(R"({
  "format": "rig/1",
  "image": {"width": %d, "height": %d},
  "intrinsics": {"fx": %.1f, "fy": %.1f, "cx": %.1f, "cy": %.1f},
  "rolling_shutter": {"readout_s": %.3f, "direction": "bottom_to_top"},
  "gyro_to_camera": [[0,-1,0],[1,0,0],[0,0,1]],
  "time_offset_s": %.3f,
  "scene": {"altitude_m": 80.0}
}
)",
                             kForeignWidth, kForeignHeight, kForeignFocalPx, kForeignFocalPx,
                             0.5 * (kForeignWidth - 1), 0.5 * (kForeignHeight - 1),
                             kForeignReadoutS, kDeclaredOffsetS));
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-20e-6, 20e-6);
  std::string gyro = "t,gx,gy,gz,temperature\n";
  for (double t = kGyroStartS; t < kGyroEndS - 0.01; t += 1.0 / 1600.0) {
    const double t_sample = t + jitter(random);
    const Eigen::Vector3d w_g = CamFromGyro().transpose() * CameraRate(t_sample);
    gyro += Format("%.7f,%.9f,%.9f,%.9f,31.5\n", t_sample, w_g.x(), w_g.y(), w_g.z());
  }
  WriteFileAtomically((root / "gyro.csv").string(), gyro);

  std::string frames = "frame,t_first_row,ref,image\n";
  for (int k = 0; k < kForeignFrames; ++k) {
    const int id = 10 * (k + 1);
    const double t_first_row = kGyroStartS - true_offset_s + 1.0 + 0.8 * k;  // camera clock
    // Bottom to top: row height-1 first. Gyro-clock time of every row.
    std::vector<double> row_time(kForeignHeight), ref_time(kForeignHeight);
    for (int v = 0; v < kForeignHeight; ++v) {
      row_time[v] = t_first_row + true_offset_s +
                    (kForeignHeight - 1 - v) * kForeignReadoutS / kForeignHeight;
    }
    for (int v = 0; v < kForeignHeight; ++v)
      ref_time[v] = row_time[0];  // the reference: row 0's time
    const std::string ref = Format("cam0/ref_%d.tif", id);
    const std::string image = Format("cam0/rs_%d.tif", id);
    // Written by OpenCV's own TIFF encoder, not shutterlab's writer.
    for (const auto& [name, times] : {std::pair{ref, &ref_time}, std::pair{image, &row_time}}) {
      const std::vector<uchar> tiff = EncodeImage(".tif", RenderGrey16(scene, orientation, *times));
      WriteFileAtomically((root / name).string(), std::string(tiff.begin(), tiff.end()));
    }
    frames += Format("%d,%.6f,%s,%s\n", id, t_first_row, ref.c_str(), image.c_str());
  }
  WriteFileAtomically((root / "frames.csv").string(), frames);
  return root.string();
}

TEST(ValidateForeignDataset, FindsTheUndeclaredThreeMilliseconds) {
  test::TempDir dir;
  const ValidationResult result =
      test::ValidateWithoutResiduals(WriteForeignDataset(dir, kDeclaredOffsetS + 0.003));
  const LoopResult& loop = result.loop;
  ASSERT_EQ(result.frames.size(), static_cast<size_t>(kForeignFrames));
  ASSERT_FALSE(loop.effects.empty()) << test::LoopSummary(result);
  EXPECT_EQ(Spec(loop.effects.front().effect).name, "time_offset") << test::LoopSummary(result);
  EXPECT_NEAR(loop.model.rig.time_offset_s, kDeclaredOffsetS + 0.003, 0.3e-3)
      << test::LoopSummary(result);
  EXPECT_FALSE(loop.unexplained) << test::LoopSummary(result);
  EXPECT_LE(loop.after.rms_px, 1.5 * loop.noise_px) << test::LoopSummary(result);
  EXPECT_GT(loop.before.rms_px, 2.0 * loop.after.rms_px) << test::LoopSummary(result);
}

TEST(ValidateForeignDataset, RightCameraJsonAddsNothing) {
  test::TempDir dir;
  const ValidationResult result =
      test::ValidateWithoutResiduals(WriteForeignDataset(dir, kDeclaredOffsetS));
  const LoopResult& loop = result.loop;
  EXPECT_TRUE(loop.effects.empty()) << test::LoopSummary(result);
  EXPECT_FALSE(loop.unexplained) << test::LoopSummary(result);
  EXPECT_LE(loop.before.rms_px, 1.5 * loop.noise_px) << test::LoopSummary(result);
  // The declared full model predicts each frame's measured D.
  for (const FrameValidation& f : result.frames) {
    EXPECT_GT(f.d_meas_px, 1.0) << "frame " << f.frame << ": the motion must distort";
    EXPECT_NEAR(f.d_full_px, f.d_meas_px, 0.05 * f.d_meas_px + 0.1) << "frame " << f.frame;
  }
}

}  // namespace
}  // namespace shutterlab
