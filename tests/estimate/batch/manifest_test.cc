// The batch manifest: what it reads, the jobs it chooses, and a refusal naming the line for every
// kind of mistake.

#include "estimate/batch/manifest.h"

#include "sim/check.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

// A folder with one log, one photo folder, a clip and a camera.json, and a manifest beside them.
class ManifestTest : public ::testing::Test {
 protected:
  void SetUp() override {
    test::WriteText(dir_, "f1.ulg", "not read here");
    std::filesystem::create_directories(dir_.path() / "photos");
    test::WriteText(dir_, "photos/a.jpg", "x");
    test::WriteText(dir_, "clip.mp4", "x");
    test::WriteText(dir_, "camera.json", "{}");
  }
  std::string Write(const std::string& text) { return test::WriteText(dir_, "m.toml", text); }
  // The one-line refusal of a manifest, "" when it is read.
  std::string Refusal(const std::string& text) {
    try {
      ReadBatchManifest(Write(text));
    } catch (const IoError& e) {
      return e.what();
    }
    return "";
  }
  test::TempDir dir_;
};

TEST_F(ManifestTest, ReadsItemsWithDefaultsAndChoosesJobsFromInputs) {
  const BatchManifest m = ReadBatchManifest(Write(R"(
[defaults]
camera = "camera.json"
group = "M3E"
limit = ["5cm", "0.1m"]
readout = "25ms"

[[item]]
id = "log-only"
log = "f1.ulg"

[[item]]
id = "photos.with-log"
log = "f1.ulg"
photos = "photos"
group = "P4P"
altitude = "80m"
jobs = ["photos", "correct", "export"]
export = ["odm", "colmap"]

[[item]]
id = "clip_1"
clip = "clip.mp4"
start_frame = 100
max_frames = 31
)"));
  ASSERT_EQ(m.items.size(), 3u);
  const BatchItem& a = m.items[0];
  EXPECT_EQ(a.id, "log-only");
  EXPECT_EQ(a.line, 8);
  EXPECT_EQ(a.group, "M3E");
  EXPECT_EQ(a.log, (dir_.path() / "f1.ulg").string());  // relative to the manifest
  EXPECT_EQ(a.camera, (dir_.path() / "camera.json").string());
  EXPECT_DOUBLE_EQ(a.readout_s, 0.025);
  EXPECT_TRUE(std::isnan(a.altitude_m));
  ASSERT_EQ(a.limits_m.size(), 2u);
  EXPECT_DOUBLE_EQ(a.limits_m[1], 0.1);
  ASSERT_EQ(a.jobs.size(), 1u);
  EXPECT_EQ(a.jobs[0], BatchJob::kAnalyze);

  const BatchItem& b = m.items[1];
  EXPECT_EQ(b.group, "P4P");
  EXPECT_DOUBLE_EQ(b.altitude_m, 80);
  ASSERT_EQ(b.jobs.size(), 3u);
  EXPECT_EQ(b.jobs[0], BatchJob::kPhotos);
  EXPECT_EQ(b.jobs[2], BatchJob::kExport);
  EXPECT_EQ(b.exports, (std::vector<std::string>{"odm", "colmap"}));

  const BatchItem& c = m.items[2];  // a clip: imported, then validated
  ASSERT_EQ(c.jobs.size(), 2u);
  EXPECT_EQ(c.jobs[0], BatchJob::kImport);
  EXPECT_EQ(c.jobs[1], BatchJob::kValidate);
  EXPECT_EQ(c.start_frame, 100);
  EXPECT_EQ(c.max_frames, 31);
  EXPECT_EQ(a.start_frame, -1);
  EXPECT_EQ(a.max_frames, -1);

  // Every file under an input, sorted: the folder whole.
  const std::vector<std::string> files = BatchItemInputFiles(b);
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0], (dir_.path() / "camera.json").string());
  EXPECT_EQ(files[2], (dir_.path() / "photos/a.jpg").string());
}

TEST_F(ManifestTest, RefusesEachMistakeNamingTheLine) {
  const std::string m = dir_ / "m.toml";
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nlog = \"missing.ulg\"\n"),
            m + ":3: log 'missing.ulg' does not exist (" + (dir_ / "missing.ulg") +
                "; relative paths are read from the manifest's folder)");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nlog = \"f1.ulg\"\nreadout = \"25\"\n"),
            m + ":4: readout '25': a duration needs a unit: did you mean 25ms or 25s? (s, ms, us, "
                "ns, min, h)");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nlog = \"f1.ulg\"\nreadout = 25\n"),
            m + ":4: 'readout' must be a string (in quotes)");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nlog = \"f1.ulg\"\nspeed = \"5m/s\"\n"),
            m + ":4: unknown key 'speed' (log, photos, clip, dataset, triggers, camera, "
                "lens_profile, id, group, readout, altitude, limit, jobs, export, start_frame, "
                "max_frames)");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nclip = \"clip.mp4\"\nmax_frames = 0\n"),
            m + ":4: 'max_frames' must be a whole number of at least 1 (no quotes)");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nclip = \"clip.mp4\"\nstart_frame = \"100\"\n"),
            m + ":4: 'start_frame' must be a whole number of at least 0 (no quotes)");
  EXPECT_EQ(Refusal("[defaults]\nmax_frames = 10\n[[item]]\nid = \"a\"\nclip = \"clip.mp4\"\n"),
            m + ":2: 'max_frames' chooses one clip's frames: give it in its [[item]]");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nlog = \"f1.ulg\"\nstart_frame = 10\n"),
            m + ":1: item 'a': start_frame and max_frames choose a clip's frames, and it has no "
                "clip");
  EXPECT_EQ(
      Refusal("[[item]]\nid = \"a\"\nlog = \"f1.ulg\"\n[[item]]\nid = \"a\"\nlog = \"f1.ulg\"\n"),
      m + ":4: id 'a' is given twice (line 1 too)");
  EXPECT_EQ(Refusal("[[item]]\nid = \"../up\"\nlog = \"f1.ulg\"\n"),
            m + ":1: id '../up' must be letters, digits, '.', '_' or '-' (it names a folder), not "
                "starting with '.'");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nlog = \"f1.ulg\"\njobs = [\"validate\"]\n"),
            m + ":1: item 'a': job 'validate' needs a dataset or a clip");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nphotos = \"photos\"\njobs = [\"photos\", \"export\"]\n"),
            m + ":1: item 'a': job 'export' needs export = [\"odm\", ...] (colmap, odm, kalibr, "
                "gyroflow, metashape, pix4d, vins)");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nphotos = \"photos\"\njobs = [\"fly\"]\n"),
            m + ":4: unknown job 'fly' (import, analyze, photos, validate, correct, export)");
  EXPECT_EQ(Refusal("[defaults]\nlog = \"f1.ulg\"\n[[item]]\nid = \"a\"\n"),
            m + ":2: 'log' is one flight's input: give it in each [[item]], not [defaults]");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\n"),
            m + ":1: item 'a' has no input: give log, photos, clip or dataset");
  EXPECT_EQ(Refusal("[defaults]\ngroup = \"x\"\n"),
            m + ":1: no [[item]]: a manifest lists its flights as [[item]] tables");
  EXPECT_EQ(Refusal("[[item]]\nid = \"a\"\nlog = \"photos\"\n"),
            m + ":3: log 'photos' is not a file");
  // toml++'s own refusal, at its line.
  const std::string syntax = Refusal("[[item]]\nid = \"a\"\nlog = f1.ulg\n");
  EXPECT_EQ(syntax.rfind(m + ":3: ", 0), 0u) << syntax;
}

}  // namespace
}  // namespace shutterlab
