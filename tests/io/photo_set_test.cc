#include "io/photo_set.h"

#include "model/readout_table.h"
#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/gyro_trace.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/io/photo_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::DjiXmp;
using test::FixturePhoto;
using test::JpegWithMetadata;

constexpr double kExact = 1e-9;  // closed-form values computed the same way

TEST(FocalPxFrom35mm, IsDefinedOnTheDiagonal) {
  // A 35 mm-equivalent equal to the full-frame diagonal images the diagonal at 45 deg half-angle:
  // f_px equals the image diagonal, whatever the aspect.
  EXPECT_NEAR(FocalPxFrom35mm(kFullFrameDiagonalMm, 4000, 3000), 5000.0, kExact);
  // A 36 x 24 mm sensor of 6000 x 4000 px (6 um pixels) with a 50 mm lens: 50 mm / 6 um.
  EXPECT_NEAR(FocalPxFrom35mm(50.0, 6000, 4000), 50.0 / 0.006, 1e-6);
  // The DJI Mini 4 Pro's 24 mm on its 16:9 photo (python: 24 / hypot(36, 24) * hypot(4032, 2268)).
  EXPECT_NEAR(FocalPxFrom35mm(24.0, 4032, 2268), 2566.101382972291, 1e-9);
  EXPECT_THROW(FocalPxFrom35mm(0.0, 10, 10), std::invalid_argument);
}

TEST(ReadoutTable, KeysOnMakeModelAndPhotoMode) {
  EXPECT_EQ(ReadoutTableKey("  DJI ", "FC8482\0"), "dji fc8482");
  // The Mini 4 Pro's four photo modes: < 12, 12-20, 20-45, >= 45 MP.
  EXPECT_DOUBLE_EQ(LookUpReadout("DJI", "FC8482", 9.14)->readout_s, 0.016);
  EXPECT_DOUBLE_EQ(LookUpReadout("DJI", "FC8482", 12.0)->readout_s, 0.021);
  EXPECT_DOUBLE_EQ(LookUpReadout("DJI", "FC8482", 36.6)->readout_s, 0.043);
  EXPECT_DOUBLE_EQ(LookUpReadout("DJI", "FC8482", 48.8)->readout_s, 0.058);
  EXPECT_DOUBLE_EQ(LookUpReadout("Hasselblad", "L1D-20c", 19.96)->readout_s, 0.056);
  EXPECT_DOUBLE_EQ(LookUpReadout("dji", "fc300x", 1.0)->readout_s, 0.033);
  EXPECT_FALSE(LookUpReadout("SIYIKEJI", "ZR10", 3.7));
  const std::string citation = LookUpReadout("DJI", "FC8482", 9.14)->Citation();
  EXPECT_NE(citation.find("16 ms for < 12 MP"), std::string::npos) << citation;
  EXPECT_NE(citation.find("OpenDroneMap"), std::string::npos) << citation;
}

// The table holds the facts of the cited snapshot: every row of the facts file (not in the
// repository: the shared data folder) gives its value at a megapixel count inside its condition.
TEST(ReadoutTableReal, MatchesTheCitedFacts) {
  SHUTTERLAB_REAL_DATA(path, "incoming/odm_rs_readout/readout_db.csv");
  const std::string text = ReadFileToString(path);  // the cursor views it
  LineCursor cursor(text);
  std::vector<std::string_view> fields;
  size_t rows = 0;
  cursor.Next();  // header
  while (const auto line = cursor.Next()) {
    if (line->empty()) continue;
    SplitFields(*line, ',', &fields);
    ASSERT_GE(fields.size(), 3u) << *line;
    const std::string key(fields[0]);
    const double readout_ms = *ParseDouble(fields[1]);
    const std::string condition(fields[2]);
    // A megapixel count inside the row's condition: the number after '<' or '>=' in its text.
    double mp = 10.0;
    if (condition.find(">=") != std::string::npos && condition.find("<") == std::string::npos) {
      mp = 1.0 + std::stod(condition.substr(condition.find(">=") + 2));
    } else if (condition.find("<=") != std::string::npos) {  // "12 <= capture_megapixels < 20"
      mp = std::stod(condition) + 0.5;
    } else if (condition.find('<') != std::string::npos) {
      mp = std::stod(condition.substr(condition.find('<') + 1)) - 0.5;
    }
    const size_t space = key.rfind(' ');
    const auto hit = LookUpReadout(key.substr(0, space), key.substr(space + 1), mp);
    ASSERT_TRUE(hit) << key << " at " << mp << " MP";
    EXPECT_DOUBLE_EQ(hit->readout_s, readout_ms * 1e-3) << key << " at " << mp << " MP";
    ++rows;
  }
  EXPECT_EQ(rows, ReadoutTableRows());
}

PhotoMetadata DjiMetadata() {
  return test::DjiMini3Metadata(117.9, Eigen::Vector3d(3.0, -4.0, 0.0));
}

TEST(PhotoRecord, DerivesCameraAndFlightStateWithSources) {
  const PhotoRecord r = MakePhotoRecord("/x/DJI_0123.JPG", DjiMetadata(), {});
  EXPECT_EQ(r.name, "DJI_0123.JPG");
  EXPECT_EQ(r.number.value_or(-1), 123);
  EXPECT_NEAR(*r.focal_px, 2566.101382972291, 1e-9);
  EXPECT_NE(r.focal_source.find("on the diagonal"), std::string::npos);
  EXPECT_DOUBLE_EQ(*r.readout_s, 0.016);
  EXPECT_EQ(r.readout_origin, ReadoutOrigin::kTable);
  EXPECT_NE(r.readout_source.find("table"), std::string::npos);
  EXPECT_DOUBLE_EQ(*r.altitude_m, 117.9);
  EXPECT_DOUBLE_EQ(*r.ground_speed_m_s, 5.0);
  EXPECT_NEAR(*r.course_deg, 360.0 - std::atan2(4.0, 3.0) * 180.0 / M_PI, 1e-9);
  EXPECT_EQ(r.missing, std::vector<std::string>{"capture time"});
}

TEST(PhotoRecord, GivenValuesWinAndMissingOnesAreListed) {
  PhotoSetOptions options;
  options.readout_s = 0.020;
  options.readout_text = "--readout 20ms";
  options.focal_px = 3000.0;
  options.altitude_m = 80.0;
  const PhotoRecord r = MakePhotoRecord("/x/a.jpg", DjiMetadata(), options);
  EXPECT_DOUBLE_EQ(*r.readout_s, 0.020);
  EXPECT_EQ(r.readout_origin, ReadoutOrigin::kUser);
  EXPECT_EQ(r.readout_source, "--readout 20ms");
  EXPECT_DOUBLE_EQ(*r.focal_px, 3000.0);
  EXPECT_DOUBLE_EQ(*r.altitude_m, 80.0);

  const PhotoMetadata bare = test::SiyiZr10Metadata();
  const PhotoRecord none = MakePhotoRecord("/x/b.jpg", bare, {});
  EXPECT_EQ(none.readout_origin, ReadoutOrigin::kNone);
  EXPECT_NE(none.readout_source.find("siyikeji zr10"), std::string::npos) << none.readout_source;
  EXPECT_EQ(none.missing, (std::vector<std::string>{"focal length", "readout", "altitude",
                                                    "flight speed", "capture time"}));
}

// A photo with an absolute altitude but no height above take-off (a non-DJI camera's EXIF
// GPSAltitude, or DJI's AbsoluteAltitude alone): flown at it minus --ground-elevation, said as
// derived; without the elevation it is missing; at or below the ground it is refused, said why.
TEST(PhotoRecord, AltitudeFromTheAbsoluteOneAndTheGroundElevation) {
  PhotoMetadata gps = test::SiyiZr10Metadata();
  gps.gps_altitude_m = 412.5;
  EXPECT_FALSE(MakePhotoRecord("/x/a.jpg", gps, {}).altitude_m.has_value());
  PhotoSetOptions options;
  options.ground_elevation_m = 371.0;
  const PhotoRecord r = MakePhotoRecord("/x/a.jpg", gps, options);
  ASSERT_TRUE(r.altitude_m.has_value());
  EXPECT_DOUBLE_EQ(*r.altitude_m, 41.5);
  EXPECT_EQ(r.altitude_source,
            "derived: 41.5 m, EXIF GPSAltitude 412.5 m minus --ground-elevation 371.0 m");
  // DJI's own absolute altitude wins over EXIF's; the height above take-off over both.
  gps.absolute_altitude_m = 489.0;
  EXPECT_DOUBLE_EQ(*MakePhotoRecord("/x/a.jpg", gps, options).altitude_m, 118.0);
  gps.relative_altitude_m = 117.9;
  EXPECT_DOUBLE_EQ(*MakePhotoRecord("/x/a.jpg", gps, options).altitude_m, 117.9);
  gps.relative_altitude_m.reset();
  options.ground_elevation_m = 500.0;
  const PhotoRecord below = MakePhotoRecord("/x/a.jpg", gps, options);
  EXPECT_FALSE(below.altitude_m.has_value());
  EXPECT_NE(below.altitude_source.find("not above the ground"), std::string::npos)
      << below.altitude_source;
  EXPECT_NE(std::find(below.missing.begin(), below.missing.end(), "altitude"), below.missing.end());
}

// A lens profile calibrated at half the photo's size, its mode's readout 12 ms: scaled to the
// photo it gives the focal length and the readout, each said, after what the user typed.
TEST(PhotoRecord, ALensProfileGivesFocalAndReadoutAfterTheUsers) {
  LensProfile profile;
  profile.name = "Mini 4 Pro 16:9";
  profile.camera.width = 2016;
  profile.camera.height = 1134;
  profile.camera.fx = profile.camera.fy = 1300.0;
  profile.camera.cx = 1007.5;
  profile.camera.cy = 566.5;
  profile.mode = {2016, 1134, 30.0, 0.012, ReadoutDirection::kTopToBottom};
  PhotoSetOptions options;
  options.lens_profile = profile;
  PhotoMetadata m = DjiMetadata();
  m.width = 4032;
  m.height = 2268;
  const PhotoRecord r = MakePhotoRecord("/x/a.jpg", m, options);
  EXPECT_DOUBLE_EQ(*r.focal_px, 2600.0);
  EXPECT_EQ(r.focal_source, "lens profile Mini 4 Pro 16:9");
  EXPECT_DOUBLE_EQ(*r.readout_s, 0.012);
  EXPECT_EQ(r.readout_origin, ReadoutOrigin::kLensProfile);
  EXPECT_EQ(r.readout_source, "lens profile Mini 4 Pro 16:9");
  ASSERT_TRUE(r.camera);  // the whole camera, for the exports: (c + 0.5) * 2 - 0.5
  EXPECT_DOUBLE_EQ(r.camera->cx, 2015.5);
  EXPECT_DOUBLE_EQ(r.camera->cy, 1133.5);

  options.readout_s = 0.020;
  options.readout_text = "--readout 20ms";
  options.focal_px = 3000.0;
  const PhotoRecord given = MakePhotoRecord("/x/a.jpg", m, options);
  EXPECT_EQ(given.readout_origin, ReadoutOrigin::kUser);
  EXPECT_DOUBLE_EQ(*given.readout_s, 0.020);
  EXPECT_DOUBLE_EQ(*given.focal_px, 3000.0);
  EXPECT_FALSE(given.camera) << "a focal length given alone gives no principal point or lens";

  // A profile without a readout leaves the table's.
  options = {};
  profile.mode.readout_s.reset();
  options.lens_profile = profile;
  const PhotoRecord table = MakePhotoRecord("/x/a.jpg", m, options);
  EXPECT_EQ(table.readout_origin, ReadoutOrigin::kTable);
  EXPECT_DOUBLE_EQ(*table.focal_px, 2600.0);
}

// camera.json's camera gives a photo of its size its principal point and lens (for the exports);
// a photo of another size keeps camera.json's focal length only.
TEST(PhotoRecord, CameraJsonsCameraGoesWithPhotosOfItsSize) {
  PinholeCamera camera;
  camera.width = 4032;
  camera.height = 2268;
  camera.fx = camera.fy = 2600.0;
  camera.cx = 2000.0;
  camera.cy = 1100.0;
  camera.distortion = BrownConrady{{-0.1, 0.02, 0, 0, 0}};
  PhotoSetOptions options;
  options.focal_px = 2600.0;
  options.focal_text = "camera.json c.json";
  options.camera = camera;
  PhotoMetadata m = DjiMetadata();
  m.width = 4032;
  m.height = 2268;
  const PhotoRecord same = MakePhotoRecord("/x/a.jpg", m, options);
  ASSERT_TRUE(same.camera);
  EXPECT_EQ(same.camera->cx, 2000.0);
  EXPECT_EQ(std::get<BrownConrady>(same.camera->distortion).coeffs[0], -0.1);
  m.width = 2016;
  m.height = 1134;
  EXPECT_FALSE(MakePhotoRecord("/x/a.jpg", m, options).camera);
}

// A photo without a speed, at north_m, east_m of (47, 8) deg, its capture time t_s to resolution_s.
PhotoRecord PhotoAt(const std::string& name, double t_s, double north_m, double east_m,
                    double resolution_s) {
  PhotoRecord r;
  r.name = name;
  r.path = "/x/" + name;
  r.metadata.latitude_deg = 47.0 + north_m / kMetresPerDegree;
  r.metadata.longitude_deg = 8.0 + east_m / (kMetresPerDegree * std::cos(47.0 * kRadPerDeg));
  ClockFace face;
  face.resolution_s = resolution_s;
  face.face_ns = SecondsToNs(std::floor(t_s / resolution_s + 1e-9) * resolution_s);
  r.metadata.capture_time = face;
  r.missing = {"flight speed"};
  return r;
}

// A lawnmower: a line flown east at 8 m/s, a 10 s turn, the next line 40 m north flown west, a
// photo every 2 s, in name order not time order. Capture times to 0.01 s: every photo takes its
// speed and course from its neighbours', a line's last and first from the two before or after
// it on their own line (the photos across the turn bend).
TEST(SpeedsFromPositions, DifferentiatesThePositionsAroundEachPhotoAlongItsLine) {
  PhotoSet set;
  for (int k = 0; k < 6; ++k) {
    set.photos.push_back(PhotoAt(FormatNumber("B_%02.0f.JPG", k), 2.0 * k, 0.0, 16.0 * k, 0.01));
    set.photos.push_back(
        PhotoAt(FormatNumber("A_%02.0f.JPG", k), 20.0 + 2.0 * k, 40.0, 80.0 - 16.0 * k, 0.01));
  }
  set.photos.push_back(PhotoAt("C_recorded.JPG", 40.0, 40.0, -80.0, 0.01));
  set.photos.back().ground_speed_m_s = 3.0;
  set.photos.back().speed_source = "XMP";
  SpeedsFromPositions(&set);
  for (const PhotoRecord& r : set.photos) {
    if (r.name == "C_recorded.JPG") {
      EXPECT_EQ(*r.ground_speed_m_s, 3.0);
      EXPECT_FALSE(r.speed_from_positions);
      continue;
    }
    ASSERT_TRUE(r.ground_speed_m_s) << r.name;
    // The positions were made with the same sphere the speed is read with: exact but for rounding.
    EXPECT_NEAR(*r.ground_speed_m_s, 8.0, 1e-6) << r.name;
    EXPECT_NEAR(*r.course_deg, r.name[0] == 'B' ? 90.0 : 270.0, 0.01) << r.name;
    EXPECT_TRUE(r.speed_from_positions);
    EXPECT_TRUE(r.missing.empty()) << r.name;
  }
  EXPECT_EQ(set.photos[2].speed_source,
            "the GPS positions of B_00.JPG and B_02.JPG: 32.0 m in 4.00 s");
  EXPECT_EQ(set.photos[10].speed_source,
            "the GPS positions of B_03.JPG and B_05.JPG: 32.0 m in 4.00 s");

  // Whole seconds: the photos around are widened until they are 10 s apart, so a time's second
  // costs at most a tenth; a photo with no such straight stretch on either side gets none.
  PhotoSet coarse;
  for (int k = 0; k < 8; ++k)
    coarse.photos.push_back(PhotoAt(FormatNumber("D_%02.0f.JPG", k), 2.0 * k + 0.3 * (k % 3), 0.0,
                                    16.0 * k + 2.4 * (k % 3), 1.0));
  coarse.photos.push_back(PhotoAt("E.JPG", 16.0, 50.0, 100.0, 1.0));
  SpeedsFromPositions(&coarse);
  int with_speed = 0;
  for (const PhotoRecord& r : coarse.photos) {
    if (!r.ground_speed_m_s) continue;
    ++with_speed;
    EXPECT_NEAR(*r.ground_speed_m_s, 8.0, 0.8) << r.name << ": " << r.speed_source;
    EXPECT_NE(r.speed_source.find(" s"), std::string::npos);
  }
  EXPECT_EQ(with_speed, 8) << "E, after a turn and 2 s away, has no straight 10 s";
  EXPECT_FALSE(coarse.photos.back().ground_speed_m_s);
  EXPECT_EQ(coarse.photos.back().missing, std::vector<std::string>{"flight speed"});
}

TEST(PhotoSet, ReadsPhotoFilesByNameAndReportsBadOnes) {
  test::TempDir dir;
  FixturePhoto good;
  good.focal_length_35mm = 24;
  good.xmp = DjiXmp({{"RelativeAltitude", "+50.0"}}, false);
  WriteFileAtomically(dir / "B_0002.JPG", JpegWithMetadata(good));
  WriteFileAtomically(dir / "a_0001.jpg", JpegWithMetadata(FixturePhoto{}));
  WriteFileAtomically(dir / "C_0003.jpeg", "broken");
  WriteFileAtomically(dir / "flight.MRK", "not a photo");
  const PhotoSet set = ReadPhotoSet(dir.path().string());
  ASSERT_EQ(set.photos.size(), 3u);
  EXPECT_EQ(set.photos[0].name, "B_0002.JPG");  // byte order: upper case first
  EXPECT_EQ(set.photos[1].name, "C_0003.jpeg");
  EXPECT_EQ(set.photos[2].name, "a_0001.jpg");
  EXPECT_TRUE(set.photos[0].ok());
  EXPECT_DOUBLE_EQ(*set.photos[0].altitude_m, 50.0);
  EXPECT_FALSE(set.photos[1].ok());
  EXPECT_NE(set.photos[1].error.find("C_0003.jpeg"), std::string::npos) << set.photos[1].error;
  EXPECT_EQ(set.photos[1].number.value_or(-1), 3);
  EXPECT_FALSE(set.photos[2].focal_px);

  test::TempDir empty;
  WriteFileAtomically(empty / "notes.txt", "x");
  EXPECT_THROW(ReadPhotoSet(empty.path().string()), IoError);
  EXPECT_THROW(ReadPhotoSet(empty / "missing"), IoError);
}

// A card's DCIM folder: the photos sit in 100MEDIA and 101MEDIA. Not read without `recursive`
// (and said so, counted), read with it and named by their path under the folder.
TEST(PhotoSet, SubfoldersAreCountedAndReadWhenAsked) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "DCIM/100MEDIA");
  std::filesystem::create_directories(dir / "DCIM/101MEDIA");
  WriteFileAtomically(dir / "DCIM/100MEDIA/DJI_0001.JPG", JpegWithMetadata(FixturePhoto{}));
  WriteFileAtomically(dir / "DCIM/101MEDIA/DJI_0002.JPG", JpegWithMetadata(FixturePhoto{}));
  try {
    ReadPhotoSet(dir / "DCIM");
    ADD_FAILURE() << "a folder with photos in its subfolders only";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("no photo files here, but its subfolders hold 2 (a "
                                         "card's DCIM/100MEDIA?): give --recursive"),
              std::string::npos)
        << e.what();
  }
  PhotoSetOptions recursive;
  recursive.recursive = true;
  const PhotoSet all = ReadPhotoSet(dir / "DCIM", recursive);
  ASSERT_EQ(all.photos.size(), 2u);
  EXPECT_EQ(all.photos[0].name, "100MEDIA/DJI_0001.JPG");
  EXPECT_EQ(all.photos[1].name, "101MEDIA/DJI_0002.JPG");
  EXPECT_EQ(all.photos[1].number.value_or(-1), 2);
  EXPECT_TRUE(all.photos[0].ok()) << all.photos[0].error;
  EXPECT_EQ(all.in_subfolders, 0u);

  WriteFileAtomically(dir / "DCIM/DJI_0003.JPG", JpegWithMetadata(FixturePhoto{}));
  const PhotoSet top = ReadPhotoSet(dir / "DCIM");
  ASSERT_EQ(top.photos.size(), 1u);
  EXPECT_EQ(top.photos[0].name, "DJI_0003.JPG");
  EXPECT_EQ(top.in_subfolders, 2u);
}

// --speed: for photos that do not record their speed, and over those that do (the direction kept).
TEST(PhotoRecord, AGivenSpeedWinsAndKeepsTheRecordedDirection) {
  PhotoSetOptions options;
  options.speed_m_s = 8.0;
  const PhotoRecord r = MakePhotoRecord("/x/DJI_0123.JPG", DjiMetadata(), options);
  EXPECT_DOUBLE_EQ(*r.ground_speed_m_s, 8.0);
  EXPECT_EQ(r.speed_source, "--speed");
  EXPECT_NEAR(*r.course_deg, 360.0 - std::atan2(4.0, 3.0) * 180.0 / M_PI, 1e-9);
  PhotoMetadata bare;
  bare.width = 2560;
  bare.height = 1440;
  const PhotoRecord given = MakePhotoRecord("/x/b.jpg", bare, options);
  EXPECT_DOUBLE_EQ(*given.ground_speed_m_s, 8.0);
  EXPECT_FALSE(given.course_deg);
  EXPECT_EQ(std::count(given.missing.begin(), given.missing.end(), "flight speed"), 0);
  options.speed_m_s = -1.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

TEST(PhotoSetReal, DjiMini4ProFolder) {
  SHUTTERLAB_REAL_DATA(dir, "incoming/dji_fc8482_clusterodm");
  const PhotoSet set = ReadPhotoSet(dir);
  ASSERT_EQ(set.photos.size(), 3u);
  const double speeds[3] = {6.9, 7.0, std::hypot(0.3, 4.6)};  // PROVENANCE.md's table
  for (size_t i = 0; i < 3; ++i) {
    const PhotoRecord& r = set.photos[i];
    SCOPED_TRACE(r.name);
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_DOUBLE_EQ(r.readout_s.value_or(0), 0.016) << "9.1 MP 16:9 mode";
    EXPECT_EQ(r.readout_origin, ReadoutOrigin::kTable);
    EXPECT_NEAR(r.focal_px.value_or(0), 2566.1, 0.1);
    EXPECT_DOUBLE_EQ(r.altitude_m.value_or(0), 117.9);
    EXPECT_NEAR(r.ground_speed_m_s.value_or(0), speeds[i], 1e-12);
    EXPECT_TRUE(r.missing.empty()) << r.missing.front();
  }
}

TEST(PhotoSetReal, HasselbladReadoutFromTheCameraModeNotTheDownscaledPixels) {
  SHUTTERLAB_REAL_DATA(path, "incoming/dji_l1d20c_exifr/issue-exifr-13.jpg");
  const PhotoSet set = ReadPhotoSet(path);
  ASSERT_EQ(set.photos.size(), 1u);
  const PhotoRecord& r = set.photos[0];
  EXPECT_DOUBLE_EQ(r.readout_s.value_or(0), 0.056) << "5472 x 3648 = 19.96 MP, not 100 x 67";
  // 28 mm on the diagonal of the 100 x 67 pixels in the file.
  EXPECT_NEAR(r.focal_px.value_or(0), 28.0 / kFullFrameDiagonalMm * std::hypot(100, 67), 1e-9);
  EXPECT_EQ(r.missing, std::vector<std::string>{"flight speed"});
}

}  // namespace
}  // namespace shutterlab
