// `batch --scan`: a folder tree turned into a manifest that the manifest reader takes as it is.

#include "estimate/batch/manifest_scan.h"

#include "estimate/batch/manifest.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

TEST(ManifestScan, FindsEachKindByContentAndTheReaderTakesTheManifest) {
  test::TempDir dir;
  const std::string gyro_csv = "t,gx,gy,gz\n0.000,0.01,0.02,0.03\n0.001,0.01,0.02,0.03\n";
  for (const char* folder :
       {"M3E/day1/photos", "M3E/day2", "phone/clip1/frames", "rig", "notes", "out/items/old"}) {
    fs::create_directories(dir.path() / folder);
  }
  test::WriteText(dir, "M3E/day1/photos/DJI_0001.JPG", "x");
  test::WriteText(dir, "M3E/day1/photos/DJI_0002.jpg", "x");
  test::WriteText(dir, "M3E/day1/photos/DJI_Timestamp.MRK", "1\t2\n");
  test::WriteText(dir, "M3E/day1/photos/flight.csv", gyro_csv);  // a log by its content
  test::WriteText(dir, "M3E/day2/a.log", gyro_csv);
  test::WriteText(dir, "M3E/day2/b.log", gyro_csv);
  test::WriteText(dir, "M3E/day2/summary.csv", "name,score\nx,1\n");  // not a log
  test::WriteText(dir, "phone/clip1/gyro.txt", "1 2 3 4\n");
  test::WriteText(dir, "phone/clip1/framestamp.txt", "1\n");
  test::WriteText(dir, "rig/camera.json", "{}");
  test::WriteText(dir, "rig/frames.csv", "frame,t\n");
  test::WriteText(dir, "notes/readme.txt", "t,gx,gy,gz\n");  // a .txt is never a log
  test::WriteText(dir, "out/items/old/made.json", "{}");     // a batch's output: skipped
  test::WriteText(dir, "out/items/old/gyro.csv", gyro_csv);

  const ManifestScan scan = ScanForManifest(dir.path().string());
  EXPECT_EQ(scan.logs, 2u);
  EXPECT_EQ(scan.photo_folders, 1u);
  EXPECT_EQ(scan.paired, 1u);
  EXPECT_EQ(scan.clips, 1u);
  EXPECT_EQ(scan.datasets, 1u);
  const std::string manifest = test::WriteText(dir, "fleet.toml", scan.toml);
  const BatchManifest m = ReadBatchManifest(manifest);
  ASSERT_EQ(m.items.size(), 5u) << scan.toml;
  const BatchItem& photos = m.items[0];
  EXPECT_EQ(photos.id, "M3E_day1_photos");
  EXPECT_EQ(photos.group, "M3E");
  EXPECT_EQ(photos.photos, dir / "M3E/day1/photos");
  EXPECT_EQ(photos.log, dir / "M3E/day1/photos/flight.csv");
  EXPECT_EQ(photos.triggers, dir / "M3E/day1/photos/DJI_Timestamp.MRK");
  ASSERT_EQ(photos.jobs.size(), 1u);
  EXPECT_EQ(photos.jobs[0], BatchJob::kPhotos);
  EXPECT_EQ(m.items[1].id, "M3E_day2_a");
  EXPECT_EQ(m.items[1].jobs[0], BatchJob::kAnalyze);
  EXPECT_EQ(m.items[2].log, dir / "M3E/day2/b.log");
  EXPECT_EQ(m.items[3].id, "phone_clip1");
  EXPECT_EQ(m.items[3].clip, dir / "phone/clip1");
  EXPECT_EQ(m.items[3].jobs[0], BatchJob::kImport);
  EXPECT_EQ(m.items[4].dataset, dir / "rig");
  EXPECT_EQ(m.items[4].group, "");
}

}  // namespace
}  // namespace shutterlab
