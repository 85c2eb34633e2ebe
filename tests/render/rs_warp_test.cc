#include "render/rs_warp.h"

#include "io/image_io.h"
#include "model/effect_io.h"
#include "model/effects.h"
#include "model/truth_model.h"
#include "sim/units.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::ConstantRateTrace;
using test::SmallRig;
using test::SmoothTexture;

// Known-answer tolerance on the double-precision truth: only rounding (1e-10 px) separates the
// library from the closed form; 1e-6 px is the brief's bar.
constexpr double kTruthTolPx = 1e-6;
// The EXR field is float32: ~1e-6 relative on displacements of tens of pixels.
constexpr double kFloatFieldTolPx = 1e-4;
// No motion at all: K^-1 then K leaves only double rounding.
constexpr double kRoundingTolPx = 1e-12;

FrameGeometry Geometry(const TrueModel& model, const GyroTrace& logged, double t_first_row_s,
                       cv::Size scene) {
  const CameraMotion motion(logged, model);
  return FrameGeometry(model.rig.camera, model.rig.altitude_m,
                       motion.Frame(SecondsToNs(t_first_row_s)), scene);
}

TrueModel Truth(const RigModel& rig) {
  TrueModel model;
  model.rig = rig;
  return model;
}

TEST(RsWarp, IdentityMotionIsSceneCrop) {
  const RigModel rig = SmallRig(96, 72);  // principal point (47.5, 35.5)
  const cv::Size scene_size(160, 120);    // centre (79.5, 59.5): the view is the crop at (32, 24)
  const GyroTrace still = ConstantRateTrace(Eigen::Vector3d::Zero());
  const FrameGeometry geometry = Geometry(Truth(rig), still, 0.5, scene_size);
  const FrameGeometry reference(rig.camera, rig.altitude_m, geometry.motion().Reference(),
                                scene_size);
  ASSERT_TRUE(geometry.RotationOnly());
  for (int type : {CV_8UC3, CV_16UC1, CV_32FC1, CV_8UC4}) {
    const cv::Mat scene = SmoothTexture(scene_size, type);
    const cv::Mat crop = scene(cv::Rect(32, 24, 96, 72));
    for (Interpolation interpolation : {Interpolation::kBilinear, Interpolation::kBicubic}) {
      cv::Mat rs, ref;
      RenderFrame(scene, geometry, interpolation, &rs);
      RenderFrame(scene, reference, interpolation, &ref);
      ASSERT_EQ(rs.type(), type);
      EXPECT_EQ(cv::norm(rs, crop, cv::NORM_INF), 0.0) << "type " << type;
      EXPECT_EQ(cv::norm(ref, crop, cv::NORM_INF), 0.0) << "type " << type;
    }
  }
  const cv::Mat field = DisplacementField(geometry);
  EXPECT_LE(cv::norm(field, cv::NORM_INF), kRoundingTolPx);
  EXPECT_LE(FrameDistortionPx(field), kRoundingTolPx);
}

TEST(RsWarp, ConstantRateAboutXDisplacesPrincipalPointByFyTan) {
  RigModel rig = SmallRig(96, 73);  // odd height: the principal point (47.5, 36) lies on a row
  const double omega_rad_s = 0.8;
  const GyroTrace trace = ConstantRateTrace(Eigen::Vector3d(omega_rad_s, 0, 0));
  for (double readout_s : {0.010, 0.030}) {
    rig.shutter.readout_s = readout_s;
    const FrameGeometry geometry = Geometry(Truth(rig), trace, 0.7, cv::Size(300, 300));
    const int row = 36;
    const double dt_s = row * readout_s / rig.camera.height;
    // p_ref ~ K Rx(w dt) (0, 0, 1) = K (0, -sin, cos): the centre moves up by fy tan(w dt).
    const Eigen::Vector2d ref = *geometry.RefPixel(rig.camera.cx, row);
    EXPECT_NEAR(ref.x() - rig.camera.cx, 0.0, kTruthTolPx);
    EXPECT_NEAR(ref.y() - row, -rig.camera.fy * std::tan(omega_rad_s * dt_s), kTruthTolPx);
    const cv::Mat field = DisplacementField(geometry);
    // Column 47 neighbours the centre; its row-36 value is the closed form at u = 47 (x shift ~ 0).
    EXPECT_NEAR(field.at<cv::Vec2f>(row, 47)[1], -rig.camera.fy * std::tan(omega_rad_s * dt_s),
                1e-2);
    // Row 0 is the reference time: no displacement at all.
    EXPECT_LE(cv::norm(field.row(0), cv::NORM_INF), kRoundingTolPx);
  }
}

// ---- An independent evaluation of docs/FORMATS.md's model, written from the text, for a constant
// logged rate (so that R(t) has a closed form), using OpenCV's own distortion code.
struct OracleParams {
  Eigen::Matrix3d cam_from_gyro = Eigen::Matrix3d::Identity();
  Eigen::Vector3d scale = Eigen::Vector3d::Ones(), bias = Eigen::Vector3d::Zero();
  double time_offset_s = 0.0, readout_s = 0.0, ppm = 0.0;
  bool bottom_to_top = false;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  std::array<double, 5> dist{};
  bool fisheye = false;  // dist[0..3] are cv::fisheye's k1..k4
  // A fisheye pixel's ray from docs/FORMATS.md's polynomial inverted by bisection (theta in
  // [0, 90) degrees, where it increases) instead of cv::fisheye::undistortPoints, which stops
  // converging near 80 degrees off the axis (below).
  bool bisect = false;
};

// theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), docs/FORMATS.md.
double ThetaDistorted(const std::array<double, 5>& k, double theta) {
  const double t2 = theta * theta;
  return theta * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}

// The normalised point (x/z, y/z) of a fisheye pixel, by bisection on theta.
cv::Point2d BisectedUndistort(const PinholeCamera& cam, const std::array<double, 5>& k, double u,
                              double v) {
  const double mx = (u - cam.cx) / cam.fx, my = (v - cam.cy) / cam.fy;
  const double theta_d = std::hypot(mx, my);
  if (theta_d == 0) return {0, 0};
  double lo = 0, hi = 0.5 * M_PI - 1e-9;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ThetaDistorted(k, mid) < theta_d ? lo : hi) = mid;
  }
  const double scale = std::tan(0.5 * (lo + hi)) / theta_d;
  return {mx * scale, my * scale};
}

Eigen::Vector2d OracleRefPixel(const RigModel& declared, const OracleParams& o,
                               const Eigen::Vector3d& logged_w, double t_first_row_s, double u,
                               int v) {
  const PinholeCamera& cam = declared.camera;
  const int h = cam.height;
  auto read_index = [&](int row) { return o.bottom_to_top ? h - 1 - row : row; };
  auto gyro_time = [&](int row) {
    const double t_cam = t_first_row_s + read_index(row) * o.readout_s / h;
    return t_cam * (1 + o.ppm * 1e-6) + o.time_offset_s;
  };
  const Eigen::Vector3d w_cam = o.cam_from_gyro * (o.scale.cwiseProduct(logged_w - o.bias));
  const double angle = w_cam.norm() * (gyro_time(v) - gyro_time(0));
  const Eigen::Matrix3d r_v = w_cam.norm() > 0
                                  ? Eigen::AngleAxisd(angle, w_cam.normalized()).toRotationMatrix()
                                  : Eigen::Matrix3d::Identity();
  const Eigen::Vector3d c_v = o.velocity * (gyro_time(v) - gyro_time(0));
  const cv::Matx33d k(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  const std::vector<double> dist(o.dist.begin(), o.dist.end());
  const cv::Vec4d fisheye_d(o.dist[0], o.dist[1], o.dist[2], o.dist[3]);
  std::vector<cv::Point2d> in = {{u, static_cast<double>(v)}}, undistorted;
  if (o.fisheye && o.bisect) {
    undistorted = {BisectedUndistort(cam, o.dist, u, v)};
  } else if (o.fisheye) {
    cv::fisheye::undistortPoints(
        in, undistorted, k, fisheye_d, cv::noArray(), cv::noArray(),
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-14));
  } else {
    cv::undistortPoints(
        in, undistorted, k, dist, cv::noArray(), cv::noArray(),
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-16));
  }
  const Eigen::Vector3d ray = r_v * Eigen::Vector3d(undistorted[0].x, undistorted[0].y, 1.0);
  const double s = (declared.altitude_m - c_v.z()) / ray.z();
  const Eigen::Vector3d x = c_v + s * ray;  // ground point; the reference pose is identity at c = 0
  std::vector<cv::Point3d> points = {{x.x(), x.y(), x.z()}};
  std::vector<cv::Point2d> projected;
  if (o.fisheye) {
    cv::fisheye::projectPoints(points, projected, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k,
                               fisheye_d);
  } else {
    cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, dist, projected);
  }
  return Eigen::Vector2d(projected[0].x, projected[0].y);
}

// One injected truth per case, compared with the oracle at 200 points (half of them whole pixels,
// where the float field is checked too): RefPixel to kTruthTolPx.
struct OracleCase {
  std::vector<std::string> injections;
  std::function<void(OracleParams*)> apply;
};

void ExpectTruthMatchesOracle(const RigModel& declared, const OracleParams& base,
                              const Eigen::Vector3d& logged_w, const std::vector<OracleCase>& cases,
                              uint64_t seed) {
  const GyroTrace trace = ConstantRateTrace(logged_w);
  const double t_first_row_s = 0.5;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> random_u(0.0, declared.camera.width - 1.0);
  std::uniform_int_distribution<int> random_v(0, declared.camera.height - 1);
  for (const OracleCase& c : cases) {
    TrueModel truth = Truth(declared);
    std::string name;
    for (const std::string& injection : c.injections) {
      ApplyInjection(injection, &truth);
      name += injection + " ";
    }
    OracleParams oracle = base;
    c.apply(&oracle);
    const FrameGeometry geometry = Geometry(truth, trace, t_first_row_s, cv::Size(400, 400));
    const cv::Mat field = DisplacementField(geometry);
    double largest_px = 0.0;
    for (int i = 0; i < 200; ++i) {
      const double u = i < 100 ? random_u(rng) : std::floor(random_u(rng));
      const int v = random_v(rng);
      const Eigen::Vector2d expected =
          OracleRefPixel(declared, oracle, logged_w, t_first_row_s, u, v);
      const Eigen::Vector2d got = *geometry.RefPixel(u, v);
      ASSERT_NEAR(got.x(), expected.x(), kTruthTolPx) << name << " at (" << u << ", " << v << ")";
      ASSERT_NEAR(got.y(), expected.y(), kTruthTolPx) << name << " at (" << u << ", " << v << ")";
      largest_px = std::max(largest_px, (expected - Eigen::Vector2d(u, v)).norm());
      if (u == std::floor(u)) {
        const cv::Vec2f d = field.at<cv::Vec2f>(v, static_cast<int>(u));
        EXPECT_NEAR(d[0], expected.x() - u, kFloatFieldTolPx) << name;
        EXPECT_NEAR(d[1], expected.y() - v, kFloatFieldTolPx) << name;
      }
    }
    EXPECT_GT(largest_px, 0.05) << name << ": the case must move pixels to test anything";
  }
}

TEST(RsWarp, TruthMatchesIndependentModelForEveryEffect) {
  RigModel declared = SmallRig(96, 72);
  declared.time_offset_s = 0.001;
  const Eigen::Vector3d logged_w(0.3, -0.5, 0.7);
  OracleParams base;
  base.time_offset_s = declared.time_offset_s;
  base.readout_s = declared.shutter.readout_s;
  const std::vector<OracleCase> cases = {
      {{}, [](OracleParams*) {}},
      {{"time_offset=4.2ms"}, [](OracleParams* o) { o->time_offset_s = 0.0042; }},
      {{"readout_time=33ms"}, [](OracleParams* o) { o->readout_s = 0.033; }},
      {{"gyro_to_camera=[[0,-1,0],[1,0,0],[0,0,1]]"},
       [](OracleParams* o) { o->cam_from_gyro << 0, -1, 0, 1, 0, 0, 0, 0, 1; }},
      {{"gyro_scale=1.02,0.97,1.01"},
       [](OracleParams* o) { o->scale = Eigen::Vector3d(1.02, 0.97, 1.01); }},
      {{"gyro_bias=0.01rad/s,-0.02rad/s,0.005rad/s"},
       [](OracleParams* o) { o->bias = Eigen::Vector3d(0.01, -0.02, 0.005); }},
      {{"velocity=3m/s,-2m/s,0.5m/s"},
       [](OracleParams* o) { o->velocity = Eigen::Vector3d(3, -2, 0.5); }},
      {{"lens_distortion={\"k1\":-0.3,\"k2\":0.1}"},
       [](OracleParams* o) {
         o->dist = {-0.3, 0.1, 0, 0, 0};
       }},
      {{"readout_direction=bottom_to_top"}, [](OracleParams* o) { o->bottom_to_top = true; }},
      {{"clock_rate=200ppm"}, [](OracleParams* o) { o->ppm = 200; }},
      {{"gyro_scale=1.02,0.97,1.01", "gyro_bias=0.01rad/s,-0.02rad/s,0.005rad/s",
        "velocity=3m/s,-2m/s,0.5m/s", "clock_rate=-150ppm",
        "lens_distortion=-0.2,0.05,0.001,-0.002,0.01", "readout_direction=bottom_to_top",
        "time_offset=-3ms"},
       [](OracleParams* o) {
         o->scale = Eigen::Vector3d(1.02, 0.97, 1.01);
         o->bias = Eigen::Vector3d(0.01, -0.02, 0.005);
         o->velocity = Eigen::Vector3d(3, -2, 0.5);
         o->ppm = -150;
         o->dist = {-0.2, 0.05, 0.001, -0.002, 0.01};
         o->bottom_to_top = true;
         o->time_offset_s = -0.003;
       }},
  };
  ExpectTruthMatchesOracle(declared, base, logged_w, cases, 42);
}

// The same independent evaluation for a fisheye camera (cv::fisheye's undistortPoints and
// projectPoints): 120 degrees across the frame's width, its lens effect injected in its own model.
TEST(RsWarp, FisheyeTruthMatchesIndependentModel) {
  RigModel declared = SmallRig(96, 72);
  declared.camera.fx = declared.camera.fy = 47.5 / (60.0 * kRadPerDeg);  // 60 degrees to the edge
  declared.camera.distortion = Fisheye({0.02, -0.01, 0.002, 0.0});
  const Eigen::Vector3d logged_w(0.3, -0.5, 0.7);
  OracleParams base;
  base.readout_s = declared.shutter.readout_s;
  base.fisheye = true;
  base.dist = {0.02, -0.01, 0.002, 0.0, 0.0};
  const std::vector<OracleCase> cases = {
      {{}, [](OracleParams*) {}},
      {{"lens_distortion=0.06,0.04,-0.04,0.015"},
       [](OracleParams* o) {
         o->dist = {0.06, 0.04, -0.04, 0.015, 0.0};
       }},
      {{"velocity=3m/s,-2m/s,0.5m/s", "readout_time=30ms", "gyro_scale=1.02,0.97,1.01"},
       [](OracleParams* o) {
         o->velocity = Eigen::Vector3d(3, -2, 0.5);
         o->readout_s = 0.03;
         o->scale = Eigen::Vector3d(1.02, 0.97, 1.01);
       }},
  };
  // A fisheye is never a homography: the per-pixel path.
  ASSERT_FALSE(Geometry(Truth(declared), ConstantRateTrace(logged_w), 0.5, cv::Size(400, 400))
                   .RotationOnly());
  ExpectTruthMatchesOracle(declared, base, logged_w, cases, 43);
}

// Wide lenses to their edge (issue 44): the fisheye truth against cv::fisheye's undistortPoints
// and projectPoints at 100, 140 and 180 degrees across the diagonal (the GoPro MAX's
// coefficients), at every pixel of a 96 x 72 frame whose ray is less than 89 degrees off the axis
// (cv::fisheye's normalised coordinates end at 90) and meets the ground inside the scene; rotation,
// translation and a 30 ms readout together. The pixel's ray is the polynomial's inverse by
// bisection (OracleParams::bisect), the projection cv::fisheye::projectPoints. At 180 degrees the
// corners look at the horizon: no truth there, and none is made up.
TEST(RsWarp, FisheyeTruthMatchesOpenCvToTheEdgeOfWideLenses) {
  const std::array<double, 4> max_lens = {0.0646075465207674, 0.039139647556618896,
                                          -0.041373671856156674, 0.014898789517094136};
  const Eigen::Vector3d logged_w(0.3, -0.5, 0.7);
  for (const double diagonal_deg : {100.0, 140.0, 180.0}) {
    RigModel declared = SmallRig(96, 72);
    const Fisheye lens(max_lens);
    const double corner_px = std::hypot(declared.camera.cx, declared.camera.cy);
    declared.camera.fx = declared.camera.fy =
        corner_px / lens.ThetaD(0.5 * diagonal_deg * kRadPerDeg);
    declared.camera.distortion = lens;
    declared.shutter.readout_s = 0.030;
    TrueModel truth = Truth(declared);
    truth.rig.velocity_mps = Eigen::Vector3d(3, -2, 0.5);
    OracleParams oracle;
    oracle.readout_s = 0.030;
    oracle.fisheye = oracle.bisect = true;
    oracle.velocity = truth.rig.velocity_mps;
    std::copy(max_lens.begin(), max_lens.end(), oracle.dist.begin());
    const GyroTrace trace = ConstantRateTrace(logged_w);
    const FrameGeometry geometry = Geometry(truth, trace, 0.5, cv::Size(4000, 4000));
    int compared = 0, no_truth = 0;
    double largest_theta_deg = 0.0;
    for (int v = 0; v < declared.camera.height; ++v) {
      for (int u = 0; u < declared.camera.width; ++u) {
        const Eigen::Vector3d ray = declared.camera.CamFromImg(Eigen::Vector2d(u, v));
        const double theta_deg = std::atan2(ray.head<2>().norm(), ray.z()) / kRadPerDeg;
        const std::optional<Eigen::Vector2d> got = geometry.RefPixel(u, v);
        if (!got) {
          ++no_truth;
          // Only where the ray looks near or above the horizon (the scene is 4000 px wide).
          EXPECT_GT(theta_deg, 60.0) << diagonal_deg << " deg at (" << u << ", " << v << ")";
          continue;
        }
        if (theta_deg >= 89.0) continue;
        const Eigen::Vector2d expected = OracleRefPixel(declared, oracle, logged_w, 0.5, u, v);
        ASSERT_NEAR(got->x(), expected.x(), 1e-6)
            << diagonal_deg << " deg at (" << u << ", " << v << "), " << theta_deg << " deg";
        ASSERT_NEAR(got->y(), expected.y(), 1e-6)
            << diagonal_deg << " deg at (" << u << ", " << v << "), " << theta_deg << " deg";
        largest_theta_deg = std::max(largest_theta_deg, theta_deg);
        ++compared;
      }
    }
    std::printf(
        "%.0f deg diagonal: %d pixels compared (to %.1f deg off the axis), %d without truth\n",
        diagonal_deg, compared, largest_theta_deg, no_truth);
    EXPECT_GT(compared, 96 * 72 * 3 / 4) << diagonal_deg;
    EXPECT_GT(largest_theta_deg, std::min(0.5 * diagonal_deg, 89.0) - 5.0) << diagonal_deg;
  }
  // Where cv::fisheye::undistortPoints itself parts ways with the polynomial (what a second
  // implementation built on it would get wrong): the first angle, in 0.1 degree steps, at which
  // its point is more than 1e-3 px (at f = 1000 px) from the bisection's.
  const PinholeCamera unit_camera{2001, 2001, 1000.0, 1000.0, 1000.0, 1000.0, Fisheye(max_lens)};
  std::array<double, 5> k{};
  std::copy(max_lens.begin(), max_lens.end(), k.begin());
  double parts_deg = 90.0;
  for (double theta_deg = 0.1; theta_deg < 90.0; theta_deg += 0.1) {
    const double r_px = 1000.0 * ThetaDistorted(k, theta_deg * kRadPerDeg);
    std::vector<cv::Point2d> in = {{1000.0 + r_px, 1000.0}}, out;
    cv::fisheye::undistortPoints(
        in, out, cv::Matx33d(1000, 0, 1000, 0, 1000, 1000, 0, 0, 1),
        cv::Vec4d(k[0], k[1], k[2], k[3]), cv::noArray(), cv::noArray(),
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-14));
    const cv::Point2d exact = BisectedUndistort(unit_camera, k, in[0].x, in[0].y);
    const double angle_error_rad = std::abs(std::atan(out[0].x) - std::atan(exact.x));
    if (!(angle_error_rad * 1000.0 < 1e-3)) {
      parts_deg = theta_deg;
      break;
    }
  }
  std::printf("cv::fisheye::undistortPoints parts from the polynomial at %.1f deg\n", parts_deg);
  // 77.5 degrees on OpenCV 4.6 (Debian 12): beyond a 140-degree lens's corners, short of 90.
  EXPECT_GT(parts_deg, 70.0);
  EXPECT_LT(parts_deg, 89.0);
}

// A 150 degree fisheye (4:3, its corners 94 degrees off the axis) looking straight down: the
// corners look above the horizon and see nothing (black, no truth); they must not wrap round to
// the ground on the other side of the image.
TEST(RsWarp, AWideFisheyeDoesNotWrapRaysBehindTheCamera) {
  RigModel rig = SmallRig(80, 61);  // odd height: the centre (39.5, 30) lies on a row
  const Fisheye lens;               // equidistant
  rig.camera.fx = rig.camera.fy = rig.camera.cx / (75.0 * kRadPerDeg);
  rig.camera.distortion = lens;
  const cv::Size scene_size(400, 400);
  const FrameGeometry geometry =
      Geometry(Truth(rig), ConstantRateTrace(Eigen::Vector3d::Zero()), 0.5, scene_size);
  for (const Eigen::Vector2d& corner : {Eigen::Vector2d(0, 0), Eigen::Vector2d(79, 0),
                                        Eigen::Vector2d(0, 60), Eigen::Vector2d(79, 60)}) {
    EXPECT_FALSE(geometry.ScenePixel(corner.x(), static_cast<int>(corner.y())).has_value())
        << corner.transpose();
    EXPECT_FALSE(geometry.RefPixel(corner.x(), static_cast<int>(corner.y())).has_value());
  }
  // The edge at mid-height, 75 degrees off nadir, sees the ground on its own side, tan(75) * f
  // from the centre of the scene.
  const std::optional<Eigen::Vector2d> edge = geometry.ScenePixel(0, 30);
  ASSERT_TRUE(edge.has_value());
  const double centre_x = (scene_size.width - 1) / 2.0;
  EXPECT_NEAR(edge->x() - centre_x, -rig.camera.fx * std::tan(75.0 * kRadPerDeg), 1e-6);
  cv::Mat rendered;
  RenderFrame(SmoothTexture(scene_size, CV_8UC1) + 1, geometry, Interpolation::kBilinear,
              &rendered);
  EXPECT_EQ(rendered.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(rendered.at<uint8_t>(60, 79), 0);
  EXPECT_GT(rendered.at<uint8_t>(30, 40), 0);
}

TEST(RsWarp, BottomToTopMirrorsTheTiming) {
  // With a constant rate, row v of a bottom_to_top frame is captured v*r/H BEFORE row 0: exactly a
  // top_to_bottom frame turning the other way.
  RigModel rig = SmallRig(64, 48);
  const Eigen::Vector3d omega(0.4, -0.9, 0.3);
  const FrameGeometry forward =
      Geometry(Truth(rig), ConstantRateTrace(-omega), 0.6, cv::Size(300, 300));
  rig.shutter.direction = ReadoutDirection::kBottomToTop;
  const FrameGeometry mirrored =
      Geometry(Truth(rig), ConstantRateTrace(omega), 0.6, cv::Size(300, 300));
  double largest_px = 0.0;
  for (int v = 0; v < rig.camera.height; v += 3) {
    for (int u = 0; u < rig.camera.width; u += 5) {
      const Eigen::Vector2d a = *forward.RefPixel(u, v), b = *mirrored.RefPixel(u, v);
      EXPECT_NEAR((a - b).norm(), 0.0, kTruthTolPx) << u << "," << v;
      largest_px = std::max(largest_px, (a - Eigen::Vector2d(u, v)).norm());
    }
  }
  EXPECT_GT(largest_px, 1.0);
}

TEST(RsWarp, ReadoutTimeScalesTheDisplacement) {
  // Twice the readout at one rate is the same rotation per row as one readout at twice the rate.
  RigModel rig = SmallRig(64, 48);
  const Eigen::Vector3d omega(0.4, -0.9, 0.3);
  rig.shutter.readout_s = 0.040;
  const FrameGeometry slow_readout =
      Geometry(Truth(rig), ConstantRateTrace(omega), 0.6, cv::Size(300, 300));
  rig.shutter.readout_s = 0.020;
  const FrameGeometry fast_turn =
      Geometry(Truth(rig), ConstantRateTrace(2 * omega), 0.6, cv::Size(300, 300));
  for (int v = 0; v < rig.camera.height; v += 3) {
    for (int u = 0; u < rig.camera.width; u += 5) {
      EXPECT_NEAR((*slow_readout.RefPixel(u, v) - *fast_turn.RefPixel(u, v)).norm(), 0.0,
                  kTruthTolPx);
    }
  }
  // And the displacement itself grows with the readout (first order: proportionally).
  const double d_slow = FrameDistortionPx(DisplacementField(slow_readout));
  rig.shutter.readout_s = 0.020;
  const double d_fast = FrameDistortionPx(
      DisplacementField(Geometry(Truth(rig), ConstantRateTrace(omega), 0.6, cv::Size(300, 300))));
  EXPECT_NEAR(d_slow / d_fast, 2.0, 0.02);
}

TEST(RsWarp, VelocityAtAltitudeShiftsByVtFOverH) {
  RigModel rig = SmallRig(64, 48);
  rig.velocity_mps = Eigen::Vector3d(6.0, -4.0, 0.0);
  const FrameGeometry geometry =
      Geometry(Truth(rig), ConstantRateTrace(Eigen::Vector3d::Zero()), 0.6, cv::Size(300, 300));
  ASSERT_FALSE(geometry.RotationOnly());
  const cv::Mat field = DisplacementField(geometry);
  for (int v = 0; v < rig.camera.height; ++v) {
    const double t_s = v * rig.shutter.readout_s / rig.camera.height;
    for (int u = 0; u < rig.camera.width; u += 7) {
      const Eigen::Vector2d d = *geometry.RefPixel(u, v) - Eigen::Vector2d(u, v);
      EXPECT_NEAR(d.x(), rig.velocity_mps.x() * t_s * rig.camera.fx / rig.altitude_m, kTruthTolPx);
      EXPECT_NEAR(d.y(), rig.velocity_mps.y() * t_s * rig.camera.fy / rig.altitude_m, kTruthTolPx);
      EXPECT_NEAR(field.at<cv::Vec2f>(v, u)[0], d.x(), kFloatFieldTolPx);
    }
  }
}

TEST(RsWarp, HomographyRowsMatchThePerPixelModel) {
  const RigModel rig = SmallRig(200, 150);
  const FrameGeometry geometry = Geometry(
      Truth(rig), ConstantRateTrace(Eigen::Vector3d(1.5, -2.0, 3.0)), 0.6, cv::Size(2000, 1500));
  ASSERT_TRUE(geometry.RotationOnly());
  std::vector<float> xs(rig.camera.width), ys(rig.camera.width);
  // float evaluation of the homography on a 2000 px scene: ~1e-4 px rounding.
  constexpr double kFloatRowTolPx = 2e-3;
  for (int v = 0; v < rig.camera.height; v += 7) {
    geometry.SceneRow(v, xs.data(), ys.data());
    for (int u = 0; u < rig.camera.width; ++u) {
      const Eigen::Vector2d s = *geometry.ScenePixel(u, v);
      ASSERT_NEAR(xs[u], s.x(), kFloatRowTolPx);
      ASSERT_NEAR(ys[u], s.y(), kFloatRowTolPx);
    }
  }
}

// A frame seen through one fixed rotation: every row the same homography, as warpPerspective does.
FrameGeometry FixedRotation(const RigModel& rig, const Eigen::Matrix3d& world_from_cam,
                            cv::Size scene) {
  FrameMotion motion;
  motion.world_from_cam.assign(rig.camera.height, world_from_cam);
  motion.cam_center_m.assign(rig.camera.height, Eigen::Vector3d::Zero());
  return FrameGeometry(rig.camera, rig.altitude_m, motion, scene);
}

TEST(RsWarp, SamplingAgreesWithOpenCvWarpPerspective) {
  const RigModel rig = SmallRig(120, 90);
  const cv::Size scene_size(240, 200);
  const FrameGeometry geometry = FixedRotation(
      rig, Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix(),
      scene_size);
  const cv::Mat scene = SmoothTexture(scene_size, CV_8UC3, 11, 1.0);
  const Eigen::Matrix3d h = geometry.SceneFromImageHomography(0);
  cv::Matx33d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = h(r, c);
  }
  // OpenCV quantises coordinates to 1/32 px, we to 1/256 px: a level or two apart on 8-bit data.
  const std::vector<std::pair<Interpolation, int>> kinds = {
      {Interpolation::kBilinear, cv::INTER_LINEAR}, {Interpolation::kBicubic, cv::INTER_CUBIC}};
  for (const auto& [ours, theirs] : kinds) {
    cv::Mat rendered, expected;
    RenderFrame(scene, geometry, ours, &rendered);
    cv::warpPerspective(scene, expected, m, rendered.size(), theirs | cv::WARP_INVERSE_MAP,
                        cv::BORDER_CONSTANT);
    cv::Mat diff;
    cv::absdiff(rendered, expected, diff);
    double max_level = 0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &max_level);
    EXPECT_LE(max_level, 3.0);
    EXPECT_LT(cv::mean(diff)[0], 0.5);
  }
}

TEST(RsWarp, RgbKernelMatchesThePerChannelScalarPath) {
  // 8-bit RGB bilinear has its own SIMD kernel; rendering each channel as a grey image takes the
  // plain scalar path. Same fixed-point weights: bit-identical, at the borders too (the scene is
  // smaller than the view, so edges, corners and the row's last pixel are all exercised).
  const RigModel rig = SmallRig(131, 97);
  const cv::Size scene_size(120, 90);
  const FrameGeometry geometry =
      Geometry(Truth(rig), ConstantRateTrace(Eigen::Vector3d(0.9, -1.3, 2.0)), 0.5, scene_size);
  ASSERT_TRUE(geometry.RotationOnly());
  const cv::Mat scene = SmoothTexture(scene_size, CV_8UC3, 21, 0.7) + cv::Scalar::all(1);
  cv::Mat rgb;
  RenderFrame(scene, geometry, Interpolation::kBilinear, &rgb);
  std::vector<cv::Mat> scene_channels, rgb_channels;
  cv::split(scene, scene_channels);
  cv::split(rgb, rgb_channels);
  size_t black = 0;
  for (int c = 0; c < 3; ++c) {
    cv::Mat grey;
    RenderFrame(scene_channels[c], geometry, Interpolation::kBilinear, &grey);
    EXPECT_EQ(cv::norm(grey, rgb_channels[c], cv::NORM_INF), 0.0) << "channel " << c;
    black += grey.total() - cv::countNonZero(grey);
  }
  EXPECT_GT(black, 0u) << "part of the view must fall outside the scene";
}

TEST(RsWarp, HomographyPathRendersLikeThePerPixelPath) {
  // A wide frame (several 512-column chunks) rendered twice: rotation only (row homographies, fixed
  // point from the start) and with a negligible velocity (1 nm/s: the exact per-pixel path).
  RigModel rig = SmallRig(1100, 24);
  rig.camera.fx = rig.camera.fy = 900.0;
  const cv::Size scene_size(1600, 400);
  const GyroTrace trace = ConstantRateTrace(Eigen::Vector3d(0.5, -0.7, 1.1));
  const FrameGeometry fast = Geometry(Truth(rig), trace, 0.5, scene_size);
  rig.velocity_mps = Eigen::Vector3d(1e-9, 0, 0);
  const FrameGeometry exact = Geometry(Truth(rig), trace, 0.5, scene_size);
  ASSERT_TRUE(fast.RotationOnly());
  ASSERT_FALSE(exact.RotationOnly());
  const cv::Mat scene = SmoothTexture(scene_size, CV_8UC3, 4, 1.0);
  cv::Mat a, b, diff;
  RenderFrame(scene, fast, Interpolation::kBilinear, &a);
  RenderFrame(scene, exact, Interpolation::kBilinear, &b);
  cv::absdiff(a, b, diff);
  double max_level = 0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &max_level);
  // The two float evaluations may round to neighbouring 1/128 px steps: one level at most.
  EXPECT_LE(max_level, 1.0);
  EXPECT_LT(cv::mean(diff)[0], 0.05);
}

TEST(RsWarp, BorderOutsideTheSceneIsBlack) {
  // A 40x30 scene behind a 96x72 frame with no motion: exactly the scene, surrounded by zeros.
  const RigModel rig = SmallRig(96, 72);
  const cv::Size scene_size(40,
                            30);  // centre (19.5, 14.5): frame pixel (u, v) sees (u - 28, v - 21)
  const FrameGeometry geometry =
      Geometry(Truth(rig), ConstantRateTrace(Eigen::Vector3d::Zero()), 0.5, scene_size);
  const cv::Mat scene = SmoothTexture(scene_size, CV_8UC1) + 1;  // no zero inside the scene
  for (Interpolation interpolation : {Interpolation::kBilinear, Interpolation::kBicubic}) {
    cv::Mat rs;
    RenderFrame(scene, geometry, interpolation, &rs);
    cv::Mat expected = cv::Mat::zeros(72, 96, CV_8UC1);
    scene.copyTo(expected(cv::Rect(28, 21, 40, 30)));
    EXPECT_EQ(cv::norm(rs, expected, cv::NORM_INF), 0.0);
  }
}

TEST(RsWarp, RenderedPairIsConsistentWithTheTruthField) {
  // RS(p) and REF(p + d(p)) see the same ground point: with a smooth float scene they agree to the
  // interpolation error of the bilinear kernel.
  RigModel rig = SmallRig(160, 120);
  rig.velocity_mps = Eigen::Vector3d(2.0, 1.0, 0.0);
  const cv::Size scene_size(400, 320);
  const FrameGeometry geometry =
      Geometry(Truth(rig), ConstantRateTrace(Eigen::Vector3d(0.6, -0.8, 1.2)), 0.5, scene_size);
  const FrameGeometry reference(rig.camera, rig.altitude_m, geometry.motion().Reference(),
                                scene_size);
  const cv::Mat scene = SmoothTexture(scene_size, CV_32FC1, 3, 4.0);
  cv::Mat rs, ref;
  RenderFrame(scene, geometry, Interpolation::kBilinear, &rs);
  RenderFrame(scene, reference, Interpolation::kBilinear, &ref);
  const cv::Mat field = DisplacementField(geometry);
  cv::Mat map(field.size(), CV_32FC2);
  for (int v = 0; v < map.rows; ++v) {
    for (int u = 0; u < map.cols; ++u)
      map.at<cv::Vec2f>(v, u) = field.at<cv::Vec2f>(v, u) + cv::Vec2f(u, v);
  }
  cv::Mat warped;
  cv::remap(ref, warped, map, cv::noArray(), cv::INTER_LINEAR);
  const cv::Rect interior(10, 10, rig.camera.width - 20, rig.camera.height - 20);
  cv::Mat diff;
  cv::absdiff(rs(interior), warped(interior), diff);
  // Texture range 0..1 with a 4 px blur: bilinear's second-order error is ~1e-3.
  EXPECT_LT(cv::mean(diff)[0], 3e-3);
  // And a wrong field (zero) is clearly worse: the test can fail.
  cv::absdiff(rs(interior), ref(interior), diff);
  EXPECT_GT(cv::mean(diff)[0], 1e-2);
}

TEST(RsWarp, OutputDoesNotDependOnThreadCount) {
  const RigModel rig = SmallRig(256, 192);
  const cv::Size scene_size(600, 500);
  const FrameGeometry geometry =
      Geometry(Truth(rig), ConstantRateTrace(Eigen::Vector3d(0.6, -0.8, 1.2)), 0.5, scene_size);
  const cv::Mat scene = SmoothTexture(scene_size, CV_8UC3);
  const int threads = cv::getNumThreads();
  cv::Mat one, many;
  cv::setNumThreads(1);
  RenderFrame(scene, geometry, Interpolation::kBicubic, &one);
  cv::setNumThreads(4);
  RenderFrame(scene, geometry, Interpolation::kBicubic, &many);
  cv::setNumThreads(threads);
  EXPECT_EQ(cv::norm(one, many, cv::NORM_INF), 0.0);
}

TEST(FrameDistortion, MatchesBruteForceDiameter) {
  std::mt19937_64 rng(5);
  std::normal_distribution<float> normal(0.0f, 3.0f);
  cv::Mat field(150, 7, CV_32FC2);
  for (int v = 0; v < field.rows; ++v) {
    for (int u = 0; u < field.cols; ++u)
      field.at<cv::Vec2f>(v, u) = cv::Vec2f(normal(rng) * (u + 1), normal(rng));
  }
  field.at<cv::Vec2f>(3, 2) = cv::Vec2f(NAN, NAN);  // undefined pixels are skipped
  double brute = 0.0;
  for (int u = 0; u < field.cols; ++u) {
    for (int a = 0; a < field.rows; ++a) {
      for (int b = a + 1; b < field.rows; ++b) {
        const cv::Vec2f p = field.at<cv::Vec2f>(a, u), q = field.at<cv::Vec2f>(b, u);
        const double n = std::hypot(double{p[0]} - q[0], double{p[1]} - q[1]);
        if (std::isfinite(n)) brute = std::max(brute, n);
      }
    }
  }
  EXPECT_NEAR(FrameDistortionPx(field), brute, 1e-9 * brute);
}

TEST(FrameDistortion, SmoothFieldMatchesBruteForce) {
  // A real field's columns are smooth curves whose hulls have many vertices: the calipers' hard
  // case.
  const RigModel rig = SmallRig(64, 48);
  const cv::Mat field = DisplacementField(Geometry(
      Truth(rig), ConstantRateTrace(Eigen::Vector3d(2.0, -3.0, 4.0)), 0.5, cv::Size(400, 400)));
  double brute = 0.0;
  for (int u = 0; u < field.cols; ++u) {
    for (int a = 0; a < field.rows; ++a) {
      for (int b = a + 1; b < field.rows; ++b) {
        const cv::Vec2f p = field.at<cv::Vec2f>(a, u), q = field.at<cv::Vec2f>(b, u);
        brute = std::max(brute, std::hypot(double{p[0]} - q[0], double{p[1]} - q[1]));
      }
    }
  }
  EXPECT_GT(brute, 1.0);
  EXPECT_NEAR(FrameDistortionPx(field), brute, 1e-9 * brute);
}

}  // namespace
}  // namespace shutterlab

namespace shutterlab {
namespace {

TEST(RsWarp, DenseOpticalFlowOnARealSceneAgreesWithTheTruth) {
  // The procedural aerial texture (render/ground_texture.h), a rendered rolling-shutter/reference
  // pair, and OpenCV's DIS optical flow from the rolling-shutter image to the reference: it must
  // find d(p).
  const cv::Mat scene = ReadImage(test::GroundScenePath(2));
  RigModel rig = SmallRig(480, 360);
  rig.camera.fx = rig.camera.fy = 900.0;
  rig.shutter.readout_s = 0.030;
  const FrameGeometry geometry =
      Geometry(Truth(rig), ConstantRateTrace(Eigen::Vector3d(0.15, -0.25, 0.3)), 0.5, scene.size());
  const FrameGeometry reference(rig.camera, rig.altitude_m, geometry.motion().Reference(),
                                scene.size());
  cv::Mat rs, ref, rs_grey, ref_grey;
  RenderFrame(scene, geometry, Interpolation::kBicubic, &rs);
  RenderFrame(scene, reference, Interpolation::kBicubic, &ref);
  cv::cvtColor(rs, rs_grey, cv::COLOR_RGB2GRAY);
  cv::cvtColor(ref, ref_grey, cv::COLOR_RGB2GRAY);
  const cv::Mat truth = DisplacementField(geometry);
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
  dis->setFinestScale(0);
  cv::Mat flow;
  dis->calc(rs_grey, ref_grey, flow);
  const int margin = 24;  // flow is unreliable where the match leaves the image
  double sum2 = 0.0, truth_max = 0.0;
  size_t n = 0;
  for (int v = margin; v < rig.camera.height - margin; ++v) {
    for (int u = margin; u < rig.camera.width - margin; ++u) {
      const cv::Vec2f e = flow.at<cv::Vec2f>(v, u) - truth.at<cv::Vec2f>(v, u);
      sum2 += e.dot(e);
      truth_max = std::max<double>(truth_max, cv::norm(truth.at<cv::Vec2f>(v, u)));
      ++n;
    }
  }
  const double rms_px = std::sqrt(sum2 / n);
  RecordProperty("flow_rms_px", std::to_string(rms_px));
  EXPECT_GT(truth_max, 3.0) << "the pair must be visibly distorted";
  EXPECT_LT(rms_px, 0.1);
}

}  // namespace
}  // namespace shutterlab
