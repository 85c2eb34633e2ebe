// `analyze --photos`: a folder of photos, without and with a log.

#include "model/camera.h"
#include "sim/civil_time.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/ulog_write.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/app/placed_flight.h"
#include "tests/io/photo_fixtures.h"
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
  test::TempDir out;
  const auto text = RunShutterlab("analyze --photos " + dir + " --out " + (out / "o"));
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.out.find("16 ms (table: dji fc8482 (Mini 4 Pro)"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("translation only"), std::string::npos);
  EXPECT_NE(text.out.find("3 over 5 cm, 2 over 10 cm"), std::string::npos) << text.out;
  // photos.csv: readout_s, readout_origin, altitude_m, speed_m_s ... D_translation_m.
  const std::string csv = ReadFileToString(out / "o/photos.csv");
  EXPECT_NE(csv.find("test-photo-1.jpg,DJI,FC8482,4032,2268,2566.101382972291,0.016,table,117.9,"
                     "6.9,,,,0.11040000000000001,"),
            std::string::npos)
      << csv;
  EXPECT_EQ(ReadFileToString(out / "o/exclude.txt"),
            "test-photo-1.jpg\ntest-photo-2.jpg\ntest-photo-3.jpg\n");

  // --readout overrides the table, and says so.
  const auto r = RunShutterlab("analyze --photos " + dir + " --readout 10ms --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["photos"].size(), 3u);
  const double speeds[3] = {6.9, 7.0, std::hypot(0.3, 4.6)};
  for (size_t i = 0; i < 3; ++i) {
    const nlohmann::json& p = j["photos"][i];
    EXPECT_EQ(p["readout_origin"], "user");
    EXPECT_DOUBLE_EQ(p["altitude_m"].get<double>(), 117.9);
    EXPECT_DOUBLE_EQ(p["speed_m_s"].get<double>(), speeds[i]);
    EXPECT_NEAR(p["D_translation_px"].get<double>(), speeds[i] * 0.010 * 2566.1014 / 117.9, 1e-4);
    EXPECT_NEAR(p["D_translation_m"].get<double>(), speeds[i] * 0.010, 1e-12);
  }
  EXPECT_EQ(j["summary"]["readout_from_table"], 0);
}

// Phantom 3 photos (2015) hold no height above take-off, only EXIF GPSAltitude (122.3 and
// 119.7 m): no altitude, and the hint names both options; --ground-elevation derives one per photo
// and says so; an elevation above the photos is refused for each, said why.
TEST(PhotosCli, AltitudeDerivedFromTheGpsAltitudeAndTheGroundElevation) {
  SHUTTERLAB_REAL_DATA(dir, "images/odm_toledo");
  const auto plain = RunShutterlab("analyze --photos " + dir);
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_NE(plain.out.find("--ground-elevation M (with the photos' GPS altitude)"),
            std::string::npos)
      << plain.out;
  const auto derived = RunShutterlab("analyze --photos " + dir + " --ground-elevation 80m --json");
  ASSERT_EQ(derived.exit_code, 0) << derived.output;
  const nlohmann::json j = nlohmann::json::parse(derived.out);
  ASSERT_EQ(j["photos"].size(), 2u);
  EXPECT_NEAR(j["photos"][0]["altitude_m"].get<double>(), 42.3, 1e-9);
  EXPECT_NEAR(j["photos"][1]["altitude_m"].get<double>(), 39.7, 1e-9);
  EXPECT_EQ(j["photos"][0]["altitude_source"],
            "derived: 42.3 m, EXIF GPSAltitude 122.3 m minus --ground-elevation 80.0 m");
  const auto above = RunShutterlab("analyze --photos " + dir + " --ground-elevation 180m --json");
  ASSERT_EQ(above.exit_code, 0) << above.output;
  const nlohmann::json a = nlohmann::json::parse(above.out);
  EXPECT_TRUE(a["photos"][0]["altitude_m"].is_null());
  EXPECT_NE(a["photos"][0]["altitude_source"].get<std::string>().find("not above the ground"),
            std::string::npos);
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
  // A photo cut inside its image data, its metadata whole (a card pulled while writing), slow
  // enough to pass on its metadata alone.
  test::FixturePhoto slow = p;
  slow.width = 640;
  slow.height = 480;
  slow.xmp = test::DjiXmp({{"RelativeAltitude", "+60"},
                           {"FlightXSpeed", "0.5"},
                           {"FlightYSpeed", "0"},
                           {"FlightZSpeed", "0"}},
                          false);
  const std::string whole = test::JpegWithMetadata(slow);
  const size_t scan = whole.find("\xff\xda");
  WriteFileAtomically(dir / "photos/DJI_0003.JPG", whole.substr(0, (scan + whole.size()) / 2));
  WriteFileAtomically(dir / "photos/DJI_0004.JPG", whole);
  const auto r = RunShutterlab("analyze --photos " + (dir / "photos") + " --readout 20ms --out " +
                               (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.out.find("DJI_0002.JPG: unreadable"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("DJI_0003.JPG: unreadable"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("DJI_0001.JPG: no capture time"), std::string::npos) << r.out;
  EXPECT_EQ(ReadFileToString(dir / "out/exclude.txt"), "DJI_0001.JPG\nDJI_0002.JPG\nDJI_0003.JPG\n")
      << "5 m/s x 20 ms = 10 cm is over 5 cm; the unreadable and the cut photo are excluded too";
  EXPECT_EQ(ReadFileToString(dir / "out/colmap_image_list.txt"), "DJI_0004.JPG\n");
  // The page for a person, announced: the verdict, each D beside the ground a pixel covers, the
  // excluded photos with their reasons, and what the photogrammetry tool's option removes.
  EXPECT_NE(r.err.find("wrote " + (dir / "out") + "/: report.html, photos.csv, exclude.txt"),
            std::string::npos)
      << r.err;
  const std::string page = ReadFileToString(dir / "out/report.html");
  for (const std::string& text :
       {std::string("2 of 4 photos predicted"), std::string("ground cm/px"),
        std::string("excluded: " + (dir / "photos/DJI_0003.JPG") +
                    ": its image data does not decode"),
        std::string("What your photogrammetry tool already removes"),
        std::string("--rolling-shutter-readout"),
        std::string("What correcting buys in the map (an estimate)"),
        std::string("without rotation"),
        std::string("0.24 times the median D off horizontally: here ")}) {
    EXPECT_NE(page.find(text), std::string::npos) << text;
  }
  test::ExpectDrawsInChromium(dir / "out/report.html", 0, "photos_report");
  EXPECT_NE(r.out.find("DJI_0003.JPG: its image data does not decode (Premature end of JPEG "
                       "file): a cut or damaged file; copy it from the card again"),
            std::string::npos)
      << r.out;

  WriteFileAtomically(dir / "empty/notes.txt", "x");
  const auto none = RunShutterlab("analyze --photos " + (dir / "empty"));
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("no photo files"), std::string::npos) << none.err;
  const auto neither = RunShutterlab("analyze");
  EXPECT_EQ(neither.exit_code, 2);
  EXPECT_NE(neither.err.find("--photos"), std::string::npos) << neither.err;
}

// A synthetic flight whose events and capture times we control: a PX4 ULog (200 Hz gyro, still for
// 5 s then swaying about x, five camera_capture events 2 s apart, GPS time every second) and five
// DJI photos whose camera clock is UTC+08:00 off by a few ms. Each photo must land on its event,
// with the camera clock's offset and the residuals reported, and carry analyze's rotation beside
// its own translation.
// --export: the photos' camera in each tool's files beside the lists, as `shutterlab export` writes
// it from the same result's JSON; a format that fails stops the command before anything is
// written.
TEST(PhotosCli, ExportsThePhotosCameraBesideTheListsOrWritesNothing) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "photos");
  for (int k = 0; k < 2; ++k) {
    test::FixturePhoto p;
    p.width = 400;
    p.height = 300;
    p.focal_length_35mm = 24;
    p.xmp = test::DjiXmp({{"RelativeAltitude", "+80.0"}, {"FlightXSpeed", "4.0"}}, false);
    WriteFileAtomically(dir / ("photos/P" + std::to_string(k) + ".JPG"), test::JpegWithMetadata(p));
  }
  const std::string photos = "analyze --photos " + (dir / "photos") + " --readout 20ms";
  const auto r = RunShutterlab(photos + " --out " + (dir / "out") + " --export odm,pix4d");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out/image_list.txt"));
  EXPECT_EQ(ReadFileToString(dir / "out/export_odm/odm_args.txt"),
            "--rolling-shutter --rolling-shutter-readout 20\n");
  const nlohmann::json opf =
      nlohmann::json::parse(ReadFileToString(dir / "out/export_pix4d/calibrated_cameras.json"));
  EXPECT_EQ(opf["sensors"][0]["internals"]["principal_point_px"], nlohmann::json({200.0, 150.0}));
  EXPECT_NE(r.err.find("export_pix4d/: calibrated_cameras.json"), std::string::npos) << r.err;
  // The same files as `shutterlab export` makes from the --json result.
  const auto json = RunShutterlab(photos + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  WriteFileAtomically(dir / "photos.json", json.out);
  ASSERT_EQ(RunShutterlab("export " + (dir / "photos.json") + " --to odm --out " + (dir / "odm"))
                .exit_code,
            0);
  EXPECT_EQ(ReadFileToString(dir / "odm/camera_models_overrides.json"),
            ReadFileToString(dir / "out/export_odm/camera_models_overrides.json"));

  // camera.json's lens goes into the exports with its principal point (COLMAP's OPENCV camera:
  // fx, fy, cx, cy, k1, k2, p1, p2; its pixel centres at half-integers: cx + 0.5).
  RigModel rig;
  rig.camera.width = 400;
  rig.camera.height = 300;
  rig.camera.fx = rig.camera.fy = 350.0;
  rig.camera.cx = 201.0;
  rig.camera.cy = 148.0;
  rig.camera.distortion = BrownConrady{{-0.12, 0.03, 0.001, -0.002, 0}};
  rig.shutter.readout_s = 0.020;
  WriteRigModel(dir / "camera.json", rig);
  const auto lens = RunShutterlab(photos + " --camera " + (dir / "camera.json") + " --out " +
                                  (dir / "lens") + " --export colmap");
  ASSERT_EQ(lens.exit_code, 0) << lens.output;
  EXPECT_NE(ReadFileToString(dir / "lens/export_colmap/cameras.txt")
                .find("1 OPENCV 400 300 350 350 201.5 148.5 -0.12 0.03 0.001 -0.002"),
            std::string::npos)
      << ReadFileToString(dir / "lens/export_colmap/cameras.txt");

  // Photos alone relate no gyro to the camera: Kalibr gets the camera chain alone.
  const auto chain = RunShutterlab(photos + " --out " + (dir / "chain") + " --export kalibr,vins");
  ASSERT_EQ(chain.exit_code, 0) << chain.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "chain/export_kalibr/camchain.yaml"));
  EXPECT_TRUE(std::filesystem::exists(dir / "chain/export_vins/vins_config.yaml"));
  // A format that fails after odm's files were made (in memory) leaves nothing written.
  const auto refused =
      RunShutterlab(photos + " --out " + (dir / "refused") + " --export odm,pix4dmapper");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_EQ(test::LineCount(refused.err), 1u) << refused.err;
  EXPECT_NE(refused.err.find("pix4dmapper"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "refused")) << refused.output;
  EXPECT_EQ(RunShutterlab(photos + " --export odm").exit_code, 2);  // no --out
}

TEST(PhotosCli, PlacesPhotosOnASyntheticLogAndReportsTheResidual) {
  test::TempDir dir;
  const int error_ms[5] = {4, -3, 0, 2, -1};  // median 0
  const std::vector<CameraEvent> events = test::WritePlacedFlight(dir.path().string(), error_ms);
  const auto r = RunShutterlab("analyze --photos " + (dir / "photos") + " " + (dir / "flight.ulg") +
                               " --json --out " + (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const nlohmann::json& photos = j["photos"];
  EXPECT_NEAR(photos["placement"]["clock_offset_s"].get<double>(), 8 * 3600.0, 1e-6);
  double sum_sq = 0;
  for (int k = 0; k < 5; ++k) {
    const nlohmann::json& p = photos["photos"][k];
    SCOPED_TRACE(p["name"].get<std::string>());
    EXPECT_NEAR(p["t"].get<double>(), events[k].t_ns * 1e-9, 1e-9);
    EXPECT_NEAR(p["residual_s"].get<double>(), error_ms[k] * 1e-3, 1e-9);
    sum_sq += error_ms[k] * error_ms[k] * 1e-6;
    // The rotation is analyze's D_full for the image of that name; the translation the speed's.
    const nlohmann::json& image = j["images"][k];
    EXPECT_EQ(image["name"], p["name"]);
    EXPECT_DOUBLE_EQ(p["D_rotation_m"].get<double>(), image["D_full_m"].get<double>());
    EXPECT_GT(p["D_rotation_m"].get<double>(), 0.0);
    EXPECT_NEAR(p["D_translation_m"].get<double>(), 5.0 * 0.016, 1e-12);  // table: 16 ms
  }
  EXPECT_NEAR(photos["placement"]["residual_rms_s"].get<double>(), std::sqrt(sum_sq / 5), 1e-9);
  // The altitude is the photos' own (the log has none), the camera theirs: nothing assumed.
  EXPECT_TRUE(j["assumptions"].empty()) << j["assumptions"].dump();
  EXPECT_NE(j["triggers"].get<std::string>().find("by capture time"), std::string::npos)
      << j["triggers"];
  // The page shows the camera analysed, the photos' own, and says the readout is the table's.
  const std::string page = ReadFileToString(dir / "out/report.html");
  EXPECT_NE(page.find("the photos&#39; DJI FC8482 (5 of 5 photos), 400x300, f 277 px"),
            std::string::npos);
  EXPECT_NE(page.find("readout 16 ms (table: dji fc8482"), std::string::npos);

  // The ULog is read as a stream, in bounded memory; on a pipe whole: the same JSON, --out's files
  // and page. Without --out the same JSON but for the report's Allan deviation.
  const auto piped = RunShutterlab(
      "analyze --photos " + (dir / "photos") + " /dev/stdin --json --out " + (dir / "piped"),
      dir / "flight.ulg");
  ASSERT_EQ(piped.exit_code, 0) << piped.output;
  EXPECT_EQ(nlohmann::json::parse(piped.out), j);
  for (const std::string file : {"photos.csv", "images.csv", "exclude.txt"})
    EXPECT_EQ(ReadFileToString(dir / ("piped/" + file)), ReadFileToString(dir / ("out/" + file)))
        << file;
  std::string page_streamed = ReadFileToString(dir / "out/report.html");
  for (size_t at = page_streamed.find("flight.ulg"); at != std::string::npos;
       at = page_streamed.find("flight.ulg", at))
    page_streamed.replace(at, 10, "stdin");  // the page names the log
  EXPECT_EQ(ReadFileToString(dir / "piped/report.html"), page_streamed);
  const auto streamed = RunShutterlab("analyze --photos " + (dir / "photos") + " " +
                                      (dir / "flight.ulg") + " --json");
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  nlohmann::json whole = j;
  whole.erase("allan");
  EXPECT_EQ(nlohmann::json::parse(streamed.out), whole);
}

// A gyro.csv, the log that grows long, with the photos named by a trigger file on its clock:
// read as a stream from a file and from a pipe (copied once to a temporary file), the same JSON
// and text (estimate/paper analyze_stream_test: the stream against the log read whole).
TEST(PhotosCli, AGyroCsvWithTriggersOnAPipeGivesTheFilesResult) {
  test::TempDir dir;
  test::WriteStillThenTurningGyroCsv(dir / "gyro.csv");
  std::filesystem::create_directories(dir / "photos");
  std::string triggers = "image,t\n";
  for (int k = 0; k < 4; ++k) {
    test::FixturePhoto p;
    p.width = 400;
    p.height = 300;
    p.focal_length_35mm = 24;
    const std::string name = "IMG_000" + std::to_string(k + 1) + ".JPG";
    WriteFileAtomically(dir / ("photos/" + name), test::JpegWithMetadata(p));
    triggers += name + "," + std::to_string(6 + 1.7 * k) + "\n";
  }
  triggers += "IMG_0009.JPG,11.99\n";  // no such photo
  WriteFileAtomically(dir / "triggers.csv", triggers);
  for (const std::string json : {" --json", ""}) {
    const std::string args = " --photos " + (dir / "photos") + " --readout 20ms --altitude 80m" +
                             " --triggers " + (dir / "triggers.csv") + json;
    const auto streamed = RunShutterlab("analyze " + (dir / "gyro.csv") + args);
    ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
    const auto piped =
        RunShutterlab("analyze /dev/stdin --format gyro.csv" + args, dir / "gyro.csv");
    ASSERT_EQ(piped.exit_code, 0) << piped.output;
    if (json.empty()) {
      EXPECT_EQ(streamed.out, piped.out);
      continue;
    }
    const nlohmann::json s = nlohmann::json::parse(streamed.out);
    ASSERT_EQ(s["images"].size(), 4u) << streamed.out;
    EXPECT_GT(s["photos"]["photos"][3]["D_rotation_m"].get<double>(), 0.0) << streamed.out;
    EXPECT_EQ(s, nlohmann::json::parse(piped.out));
  }
}

// The three real DJI photos named by a trigger file on a log's clock (seconds after its first
// sample).
const char kRealPhotoTriggers[] =
    "image,t\ntest-photo-1.jpg,112.7\ntest-photo-2.jpg,117.614\ntest-photo-3.jpg,160.3\n";

// Real photos on a real log: the three DJI photos named by a trigger file on the PX4 log's clock
// (they were not taken on that flight: this checks the command's reading of real bytes, from a
// file and from a pipe, not the photos' truth;
// AnalyzeStream.PhotoFlightOfRealPhotosOnARealLogEqualsTheWholeLog checks the stream against the
// whole read). The second photo's readout falls in a fast turn.
TEST(PhotosCli, RealPhotosOnARealLogFromAFileAndAPipe) {
  SHUTTERLAB_REAL_DATA(photos, "incoming/dji_fc8482_clusterodm");
  SHUTTERLAB_REAL_DATA(log, "gyro/px4_ulog/sample.ulg");
  test::TempDir dir;
  WriteFileAtomically(dir / "t.csv", kRealPhotoTriggers);
  const std::string args = " --triggers " + (dir / "t.csv") + " --json";
  const auto streamed = RunShutterlab("analyze --photos " + photos + " " + log + args);
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  const auto piped = RunShutterlab("analyze --photos " + photos + " /dev/stdin" + args, log);
  ASSERT_EQ(piped.exit_code, 0) << piped.output;
  const nlohmann::json s = nlohmann::json::parse(streamed.out);
  EXPECT_EQ(s, nlohmann::json::parse(piped.out));
  ASSERT_EQ(s["images"].size(), 3u);
  EXPECT_GT(s["photos"]["photos"][1]["D_rotation_m"].get<double>(), 0.5) << streamed.out;
  EXPECT_EQ(s["warnings"].size(), 2u) << "the log's two gap warnings";
}

// The photos on a 50 Hz log (log171): their 16 ms readout holds too few samples to judge, and the
// analysis says so on stderr as in the --json, beside the reader's warnings.
TEST(PhotosCli, PhotosOnALowRateLogSayTooFewSamplesOnStderrAsInTheJson) {
  SHUTTERLAB_REAL_DATA(photos, "incoming/dji_fc8482_clusterodm");
  SHUTTERLAB_REAL_DATA(log, "incoming/ardupilot_log171/log171.bin");
  test::TempDir dir;
  WriteFileAtomically(dir / "t.csv", kRealPhotoTriggers);
  const auto r = RunShutterlab("analyze --photos " + photos + " " + log + " --triggers " +
                               (dir / "t.csv") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  std::vector<std::string> kinds;
  for (const nlohmann::json& w : j.at("warnings")) {
    kinds.push_back(w.at("kind").get<std::string>());
    EXPECT_NE(r.err.find("warning: " + log + ": " + kinds.back() + ": " +
                         w.at("message").get<std::string>() + "\n"),
              std::string::npos)
        << r.err;
  }
  EXPECT_EQ(kinds, (std::vector<std::string>{"gap", "saturated", "too_few_samples"}));
}

}  // namespace
}  // namespace shutterlab
