#include "io/import_io.h"

#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

namespace shutterlab {
namespace {

using nlohmann::json;

ImportRecord CommonRecord() {
  ImportRecord r;
  r.path = "clip";
  r.time_origin_s = 4328040.0;
  r.clock = "device clock";
  r.gyro_samples = 3;
  r.gyro_rate_hz = 412.5;
  r.gyro_columns = "gx,gy,gz";
  r.frame_count = 2;
  r.t_first_row = "start of frame";
  r.outside_gyro = {7};
  r.exposures = {{7, 0.005}, {8, std::nullopt}};
  Eigen::Matrix3d m;
  m << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  r.claims = {{"intrinsics", std::map<std::string, double>{{"fy", 2.0}, {"fx", 1.0}},
               ClaimStatus::kSourceClaim, "the source"},
              {"readout_s", 0.033, ClaimStatus::kGuess, "a guess"},
              {"gyro_to_camera", m, ClaimStatus::kSourceClaimInferred, "both"},
              {"direction", std::string("top_to_bottom"), ClaimStatus::kInferred, "the data"}};
  r.warnings = {{"gap", "1 interval(s) over 3x the median", 12.5, 1}};
  return r;
}

TEST(ImportIo, ClaimValuesAsCompactJson) {
  EXPECT_EQ(ClaimValueJson(0.015), "0.015");
  EXPECT_EQ(ClaimValueJson(0.0), "0.0");
  EXPECT_EQ(ClaimValueJson(std::string("top_to_bottom")), "\"top_to_bottom\"");
  Eigen::Matrix3d m;
  m << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  EXPECT_EQ(ClaimValueJson(m), "[[0.0,-1.0,0.0],[0.0,0.0,-1.0],[1.0,0.0,0.0]]");  // rows
  EXPECT_EQ(ClaimValueJson(std::map<std::string, double>{{"fx", 573.8534}, {"cx", 406.0101}}),
            "{\"cx\":406.0101,\"fx\":573.8534}");
}

TEST(ImportIo, StatusNamesAreTheFormatsWords) {
  EXPECT_STREQ(ClaimStatusName(ClaimStatus::kSourceClaim), "source claim");
  EXPECT_STREQ(ClaimStatusName(ClaimStatus::kInferred), "inferred");
  EXPECT_STREQ(ClaimStatusName(ClaimStatus::kSourceClaimInferred), "source claim + inferred");
  EXPECT_STREQ(ClaimStatusName(ClaimStatus::kGuess), "guess");
}

TEST(ImportIo, PhoneRecordHoldsTheCommonFieldsAndThePhoneExtras) {
  ImportRecord r = CommonRecord();
  PhoneImportDetails phone;
  phone.origin = "a repository";
  phone.sof_times = 2146;
  phone.images_in_source = 20;
  phone.dump_sof_max_diff_s = 1e-6;
  phone.exposure_min_s = 0.004946;
  phone.exposure_max_s = 0.005906;
  r.details = phone;
  const std::string text = ImportJson(r);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  EXPECT_EQ(text.rfind("{\n  \"claims\": [\n    {\n      \"source\": \"the source\",", 0), 0u)
      << text;  // two-space indent, keys sorted
  const json j = json::parse(text);
  EXPECT_EQ(j["format"], "import/1");
  EXPECT_EQ(j["source"],
            (json{{"kind", "phone_folder"}, {"path", "clip"}, {"origin", "a repository"}}));
  EXPECT_EQ(j["time_origin_s"], 4328040.0);
  EXPECT_EQ(j["clock"], "device clock");
  EXPECT_EQ(j["gyro"], (json{{"samples", 3}, {"rate_hz", 412.5}, {"columns", "gx,gy,gz"}}));
  EXPECT_EQ(j["frames"], (json{{"count", 2},
                               {"t_first_row", "start of frame"},
                               {"outside_gyro", {7}},
                               {"sof_times", 2146},
                               {"images_in_source", 20},
                               {"dump_sof_max_diff_s", 1e-6}}));
  EXPECT_EQ(j["exposure_s"], json::parse(R"([{"frame":7,"exposure_s":0.005},
                                             {"frame":8,"exposure_s":null}])"));
  EXPECT_EQ(j["exposure_range_s"], json::parse("[0.004946, 0.005906]"));
  ASSERT_EQ(j["claims"].size(), 4u);
  EXPECT_EQ(j["claims"][0], json::parse(R"({"what":"intrinsics","value":{"fx":1.0,"fy":2.0},
                                            "status":"source claim","source":"the source"})"));
  EXPECT_EQ(j["claims"][2]["value"], json::parse("[[0,-1,0],[-1,0,0],[0,0,-1]]"));
  EXPECT_EQ(j["claims"][2]["status"], "source claim + inferred");
  EXPECT_EQ(j["claims"][3]["value"], "top_to_bottom");
  EXPECT_EQ(j["warnings"],
            json::parse(R"([{"kind":"gap","message":"1 interval(s) over 3x the median",
                                            "t_s":12.5,"count":1}])"));
  EXPECT_EQ(j.size(), 10u);  // nothing of the GoPro's

  // No exposure known: the range is written as nulls.
  phone.exposure_min_s = INFINITY;
  phone.exposure_max_s = -INFINITY;
  r.details = phone;
  EXPECT_EQ(json::parse(ImportJson(r))["exposure_range_s"], json::parse("[null, null]"));
}

TEST(ImportIo, GoproRecordHoldsTheGoproExtrasAndIsWrittenWhole) {
  ImportRecord r = CommonRecord();
  GoproImportDetails gopro;
  gopro.device = "Camera";
  gopro.stream_name = "Gyroscope (z,x,y)";
  gopro.axis_order = "STNM 'Gyroscope (z,x,y)'";
  gopro.scal = {3755};
  gopro.payload_samples = {392, 28};
  gopro.timing = "one line";
  gopro.fit_max_residual_s = 0.009;
  gopro.decoding.video_samples = 362;
  gopro.decoding.decoded = 362;
  gopro.decoding.failed_grabs = 1;
  gopro.times = "sample table";
  r.details = gopro;
  test::TempDir dir;
  WriteImportJson(dir / "import.json", r);
  const std::string text = ReadFileToString(dir / "import.json");
  EXPECT_EQ(text, ImportJson(r));
  const json j = json::parse(text);
  EXPECT_EQ(j["source"], (json{{"kind", "gopro_mp4"}, {"path", "clip"}, {"device", "Camera"}}));
  EXPECT_EQ(j["gyro"]["stream_name"], "Gyroscope (z,x,y)");
  EXPECT_EQ(j["gyro"]["axis_order"], "STNM 'Gyroscope (z,x,y)'");
  EXPECT_EQ(j["gyro"]["scal"], json::parse("[3755.0]"));
  EXPECT_EQ(j["gyro"]["payload_samples"], json::parse("[392, 28]"));
  EXPECT_EQ(j["gyro"]["timing"], "one line");
  EXPECT_EQ(j["gyro"]["fit_max_residual_s"], 0.009);
  EXPECT_EQ(j["gyro"].size(), 9u);
  EXPECT_EQ(j["frames"]["video_samples"], 362);
  EXPECT_EQ(j["frames"]["decoded"], 362);
  EXPECT_EQ(j["frames"]["failed_grabs"], 1);
  EXPECT_EQ(j["frames"]["reader_time_mismatches"], 0);
  EXPECT_EQ(j["frames"]["times"], "sample table");
  EXPECT_EQ(j["frames"].size(), 8u);
  EXPECT_FALSE(j.contains("exposure_range_s"));
  EXPECT_EQ(j.size(), 9u);
}

}  // namespace
}  // namespace shutterlab
