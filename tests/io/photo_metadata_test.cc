#include "io/photo_metadata.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/io/photo_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <map>
#include <string>

namespace shutterlab {
namespace {

using test::DjiMakerNote;
using test::DjiXmp;
using test::FixturePhoto;
using test::JpegWithMetadata;

// XMP values are decimal text; EXIF rationals are exact; maker-note values are float32.
constexpr double kFloat32Tol = 1e-6;

std::string WritePhoto(const test::TempDir& dir, const std::string& name, const FixturePhoto& p) {
  const std::string path = dir / name;
  WriteFileAtomically(path, JpegWithMetadata(p));
  return path;
}

const std::map<std::string, std::string> kDjiValues = {
    {"RelativeAltitude", "+117.90"}, {"AbsoluteAltitude", "+314.661"},
    {"GimbalRollDegree", "+0.00"},   {"GimbalPitchDegree", "-90.00"},
    {"GimbalYawDegree", "-93.50"},   {"FlightRollDegree", "-4.90"},
    {"FlightPitchDegree", "-12.40"}, {"FlightYawDegree", "-90.10"},
    {"FlightXSpeed", "0.3"},         {"FlightYSpeed", "-6.9"},
    {"FlightZSpeed", "0.0"}};

TEST(PhotoMetadata, ReadsExifFieldsWrittenByHand) {
  test::TempDir dir;
  FixturePhoto p;
  p.width = 320;
  p.height = 180;
  p.make = "DJI";
  p.model = "FC8482";
  p.date_time_original = "2024:07:16 09:41:37";
  p.sub_sec_time_original = "125";
  p.offset_time_original = "+08:00";
  p.focal_length_mm = {67, 10};
  p.focal_length_35mm = 24;
  p.exposure_s = {1, 725};
  p.exif_width = 4032;
  p.exif_height = 2268;
  const PhotoMetadata m = ReadPhotoMetadata(WritePhoto(dir, "a.jpg", p));
  EXPECT_EQ(m.make, "DJI");
  EXPECT_EQ(m.model, "FC8482");
  EXPECT_EQ(m.width, 320);
  EXPECT_EQ(m.height, 180);
  EXPECT_EQ(m.exif_width, 4032);
  EXPECT_EQ(m.exif_height, 2268);
  EXPECT_DOUBLE_EQ(*m.focal_length_mm, 6.7);
  EXPECT_DOUBLE_EQ(*m.focal_length_35mm, 24.0);
  EXPECT_DOUBLE_EQ(*m.exposure_s, 1.0 / 725.0);
  ASSERT_TRUE(m.capture_time) << m.capture_time_problem;
  EXPECT_EQ(m.capture_time->face_ns, 1721122897LL * kNsPerSecond + 125'000'000);
  EXPECT_EQ(*m.capture_time->utc_offset_s, 8 * 3600);
  EXPECT_DOUBLE_EQ(m.capture_time->resolution_s, 0.001);
  EXPECT_FALSE(m.relative_altitude_m);
  EXPECT_FALSE(m.speed_m_s);
  EXPECT_TRUE(m.flight_state_source.empty());
}

// DJI writes drone-dji as attributes; ExifTool rewrites them as elements; a file may bind the
// namespace to another prefix. All three read the same.
TEST(PhotoMetadata, ReadsDjiXmpAsAttributesElementsOrAnyPrefix) {
  test::TempDir dir;
  struct Form {
    bool elements;
    std::string prefix;
  };
  for (const Form& form : {Form{false, "drone-dji"}, Form{true, "drone-dji"}, Form{false, "dji"}}) {
    SCOPED_TRACE(std::string(form.elements ? "elements" : "attributes") + " " + form.prefix);
    FixturePhoto p;
    p.make = "Hasselblad";
    p.model = "L1D-20c";
    p.xmp = DjiXmp(kDjiValues, form.elements, form.prefix);
    const PhotoMetadata m = ReadPhotoMetadata(WritePhoto(dir, form.prefix + ".jpg", p));
    EXPECT_EQ(m.make, "Hasselblad") << "EXIF's Make, not XMP's tiff:Make";
    EXPECT_EQ(m.model, "L1D-20c");
    ASSERT_TRUE(m.relative_altitude_m);
    EXPECT_DOUBLE_EQ(*m.relative_altitude_m, 117.9);
    EXPECT_DOUBLE_EQ(*m.absolute_altitude_m, 314.661);
    ASSERT_TRUE(m.gimbal && m.flight && m.speed_m_s);
    EXPECT_DOUBLE_EQ(m.gimbal->pitch_deg, -90.0);
    EXPECT_DOUBLE_EQ(m.gimbal->yaw_deg, -93.5);
    EXPECT_DOUBLE_EQ(m.flight->roll_deg, -4.9);
    EXPECT_DOUBLE_EQ(m.flight->pitch_deg, -12.4);
    EXPECT_DOUBLE_EQ(m.flight->yaw_deg, -90.1);
    EXPECT_DOUBLE_EQ(m.speed_m_s->x(), 0.3);
    EXPECT_DOUBLE_EQ(m.speed_m_s->y(), -6.9);
    EXPECT_EQ(m.flight_state_source, "XMP drone-dji");
  }
}

TEST(PhotoMetadata, DecodesDjiPhantomMakerNote) {
  test::TempDir dir;
  FixturePhoto p;
  p.model = "FC300X";
  // SpeedX/Y/Z, Pitch, Yaw, Roll, CameraPitch, CameraYaw, CameraRoll (ExifTool's DJI tags 3..11).
  p.maker_note = DjiMakerNote({{3, 0.1f},
                               {4, -5.5f},
                               {5, 0.0f},
                               {6, -3.6f},
                               {7, 3.1f},
                               {8, -3.8f},
                               {9, -89.9f},
                               {10, 3.8f},
                               {11, 0.0f}});
  const PhotoMetadata m = ReadPhotoMetadata(WritePhoto(dir, "note.jpg", p));
  ASSERT_TRUE(m.speed_m_s && m.flight && m.gimbal);
  EXPECT_NEAR(m.speed_m_s->x(), 0.1, kFloat32Tol);
  EXPECT_NEAR(m.speed_m_s->y(), -5.5, kFloat32Tol);
  EXPECT_NEAR(m.flight->pitch_deg, -3.6, kFloat32Tol);
  EXPECT_NEAR(m.flight->yaw_deg, 3.1, kFloat32Tol);
  EXPECT_NEAR(m.flight->roll_deg, -3.8, kFloat32Tol);
  EXPECT_NEAR(m.gimbal->pitch_deg, -89.9, 1e-5);
  EXPECT_NEAR(m.gimbal->yaw_deg, 3.8, kFloat32Tol);
  EXPECT_EQ(m.flight_state_source, "DJI maker note");

  // Another maker's note is not read as DJI's.
  p.make = "SIYIKEJI";
  const PhotoMetadata other = ReadPhotoMetadata(WritePhoto(dir, "other.jpg", p));
  EXPECT_FALSE(other.speed_m_s);
}

TEST(PhotoMetadata, BlankDateIsAProblemNotAnError) {
  test::TempDir dir;
  FixturePhoto p;
  p.date_time_original = "    :  :     :  :  ";
  const PhotoMetadata m = ReadPhotoMetadata(WritePhoto(dir, "blank.jpg", p));
  EXPECT_FALSE(m.capture_time);
  EXPECT_NE(m.capture_time_problem.find("YYYY:MM:DD"), std::string::npos) << m.capture_time_problem;
}

TEST(PhotoMetadata, NotAnImageIsAnIoErrorNamingThePath) {
  test::TempDir dir;
  const std::string path = dir / "notes.jpg";
  WriteFileAtomically(path, "not a photo\n");
  try {
    ReadPhotoMetadata(path);
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line";
  }
}

TEST(PhotoMetadataReal, DjiMini4ProPhotos) {
  SHUTTERLAB_REAL_DATA(path, "incoming/dji_fc8482_clusterodm/test-photo-1.jpg");
  const PhotoMetadata m = ReadPhotoMetadata(path);
  EXPECT_EQ(m.make, "DJI");
  EXPECT_EQ(m.model, "FC8482");
  EXPECT_EQ(m.width, 4032);
  EXPECT_EQ(m.height, 2268);
  EXPECT_DOUBLE_EQ(m.focal_length_35mm.value_or(0), 24.0);
  EXPECT_DOUBLE_EQ(m.focal_length_mm.value_or(0), 6.7);
  EXPECT_DOUBLE_EQ(m.relative_altitude_m.value_or(0), 117.9);
  ASSERT_TRUE(m.speed_m_s && m.gimbal && m.flight);
  EXPECT_DOUBLE_EQ(m.speed_m_s->y(), -6.9);
  EXPECT_DOUBLE_EQ(m.gimbal->pitch_deg, -90.0);
  EXPECT_DOUBLE_EQ(m.flight->yaw_deg, -90.1);
  ASSERT_TRUE(m.capture_time);
  EXPECT_EQ(m.capture_time_text, "2024:07:16 09:41:37");
  EXPECT_FALSE(m.capture_time->utc_offset_s) << "no OffsetTimeOriginal in these files";
  ASSERT_TRUE(m.latitude_deg);
  EXPECT_NEAR(*m.latitude_deg, -8.443, 1e-3);
}

TEST(PhotoMetadataReal, HasselbladKeepsExifMakeAndSensorModeSize) {
  SHUTTERLAB_REAL_DATA(path, "incoming/dji_l1d20c_exifr/issue-exifr-13.jpg");
  const PhotoMetadata m = ReadPhotoMetadata(path);
  EXPECT_EQ(m.make, "Hasselblad") << "XMP's tiff:Make is DJI; EXIF's is Hasselblad";
  EXPECT_EQ(m.model, "L1D-20c");
  EXPECT_EQ(m.width, 100);
  EXPECT_EQ(m.height, 67);
  EXPECT_EQ(m.exif_width, 5472);
  EXPECT_EQ(m.exif_height, 3648);
  EXPECT_DOUBLE_EQ(m.relative_altitude_m.value_or(0), 125.3);
  EXPECT_FALSE(m.speed_m_s) << "this file has no FlightX/Y/ZSpeed";
}

TEST(PhotoMetadataReal, PhantomMakerNoteAndSiyiWithoutFlightState) {
  SHUTTERLAB_REAL_DATA(phantom, "images/odm_toledo/1JI_0064.JPG");
  const PhotoMetadata m = ReadPhotoMetadata(phantom);
  EXPECT_EQ(m.model, "FC300X");
  EXPECT_EQ(m.flight_state_source, "DJI maker note");
  ASSERT_TRUE(m.flight && m.gimbal && m.speed_m_s);
  // SOURCES.md (ExifTool): airframe pitch -3.6, roll -3.8, yaw +3.1; gimbal pitch -89.9, yaw +3.8.
  EXPECT_NEAR(m.flight->pitch_deg, -3.6, kFloat32Tol);
  EXPECT_NEAR(m.flight->roll_deg, -3.8, kFloat32Tol);
  EXPECT_NEAR(m.flight->yaw_deg, 3.1, kFloat32Tol);
  EXPECT_NEAR(m.gimbal->pitch_deg, -89.9, 1e-5);
  EXPECT_NEAR(m.gimbal->yaw_deg, 3.8, kFloat32Tol);
  EXPECT_FALSE(m.relative_altitude_m);
  // EXIF GPSAltitude 122.3 m (exiv2 -pa: 1223/10 m, reference above sea level); with no height
  // above take-off it is what --ground-elevation derives a height from.
  EXPECT_NEAR(m.gps_altitude_m.value_or(0), 122.3, 1e-9);

  SHUTTERLAB_REAL_DATA(siyi, "images/siyi_zr10/IMG_0150.jpg");
  const PhotoMetadata s = ReadPhotoMetadata(siyi);
  EXPECT_EQ(s.make, "SIYIKEJI");
  EXPECT_EQ(s.width, 2560);
  EXPECT_FALSE(s.latitude_deg) << "GPS 0,0 is no fix";
  EXPECT_FALSE(s.gps_altitude_m) << "no fix, no altitude";
  EXPECT_FALSE(s.speed_m_s);
  EXPECT_TRUE(s.flight_state_source.empty());
}

}  // namespace
}  // namespace shutterlab
