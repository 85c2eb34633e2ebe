// `analyze --photos`: a folder of photos, without and with a log.

#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/photo_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

using test::RunShutterlab;

// The case: three nadir DJI Mini 4 Pro photos at 117.9 m flying about 7 m/s. Their readout
// comes from the table (16 ms for the 9.1 MP 16:9 mode) and says so; D = v * 16 ms * f / h with f
// from the 24 mm equivalent on the 4032 x 2268 diagonal (2566.1 px).
TEST(PhotosCli, DjiMini4ProTranslationOnly) {
  SHUTTERLAB_REAL_DATA(dir, "incoming/dji_fc8482_clusterodm");
  const auto text = RunShutterlab("analyze --photos " + dir);
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.out.find("16 ms (table: dji fc8482 (Mini 4 Pro)"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("translation only"), std::string::npos);
  EXPECT_NE(text.out.find("test-photo-1.jpg"), std::string::npos);

  const auto r = RunShutterlab("analyze --photos " + dir + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["photos"].size(), 3u);
  const double speeds[3] = {6.9, 7.0, std::hypot(0.3, 4.6)};
  for (size_t i = 0; i < 3; ++i) {
    const nlohmann::json& p = j["photos"][i];
    EXPECT_EQ(p["readout_origin"], "table");
    EXPECT_DOUBLE_EQ(p["readout_s"].get<double>(), 0.016);
    EXPECT_DOUBLE_EQ(p["altitude_m"].get<double>(), 117.9);
    EXPECT_DOUBLE_EQ(p["speed_m_s"].get<double>(), speeds[i]);
    EXPECT_NEAR(p["D_translation_px"].get<double>(), speeds[i] * 0.016 * 2566.1014 / 117.9, 1e-4);
    EXPECT_NEAR(p["D_translation_m"].get<double>(), speeds[i] * 0.016, 1e-12);
  }
  EXPECT_EQ(j["summary"]["readout_from_table"], 3);

  // --readout overrides the table, and says so.
  const auto own = RunShutterlab("analyze --photos " + dir + " --readout 10ms --json");
  ASSERT_EQ(own.exit_code, 0) << own.output;
  const nlohmann::json o = nlohmann::json::parse(own.out);
  EXPECT_EQ(o["photos"][0]["readout_origin"], "user");
  EXPECT_NEAR(o["photos"][0]["D_translation_m"].get<double>(), 0.069, 1e-12);
  EXPECT_EQ(o["summary"]["readout_from_table"], 0);
}

TEST(PhotosCli, BadPhotosAreReportedAndAFolderWithoutPhotosIsAnError) {
  test::TempDir dir;
  test::FixturePhoto p;
  p.focal_length_35mm = 24;
  p.xmp = test::DjiXmp({{"RelativeAltitude", "+60"},
                        {"FlightXSpeed", "5"},
                        {"FlightYSpeed", "0"},
                        {"FlightZSpeed", "0"}},
                       false);
  std::filesystem::create_directories(dir / "photos");
  std::filesystem::create_directories(dir / "empty");
  WriteFileAtomically(dir / "photos/DJI_0001.JPG", test::JpegWithMetadata(p));
  WriteFileAtomically(dir / "photos/DJI_0002.JPG", "cut off");
  const auto r = RunShutterlab("analyze --photos " + (dir / "photos") + " --readout 20ms --out " +
                               (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.out.find("DJI_0002.JPG: unreadable"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("DJI_0001.JPG: no capture time"), std::string::npos) << r.out;
  EXPECT_EQ(ReadFileToString(dir / "out/exclude.txt"), "DJI_0001.JPG\nDJI_0002.JPG\n")
      << "5 m/s x 20 ms = 10 cm is over 5 cm; the unreadable photo is excluded too";

  WriteFileAtomically(dir / "empty/notes.txt", "x");
  const auto none = RunShutterlab("analyze --photos " + (dir / "empty"));
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("no photo files"), std::string::npos) << none.err;
  const auto neither = RunShutterlab("analyze");
  EXPECT_EQ(neither.exit_code, 2);
  EXPECT_NE(neither.err.find("--photos"), std::string::npos) << neither.err;
}

}  // namespace
}  // namespace shutterlab
