#include "model/lens_distortion.h"

#include "model/camera.h"
#include "sim/units.h"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include <cmath>
#include <random>
#include <vector>

namespace shutterlab {
namespace {

// Our pixel and OpenCV's are the same double arithmetic in a different order: ~1e-12 px.
constexpr double kTwinTolPx = 1e-9;
// Undistortion: both solve theta to ~1e-15 rad; times f (~1000 px) and the slope of tan at the
// edge of a 137 degree lens.
constexpr double kUndistortTol = 1e-9;
// Our own round trip (Newton to 1e-15 rad, times f).
constexpr double kLensRoundTripTolPx = 1e-9;

// The GoPro MAX's Gyroflow profile (Wide, HS EIS, 1920x1080; ../shared/data/incoming_rs/
// gopro_max_heromode/reference): a 137 degree diagonal field of view.
PinholeCamera MaxCamera() {
  PinholeCamera camera;
  camera.width = 1920;
  camera.height = 1080;
  camera.fx = 834.7142002058372;
  camera.fy = 834.242691007013;
  camera.cx = 961.0868688356376;
  camera.cy = 537.8612238194443;
  camera.distortion = Fisheye(
      {0.0646075465207674, 0.039139647556618896, -0.041373671856156674, 0.014898789517094136});
  return camera;
}

// A 150 degree (horizontal) equidistant-like lens on a 4:3 sensor: its corners are 94 degrees off
// the axis, behind the image plane.
PinholeCamera WideCamera() {
  PinholeCamera camera;
  camera.width = 800;
  camera.height = 600;
  camera.cx = 399.5;
  camera.cy = 299.5;
  const Fisheye lens({0.01, -0.002, 0.0, 0.0});
  camera.fx = camera.fy = camera.cx / lens.ThetaD(75.0 * kRadPerDeg);
  camera.distortion = lens;
  return camera;
}

cv::Matx33d CvK(const PinholeCamera& camera) {
  return cv::Matx33d(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
}

cv::Vec4d CvD(const PinholeCamera& camera) {
  const std::array<double, 4>& k = std::get<Fisheye>(camera.distortion).coeffs();
  return cv::Vec4d(k[0], k[1], k[2], k[3]);
}

TEST(Fisheye, DistortsAsOpenCvsFisheyeModule) {
  for (PinholeCamera camera : {MaxCamera(), WideCamera()}) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> theta(0.0, 85.0 * kRadPerDeg), phi(-kPi, kPi);
    std::vector<cv::Point2d> undistorted;
    std::vector<Eigen::Vector3d> rays;
    for (int i = 0; i < 500; ++i) {
      const double t = i == 0 ? 0.0 : theta(rng), p = phi(rng);
      rays.emplace_back(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      undistorted.emplace_back(rays.back().x() / rays.back().z(),
                               rays.back().y() / rays.back().z());
    }
    std::vector<cv::Point2d> expected;
    cv::fisheye::distortPoints(undistorted, expected, CvK(camera), CvD(camera));
    for (size_t i = 0; i < rays.size(); ++i) {
      // The same ray at another length has the same pixel.
      const std::optional<Eigen::Vector2d> px = camera.ImgFromCam(3.7 * rays[i]);
      ASSERT_TRUE(px.has_value());
      ASSERT_NEAR(px->x(), expected[i].x, kTwinTolPx) << i;
      ASSERT_NEAR(px->y(), expected[i].y, kTwinTolPx) << i;
    }
  }
}

TEST(Fisheye, UndistortsAsOpenCvsFisheyeModule) {
  const PinholeCamera camera = MaxCamera();
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0.0, camera.width - 1.0), v(0.0, camera.height - 1.0);
  std::vector<cv::Point2d> distorted = {
      {0.0, 0.0}, {camera.width - 1.0, camera.height - 1.0}, {camera.cx, camera.cy}};
  for (int i = 0; i < 500; ++i) distorted.emplace_back(u(rng), v(rng));
  std::vector<cv::Point2d> expected;
  cv::fisheye::undistortPoints(
      distorted, expected, CvK(camera), CvD(camera), cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, 100, 1e-14));
  for (size_t i = 0; i < distorted.size(); ++i) {
    const Eigen::Vector3d ray = camera.CamFromImg(Eigen::Vector2d(distorted[i].x, distorted[i].y));
    ASSERT_DOUBLE_EQ(ray.z(), 1.0);
    ASSERT_NEAR(ray.x(), expected[i].x, kUndistortTol) << i;
    ASSERT_NEAR(ray.y(), expected[i].y, kUndistortTol) << i;
  }
}

TEST(Fisheye, A150DegreeLensRoundTripsToItsCornersWithoutWrapping) {
  const PinholeCamera camera = WideCamera();
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, camera.width - 1.0), v(0.0, camera.height - 1.0);
  std::vector<Eigen::Vector2d> pixels = {{0, 0},
                                         {camera.width - 1.0, 0},
                                         {0, camera.height - 1.0},
                                         {camera.width - 1.0, camera.height - 1.0},
                                         {camera.cx, camera.cy},
                                         {0, camera.cy},
                                         {camera.width - 1.0, camera.cy}};
  for (int i = 0; i < 1000; ++i) pixels.emplace_back(u(rng), v(rng));
  for (const Eigen::Vector2d& px : pixels) {
    const Eigen::Vector3d ray = camera.CamFromImg(px);
    ASSERT_TRUE(ray.allFinite()) << px.transpose();
    // The ray leans the pixel's way: a corner beyond 90 degrees points backwards, not across.
    const Eigen::Vector2d from_centre(px.x() - camera.cx, px.y() - camera.cy);
    EXPECT_GE(ray.head<2>().dot(from_centre), 0.0) << px.transpose();
    const std::optional<Eigen::Vector2d> back = camera.ImgFromCam(ray);
    ASSERT_TRUE(back.has_value()) << px.transpose();
    ASSERT_NEAR((*back - px).norm(), 0.0, kLensRoundTripTolPx) << px.transpose();
  }
  // The corners lie 94 degrees off the axis: behind the image plane.
  const Eigen::Vector3d corner = camera.CamFromImg(Eigen::Vector2d(0, 0));
  EXPECT_LT(corner.z(), 0.0);
  EXPECT_NEAR(std::atan2(corner.head<2>().norm(), corner.z()) * kDegPerRad, 93.75, 0.5);
  // The edge at mid-height is the 75 degree half-field the camera was built for.
  const Eigen::Vector3d edge = camera.CamFromImg(Eigen::Vector2d(0, camera.cy));
  EXPECT_NEAR(std::atan2(-edge.x(), edge.z()) * kDegPerRad, 75.0, 1e-9);
}

TEST(Fisheye, ZeroCoefficientsAreTheEquidistantProjection) {
  PinholeCamera camera = WideCamera();
  camera.distortion = Fisheye();
  EXPECT_TRUE(camera.HasDistortion()) << "equidistant is not a pinhole";
  for (double theta_deg : {0.0, 1e-9, 10.0, 45.0, 89.0, 90.0, 120.0, 179.0}) {
    const double theta = theta_deg * kRadPerDeg;
    const std::optional<Eigen::Vector2d> px =
        camera.ImgFromCam(Eigen::Vector3d(std::sin(theta), 0, std::cos(theta)));
    ASSERT_TRUE(px.has_value()) << theta_deg;
    EXPECT_NEAR(px->x() - camera.cx, camera.fx * theta, 1e-9) << theta_deg;
    EXPECT_NEAR(px->y() - camera.cy, 0.0, 1e-12) << theta_deg;
  }
  EXPECT_FALSE(camera.ImgFromCam(Eigen::Vector3d(0, 0, -1)).has_value()) << "straight back";
}

TEST(Fisheye, BeyondWhereThePolynomialTurnsThereIsNothing) {
  // theta_d = theta (1 - 0.3 theta^2) turns at theta^2 = 1 / 0.9.
  const Fisheye lens({-0.3, 0.0, 0.0, 0.0});
  const double fold = std::sqrt(1.0 / 0.9);
  EXPECT_NEAR(lens.max_theta_rad(), fold, 1e-12);
  EXPECT_TRUE(lens.DistortedFromRay(Eigen::Vector3d(std::tan(fold - 0.01), 0, 1)).has_value());
  EXPECT_FALSE(lens.DistortedFromRay(Eigen::Vector3d(std::tan(fold + 0.01), 0, 1)).has_value());
  const double edge = lens.ThetaD(fold);
  EXPECT_TRUE(lens.RayFromDistorted(Eigen::Vector2d(0.999 * edge, 0)).allFinite());
  EXPECT_FALSE(lens.RayFromDistorted(Eigen::Vector2d(1.001 * edge, 0)).allFinite());
  // Just inside the fold the solve still finds the angle (the slope there is nearly 0).
  const Eigen::Vector3d ray = lens.RayFromDistorted(Eigen::Vector2d(0, 0.999999 * edge));
  EXPECT_NEAR(lens.ThetaD(std::atan2(ray.y(), ray.z())), 0.999999 * edge, 1e-12);
  // A camera whose corners lie beyond the fold is not monotonic over its image.
  PinholeCamera camera = WideCamera();
  camera.distortion = lens;
  EXPECT_FALSE(camera.DistortionMonotonicOverImage());
  EXPECT_TRUE(MaxCamera().DistortionMonotonicOverImage());
}

TEST(LensDistortion, TheModelsAreToldApartByTheirType) {
  EXPECT_STREQ(LensModelName(BrownConrady{}), "brown");
  EXPECT_STREQ(LensModelName(Fisheye()), "fisheye");
  EXPECT_FALSE(HasDistortion(BrownConrady{}));
  EXPECT_TRUE(HasDistortion(BrownConrady{{0, 0, 0, 1e-9, 0}}));
  EXPECT_FALSE(LensDistortion(BrownConrady{}) == LensDistortion(Fisheye()));
  // Binary fractions: the sums are exact.
  LensDistortion lens = Fisheye({0.5, 0.25, 0.3, 0.4});
  AddToK1K2(0.125, -0.0625, &lens);
  EXPECT_TRUE(lens == LensDistortion(Fisheye({0.625, 0.1875, 0.3, 0.4})));
  lens = BrownConrady{{0.5, 0.25, 0.3, 0.4, 0.5}};
  AddToK1K2(0.125, -0.0625, &lens);
  EXPECT_TRUE(lens == LensDistortion(BrownConrady{{0.625, 0.1875, 0.3, 0.4, 0.5}}));
  EXPECT_FALSE(DistortionFinite(Fisheye({0, std::nan(""), 0, 0})));
}

}  // namespace
}  // namespace shutterlab
