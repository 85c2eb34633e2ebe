// Scoring a reconstruction against a survey's truth (render/survey_score.h) and reading COLMAP's
// text model (io/colmap_model.h): known answers from models built out of the truth itself.

#include "render/survey_score.h"

#include "io/colmap_model.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/render/survey_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// A written survey of 6 photos (test::SmallSurvey).
std::string WrittenSurvey(const test::TempDir& dir) {
  const SurveyOptions o = test::SmallSurvey();
  WriteSurvey(o, test::StillGyro(SurveyEndS(o) + 1.0), dir / "survey");
  return dir / "survey";
}

// What COLMAP would write for the truth seen through a similarity x_model = s R x_world + t:
// every photo (the `turn` of photo `turned` added to its orientation, photo `missing` left out)
// and points on the terrain (the last one `lift_m` above it).
struct ModelFromTruth {
  double scale = 0.2;
  Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::Vector3d translation = Eigen::Vector3d(3, -7, 11);
  int turned = -1;
  double turn_deg = 0.0;
  int missing = -1;
  double lift_m = 0.0;
};
void WriteModel(const SurveyTruth& truth, const ModelFromTruth& m, const std::string& dir) {
  fs::create_directories(dir);
  WriteFileAtomically(dir + "/cameras.txt",
                      "# Camera list with one line of data per camera:\n"
                      "1 PINHOLE 160 120 140 140 80 60\n");
  std::string images = "# Image list with two lines of data per image:\n";
  for (size_t k = 0; k < truth.photos.size(); ++k) {
    if (static_cast<int>(k) == m.missing) continue;
    Eigen::Matrix3d world_from_cam = truth.photos[k].mid.world_from_cam;
    if (static_cast<int>(k) == m.turned) {
      world_from_cam =
          world_from_cam * Eigen::AngleAxisd(m.turn_deg * kRadPerDeg, Eigen::Vector3d::UnitX());
    }
    // In the model: centre s R c + t, model_from_cam = R world_from_cam.
    const Eigen::Vector3d center =
        m.scale * m.rotation * truth.photos[k].mid.center_m + m.translation;
    const Eigen::Matrix3d cam_from_model = (m.rotation * world_from_cam).transpose();
    const Eigen::Vector3d t = -cam_from_model * center;
    const Eigen::Quaterniond q(cam_from_model);
    images += std::to_string(k + 1) + FormatNumber(" %.17g", q.w()) +
              FormatNumber(" %.17g", q.x()) + FormatNumber(" %.17g", q.y()) +
              FormatNumber(" %.17g", q.z()) + FormatNumber(" %.17g", t.x()) +
              FormatNumber(" %.17g", t.y()) + FormatNumber(" %.17g", t.z()) + " 1 images/" +
              truth.photos[k].name + "\n" + (k % 2 == 0 ? "10.5 20.5 1 30 40 -1\n" : "\n");
  }
  WriteFileAtomically(dir + "/images.txt", images);
  std::string points = "# 3D point list with one line of data per point:\n";
  const int n = 20;
  for (int i = 0; i < n; ++i) {
    const double x = 20 + 2.0 * i, y = 25 + 1.5 * i;
    const double z = *truth.terrain.HeightAt(x, y) + (i == n - 1 ? m.lift_m : 0.0);
    const Eigen::Vector3d p = m.scale * m.rotation * Eigen::Vector3d(x, y, z) + m.translation;
    points += std::to_string(i + 1) + FormatNumber(" %.17g", p.x()) +
              FormatNumber(" %.17g", p.y()) + FormatNumber(" %.17g", p.z()) + " 128 128 128 " +
              (i < 10 ? "0.5" : "1.0") + " 1 0 2 0" + (i < 10 ? "" : " 3 1") + "\n";
  }
  WriteFileAtomically(dir + "/points3D.txt", points);
}

TEST(ScoreReconstruction, TheTruthSeenThroughASimilarityScoresZero) {
  test::TempDir dir;
  const SurveyTruth truth = ReadSurveyTruth(WrittenSurvey(dir));
  ASSERT_EQ(truth.photos.size(), 6u);
  WriteModel(truth, {}, dir / "model");
  const ReconstructionScore score = ScoreReconstruction(truth, dir / "model");
  EXPECT_EQ(score.registered, 6u);
  EXPECT_NEAR(score.alignment_scale, 5.0, 1e-9) << "metres per model unit: 1 / 0.2";
  EXPECT_LT(score.horizontal_rms_m, 1e-8);
  EXPECT_LT(std::abs(score.vertical_rms_m), 1e-8);
  EXPECT_LT(score.orientation_rms_deg, 1e-6);
  EXPECT_EQ(score.points, 20u);
  EXPECT_EQ(score.points_on_terrain, 20u);
  EXPECT_LT(score.point_rms_m, 1e-8);
  // Ten points seen twice at 0.5 px, ten seen three times at 1 px: (10 + 30) / 50 = 0.8 px.
  EXPECT_NEAR(score.mean_reprojection_error_px, 0.8, 1e-12);
  EXPECT_TRUE(score.notes.empty());
}

TEST(ScoreReconstruction, ATurnedPhotoALiftedPointAndAMissingPhotoAreEachMeasured) {
  test::TempDir dir;
  const SurveyTruth truth = ReadSurveyTruth(WrittenSurvey(dir));
  ModelFromTruth m;
  m.turned = 2;
  m.turn_deg = 0.5;
  m.missing = 4;
  m.lift_m = 0.8;
  WriteModel(truth, m, dir / "model");
  const ReconstructionScore score = ScoreReconstruction(truth, dir / "model");
  EXPECT_EQ(score.registered, 5u);
  EXPECT_FALSE(score.per_photo[4].registered);
  EXPECT_NEAR(score.per_photo[2].orientation_error_deg, 0.5, 1e-6);
  EXPECT_NEAR(score.per_photo[1].orientation_error_deg, 0.0, 1e-6);
  EXPECT_NEAR(score.orientation_rms_deg, 0.5 / std::sqrt(5.0), 1e-6);
  EXPECT_LT(score.horizontal_rms_m, 1e-8) << "a turn leaves the centres";
  EXPECT_NEAR(score.point_rms_m, 0.8 / std::sqrt(20.0), 1e-7);
  EXPECT_LT(score.point_median_m, 1e-8);
  ASSERT_EQ(score.notes.size(), 1u);
  EXPECT_EQ(score.notes[0], "1 photo(s) not registered");
}

TEST(ScoreReconstruction, CamerasOnOneLineLeaveTheRollUndeterminedAndSayIt) {
  // Only the first line's three photos registered: their centres lie on a line, about which the
  // alignment could turn freely; the centres are scored, the orientations and points are not.
  test::TempDir dir;
  const SurveyTruth truth = ReadSurveyTruth(WrittenSurvey(dir));
  WriteModel(truth, {}, dir / "model");
  std::string images = ReadFileToString(dir / "model/images.txt"), kept;
  size_t start = 0;
  for (int line = 0; start < images.size(); ++line) {
    const size_t end = images.find('\n', start);
    // The header line, then two lines an image: keep the first three images (lines 1-6).
    if (line <= 6) kept += images.substr(start, end - start + 1);
    start = end + 1;
  }
  WriteFileAtomically(dir / "model/images.txt", kept + "\n\n");  // trailing blank lines too
  const ReconstructionScore score = ScoreReconstruction(truth, dir / "model");
  EXPECT_EQ(score.registered, 3u);
  EXPECT_LT(score.horizontal_rms_m, 1e-8);
  EXPECT_TRUE(std::isnan(score.orientation_rms_deg));
  EXPECT_TRUE(std::isnan(score.point_median_m));
  ASSERT_FALSE(score.notes.empty());
  EXPECT_NE(score.notes.back().find("lie on one line"), std::string::npos) << score.notes.back();
}

TEST(ColmapModel, MalformedLinesAndABinaryModelAreNamed) {
  test::TempDir dir;
  const SurveyTruth truth = ReadSurveyTruth(WrittenSurvey(dir));
  WriteModel(truth, {}, dir / "model");
  WriteFileAtomically(dir / "model/images.txt", "# header\n1 1 0 0 0 0 0 0 1\n\n");
  try {
    ReadColmapTextModel(dir / "model");
    FAIL() << "an image line without a name";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("images.txt:2: an image line needs"), std::string::npos)
        << e.what();
  }
  WriteFileAtomically(dir / "model/images.txt", "1 2 0 0 0 0 0 0 1 a.jpg\n\n");
  EXPECT_THROW(ReadColmapTextModel(dir / "model"), IoError) << "not a unit quaternion";
  fs::create_directories(dir / "binary");
  WriteFileAtomically(dir / "binary/cameras.bin", "");
  try {
    ReadColmapTextModel(dir / "binary");
    FAIL() << "a binary model";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("colmap model_converter"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace shutterlab
