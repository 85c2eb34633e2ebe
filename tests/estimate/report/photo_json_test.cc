// `analyze --photos --json`: the keys docs/FORMATS.md names, nulls where a value is unknown, the
// readout's origin spelt out, an unreadable photo as name, path and error only.

#include "estimate/report/photo_json.h"

#include "tests/io/photo_fixtures.h"

#include <gtest/gtest.h>

#include <string>

namespace shutterlab {
namespace {

PhotoSet TwoPhotos() {
  PhotoMetadata m = test::DjiMini3Metadata(100.0, Eigen::Vector3d(5.0, 0.0, 0.0));
  std::string problem;
  m.capture_time = ParseExifDateTime("2024:07:16 09:41:37", "5", "+02:00", &problem);
  PhotoSet set;
  set.source = "/p";
  set.photos.push_back(MakePhotoRecord("/p/DJI_0001.JPG", m, {}));
  PhotoRecord broken;
  broken.path = "/p/DJI_0002.JPG";
  broken.name = "DJI_0002.JPG";
  broken.error = "/p/DJI_0002.JPG: cannot read the photo's metadata";
  set.photos.push_back(broken);
  return set;
}

TEST(PhotoAnalysisToJson, NamesSourcesAndNullsAsTheContractSays) {
  const PhotoSet set = TwoPhotos();
  const nlohmann::json j = PhotoAnalysisToJson(set, AnalyzePhotos(set, {}));
  EXPECT_EQ(j["model"], "translation only (recorded speed)");
  ASSERT_EQ(j["photos"].size(), 2u);
  const nlohmann::json& p = j["photos"][0];
  EXPECT_EQ(p["readout_origin"], "table");
  EXPECT_DOUBLE_EQ(p["readout_s"].get<double>(), 0.016);
  EXPECT_NE(p["readout_source"].get<std::string>().find("OpenDroneMap"), std::string::npos);
  EXPECT_DOUBLE_EQ(p["D_translation_m"].get<double>(), 5.0 * 0.016);
  EXPECT_TRUE(p["along_readout_px"].is_null()) << "no gimbal attitude: no split";
  EXPECT_TRUE(p["exposure_s"].is_null());
  EXPECT_EQ(p["capture_time"]["utc_offset"], "+02:00");
  EXPECT_EQ(p["capture_time"]["utc"], "2024-07-16 07:41:37.500");
  EXPECT_DOUBLE_EQ(p["capture_time"]["resolution_s"].get<double>(), 0.1);
  EXPECT_EQ(p["flagged"]["0.05"], true);
  EXPECT_EQ(p["flagged"]["0.1"], false);
  EXPECT_TRUE(p["missing"].empty());
  EXPECT_FALSE(p.contains("t")) << "placement keys only with a log";
  const nlohmann::json& bad = j["photos"][1];
  EXPECT_EQ(bad.size(), 3u) << bad.dump();
  EXPECT_NE(bad["error"].get<std::string>().find("DJI_0002.JPG"), std::string::npos);
  EXPECT_EQ(j["summary"]["read"], 1);
  EXPECT_EQ(j["summary"]["readout_from_table"], 1);
  EXPECT_EQ(j["summary"]["flagged"], nlohmann::json::array({1, 0}));
}

}  // namespace
}  // namespace shutterlab
