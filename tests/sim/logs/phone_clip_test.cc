#include "sim/logs/phone_clip.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// Times are dyadic fractions of a second, exact in a double, so that every nanosecond is known.
const char kGyroTxt[] =
    "0.1,0.2,0.3,1000.5\n"
    "0.4,0.5,0.6,1000.5078125\n"
    "0.7,0.8,0.9,1000.515625\n";
const char kFramestampTxt[] = "1000.25\n1000.3125\n1000.375\n";
// Frame 3's SOF is 10 us later than framestamp.txt's; lines not starting with SOF are skipped.
const char kGyroDumpTxt[] =
    "SOF  1000312500,  frameNum :2 exp time 0.005\n"
    "frameid:2 gyro:0 x 0.1 y 0.2 z 0.3 ts 1000312600\n"
    "SOF  1000375010,  frameNum :3 exp time 0.0061\n";

// A clip folder with the three text files and images for frames 1 and 3, plus files the reader
// must pass over.
fs::path MakeClip(const test::TempDir& dir) {
  const fs::path clip = dir.path() / "clip";
  fs::create_directories(clip / "frames");
  WriteFileAtomically(clip / "gyro.txt", kGyroTxt);
  WriteFileAtomically(clip / "framestamp.txt", kFramestampTxt);
  WriteFileAtomically(clip / "gyro_dump.txt", kGyroDumpTxt);
  WriteFileAtomically(clip / "frames/RE_frame-1.jpg", "not decoded here");
  WriteFileAtomically(clip / "frames/RE_frame-3.PNG", "not decoded here");
  WriteFileAtomically(clip / "frames/RE_frame-2.gif", "not an image extension the layout uses");
  WriteFileAtomically(clip / "frames/notes.txt", "");
  return clip;
}

void ExpectIoError(const fs::path& clip, const std::string& needle) {
  try {
    ReadPhoneClip(clip.string());
    ADD_FAILURE() << "no error, expected " << needle;
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << e.what() << "\n  wanted: " << needle;
  }
}

TEST(PhoneClip, KnownFolderReadsExactly) {
  test::TempDir dir;
  const fs::path clip_dir = MakeClip(dir);
  const PhoneClip clip = ReadPhoneClip(clip_dir.string());
  EXPECT_EQ(clip.time_origin_ns, 1'000'000'000'000);  // the first gyro time's whole seconds
  ASSERT_EQ(clip.gyro.size(), 3u);
  EXPECT_EQ(clip.gyro.samples()[0].t_ns, 500'000'000);
  EXPECT_EQ(clip.gyro.samples()[1].t_ns, 507'812'500);
  EXPECT_EQ(clip.gyro.samples()[2].t_ns, 515'625'000);
  EXPECT_EQ(clip.gyro.samples()[1].omega_rad_s, Eigen::Vector3d(0.4, 0.5, 0.6));
  EXPECT_EQ(clip.sof_ns, (std::vector<int64_t>{250'000'000, 312'500'000, 375'000'000}));
  EXPECT_EQ(clip.exposure_s, (std::map<int64_t, double>{{2, 0.005}, {3, 0.0061}}));
  EXPECT_DOUBLE_EQ(clip.dump_sof_max_diff_s, 10e-6);
  ASSERT_EQ(clip.frame_images.size(), 2u);
  EXPECT_EQ(clip.frame_images.at(1), (clip_dir / "frames/RE_frame-1.jpg").string());
  EXPECT_EQ(clip.frame_images.at(3), (clip_dir / "frames/RE_frame-3.PNG").string());
}

TEST(PhoneClip, GyroDumpIsOptional) {
  test::TempDir dir;
  const fs::path clip_dir = MakeClip(dir);
  fs::remove(clip_dir / "gyro_dump.txt");
  const PhoneClip clip = ReadPhoneClip(clip_dir.string());
  EXPECT_TRUE(clip.exposure_s.empty());
  EXPECT_EQ(clip.dump_sof_max_diff_s, 0.0);
  EXPECT_EQ(clip.sof_ns.size(), 3u);
}

TEST(PhoneClip, MissingPartIsNamed) {
  test::TempDir dir;
  const fs::path clip_dir = MakeClip(dir);
  EXPECT_EQ(MissingPhoneClipPart(clip_dir.string()), "");
  fs::remove(clip_dir / "gyro_dump.txt");  // optional
  EXPECT_EQ(MissingPhoneClipPart(clip_dir.string()), "");
  fs::remove_all(clip_dir / "frames");
  EXPECT_EQ(MissingPhoneClipPart(clip_dir.string()), "frames");
  fs::remove(clip_dir / "framestamp.txt");
  EXPECT_EQ(MissingPhoneClipPart(clip_dir.string()), "framestamp.txt");
  fs::remove(clip_dir / "gyro.txt");
  EXPECT_EQ(MissingPhoneClipPart(clip_dir.string()), "gyro.txt");
}

TEST(PhoneClip, MalformedFilesNameTheFileAndLine) {
  test::TempDir dir;
  const fs::path clip = MakeClip(dir);
  const auto with = [&](const std::string& name, const std::string& text,
                        const std::string& needle) {
    const std::string original = ReadFileToString((clip / name).string());
    WriteFileAtomically(clip / name, text);
    ExpectIoError(clip, needle);
    WriteFileAtomically(clip / name, original);
  };
  with("gyro.txt", "0.1,0.2,0.3,1000.5\n0.1,0.2,1000.6\n",
       "gyro.txt:2: column 4 (time) missing: the line has 3 fields");
  with("gyro.txt", "0.1,0.2,0.3,1000.5\n0.1,x,0.3,1000.6\n",
       "gyro.txt:2: column 2 (y) is not a number: 'x'");
  with("gyro.txt", "0.1,0.2,0.3,1000.5\n0.1,0.2,0.3,1000.4\n", "gyro.txt:2: time goes backwards");
  with("gyro.txt", "0.1,0.2,0.3,1000.5\n", "gyro.txt: fewer than 2 samples");
  with("framestamp.txt", "1000.25\n\n1000.375\n",
       "framestamp.txt:3: blank line: line N must be frame N");
  with("framestamp.txt", "1000.25\nsoon\n", "framestamp.txt:2: not a time in seconds");
  with("framestamp.txt", "\n", "framestamp.txt: no start-of-frame times");
  with("gyro_dump.txt", "SOF  1000312500,  frameNum :2\n",
       "gyro_dump.txt:1: expected 'SOF <us>, frameNum :N exp time <s>'");
  // Frame 3 has an image but framestamp.txt now ends at frame 2.
  with("framestamp.txt", "1000.25\n1000.3125\n",
       "RE_frame-3.PNG: frame 3 has no time in framestamp.txt (2 lines)");
  fs::remove(clip / "frames/RE_frame-1.jpg");
  fs::remove(clip / "frames/RE_frame-3.PNG");
  ExpectIoError(clip, "frames: no RE_frame-N.jpg images");
}

// A gyro.txt cut inside its last line (a copy stopped mid-write) is read up to the last whole line,
// and says what it left out; the same line with its line break is an error.
TEST(PhoneClip, GyroCutInsideItsLastLineIsReadAndSaid) {
  test::TempDir dir;
  const fs::path clip = MakeClip(dir);
  const std::string whole = "0.1,0.2,0.3,1000.5\n0.1,0.2,0.3,1000.75\n0.4,0.5,0.6,1001.0\n";
  // Cut 1 to 3 bytes before the end, the last line still reads (1001.0, "1001." or "1001");
  // from 4 on it is short of a field or a time before the line above it ("100"): left out.
  for (size_t cut = 4; cut < 19; ++cut) {
    WriteFileAtomically(clip / "gyro.txt", whole.substr(0, whole.size() - cut));
    const PhoneClip read = ReadPhoneClip(clip.string());
    ASSERT_EQ(read.gyro.size(), 2u) << "cut " << cut;
    EXPECT_EQ(read.gyro.samples()[1].t_ns, 750'000'000) << "cut " << cut;
    ASSERT_EQ(read.warnings.size(), 1u) << "cut " << cut;
    EXPECT_EQ(read.warnings[0].kind, "truncated");
    EXPECT_EQ(read.warnings[0].t_s, 0.75) << "the time of the last sample kept";
    EXPECT_NE(read.warnings[0].message.find("line 3"), std::string::npos)
        << read.warnings[0].message;
  }
  WriteFileAtomically(clip / "gyro.txt", whole);
  EXPECT_TRUE(ReadPhoneClip(clip.string()).warnings.empty());
  WriteFileAtomically(clip / "gyro.txt", whole.substr(0, whole.size() - 5) + "\n");
  ExpectIoError(clip, "gyro.txt:3:");
}

// The shared data's phone clip (lhaippp/gyro-video-stabilization 20200109_145447).
TEST(PhoneClip, RealClip) {
  SHUTTERLAB_REAL_DATA(folder, "rs/phone_gyro_video_20200109_145447");
  EXPECT_EQ(MissingPhoneClipPart(folder), "");
  const PhoneClip clip = ReadPhoneClip(folder);
  const std::string gyro_text = ReadFileToString(folder + "/gyro.txt");
  const double first_t_s =
      std::stod(gyro_text.substr(gyro_text.rfind(',', gyro_text.find('\n')) + 1));
  EXPECT_EQ(clip.time_origin_ns, static_cast<int64_t>(std::floor(first_t_s)) * 1'000'000'000);
  EXPECT_EQ(clip.gyro.size(), 29466u);
  EXPECT_NEAR(clip.gyro.sampling().RateHz(), 412.2, 0.3);
  EXPECT_EQ(clip.sof_ns.size(), 2146u);
  ASSERT_EQ(clip.frame_images.size(), 20u);
  EXPECT_EQ(clip.frame_images.begin()->first, 100);
  EXPECT_EQ(clip.frame_images.rbegin()->first, 119);
  EXPECT_DOUBLE_EQ(clip.exposure_s.at(100), 0.005405);  // "frameNum :100 exp time 0.005405"
  EXPECT_LE(clip.dump_sof_max_diff_s, 1e-6);            // the dump agrees with framestamp.txt
}

}  // namespace
}  // namespace shutterlab
