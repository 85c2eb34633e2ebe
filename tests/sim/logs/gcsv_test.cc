#include "sim/logs/gcsv.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace shutterlab {
namespace {

// A value times a scale read back from text: one double rounding.
constexpr double kScaleTolRel = 1e-15;

const char kHeader[] =
    "GYROFLOW IMU LOG\n"
    "version,1.3\n"
    "id,potatocam_mark1\n"
    "orientation,XYZ\n"
    "note,a note, with a comma\n"
    "fwversion,FIRMWARE_0.1.0\n"
    "timestamp,1644159993\n"
    "vendor,potatocam\n"
    "videofilename,videofilename.mp4\n"
    "lensprofile,potatocam/potatocam_mark1_prime_7_5mm_4k\n"
    "lens_info,wide\n"
    "frame_readout_time,15.23\n"
    "frame_readout_direction,0\n"
    "tscale,0.001\n"
    "gscale,0.00122173\n"
    "ascale,0.00059875488\n";

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

void ExpectIoError(const std::string& path, long line, const std::string& problem) {
  try {
    ReadGcsv(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const IoError& e) {
    const std::string what = e.what();
    const std::string where = line > 0 ? path + ":" + std::to_string(line) + ":" : path + ":";
    EXPECT_NE(what.find(where), std::string::npos) << what;
    EXPECT_NE(what.find(problem), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(Gcsv, ReadsTheDocumentedExample) {
  test::TempDir dir;
  const std::string path = test::WriteText(dir, "a.gcsv",
                                           std::string(kHeader) +
                                               "t,gx,gy,gz,ax,ay,az\n"
                                               "0,39,86,183,-1137,-15689,-2986\n"
                                               "1,56,100,202,-1179,-15694,-2887\n"
                                               "2,63,108,218,-1247,-15702,-2794\n");
  const GcsvLog log = ReadGcsv(path);
  ASSERT_EQ(log.trace.size(), 3u);
  EXPECT_EQ(log.trace[1].t_ns, 1000000);  // 1 * tscale 0.001 s, exact
  EXPECT_EQ(log.trace[2].t_ns, 2000000);
  EXPECT_NEAR(log.trace[0].omega_rad_s.x(), 39 * 0.00122173, 39 * 0.00122173 * kScaleTolRel);
  EXPECT_NEAR(log.trace[2].omega_rad_s.z(), 218 * 0.00122173, 218 * 0.00122173 * kScaleTolRel);
  EXPECT_EQ(log.orientation, "XYZ");
  ASSERT_TRUE(log.frame_readout_s.has_value());
  EXPECT_DOUBLE_EQ(*log.frame_readout_s, 0.01523);  // Gyroflow writes milliseconds
  EXPECT_EQ(log.frame_readout_direction, ReadoutDirection::kTopToBottom);
  EXPECT_EQ(log.tscale, 0.001);
  ASSERT_EQ(log.header.size(), 15u);
  EXPECT_EQ(log.header[3].first, "note");
  EXPECT_EQ(log.header[3].second, "a note, with a comma");
  EXPECT_TRUE(log.warnings.empty());
}

TEST(Gcsv, OrientationFollowsTelemetryParser) {
  // out[i] = sign * in[letter i]: "yXz" on input (1, 2, 3) gives (-2, 1, -3).
  const Eigen::Matrix3d m = GcsvOrientationMatrix("yXz");
  EXPECT_EQ(m * Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(-2, 1, -3));
  EXPECT_EQ(GcsvOrientationMatrix("XYZ"), Eigen::Matrix3d::Identity());
  EXPECT_EQ(GcsvOrientationMatrix("xzY") * Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(-1, -3, 2));
  EXPECT_THROW(GcsvOrientationMatrix("XXZ"), std::invalid_argument);
  EXPECT_THROW(GcsvOrientationMatrix("XY"), std::invalid_argument);
  EXPECT_THROW(GcsvOrientationMatrix("XYW"), std::invalid_argument);

  test::TempDir dir;
  const std::string text =
      Replace(kHeader, "orientation,XYZ", "orientation,YxZ") + "t,gx,gy,gz\n0,1,2,3\n";
  const GcsvLog log = ReadGcsv(test::WriteText(dir, "o.gcsv", text));
  const Eigen::Vector3d expected = Eigen::Vector3d(2, -1, 3) * 0.00122173;
  EXPECT_NEAR((log.trace[0].omega_rad_s - expected).norm(), 0.0, 1e-15);
}

TEST(Gcsv, MissingOrientationDefaultsLikeGyroflow) {
  test::TempDir dir;
  const std::string text = Replace(kHeader, "orientation,XYZ\n", "") + "t,gx,gy,gz\n0,1,2,3\n";
  const GcsvLog log = ReadGcsv(test::WriteText(dir, "o.gcsv", text));
  EXPECT_EQ(log.orientation, "xzY");
  EXPECT_EQ(log.warnings.size(), 1u);
  EXPECT_NEAR(log.trace[0].omega_rad_s.y(), -3 * 0.00122173, 1e-15);
}

TEST(Gcsv, ReadoutDirectionCodes) {
  test::TempDir dir;
  const struct {
    const char* code;
    const char* word;
  } cases[] = {{"0", "top_to_bottom"}, {"1", "bottom_to_top"},           {"180", "bottom_to_top"},
               {"2", "left_to_right"}, {"RightToLeft", "right_to_left"}, {"90", "right_to_left"}};
  for (const auto& c : cases) {
    const std::string text = Replace(kHeader, "frame_readout_direction,0",
                                     std::string("frame_readout_direction,") + c.code) +
                             "t,gx,gy,gz\n0,1,2,3\n";
    EXPECT_STREQ(ReadoutDirectionName(
                     ReadGcsv(test::WriteText(dir, "d.gcsv", text)).frame_readout_direction),
                 c.word)
        << c.code;
  }
  // Legacy sign encoding: a negative time means the other direction.
  const std::string negative =
      Replace(kHeader, "frame_readout_time,15.23", "frame_readout_time,-15.23") +
      "t,gx,gy,gz\n0,1,2,3\n";
  const GcsvLog log = ReadGcsv(test::WriteText(dir, "n.gcsv", negative));
  EXPECT_EQ(log.frame_readout_direction, ReadoutDirection::kBottomToTop);
  EXPECT_DOUBLE_EQ(*log.frame_readout_s, 0.01523);
  // No readout line: none.
  const std::string none =
      Replace(kHeader, "frame_readout_time,15.23\n", "") + "t,gx,gy,gz\n0,1,2,3\n";
  EXPECT_FALSE(ReadGcsv(test::WriteText(dir, "x.gcsv", none)).frame_readout_s.has_value());
}

TEST(Gcsv, NonDecimalTscaleGoesThroughDouble) {
  test::TempDir dir;
  const std::string text =
      Replace(kHeader, "tscale,0.001", "tscale,0.00025") + "t,gx,gy,gz\n4,0,0,0\n8.5,0,0,0\n";
  const GcsvLog log = ReadGcsv(test::WriteText(dir, "t.gcsv", text));
  EXPECT_EQ(log.trace[0].t_ns, 1000000);
  EXPECT_EQ(log.trace[1].t_ns, 2125000);
}

TEST(Gcsv, WriterRoundTripsLosslessAndQuantised) {
  test::TempDir dir;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> rate(0.0, 2.0);
  std::vector<GyroSample> samples;
  for (int k = 0; k < 300; ++k) {
    samples.push_back(
        {1600000000000000000LL + k * 2000123LL, Eigen::Vector3d(rate(rng), rate(rng), rate(rng))});
  }
  const GyroTrace trace(samples);
  for (const char* orientation : {"XYZ", "yXz", "zxY"}) {
    for (TimeUnit unit : {TimeUnit::kSeconds, TimeUnit::kMilliseconds, TimeUnit::kMicroseconds,
                          TimeUnit::kNanoseconds}) {
      GcsvWriteOptions options;
      options.orientation = orientation;
      options.time_unit = unit;
      options.frame_readout_s = 0.0213;
      options.frame_readout_direction = ReadoutDirection::kBottomToTop;
      options.extra_header = {{"note", "synthetic, seed 7"}, {"vendor", "shutterlab"}};
      const std::string path = dir / "rt.gcsv";
      WriteGcsv(path, trace, options);
      const GcsvLog log = ReadGcsv(path);
      EXPECT_EQ(log.orientation, orientation);
      EXPECT_DOUBLE_EQ(*log.frame_readout_s, 0.0213);
      EXPECT_EQ(log.frame_readout_direction, ReadoutDirection::kBottomToTop);
      ASSERT_EQ(log.trace.size(), trace.size());
      for (size_t i = 0; i < trace.size(); ++i) {
        EXPECT_EQ(log.trace[i].t_ns, trace[i].t_ns);
        EXPECT_EQ(log.trace[i].omega_rad_s, trace[i].omega_rad_s);  // shortest round-trip text
      }
    }
  }
  GcsvWriteOptions quantised;
  quantised.orientation = "yXz";
  quantised.gscale = 0.00122173;
  WriteGcsv(dir / "q.gcsv", trace, quantised);
  const GcsvLog log = ReadGcsv(dir / "q.gcsv");
  for (size_t i = 0; i < trace.size(); ++i) {
    // Rounding to the nearest count: at most half a count per axis (plus double rounding).
    EXPECT_LE((log.trace[i].omega_rad_s - trace[i].omega_rad_s).cwiseAbs().maxCoeff(),
              0.5 * quantised.gscale * (1 + 1e-9));
  }
}

TEST(Gcsv, WriterRejectsBadOptions) {
  test::TempDir dir;
  const GyroTrace trace({{0, Eigen::Vector3d::Zero()}});
  GcsvWriteOptions options;
  options.orientation = "XYY";
  EXPECT_THROW(WriteGcsv(dir / "a.gcsv", trace, options), std::invalid_argument);
  options = {};
  options.extra_header = {{"tscale", "5"}};
  EXPECT_THROW(WriteGcsv(dir / "a.gcsv", trace, options), std::invalid_argument);
  options = {};
  options.extra_header = {{"note", "two\nlines"}};
  EXPECT_THROW(WriteGcsv(dir / "a.gcsv", trace, options), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "a.gcsv"));
}

TEST(Gcsv, RejectsBadInputNamingTheLine) {
  test::TempDir dir;
  const std::string rows = "t,gx,gy,gz\n0,1,2,3\n1,1,2,3\n";
  ExpectIoError(test::WriteText(dir, "a", "version,1.3\n" + rows), 1,
                "missing first line 'GYROFLOW IMU LOG'");
  // Truncated inside the header block.
  ExpectIoError(test::WriteText(dir, "b", "GYROFLOW IMU LOG\nversion,1.3\nid,x\n"), 3,
                "header ends before the column line");
  ExpectIoError(test::WriteText(dir, "c", Replace(kHeader, "tscale,0.001\n", "") + rows), 16,
                "no tscale");
  ExpectIoError(test::WriteText(dir, "d", Replace(kHeader, "gscale,0.00122173\n", "") + rows), 16,
                "no gscale");
  ExpectIoError(
      test::WriteText(dir, "e", Replace(kHeader, "gscale,0.00122173", "gscale,-1") + rows), 15,
      "gscale must be a positive number");
  ExpectIoError(
      test::WriteText(dir, "f", Replace(kHeader, "orientation,XYZ", "orientation,XYQ") + rows), 4,
      "orientation 'XYQ'");
  ExpectIoError(
      test::WriteText(
          dir, "g",
          Replace(kHeader, "frame_readout_direction,0", "frame_readout_direction,7") + rows),
      13, "unknown frame_readout_direction '7'");
  ExpectIoError(test::WriteText(dir, "h", std::string(kHeader) + "t,gy,gx,gz\n0,1,2,3\n"), 17,
                "column line must start");
  ExpectIoError(
      test::WriteText(dir, "i",
                      std::string(kHeader) + "t,gx,gy,gz,ax,ay,az\n0,1,2,3,4,5,6\n1,1,2,3\n"),
      19, "expected 7 columns as on line 17, found 4");
  ExpectIoError(test::WriteText(dir, "j", std::string(kHeader) + rows + "2,1,abc,3\n"), 20,
                "gy is not a finite number: 'abc'");
  ExpectIoError(test::WriteText(dir, "k", std::string(kHeader) + rows + "2,1,nan,3\n"), 20,
                "gy is not a finite number");
  ExpectIoError(test::WriteText(dir, "l", std::string(kHeader) + rows + "0.5,1,2,3\n"), 20,
                "timestamp decreases");
  ExpectIoError(test::WriteText(dir, "m", std::string(kHeader) + rows + "inf,1,2,3\n"), 20,
                "t is not a finite number");
  ExpectIoError(test::WriteText(dir, "n", std::string(kHeader) + "t,gx,gy,gz\n"), 0, "no samples");
  ExpectIoError(test::WriteText(dir, "o", Replace(kHeader, "version,1.3", "version") + rows), 2,
                "not 'key,value'");
}

TEST(Gcsv, GapLinesOfTheHeaderAreGapWarnings) {
  test::TempDir dir;
  const std::string path =
      test::WriteText(dir, "rec.gcsv",
                      "GYROFLOW IMU LOG\nversion,1.3\norientation,XYZ\n"
                      "gap,1.010612500,315,fifo_overflow\n"
                      "gap,2.5,7\n"
                      "gap,soon,7,bad_data\n"
                      "tscale,0.001\ngscale,1\nt,gx,gy,gz\n0,1,2,3\n1,1,2,3\n");
  const GcsvLog log = ReadGcsv(path);
  ASSERT_EQ(log.warnings.size(), 3u) << test::JoinedWarnings(log.warnings);
  EXPECT_EQ(log.warnings[0].kind, "gap");
  EXPECT_EQ(log.warnings[0].t_s.value_or(-1), 1.0106125);
  EXPECT_EQ(log.warnings[0].count.value_or(0), 315u);
  EXPECT_NE(log.warnings[0].message.find("fifo_overflow"), std::string::npos);
  EXPECT_EQ(log.warnings[1].kind, "gap");  // the kind is optional
  EXPECT_EQ(log.warnings[1].count.value_or(0), 7u);
  EXPECT_EQ(log.warnings[2].kind, "format");  // a gap line that does not parse never fails the file
  EXPECT_EQ(log.trace.size(), 2u);
}

}  // namespace
}  // namespace shutterlab
