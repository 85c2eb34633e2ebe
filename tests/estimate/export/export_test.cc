// The exports against the tools' own models: each exported camera, read back as its tool reads it
// (COLMAP's text model through the colmap program where installed, Kalibr's YAML through Python's
// YAML parser, the rest by their documented fields), projects 3D points to the pixels shutterlab's
// camera gives, in the tool's pixel convention, by the tool's equations written out here from its
// documentation (a second implementation: none of shutterlab's projection code). And the
// conventions that are not projections: readout, row reference, offset sign, refusals.

#include "estimate/export/colmap_export.h"
#include "estimate/export/export_camera.h"
#include "estimate/export/exports.h"
#include "estimate/export/gyroflow_export.h"
#include "estimate/export/kalibr_export.h"
#include "estimate/export/metashape_export.h"
#include "estimate/export/odm_export.h"
#include "estimate/export/pix4d_export.h"
#include "estimate/export/vins_export.h"
#include "io/lens_profile.h"
#include "model/camera.h"
#include "model/effect_io.h"
#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/test_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core/persistence.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// Sub-nanopixel: the exports write every number to the precision that reads back exactly.
constexpr double kProjectionTolPx = 1e-7;

// A camera with nothing at its default: fx != fy, an off-centre principal point, every
// Brown-Conrady coefficient (a fisheye where asked), a 27.1 ms bottom-to-top readout, a 4.3 ms
// time offset, a mounting off the axes.
ExportCamera TestCamera(bool fisheye = false) {
  ExportCamera camera;
  camera.source = "a test camera";
  camera.make = "DJI";
  camera.model = "FC6310";
  PinholeCamera& c = camera.truth.rig.camera;
  c.width = 1280, c.height = 960;
  c.fx = 1101.25, c.fy = 1098.5, c.cx = 651.3, c.cy = 470.8;
  if (fisheye) {
    c.fx = c.fy = 600.0;
    c.distortion = Fisheye({0.06, 0.04, -0.04, 0.015});
  } else {
    c.distortion = BrownConrady{{-0.12, 0.045, 0.0011, -0.0007, -0.008}};
  }
  camera.truth.rig.shutter.readout_s = 0.0271;
  camera.truth.rig.shutter.direction = ReadoutDirection::kBottomToTop;
  camera.truth.rig.time_offset_s = 0.0043;
  camera.truth.rig.cam_from_gyro = ExpSO3(Eigen::Vector3d(0.02, -0.01, 0.03)).toRotationMatrix();
  camera.time_offset_stderr_s = 1e-5;
  camera.readout_stderr_s = 2e-4;
  return camera;
}

// Points in front of the camera spread over its whole image (up to 60 degrees off the axis).
std::vector<Eigen::Vector3d> PointsInView(int count = 200) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> xy(-0.7, 0.7), depth(2.0, 80.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) {
    const double z = depth(rng);
    points.push_back({xy(rng) * z, xy(rng) * z, z});
  }
  return points;
}

const ExportFile& FileNamed(const ExportOutput& out, const std::string& name) {
  for (const ExportFile& file : out.files) {
    if (file.name == name) return file;
  }
  throw std::runtime_error("no " + name);
}

std::vector<double> Numbers(const std::string& text) {
  std::vector<double> values;
  std::istringstream in(text);
  for (double v; in >> v;) values.push_back(v);
  return values;
}

// OpenCV's Brown-Conrady distortion of a normalised point, and its fisheye model, written out
// (OpenCV calib3d and fisheye docs; COLMAP's FULL_OPENCV and OPENCV_FISHEYE, OpenSfM's brown and
// fisheye_opencv, Kalibr's radtan and equidistant are these).
Eigen::Vector2d BrownDistorted(double x, double y, double k1, double k2, double p1, double p2,
                               double k3) {
  const double r2 = x * x + y * y;
  const double radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + 2 * p2 * x * y + p1 * (r2 + 2 * y * y)};
}
Eigen::Vector2d FisheyeDistorted(double x, double y, double k1, double k2, double k3, double k4) {
  const double r = std::hypot(x, y), theta = std::atan(r);
  const double t2 = theta * theta;
  const double theta_d =
      theta * (1 + k1 * t2 + k2 * t2 * t2 + k3 * t2 * t2 * t2 + k4 * t2 * t2 * t2 * t2);
  return r > 0 ? Eigen::Vector2d(x * theta_d / r, y * theta_d / r) : Eigen::Vector2d(0, 0);
}

TEST(ColmapExport, CamerasTxtProjectsAsColmapsModelWithItsHalfPixel) {
  for (bool fisheye : {false, true}) {
    const ExportCamera camera = TestCamera(fisheye);
    const ExportOutput out = ColmapExport(camera, {});
    // The camera line: the last line of cameras.txt that is not a comment.
    std::string line;
    std::istringstream lines(FileNamed(out, "cameras.txt").text);
    for (std::string l; std::getline(lines, l);) {
      if (!l.empty() && l[0] != '#') line = l;
    }
    std::istringstream fields(line);
    std::string id, model;
    int width = 0, height = 0;
    fields >> id >> model >> width >> height;
    std::string rest;
    std::getline(fields, rest);
    const std::vector<double> p = Numbers(rest);
    EXPECT_EQ(model, fisheye ? "OPENCV_FISHEYE" : "FULL_OPENCV");
    ASSERT_EQ(p.size(), fisheye ? 8u : 12u);
    EXPECT_EQ(width, 1280);
    EXPECT_EQ(height, 960);
    for (const Eigen::Vector3d& point : PointsInView()) {
      const double x = point.x() / point.z(), y = point.y() / point.z();
      const Eigen::Vector2d d = fisheye ? FisheyeDistorted(x, y, p[4], p[5], p[6], p[7])
                                        : BrownDistorted(x, y, p[4], p[5], p[6], p[7], p[8]);
      // COLMAP: the top-left pixel's centre is (0.5, 0.5); shutterlab (OpenCV): (0, 0).
      const Eigen::Vector2d colmap(p[0] * d.x() + p[2], p[1] * d.y() + p[3]);
      const Eigen::Vector2d ours = *camera.truth.rig.camera.ImgFromCam(point);
      EXPECT_NEAR(colmap.x(), ours.x() + 0.5, kProjectionTolPx);
      EXPECT_NEAR(colmap.y(), ours.y() + 0.5, kProjectionTolPx);
    }
  }
  // Without k3 the 8-parameter OPENCV model serves.
  ExportCamera plain = TestCamera();
  std::get<BrownConrady>(plain.truth.rig.camera.distortion).coeffs[4] = 0.0;
  EXPECT_NE(FileNamed(ColmapExport(plain, {}), "cameras.txt").text.find("\n1 OPENCV 1280 960 "),
            std::string::npos);
}

// COLMAP's own reader takes the text model: converted to its binary model and back, the camera
// line holds the same numbers.
TEST(ColmapExport, ColmapsModelConverterReadsTheModel) {
  if (std::system("colmap help >/dev/null 2>&1") != 0) {
    if (test::RealDataRequired()) FAIL() << "colmap is not installed (scripts/test.sh installs it)";
    GTEST_SKIP() << "colmap is not installed (apt-get install colmap)";
  }
  test::TempDir dir;
  const ExportOutput out = ColmapExport(TestCamera(), {});
  WriteExport(out, dir / "model");
  const std::string bin = dir / "bin", txt = dir / "txt";
  std::filesystem::create_directories(bin);
  std::filesystem::create_directories(txt);
  // GLOG_log_dir: COLMAP's log files (glog) in the test's folder, not left in /tmp.
  ASSERT_EQ(std::system(("GLOG_log_dir='" + dir.path().string() +
                         "' colmap model_converter --input_path '" + (dir / "model") +
                         "' --output_path '" + bin + "' --output_type BIN >/dev/null 2>&1")
                            .c_str()),
            0);
  ASSERT_EQ(std::system(("GLOG_log_dir='" + dir.path().string() +
                         "' colmap model_converter --input_path '" + bin + "' --output_path '" +
                         txt + "' --output_type TXT >/dev/null 2>&1")
                            .c_str()),
            0);
  const auto camera_numbers = [](const std::string& text) {
    std::istringstream lines(text);
    std::string line;
    for (std::string l; std::getline(lines, l);) {
      if (!l.empty() && l[0] != '#') line = l;
    }
    return Numbers(line.substr(line.find(' ', line.find(' ') + 1)));  // after "1 MODEL"
  };
  const std::vector<double> ours = camera_numbers(FileNamed(out, "cameras.txt").text);
  const std::vector<double> colmaps = camera_numbers(ReadFileToString(txt + "/cameras.txt"));
  ASSERT_EQ(colmaps.size(), ours.size());
  for (size_t i = 0; i < ours.size(); ++i) EXPECT_EQ(colmaps[i], ours[i]) << i;
}

// OpenSfM: normalised by the larger side from the image centre, with its half-pixel: pixel =
// S * n + (W - 1) / 2 (OpenSfM doc/source/geometry.rst) for n = focal * distorted + c.
TEST(OdmExport, CameraOverridesProjectAsOpenSfmsNormalisedModel) {
  for (bool fisheye : {false, true}) {
    ExportCamera camera = TestCamera(fisheye);
    camera.truth.rig.shutter.direction = ReadoutDirection::kTopToBottom;
    const ExportOutput out = OdmExport(camera, {});
    const nlohmann::json all =
        nlohmann::json::parse(FileNamed(out, "camera_models_overrides.json").text).at("all");
    EXPECT_EQ(all.at("projection_type"), fisheye ? "fisheye_opencv" : "brown");
    const double s = 1280.0;
    for (const Eigen::Vector3d& point : PointsInView()) {
      const double x = point.x() / point.z(), y = point.y() / point.z();
      const Eigen::Vector2d d =
          fisheye ? FisheyeDistorted(x, y, all["k1"], all["k2"], all["k3"], all["k4"])
                  : BrownDistorted(x, y, all["k1"], all["k2"], all["p1"], all["p2"], all["k3"]);
      const double nx = all["focal_x"].get<double>() * d.x() + all["c_x"].get<double>();
      const double ny = all["focal_y"].get<double>() * d.y() + all["c_y"].get<double>();
      const Eigen::Vector2d ours = *camera.truth.rig.camera.ImgFromCam(point);
      EXPECT_NEAR(s * nx + (1280 - 1) / 2.0, ours.x(), kProjectionTolPx);
      EXPECT_NEAR(s * ny + (960 - 1) / 2.0, ours.y(), kProjectionTolPx);
    }
  }
}

// Read back as `--lens-profile` reads OpenSfM's cameras: the same camera.
TEST(OdmExport, CameraOverridesReadBackAsTheSameCamera) {
  for (bool fisheye : {false, true}) {
    const ExportCamera camera = TestCamera(fisheye);
    test::TempDir dir;
    ExportOptions force;
    force.force = true;  // bottom to top: the readout is not written, the camera is
    WriteExport(OdmExport(camera, force), dir.path().string());
    const LensProfile back = ReadLensProfile(dir / "camera_models_overrides.json");
    const PinholeCamera& c = camera.truth.rig.camera;
    EXPECT_NEAR(back.camera.fx, c.fx, 1e-9);
    EXPECT_NEAR(back.camera.fy, c.fy, 1e-9);
    EXPECT_NEAR(back.camera.cx, c.cx, 1e-9);
    EXPECT_NEAR(back.camera.cy, c.cy, 1e-9);
    EXPECT_EQ(back.camera.distortion, c.distortion);
  }
}

TEST(OdmExport, ReadoutInWholeMillisecondsTopToBottomOnly) {
  ExportCamera camera = TestCamera();
  camera.truth.rig.shutter.direction = ReadoutDirection::kTopToBottom;
  const ExportOutput out = OdmExport(camera, {});
  EXPECT_EQ(FileNamed(out, "odm_args.txt").text,
            "--rolling-shutter --rolling-shutter-readout 27\n");
  camera.truth.rig.shutter.direction = ReadoutDirection::kBottomToTop;
  EXPECT_THROW(OdmExport(camera, {}), std::invalid_argument);
  ExportOptions force;
  force.force = true;
  const ExportOutput forced = OdmExport(camera, force);  // the camera, without the readout
  EXPECT_NO_THROW(FileNamed(forced, "camera_models_overrides.json"));
  EXPECT_THROW(FileNamed(forced, "odm_args.txt"), std::runtime_error);
}

// Kalibr's file read by a YAML parser (Python's), the camera projected by radtan's equations, the
// rotation, time shift and line delay as Kalibr defines them.
TEST(KalibrExport, PythonsYamlReadsTheChainAsKalibrDefinesIt) {
  ExportCamera camera = TestCamera();
  std::get<BrownConrady>(camera.truth.rig.camera.distortion).coeffs[4] = 0.0;  // radtan: no k3
  camera.truth.rig.shutter.direction = ReadoutDirection::kTopToBottom;
  test::TempDir dir;
  WriteExport(KalibrExport(camera, {}), dir.path().string());
  const std::string script =
      "import json, sys, yaml\n"
      "c = yaml.safe_load(open(sys.argv[1]))['cam0']\n"
      "print(json.dumps(c))\n";
  WriteFileAtomically(dir / "read.py", script);
  const std::string command = "/usr/bin/python3 '" + (dir / "read.py") + "' '" +
                              (dir / "camchain-imucam.yaml") + "' > '" + (dir / "cam0.json") + "'";
  if (std::system(command.c_str()) != 0) {
    if (test::RealDataRequired()) FAIL() << "python3-yaml is missing (scripts/test.sh installs it)";
    GTEST_SKIP() << "/usr/bin/python3 with python3-yaml is missing";
  }
  const nlohmann::json cam0 = nlohmann::json::parse(ReadFileToString(dir / "cam0.json"));
  EXPECT_EQ(cam0.at("camera_model"), "pinhole");
  EXPECT_EQ(cam0.at("distortion_model"), "radtan");
  EXPECT_EQ(cam0.at("resolution"), nlohmann::json::array({1280, 960}));
  const std::vector<double> in = cam0.at("intrinsics"), k = cam0.at("distortion_coeffs");
  for (const Eigen::Vector3d& point : PointsInView()) {
    const Eigen::Vector2d d =
        BrownDistorted(point.x() / point.z(), point.y() / point.z(), k[0], k[1], k[2], k[3], 0.0);
    const Eigen::Vector2d ours = *camera.truth.rig.camera.ImgFromCam(point);
    EXPECT_NEAR(in[0] * d.x() + in[2], ours.x(), kProjectionTolPx);
    EXPECT_NEAR(in[1] * d.y() + in[3], ours.y(), kProjectionTolPx);
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      EXPECT_EQ(cam0["T_cam_imu"][i][j].get<double>(), camera.truth.rig.cam_from_gyro(i, j));
  }
  // t_imu = t_cam + shift; row v at v * line delay after the frame's (first row's) time.
  EXPECT_EQ(cam0.at("timeshift_cam_imu").get<double>(), 0.0043);
  EXPECT_NEAR(cam0.at("line_delay_nanoseconds").get<double>() * 960 * 1e-9, 0.0271, 1e-15);
}

TEST(KalibrExport, RefusesWhatTheChainCannotHoldUnlessForced) {
  ExportCamera camera = TestCamera();  // k3 != 0 and bottom to top
  try {
    KalibrExport(camera, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no k3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  ExportOptions force;
  force.force = true;
  const ExportOutput out = KalibrExport(camera, force);
  EXPECT_NE(FileNamed(out, "shutterlab_export.txt").text.find("the rest written (--force)"),
            std::string::npos);
  // A time offset the data did not determine is refused too.
  camera = TestCamera();
  std::get<BrownConrady>(camera.truth.rig.camera.distortion).coeffs[4] = 0.0;
  camera.truth.rig.shutter.direction = ReadoutDirection::kTopToBottom;
  camera.undetermined["time_offset"] = "fitted, with a standard error that is not a number";
  EXPECT_THROW(KalibrExport(camera, {}), std::invalid_argument);
}

// VINS reads its files through OpenCV's cv::FileStorage and camodocal's cameras: read back so, the
// camera projects as camodocal's PINHOLE (OpenCV's terms without k3) and KANNALA_BRANDT (theta +
// k2 theta^3 + ... + k5 theta^9, then mu, mv, u0, v0) do; td counts from the middle row
// (projection_td_factor.cpp: td + tr / ROW * (row - ROW / 2)), so a row v read at camera time
// t + readout * v / H is at IMU time t + td + tr * (v - H / 2) / H, the same.
TEST(VinsExport, OpenCvsFileStorageReadsItAndItProjectsAsCamodocalsModels) {
  for (bool fisheye : {false, true}) {
    ExportCamera camera = TestCamera(fisheye);
    if (!fisheye) std::get<BrownConrady>(camera.truth.rig.camera.distortion).coeffs[4] = 0.0;
    camera.truth.rig.shutter.direction = ReadoutDirection::kTopToBottom;
    test::TempDir dir;
    WriteExport(VinsExport(camera, {}), dir.path().string());
    cv::FileStorage cam(dir / "camera.yaml", cv::FileStorage::READ);
    ASSERT_TRUE(cam.isOpened());
    EXPECT_EQ(static_cast<int>(cam["image_width"]), 1280);
    EXPECT_EQ(static_cast<int>(cam["image_height"]), 960);
    const cv::FileNode p = cam["projection_parameters"], d = cam["distortion_parameters"];
    for (const Eigen::Vector3d& point : PointsInView()) {
      const Eigen::Vector2d ours = *camera.truth.rig.camera.ImgFromCam(point);
      Eigen::Vector2d theirs;
      if (fisheye) {
        EXPECT_EQ(static_cast<std::string>(cam["model_type"]), "KANNALA_BRANDT");
        const double theta = std::acos(point.z() / point.norm());
        const double phi = std::atan2(point.y(), point.x()), t2 = theta * theta;
        const double r = theta + double(p["k2"]) * theta * t2 + double(p["k3"]) * theta * t2 * t2 +
                         double(p["k4"]) * theta * t2 * t2 * t2 +
                         double(p["k5"]) * theta * t2 * t2 * t2 * t2;
        theirs = {double(p["mu"]) * r * std::cos(phi) + double(p["u0"]),
                  double(p["mv"]) * r * std::sin(phi) + double(p["v0"])};
      } else {
        EXPECT_EQ(static_cast<std::string>(cam["model_type"]), "PINHOLE");
        const Eigen::Vector2d x = BrownDistorted(point.x() / point.z(), point.y() / point.z(),
                                                 d["k1"], d["k2"], d["p1"], d["p2"], 0.0);
        theirs = {double(p["fx"]) * x.x() + double(p["cx"]),
                  double(p["fy"]) * x.y() + double(p["cy"])};
      }
      EXPECT_NEAR(theirs.x(), ours.x(), kProjectionTolPx) << fisheye;
      EXPECT_NEAR(theirs.y(), ours.y(), kProjectionTolPx) << fisheye;
    }
    cv::FileStorage config(dir / "vins_config.yaml", cv::FileStorage::READ);
    ASSERT_TRUE(config.isOpened());
    cv::Mat imu_r_cam;
    config["extrinsicRotation"] >> imu_r_cam;
    ASSERT_EQ(imu_r_cam.rows, 3);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        EXPECT_EQ(imu_r_cam.at<double>(i, j), camera.truth.rig.cam_from_gyro(j, i));
    }
    EXPECT_EQ(static_cast<int>(config["rolling_shutter"]), 1);
    const double tr = config["rolling_shutter_tr"], td = config["td"];
    EXPECT_EQ(tr, 0.0271);
    for (const double row : {0.0, 100.0, 959.0}) {
      const double ours = 0.0043 + 0.0271 * row / 960;  // IMU time of the row, frame time 0
      EXPECT_NEAR(td + tr / 960 * (row - 960 / 2), ours, 1e-15) << row;
    }
  }
  // A bottom-to-top readout, which VINS cannot hold, is refused; a clock rate too.
  EXPECT_THROW(VinsExport(TestCamera(/*fisheye=*/true), {}), std::invalid_argument);
}

// A report whose model carries a declared value that its claims did not confirm (import.json's
// guess of a readout, on a clip whose images do not follow the gyro: every claim "not
// determined") exports it only with --force; a claim that holds, the source's own statement that
// the data could not test, or a fitted effect, exports.
TEST(ExportSource, AClaimTheReportCouldNotTestIsRefusedUnlessForced) {
  test::TempDir dir;
  ExportCamera camera = TestCamera(/*fisheye=*/true);
  camera.truth.rig.shutter.direction = ReadoutDirection::kTopToBottom;
  const auto claim = [](const std::string& effect, const std::string& verdict) {
    return nlohmann::json{{"claim", effect == "readout_time" ? "readout_s" : "time_offset_s"},
                          {"effect", effect},
                          {"status", "guess"},
                          {"verdict", verdict}};
  };
  nlohmann::json report = {{"format", "validation/1"},
                           {"effects", nlohmann::json::array()},
                           {"unexplained", true},
                           {"fitted_model", TrueModelToJson(camera.truth)},
                           {"claims",
                            {claim("readout_time", "not determined: found 17.7 +- 0.1 ms"),
                             claim("time_offset", "claim holds: found 4.3 +- 0.1 ms")}}};
  WriteFileAtomically(dir / "report.json", report.dump());
  const ExportCamera from_report = ReadExportSource(dir / "report.json");
  ASSERT_EQ(from_report.undetermined.count("readout_time"), 1u);
  EXPECT_EQ(from_report.undetermined.count("time_offset"), 0u);
  for (const ExportFormat* format :
       {&FindExportFormat("gyroflow"), &FindExportFormat("odm"), &FindExportFormat("vins")}) {
    try {
      format->write(from_report, {});
      FAIL() << format->name;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("readout_time was not determined"), std::string::npos) << what;
      EXPECT_NE(what.find("declared readout_s (guess)"), std::string::npos) << what;
      EXPECT_NE(what.find("17.7"), std::string::npos) << what;
      EXPECT_NE(what.find("--force"), std::string::npos) << what;
    }
  }
  ExportOptions force;
  force.force = true;
  EXPECT_NE(FileNamed(GyroflowExport(from_report, force), "shutterlab_export.txt")
                .text.find("readout_time was not determined"),
            std::string::npos);
  // The source's own statement that the data could not test is exported as stated, and said;
  // contradicted, it is refused whoever stated it.
  report["claims"][0]["status"] = "source claim";
  WriteFileAtomically(dir / "report.json", report.dump());
  const ExportCamera stated = ReadExportSource(dir / "report.json");
  EXPECT_EQ(stated.undetermined.count("readout_time"), 0u);
  EXPECT_NE(FileNamed(GyroflowExport(stated, {}), "shutterlab_export.txt")
                .text.find("readout_time is the source's own readout_s (source claim)"),
            std::string::npos);
  report["claims"][0]["verdict"] = "claim contradicted: 17.7 +- 0.1 ms against 27.1 ms";
  WriteFileAtomically(dir / "report.json", report.dump());
  EXPECT_EQ(ReadExportSource(dir / "report.json").undetermined.count("readout_time"), 1u);
  // Fitted, the readout is the data's: the claim about the declared one no longer matters.
  report["effects"] = {{{"name", "readout_time"}, {"value", 0.0271}}};
  WriteFileAtomically(dir / "report.json", report.dump());
  EXPECT_EQ(ReadExportSource(dir / "report.json").undetermined.count("readout_time"), 0u);
}

// Gyroflow's lens profile, as shutterlab's reader of Gyroflow's profiles reads it, and the sync
// offset from the middle row: -1000 (time_offset_s + readout_s / 2) ms.
TEST(GyroflowExport, TheProfileReadsBackAndTheOffsetCountsFromTheMiddleRow) {
  for (bool fisheye : {false, true}) {
    const ExportCamera camera = TestCamera(fisheye);
    test::TempDir dir;
    const ExportOutput out = GyroflowExport(camera, {});
    WriteExport(out, dir.path().string());
    const LensProfile profile = ReadLensProfile(dir / "lens_profile.json");
    const PinholeCamera& c = camera.truth.rig.camera;
    EXPECT_EQ(profile.camera.fx, c.fx);
    EXPECT_EQ(profile.camera.fy, c.fy);
    EXPECT_EQ(profile.camera.cx, c.cx);
    EXPECT_EQ(profile.camera.cy, c.cy);
    EXPECT_EQ(profile.camera.distortion, c.distortion);
    ASSERT_TRUE(profile.mode.readout_s);
    EXPECT_NEAR(*profile.mode.readout_s, 0.0271, 1e-15);
    EXPECT_EQ(profile.mode.direction, ReadoutDirection::kBottomToTop);
    const nlohmann::json project = nlohmann::json::parse(FileNamed(out, "project.gyroflow").text);
    EXPECT_NEAR(project["offsets"]["0"].get<double>(), -1e3 * (0.0043 + 0.0271 / 2), 1e-12);
    EXPECT_EQ(project["calibration_data"]["asymmetrical"], true);
    // The project reads back too, its readout and direction by Gyroflow's names.
    EXPECT_EQ(project["stabilization"]["frame_readout_direction"], "BottomToTop");
    const LensProfile from_project = ReadLensProfile(dir / "project.gyroflow");
    EXPECT_EQ(from_project.camera.distortion, c.distortion);
    ASSERT_TRUE(from_project.mode.readout_s);
    EXPECT_NEAR(*from_project.mode.readout_s, 0.0271, 1e-15);
    EXPECT_EQ(from_project.mode.direction, ReadoutDirection::kBottomToTop);
  }
}

// The gyro's mounting in a Gyroflow project, applied as Gyroflow's IMUTransforms does (rebuilt
// here from its description: output axis i = the input axis letter i names, lowercase negated;
// then R = Rz(roll) Ry(pitch) Rx(yaw) of the "rotation" [pitch, roll, yaw] in degrees), turns
// every gyro rate into the camera's rate on Gyroflow's axes: x right, y up, z back (shutterlab's
// with y and z negated). Axes onto axes are written as letters alone.
TEST(GyroflowExport, TheMountingTurnsTheGyroOntoGyroflowsCameraAxes) {
  const auto gyroflow_applies = [](const nlohmann::json& source, const Eigen::Vector3d& w) {
    const std::string letters = source["imu_orientation"];
    Eigen::Vector3d oriented;
    for (int i = 0; i < 3; ++i) {
      const char letter = letters[i];
      const int axis = std::toupper(letter) - 'X';
      oriented[i] = (std::isupper(letter) ? 1.0 : -1.0) * w[axis];
    }
    if (source["rotation"].is_null()) return oriented;
    const double pitch = source["rotation"][0].get<double>() * kPi / 180;
    const double roll = source["rotation"][1].get<double>() * kPi / 180;
    const double yaw = source["rotation"][2].get<double>() * kPi / 180;
    const Eigen::Matrix3d r = (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    return Eigen::Vector3d(r * oriented);
  };
  struct Case {
    Eigen::Matrix3d cam_from_gyro;
    std::string letters;  // "" when a rotation is needed
  };
  Eigen::Matrix3d quarter;  // camera x = gyro y, camera y = -gyro x
  quarter << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  const Eigen::Matrix3d tilted =
      (Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())).toRotationMatrix();
  for (const Case& c : {Case{Eigen::Matrix3d::Identity(), "Xyz"}, Case{quarter, "YXz"},
                        Case{tilted, ""}, Case{tilted * quarter, ""}}) {
    ExportCamera camera = TestCamera();
    camera.truth.rig.cam_from_gyro = c.cam_from_gyro;
    const ExportOutput out = GyroflowExport(camera, {});
    const nlohmann::json source =
        nlohmann::json::parse(FileNamed(out, "project.gyroflow").text)["gyro_source"];
    if (!c.letters.empty()) {
      EXPECT_EQ(source["imu_orientation"], c.letters);
      EXPECT_TRUE(source["rotation"].is_null()) << source;
    } else {
      EXPECT_EQ(source["imu_orientation"], "XYZ");
      EXPECT_FALSE(source["rotation"].is_null()) << source;
    }
    for (const Eigen::Vector3d& w :
         {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0.3, -0.7, 0.2)}) {
      const Eigen::Vector3d camera_rate = c.cam_from_gyro * w;
      const Eigen::Vector3d expected(camera_rate.x(), -camera_rate.y(), -camera_rate.z());
      EXPECT_LT((gyroflow_applies(source, w) - expected).norm(), 1e-12)
          << source << " on " << w.transpose();
    }
    EXPECT_NE(FileNamed(out, "shutterlab_export.txt").text.find("imu_orientation"),
              std::string::npos);
  }
}

// Metashape's frame model (its manual's appendix, "Frame cameras"): u = w/2 + cx + x'(f + b1) +
// y' b2, v = h/2 + cy + y' f, its P1 and P2 on the terms where OpenCV has p2 and p1; pixel
// coordinates from the image's top-left corner.
TEST(MetashapeExport, CalibrationProjectsAsMetashapesFrameModel) {
  const ExportCamera camera = TestCamera();
  const std::string xml = FileNamed(MetashapeExport(camera, {}), "calibration.xml").text;
  std::map<std::string, double> v;
  const std::regex element("<(\\w+)>([^<]*)</\\w+>");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), element);
       it != std::sregex_iterator(); ++it) {
    if ((*it)[1] != "projection") v[(*it)[1]] = std::stod((*it)[2]);
  }
  EXPECT_NE(xml.find("<projection>frame</projection>"), std::string::npos);
  for (const Eigen::Vector3d& point : PointsInView()) {
    const double x = point.x() / point.z(), y = point.y() / point.z(), r2 = x * x + y * y;
    const double radial = 1 + v["k1"] * r2 + v["k2"] * r2 * r2 + v["k3"] * r2 * r2 * r2;
    const double xd = x * radial + v["p1"] * (r2 + 2 * x * x) + 2 * v["p2"] * x * y;
    const double yd = y * radial + v["p2"] * (r2 + 2 * y * y) + 2 * v["p1"] * x * y;
    const double u = 0.5 * v["width"] + v["cx"] + xd * (v["f"] + v["b1"]) + yd * v["b2"];
    const double w = 0.5 * v["height"] + v["cy"] + yd * v["f"];
    const Eigen::Vector2d ours = *camera.truth.rig.camera.ImgFromCam(point);
    EXPECT_NEAR(u, ours.x() + 0.5, kProjectionTolPx);
    EXPECT_NEAR(w, ours.y() + 0.5, kProjectionTolPx);
  }
  EXPECT_THROW(MetashapeExport(TestCamera(/*fisheye=*/true), {}), std::invalid_argument);
}

// Pix4D's OPF calibrated camera: the fields its specification requires (calibrated_cameras and
// sensor_internals, written out here), an extension named as OPF names them, and the camera
// projecting as Pix4D's own converter to COLMAP (pyopf opf2colmap) reads it: FULL_OPENCV with fx =
// fy = focal_length_px, the principal point as written (COLMAP's and OPF's (0, 0) are the top-left
// pixel's corner), k1..k3 the radial and p1, p2 the tangential terms as they are.
TEST(Pix4dExport, CalibratedCameraHasOpfsFieldsAndProjectsAsPix4dsConverterReadsIt) {
  ExportCamera camera = TestCamera();
  camera.truth.rig.camera.fy = camera.truth.rig.camera.fx;
  const nlohmann::json opf =
      nlohmann::json::parse(FileNamed(Pix4dExport(camera, {}), "calibrated_cameras.json").text);
  EXPECT_EQ(opf.at("format"), "application/opf-calibrated-cameras+json");
  EXPECT_EQ(opf.at("version"), "1.0");
  EXPECT_TRUE(opf.at("cameras").is_array());
  ASSERT_EQ(opf.at("sensors").size(), 1u);
  const nlohmann::json& sensor = opf["sensors"][0];
  EXPECT_TRUE(sensor.at("id").is_number_unsigned());
  const nlohmann::json& in = sensor.at("internals");
  EXPECT_EQ(in.at("type"), "perspective");
  const std::vector<double> pp = in.at("principal_point_px"), radial = in.at("radial_distortion"),
                            tangential = in.at("tangential_distortion");
  ASSERT_EQ(pp.size(), 2u);
  ASSERT_EQ(radial.size(), 3u);
  ASSERT_EQ(tangential.size(), 2u);
  const double f = in.at("focal_length_px");
  for (const Eigen::Vector3d& point : PointsInView()) {
    const Eigen::Vector2d d =
        BrownDistorted(point.x() / point.z(), point.y() / point.z(), radial[0], radial[1],
                       tangential[0], tangential[1], radial[2]);
    const Eigen::Vector2d ours = *camera.truth.rig.camera.ImgFromCam(point);
    EXPECT_NEAR(f * d.x() + pp[0], ours.x() + 0.5, kProjectionTolPx);
    EXPECT_NEAR(f * d.y() + pp[1], ours.y() + 0.5, kProjectionTolPx);
  }
  const std::regex extension_name("^([A-Z]+[A-Z0-9]*)_[a-z][a-z0-9_]+$");
  ASSERT_EQ(sensor.at("extensions").size(), 1u);
  for (const auto& [name, value] : sensor["extensions"].items()) {
    EXPECT_TRUE(std::regex_match(name, extension_name)) << name;
    EXPECT_EQ(value.at("readout_time_s"), 0.0271);
    EXPECT_EQ(value.at("readout_direction"), "bottom_to_top");
    EXPECT_EQ(value.at("shutter_type"), "rolling");
  }
  // One focal length: fx != fy is refused (with what their mean costs) unless forced; a fisheye
  // (Pix4D's polynomial model) always.
  try {
    Pix4dExport(TestCamera(), {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("one focal length"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  ExportOptions force;
  force.force = true;
  const nlohmann::json forced = nlohmann::json::parse(
      FileNamed(Pix4dExport(TestCamera(), force), "calibrated_cameras.json").text);
  EXPECT_EQ(forced["sensors"][0]["internals"]["focal_length_px"], 0.5 * (1101.25 + 1098.5));
  EXPECT_THROW(Pix4dExport(TestCamera(/*fisheye=*/true), force), std::invalid_argument);
}

// From an analyze --photos result, OPF's input cameras and camera list beside the calibrated
// camera: the calibrated sensor's id is an input sensor's (OPF requires it), its pixel size is the
// EXIF focal length in mm over the focal length in pixels (4.5 mm / 3000 px = 1.5 um), its shutter
// the readout's (EXIF FocalPlaneXResolution first where a photo has it), a capture of one camera
// for each JPEG of the camera's size with a capture time (ISO 8601: UTC with Z where the zone is
// known, the camera clock without one where not), every id unique, and the camera list naming each
// capture's photo as a URI reference. Without a focal length in mm, neither file, and it is said.
TEST(Pix4dExport, PhotosGiveOpfsInputCamerasAndCameraList) {
  const auto photo = [](const std::string& name, int width, const nlohmann::json& time) {
    return nlohmann::json{{"name", name},        {"path", "/p/" + name}, {"make", "DJI"},
                          {"model", "FC8482"},   {"width", width},       {"height", 2000},
                          {"focal_px", 3000.0},  {"focal_mm", 4.5},      {"readout_s", 0.016},
                          {"capture_time", time}};
  };
  const nlohmann::json utc = {{"camera_clock", "2024-07-16 17:41:37.250"},
                              {"utc", "2024-07-16 09:41:37.250"}};
  const nlohmann::json face_only = {{"camera_clock", "2024-07-16 17:41:39.000"}, {"utc", nullptr}};
  const nlohmann::json photos = nlohmann::json::array(
      {photo("DJI_0001.JPG", 3000, utc), photo("DJI 0002.jpeg", 3000, face_only),
       photo("DJI_0003.JPG", 1500, utc), photo("DJI_0004.tif", 3000, utc),
       photo("DJI_0005.JPG", 3000, nullptr)});
  const ExportCamera camera = ExportCameraFromPhotos(photos, "photos.json");
  const ExportOutput out = Pix4dExport(camera, {});
  const nlohmann::json calibrated =
      nlohmann::json::parse(FileNamed(out, "calibrated_cameras.json").text);
  const nlohmann::json input = nlohmann::json::parse(FileNamed(out, "input_cameras.json").text);
  const nlohmann::json list = nlohmann::json::parse(FileNamed(out, "camera_list.json").text);
  EXPECT_EQ(input.at("format"), "application/opf-input-cameras+json");
  EXPECT_EQ(input.at("version"), "1.0");
  EXPECT_EQ(list.at("format"), "application/opf-camera-list+json");
  ASSERT_EQ(input.at("sensors").size(), 1u);
  const nlohmann::json& sensor = input["sensors"][0];
  EXPECT_EQ(sensor.at("id"), calibrated.at("sensors")[0].at("id"));
  EXPECT_NEAR(sensor.at("pixel_size_um").get<double>(), 1.5, 1e-12);
  EXPECT_EQ(sensor.at("shutter_type"), "rolling");
  EXPECT_EQ(sensor.at("image_size_px"), nlohmann::json({3000, 2000}));
  EXPECT_EQ(sensor.at("internals"), calibrated.at("sensors")[0].at("internals"));
  double band_weights = 0.0;
  for (const nlohmann::json& band : sensor.at("bands"))
    band_weights += band.at("weight").get<double>();
  EXPECT_NEAR(band_weights, 1.0, 1e-12);
  const nlohmann::json& captures = input.at("captures");
  ASSERT_EQ(captures.size(), 2u) << "the half-size photo, the TIFF and the undated one have none";
  EXPECT_EQ(captures[0].at("time"), "2024-07-16T09:41:37.250Z");
  EXPECT_EQ(captures[1].at("time"), "2024-07-16T17:41:39.000");
  std::set<uint64_t> ids = {sensor.at("id").get<uint64_t>()};
  ASSERT_EQ(list.at("cameras").size(), 2u);
  for (size_t k = 0; k < captures.size(); ++k) {
    const nlohmann::json& capture = captures[k];
    ASSERT_EQ(capture.at("cameras").size(), 1u);
    const nlohmann::json& shot = capture["cameras"][0];
    EXPECT_EQ(capture.at("reference_camera_id"), shot.at("id"));
    EXPECT_EQ(shot.at("sensor_id"), sensor.at("id"));
    EXPECT_EQ(shot.at("model_source"), "generic_from_exif");
    EXPECT_EQ(shot.at("pixel_type"), "uint8");
    EXPECT_EQ(capture.at("rig_model_source"), "not_applicable");
    EXPECT_EQ(list["cameras"][k].at("id"), shot.at("id"));
    EXPECT_TRUE(ids.insert(shot.at("id").get<uint64_t>()).second);
    EXPECT_TRUE(ids.insert(capture.at("id").get<uint64_t>()).second);
  }
  EXPECT_EQ(list["cameras"][0].at("uri"), "DJI_0001.JPG");
  EXPECT_EQ(list["cameras"][1].at("uri"), "DJI%200002.jpeg");
  const auto notes_say = [](const ExportOutput& output, const std::string& words) {
    return std::any_of(output.notes.begin(), output.notes.end(), [&](const std::string& note) {
      return note.find(words) != std::string::npos;
    });
  };
  EXPECT_FALSE(notes_say(out, "flagged")) << "no photo is flagged";
  // A flagged photo keeps its capture (OPF describes captures; it has no subset to process), and
  // the note says so and where the subset is.
  nlohmann::json with_flagged = photos;
  with_flagged[0]["flagged"] = {{"0.05", true}};
  const ExportOutput flagged_out =
      Pix4dExport(ExportCameraFromPhotos(with_flagged, "photos.json"), {});
  EXPECT_EQ(nlohmann::json::parse(FileNamed(flagged_out, "input_cameras.json").text)
                .at("captures")
                .size(),
            2u);
  EXPECT_TRUE(notes_say(flagged_out, "describes the 1 photo(s) flagged over a limit too"));
  EXPECT_TRUE(notes_say(flagged_out, "image_list.txt leave them out"));
  // EXIF FocalPlaneXResolution goes first, as Pix4D reads it: 400 px/mm, 2.5 um.
  nlohmann::json focal_plane = photos;
  focal_plane[1]["focal_plane_px_per_mm"] = 400.0;
  EXPECT_NEAR(nlohmann::json::parse(
                  FileNamed(Pix4dExport(ExportCameraFromPhotos(focal_plane, "p.json"), {}),
                            "input_cameras.json")
                      .text)["sensors"][0]["pixel_size_um"]
                  .get<double>(),
              2.5, 1e-12);
  nlohmann::json no_focal_mm = photos;
  for (nlohmann::json& p : no_focal_mm) p.erase("focal_mm");
  const ExportOutput without = Pix4dExport(ExportCameraFromPhotos(no_focal_mm, "photos.json"), {});
  EXPECT_THROW(FileNamed(without, "input_cameras.json"), std::runtime_error);
  EXPECT_NE(FileNamed(without, "shutterlab_export.txt").text.find("pixel_size_um"),
            std::string::npos);
  // Without the readout too, the note names both.
  nlohmann::json neither = no_focal_mm;
  for (nlohmann::json& p : neither) p.erase("readout_s");
  const ExportOutput lacking = Pix4dExport(ExportCameraFromPhotos(neither, "photos.json"), {});
  EXPECT_NE(FileNamed(lacking, "shutterlab_export.txt")
                .text.find("a readout (OPF's shutter_type) nor a FocalPlaneXResolution"),
            std::string::npos);
}

// The sources: a validation report's fitted model with its effects' standard errors, a
// camera.json, a folder holding one, the photos of an analyze --photos result.
TEST(ExportSource, ReadsAReportACameraJsonAFolderAndPhotos) {
  test::TempDir dir;
  const ExportCamera camera = TestCamera();
  const nlohmann::json report = {{"format", "validation/1"},
                                 {"effects",
                                  {{{"name", "time_offset"},
                                    {"value", 0.0043},
                                    {"parameters", {0.0043}},
                                    {"covariance", {{1e-10}}}},
                                   {{"name", "gyro_scale"},
                                    {"value", {1.01, 0.99, 1.0}},
                                    {"parameters", {0.01, -0.01, 0.0}},
                                    {"covariance", {{4e-6, 0, 0}, {0, 9e-6, 0}, {0, 0, -1.0}}}},
                                   {{"name", "readout_direction"}, {"value", "bottom_to_top"}}}},
                                 {"fitted_model", TrueModelToJson(camera.truth)}};
  WriteFileAtomically(dir / "report.json", report.dump());
  const ExportCamera from_report = ReadExportSource(dir / "report.json");
  EXPECT_EQ(from_report.truth.rig.camera.fx, 1101.25);
  EXPECT_EQ(from_report.truth.rig.time_offset_s, 0.0043);
  ASSERT_TRUE(from_report.time_offset_stderr_s);
  EXPECT_NEAR(*from_report.time_offset_stderr_s, 1e-5, 1e-12);
  // The side note carries it (most tools' files have no place for it).
  const std::string note = FileNamed(ColmapExport(from_report, {}), "shutterlab_export.txt").text;
  EXPECT_NE(note.find("time_offset 0.0043 +- 1"), std::string::npos) << note;
  // Every fitted effect, in its value's shape: a variance below 0 is not determined (null), an
  // effect without a covariance has none.
  ASSERT_EQ(from_report.fitted.size(), 3u);
  EXPECT_NE(note.find("    time_offset 0.0043 +- 1e-05 s\n"), std::string::npos) << note;
  EXPECT_NE(note.find("    gyro_scale [1.01,0.99,1.0] +- [0.002,0.003,null]\n"), std::string::npos)
      << note;
  // A standard error with an entry that is not a number leaves the effect not determined.
  EXPECT_EQ(from_report.undetermined.count("gyro_scale"), 1u);
  EXPECT_EQ(from_report.undetermined.count("time_offset"), 0u);
  EXPECT_NE(note.find("    readout_direction \"bottom_to_top\" +- none\n"), std::string::npos)
      << note;

  std::filesystem::create_directories(dir / "dataset");
  WriteRigModel(dir / "dataset/camera.json", camera.truth.rig);
  for (const std::string& path : {dir / "dataset/camera.json", dir / "dataset"}) {
    const ExportCamera from_json = ReadExportSource(path);
    EXPECT_EQ(from_json.truth.rig.camera.cy, 470.8) << path;
    EXPECT_EQ(from_json.truth.rig.shutter.readout_s, 0.0271) << path;
    EXPECT_TRUE(from_json.masks_dir.empty()) << path;
  }
  // A correction's output folder: its masks go to COLMAP's feature extractor.
  std::filesystem::create_directories(dir / "dataset/masks");
  const ExportCamera corrected = ReadExportSource(dir / "dataset");
  EXPECT_EQ(corrected.masks_dir, std::filesystem::absolute(dir / "dataset/masks").string());
  EXPECT_NE(FileNamed(ColmapExport(corrected, {}), "colmap_args.txt")
                .text.find("--ImageReader.mask_path " + corrected.masks_dir),
            std::string::npos);
  EXPECT_TRUE(corrected.images_dir.empty()) << "a dataset's images are under the folder itself";
  // A correction of photos: the corrected photos alone in images/, COLMAP's --image_path.
  std::filesystem::create_directories(dir / "dataset/images");
  WriteFileAtomically(dir / "dataset/correct.json",
                      R"({"format": "correction/1", "image_root": "images"})");
  const ExportCamera photos_corrected = ReadExportSource(dir / "dataset");
  EXPECT_EQ(photos_corrected.images_dir,
            std::filesystem::absolute(dir / "dataset/images").string());
  EXPECT_NE(FileNamed(ColmapExport(photos_corrected, {}), "colmap_args.txt")
                .text.find("--image_path " + photos_corrected.images_dir + " "),
            std::string::npos);

  const nlohmann::json photos = {
      {"source", "DIR"},
      {"photos",
       {{{"name", "a.jpg"},
         {"path", "/p/a.jpg"},
         {"make", "DJI"},
         {"model", "FC8482"},
         {"width", 4032},
         {"height", 2268},
         {"focal_px", 2566.1},
         {"readout_s", 0.016},
         {"speed_m_s", 6.9},
         {"flagged", {{"0.05", true}, {"0.1", false}}}},
        {{"name", "b.jpg"}, {"path", "/p/b.jpg"}, {"error", "unreadable"}},
        {{"name", "c.jpg"},
         {"path", "/p/c.jpg"},
         {"width", 4032},
         {"height", 2268},
         {"focal_px", 2566.1},
         {"readout_s", 0.016},
         {"flagged", {{"0.05", false}}}}}}};
  WriteFileAtomically(dir / "photos.json", photos.dump());
  const ExportCamera from_photos = ReadExportSource(dir / "photos.json");
  EXPECT_EQ(from_photos.truth.rig.camera.width, 4032);
  EXPECT_EQ(from_photos.truth.rig.camera.cx, 2015.5);
  EXPECT_EQ(from_photos.truth.rig.shutter.readout_s, 0.016);
  EXPECT_EQ(from_photos.make, "DJI");
  ASSERT_EQ(from_photos.photos.size(), 2u);  // the unreadable one left out
  EXPECT_TRUE(from_photos.photos[0].flagged);
  EXPECT_EQ(FileNamed(ColmapExport(from_photos, {}), "image_list.txt").text, "c.jpg\n");
  EXPECT_EQ(FileNamed(OdmExport(from_photos, {}), "image_list.txt").text, "/p/c.jpg\n");
  // Photos alone relate no gyro to the camera: Kalibr's camera chain alone (what its camera-IMU
  // calibration starts from), VINS told to calibrate the rotation and td, no sync offset for
  // Gyroflow.
  EXPECT_FALSE(from_photos.gyro_known);
  const ExportOutput kalibr = KalibrExport(from_photos, {});
  const std::string& chain = FileNamed(kalibr, "camchain.yaml").text;
  EXPECT_NE(chain.find("  intrinsics: [2566.1, 2566.1, 2015.5, 1133.5]\n"), std::string::npos)
      << chain;
  EXPECT_NE(chain.find("  line_delay_nanoseconds: "), std::string::npos) << chain;
  EXPECT_EQ(chain.find("T_cam_imu"), std::string::npos) << chain;
  EXPECT_EQ(chain.find("timeshift_cam_imu"), std::string::npos) << chain;
  const std::string vins_config = FileNamed(VinsExport(from_photos, {}), "vins_config.yaml").text;
  cv::FileStorage vins(vins_config, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  EXPECT_EQ(static_cast<int>(vins["estimate_extrinsic"]), 2);
  EXPECT_EQ(static_cast<int>(vins["estimate_td"]), 1);
  EXPECT_EQ(static_cast<double>(vins["td"]), 0.0);
  EXPECT_EQ(static_cast<double>(vins["rolling_shutter_tr"]), 0.016);
  EXPECT_TRUE(vins["extrinsicRotation"].empty()) << vins_config;
  EXPECT_FALSE(
      nlohmann::json::parse(FileNamed(GyroflowExport(from_photos, {}), "project.gyroflow").text)
          .contains("offsets"));
  EXPECT_TRUE(from_report.gyro_known);

  // A photo whose camera came from camera.json or a lens profile: its principal point and lens.
  nlohmann::json profiled = photos;
  profiled["photos"][0]["camera"] = {
      {"fx", 2570.0},
      {"fy", 2562.0},
      {"cx", 2010.0},
      {"cy", 1130.0},
      {"distortion", DistortionJson(Fisheye({0.06, 0.04, -0.04, 0.015}))}};
  WriteFileAtomically(dir / "profiled.json", profiled.dump());
  const PinholeCamera lens = ReadExportSource(dir / "profiled.json").truth.rig.camera;
  EXPECT_EQ(lens.fy, 2562.0);
  EXPECT_EQ(lens.cx, 2010.0);
  ASSERT_TRUE(std::holds_alternative<Fisheye>(lens.distortion));
  EXPECT_EQ(std::get<Fisheye>(lens.distortion).coeffs()[3], 0.015);

  WriteFileAtomically(dir / "other.json", "{\"format\": \"measure/1\"}");
  EXPECT_THROW(ReadExportSource(dir / "other.json"), IoError);
}

TEST(ExportFormats, EveryFormatWritesItsSideNoteLastAndUnknownNamesAreListed) {
  ExportOptions force;
  force.force = true;
  for (const ExportFormat& format : ExportFormats()) {
    const ExportOutput out = format.write(TestCamera(), force);
    ASSERT_FALSE(out.files.empty()) << format.name;
    EXPECT_EQ(out.files.back().name, "shutterlab_export.txt") << format.name;
    EXPECT_NE(out.files.back().text.find(std::string("--to ") + format.name), std::string::npos);
    EXPECT_EQ(&FindExportFormat(format.name), &format);
  }
  try {
    FindExportFormat("pix4dmapper");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("colmap, odm, kalibr, gyroflow, metashape, pix4d, vins"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace shutterlab
