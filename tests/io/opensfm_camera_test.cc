// OpenSfM's cameras read as a lens profile, against OpenSfM's own projection equations written out
// from its documentation (doc/source/geometry.rst): normalised coordinates n = f d(x) + c scaled by
// S = max(width, height) about the image centre, pixel = S n + (size - 1) / 2 in OpenCV's pixel
// centres (OpenSfM's pixel coordinates have their corner at -size / 2 S).

#include "io/opensfm_camera.h"

#include "io/lens_profile.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

namespace shutterlab {
namespace {

using nlohmann::json;

// OpenSfM's distortion of a normalised point, per projection type.
Eigen::Vector2d OpenSfmDistorted(const json& c, double x, double y) {
  const std::string type = c["projection_type"];
  const auto k = [&](const char* name) { return c.value(name, 0.0); };
  const double r2 = x * x + y * y;
  if (type == "perspective") {
    const double d = 1 + k("k1") * r2 + k("k2") * r2 * r2;
    return {d * x, d * y};
  }
  if (type == "brown") {
    const double d = 1 + k("k1") * r2 + k("k2") * r2 * r2 + k("k3") * r2 * r2 * r2;
    return {d * x + 2 * k("p1") * x * y + k("p2") * (r2 + 2 * x * x),
            d * y + 2 * k("p2") * x * y + k("p1") * (r2 + 2 * y * y)};
  }
  const double r = std::sqrt(r2), theta = std::atan(r), t2 = theta * theta;
  double d = 1 + k("k1") * t2 + k("k2") * t2 * t2;
  if (type == "fisheye_opencv") d += k("k3") * t2 * t2 * t2 + k("k4") * t2 * t2 * t2 * t2;
  return {theta * d * x / r, theta * d * y / r};
}

TEST(OpenSfmCamera, EveryProjectionReadsAsOpenSfmProjectsIt) {
  const json cameras[] = {{{"projection_type", "perspective"},
                           {"width", 4000},
                           {"height", 3000},
                           {"focal", 0.85},
                           {"k1", -0.08},
                           {"k2", 0.01}},
                          {{"projection_type", "brown"},
                           {"width", 4032},
                           {"height", 2268},
                           {"focal_x", 0.7213},
                           {"focal_y", 0.7201},
                           {"c_x", 0.0041},
                           {"c_y", -0.0062},
                           {"k1", -0.11},
                           {"k2", 0.04},
                           {"k3", -0.006},
                           {"p1", 0.0009},
                           {"p2", -0.0004}},
                          {{"projection_type", "fisheye"},
                           {"width", 1920},
                           {"height", 1080},
                           {"focal", 0.45},
                           {"k1", 0.03},
                           {"k2", -0.01}},
                          {{"projection_type", "fisheye_opencv"},
                           {"width", 2704},
                           {"height", 1520},
                           {"focal_x", 0.52},
                           {"focal_y", 0.521},
                           {"c_x", 0.002},
                           {"c_y", 0.001},
                           {"k1", 0.046},
                           {"k2", 0.005},
                           {"k3", 0.021},
                           {"k4", -0.018}}};
  test::TempDir dir;
  for (const json& c : cameras) {
    WriteFileAtomically(dir / "cameras.json",
                        json{{"v2 dji fc6310 4000 3000 perspective 0.85", c}}.dump());
    const LensProfile p = ReadLensProfile(dir / "cameras.json");
    const int w = c["width"], h = c["height"];
    EXPECT_EQ(p.camera.width, w);
    EXPECT_EQ(p.camera.height, h);
    EXPECT_FALSE(p.mode.readout_s);
    const double s = std::max(w, h);
    const bool one_focal = c.contains("focal");
    const double fx = one_focal ? c["focal"].get<double>() : c["focal_x"].get<double>();
    const double fy = one_focal ? fx : c["focal_y"].get<double>();
    for (double u : {-0.6, -0.2, 0.0, 0.3, 0.55}) {
      for (double v : {-0.4, 0.1, 0.35}) {
        const Eigen::Vector2d d = OpenSfmDistorted(c, u, v);
        const double nx = fx * d.x() + c.value("c_x", 0.0), ny = fy * d.y() + c.value("c_y", 0.0);
        const Eigen::Vector2d ours = *p.camera.ImgFromCam(Eigen::Vector3d(u, v, 1.0));
        EXPECT_NEAR(s * nx + (w - 1) / 2.0, ours.x(), 1e-7) << c["projection_type"];
        EXPECT_NEAR(s * ny + (h - 1) / 2.0, ours.y(), 1e-7) << c["projection_type"];
      }
    }
  }
}

TEST(OpenSfmCamera, RefusesWhatItCannotTakeNamingIt) {
  test::TempDir dir;
  const json brown = {{"projection_type", "brown"},
                      {"width", 100},
                      {"height", 80},
                      {"focal_x", 0.8},
                      {"focal_y", 0.8},
                      {"c_x", 0},
                      {"c_y", 0}};
  const auto error = [&](const json& j) {
    WriteFileAtomically(dir / "cameras.json", j.dump());
    try {
      ReadLensProfile(dir / "cameras.json");
    } catch (const IoError& e) {
      return std::string(e.what());
    }
    return std::string("read");
  };
  EXPECT_NE(error({{"a", brown}, {"b", brown}}).find("2 cameras"), std::string::npos);
  json spherical = brown;
  spherical["projection_type"] = "spherical";
  EXPECT_NE(error({{"all", spherical}}).find("spherical"), std::string::npos);
  json no_width = brown;
  no_width.erase("width");
  EXPECT_NE(error({{"all", no_width}}).find("no width"), std::string::npos);
  json bad_focal = brown;
  bad_focal["focal_x"] = "wide";
  EXPECT_NE(error({{"all", bad_focal}}).find("focal_x"), std::string::npos);
  EXPECT_NE(error({{"all", bad_focal}}).find("cameras.json"), std::string::npos);
  // Several cameras with an "all" take "all" (camera_models_overrides.json's key for every image).
  EXPECT_EQ(error({{"all", brown}, {"b", spherical}}), "read");
  EXPECT_FALSE(IsOpenSfmCameras(json{{"name", "a profile"}}));
}

}  // namespace
}  // namespace shutterlab
