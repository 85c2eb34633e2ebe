#include "estimate/paper/photo_analysis.h"

#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <string>

namespace shutterlab {
namespace {

constexpr double kTol = 1e-9;  // closed-form values

// A nadir photo: f 2000 px, 100 m up, 20 ms readout (given), 1 ms exposure, flying at (north,
// east) m/s with the gimbal's yaw.
PhotoRecord Photo(const std::string& name, double north, double east, double gimbal_yaw_deg,
                  double gimbal_pitch_deg = -90.0) {
  PhotoMetadata m;
  m.make = "Test";
  m.model = "Cam";
  m.width = 4000;
  m.height = 3000;
  m.exposure_s = 0.001;
  m.speed_m_s = Eigen::Vector3d(north, east, 0.0);
  m.gimbal = AttitudeDeg{0.0, gimbal_pitch_deg, gimbal_yaw_deg};
  m.flight_state_source = "XMP drone-dji";
  PhotoSetOptions options;
  options.readout_s = 0.020;
  options.focal_px = 2000.0;
  options.altitude_m = 100.0;
  return MakePhotoRecord("/photos/" + name, m, options);
}

PhotoSet Set(std::vector<PhotoRecord> photos) {
  PhotoSet set;
  set.source = "/photos";
  set.photos = std::move(photos);
  return set;
}

// D = v * T * f / h: 10 m/s, 20 ms, 2000 px, 100 m -> 0.2 m on the ground, 4 px in the image.
TEST(AnalyzePhotos, TranslationOnlyMatchesTheClosedForm) {
  const PhotoAnalysis a = AnalyzePhotos(Set({Photo("north.jpg", 10.0, 0.0, 0.0)}), {});
  ASSERT_EQ(a.photos.size(), 1u);
  const PhotoResult& p = a.photos[0];
  EXPECT_NEAR(*p.d_translation_m, 0.2, kTol);
  EXPECT_NEAR(*p.d_translation_px, 4.0, kTol);
  EXPECT_NEAR(*p.blur_px, 10.0 * 0.001 * 20.0, kTol);
  // Flying where the top of the photo faces: the ground moves down the photo, with the readout.
  EXPECT_NEAR(*p.along_readout_px, 4.0, kTol);
  EXPECT_NEAR(*p.across_readout_px, 0.0, kTol);
  EXPECT_EQ(p.flagged, (std::vector<std::optional<bool>>{true, true}));
  EXPECT_EQ(a.predicted, 1u);
  EXPECT_NE(a.verdict.find("translation only"), std::string::npos) << a.verdict;
}

TEST(AnalyzePhotos, SplitsTheMotionAlongAndAcrossTheReadout) {
  // Top of the photo facing east, flying north: the photo's right faces south, so the ground
  // moves right across the readout. Facing south, flying north: against the readout.
  const PhotoAnalysis a =
      AnalyzePhotos(Set({Photo("east.jpg", 10.0, 0.0, 90.0), Photo("south.jpg", 10.0, 0.0, 180.0),
                         Photo("diag.jpg", 3.0, 4.0, 0.0)}),
                    {});
  EXPECT_NEAR(*a.photos[0].along_readout_px, 0.0, kTol);
  EXPECT_NEAR(*a.photos[0].across_readout_px, 4.0, kTol);
  EXPECT_NEAR(*a.photos[1].along_readout_px, -4.0, kTol);
  EXPECT_NEAR(*a.photos[2].along_readout_px, 3.0 * 0.4, kTol);    // v . north * T f / h
  EXPECT_NEAR(*a.photos[2].across_readout_px, -4.0 * 0.4, kTol);  // east is the photo's right
  EXPECT_NEAR(*a.photos[2].d_translation_px, 2.0, kTol);          // |(3, 4)| * 0.4
}

// Looking straight down, yaw and roll turn about the same axis: yaw 90 with roll 180 faces 270
// (west), so flying north moves the ground to the photo's left.
TEST(AnalyzePhotos, GimbalRollAtNadirTurnsThePhotoLikeYaw) {
  PhotoRecord r = Photo("rolled.jpg", 10.0, 0.0, 90.0);
  r.metadata.gimbal->roll_deg = 180.0;
  const PhotoAnalysis a = AnalyzePhotos(Set({r}), {});
  EXPECT_NEAR(*a.photos[0].along_readout_px, 0.0, kTol);
  EXPECT_NEAR(*a.photos[0].across_readout_px, -4.0, kTol);
  EXPECT_TRUE(a.photos[0].notes.empty());
}

TEST(AnalyzePhotos, ObliqueMissingAndUnreadablePhotosAreSaidNotGuessed) {
  PhotoRecord oblique = Photo("oblique.jpg", 2.0, 0.0, 0.0, -45.0);
  PhotoMetadata bare;
  bare.width = 10;
  bare.height = 10;
  PhotoRecord missing = MakePhotoRecord("/photos/bare.jpg", bare, {});
  PhotoRecord broken;
  broken.path = "/photos/broken.jpg";
  broken.name = "broken.jpg";
  broken.error = "/photos/broken.jpg: cannot read the photo's metadata";
  const PhotoSet set = Set({oblique, missing, broken});
  const PhotoAnalysis a = AnalyzePhotos(set, {});
  EXPECT_NEAR(*a.photos[0].d_translation_m, 0.04, kTol);
  EXPECT_FALSE(a.photos[0].along_readout_px) << "no split without a nadir gimbal";
  ASSERT_EQ(a.photos[0].notes.size(), 1u);
  EXPECT_NE(a.photos[0].notes[0].find("oblique"), std::string::npos);
  EXPECT_EQ(a.photos[0].flagged, (std::vector<std::optional<bool>>{false, false}));
  EXPECT_FALSE(a.photos[1].d_translation_m);
  EXPECT_FALSE(a.photos[1].flagged[0].has_value());
  EXPECT_EQ(a.read, 2u);
  const std::string report = PhotoAnalysisReport(set, a);
  EXPECT_NE(report.find("bare.jpg: no focal length, no readout, no altitude, no flight speed, "
                        "no capture time"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("broken.jpg: unreadable"), std::string::npos) << report;
  EXPECT_NE(a.verdict.find("--altitude"), std::string::npos) << a.verdict;
}

TEST(AnalyzePhotos, WithALogFlagsOnRotationPlusTranslation) {
  const PhotoSet set = Set({Photo("a.jpg", 2.0, 0.0, 0.0), Photo("b.jpg", 2.0, 0.0, 0.0)});
  AnalyzeResult log;
  ImageResult image;
  image.name = "a.jpg";
  image.in_trace = true;
  image.d_full_m = 0.03;
  image.d_full_px = 0.6;
  log.images = {image};
  std::vector<PhotoPlacement> placements(2);
  placements[0].t_ns = 5'000'000'000;
  placements[0].method = "test";
  placements[1].problem = "no event";
  const PhotoAnalysis a = AnalyzePhotosWithLog(set, {}, placements, log);
  EXPECT_TRUE(a.with_log);
  EXPECT_DOUBLE_EQ(*a.photos[0].d_rotation_m, 0.03);
  // 0.03 (rotation) + 0.04 (translation) = 0.07: over 5 cm, under 10 cm.
  EXPECT_EQ(a.photos[0].flagged, (std::vector<std::optional<bool>>{true, false}));
  EXPECT_FALSE(a.photos[1].d_rotation_m);
  EXPECT_EQ(a.photos[1].flagged, (std::vector<std::optional<bool>>{false, false}));
  ASSERT_FALSE(a.photos[1].notes.empty());
  EXPECT_NE(a.photos[1].notes[0].find("no event"), std::string::npos);
  EXPECT_EQ(a.placed, 1u);
}

// Three photos at 10 m/s and a 20 ms readout: all shifted 20 cm, all over 5 cm. When exclude.txt
// would drop more than half of them, the verdict says how large the shifts are in pixels at their
// ground sampling and what else would do.
TEST(AnalyzePhotos, AnExclusionOfMostPhotosSaysWhyInPixels) {
  const PhotoSet set = Set({Photo("a.jpg", 10.0, 0.0, 0.0), Photo("b.jpg", 10.0, 0.0, 0.0),
                            Photo("c.jpg", 1.0, 0.0, 0.0)});
  const PhotoAnalysis a = AnalyzePhotos(set, {});
  EXPECT_EQ(a.excluded, 2u);
  // 100 m / 2000 px = 5 cm/px: 20 cm is 4 px, 5 cm is 1 px.
  EXPECT_NE(a.verdict.find("; exclude.txt drops 2 of 3 photos: their shifts are 4 px at 5 cm/px, "
                           "where 5 cm is 1 px; a larger --limit keeps more, and a "
                           "photogrammetry tool's own rolling-shutter option (ODM "
                           "--rolling-shutter) removes the translation part"),
            std::string::npos)
      << a.verdict;
  const PhotoAnalysis few =
      AnalyzePhotos(Set({Photo("a.jpg", 10.0, 0.0, 0.0), Photo("b.jpg", 1.0, 0.0, 0.0)}), {});
  EXPECT_EQ(few.excluded, 1u);
  EXPECT_EQ(few.verdict.find("exclude.txt drops"), std::string::npos) << few.verdict;

  // Unreadable photos are dropped whatever the limit: counted as such, and a larger --limit is
  // offered only where a shift dropped one.
  PhotoRecord broken = Photo("d.jpg", 0.0, 0.0, 0.0);
  broken.error = "cannot read the photo's metadata";
  const PhotoAnalysis unreadable = AnalyzePhotos(Set({broken, Photo("e.jpg", 1.0, 0.0, 0.0)}), {});
  EXPECT_EQ(unreadable.excluded, 1u);
  const PhotoAnalysis mostly_unreadable =
      AnalyzePhotos(Set({broken, broken, Photo("e.jpg", 1.0, 0.0, 0.0)}), {});
  EXPECT_EQ(mostly_unreadable.excluded, 2u);
  EXPECT_NE(mostly_unreadable.verdict.find("exclude.txt drops 2 of 3 photos (2 unreadable)"),
            std::string::npos)
      << mostly_unreadable.verdict;
  EXPECT_EQ(mostly_unreadable.verdict.find("--limit"), std::string::npos)
      << mostly_unreadable.verdict;
  const PhotoAnalysis both = AnalyzePhotos(
      Set({broken, Photo("a.jpg", 10.0, 0.0, 0.0), Photo("b.jpg", 10.0, 0.0, 0.0)}), {});
  EXPECT_NE(both.verdict.find("exclude.txt drops 3 of 3 photos (1 unreadable): the others' shifts "
                              "are 4 px"),
            std::string::npos)
      << both.verdict;
  EXPECT_NE(both.verdict.find("a larger --limit keeps more"), std::string::npos) << both.verdict;
}

// The log's analysis used one altitude (50 m) for every photo; the ground shift of the same image
// rotation is at each photo's own height (100 m and 41 m here), unless the user's altitude wins.
TEST(AnalyzePhotos, TheRotationPartIsAtEachPhotosOwnAltitude) {
  PhotoRecord low = Photo("low.jpg", 0.0, 0.0, 0.0);
  low.altitude_m = 41.0;
  const PhotoSet set = Set({Photo("high.jpg", 0.0, 0.0, 0.0), low});
  AnalyzeResult log;
  log.altitude_m = 50.0;
  for (const char* name : {"high.jpg", "low.jpg"}) {
    ImageResult image;
    image.name = name;
    image.in_trace = true;
    image.d_full_px = 2.0;
    image.d_full_m = 2.0 * 50.0 / 2000.0;  // 5 cm at 50 m and f 2000 px
    image.d_paper_m = 0.04;
    log.images.push_back(image);
  }
  std::vector<PhotoPlacement> placements(2);
  placements[0].t_ns = 1'000'000'000;
  placements[1].t_ns = 2'000'000'000;
  PhotoAnalysisOptions each;
  each.rotation_at_each_photo_altitude = true;
  const PhotoAnalysis a = AnalyzePhotosWithLog(set, each, placements, log);
  EXPECT_DOUBLE_EQ(*a.photos[0].d_rotation_m, 2.0 * 100.0 / 2000.0);
  EXPECT_DOUBLE_EQ(*a.photos[1].d_rotation_m, 2.0 * 41.0 / 2000.0);
  EXPECT_DOUBLE_EQ(*a.photos[1].d_rotation_px, 2.0);
  EXPECT_DOUBLE_EQ(*a.photos[1].d_paper_m, 0.04 * 41.0 / 50.0) << "the paper's D scales alike";
  const PhotoAnalysis one = AnalyzePhotosWithLog(set, {}, placements, log);
  EXPECT_DOUBLE_EQ(*one.photos[0].d_rotation_m, 0.05);
  EXPECT_DOUBLE_EQ(*one.photos[1].d_rotation_m, 0.05);
  // A log's own height above ground stands: the photos' heights are above take-off.
  log.altitude_source = "log";
  const PhotoAnalysis from_log = AnalyzePhotosWithLog(set, each, placements, log);
  EXPECT_DOUBLE_EQ(*from_log.photos[1].d_rotation_m, 0.05);
}

TEST(WritePhotoOutputs, ExcludesFlaggedAndUnreadableAndListsTheRest) {
  test::TempDir dir;
  PhotoRecord broken;
  broken.path = "/photos/broken.jpg";
  broken.name = "broken.jpg";
  broken.error = "unreadable";
  const PhotoSet set =
      Set({Photo("fast.jpg", 10.0, 0.0, 0.0), Photo("slow.jpg", 1.0, 0.0, 0.0), broken});
  const PhotoAnalysis a = AnalyzePhotos(set, {});
  WritePhotoOutputs(dir / "out", set, a);
  EXPECT_EQ(ReadFileToString(dir / "out/exclude.txt"), "fast.jpg\nbroken.jpg\n");
  EXPECT_EQ(ReadFileToString(dir / "out/colmap_image_list.txt"), "slow.jpg\n");
  EXPECT_EQ(ReadFileToString(dir / "out/image_list.txt"), "/photos/slow.jpg\n");
  const std::string csv = ReadFileToString(dir / "out/photos.csv");
  EXPECT_NE(csv.find("slow.jpg,Test,Cam,4000,3000,2000,0.02,user,100,1,,,,0.02,0.4,0.4,"),
            std::string::npos)
      << csv;
  EXPECT_NE(csv.find("broken.jpg,,,0,0,,,none,,,,,,,,,,,,,unreadable"), std::string::npos) << csv;
}

}  // namespace
}  // namespace shutterlab
