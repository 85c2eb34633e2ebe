#include "sim/logs/trigger_file.h"

#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/ulog_write.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <string>

namespace shutterlab {
namespace {

// Two photos in DJI's layout (tabs), the second with an odd editor's spaces instead.
constexpr char kMrk[] =
    "1\t396015.412566\t[2110]\t   -17,N\t    11,E\t   196,V\t22.56859393,Lat\t113.94289563,Lon\t"
    "-1.473,Ellh\t0.012520, 0.011839, 0.024812\t50,Q\n"
    "2 396017.5 [2110] -17,N 11,E 196,V 22.5686,Lat 113.9429,Lon -1.5,Ellh 0.01, 0.01, 0.02 "
    "16,Q\n";

TEST(TriggerFile, ReadsAHandWrittenMrk) {
  test::TempDir dir;
  const TriggerFile f = ReadTriggerFile(test::WriteText(dir, "a_Timestamp.MRK", kMrk));
  EXPECT_EQ(f.format, "mrk");
  EXPECT_EQ(f.clock, TriggerClock::kGps);
  ASSERT_EQ(f.events.size(), 2u);
  EXPECT_EQ(f.events[0].sequence, 1);
  EXPECT_EQ(f.events[0].t_ns, (2110LL * 604800 + 396015) * kNsPerSecond + 412'566'000);
  EXPECT_DOUBLE_EQ(*f.events[0].latitude_deg, 22.56859393);
  EXPECT_DOUBLE_EQ(*f.events[0].longitude_deg, 113.94289563);
  EXPECT_DOUBLE_EQ(*f.events[0].height_m, -1.473);
  EXPECT_EQ(f.events[1].sequence, 2);
  EXPECT_EQ(f.events[1].t_ns - f.events[0].t_ns, 2'087'434'000);
  EXPECT_DOUBLE_EQ(*f.events[1].latitude_deg, 22.5686);
  EXPECT_TRUE(f.warnings.empty()) << test::JoinedWarnings(f.warnings);
}

TEST(TriggerFile, MrkErrorsNameTheLine) {
  EXPECT_FALSE(LooksLikeMrk("image,t\n1,2\n"));
  try {
    ParseMrk("1\t396015.4\t[2110]\n2\t39x6017.5\t[2110]\n", "f.MRK");
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("f.MRK:2: bad GPS seconds of week '39x6017.5'"),
              std::string::npos)
        << e.what();
  }
  const TriggerFile f = ParseMrk("2\t10.0\t[2110]\n1\t5.0\t[2110]\n2\t12.0\t[2110]\n", "f.MRK");
  EXPECT_TRUE(test::AnyWarningContains(f.warnings, "earlier than the one before"))
      << test::JoinedWarnings(f.warnings);
  EXPECT_TRUE(test::AnyWarningContains(f.warnings, "photo number(s) given twice"));
}

// A file cut while it was written: a last line that does not read is left out, one cut among its
// labelled fields keeps its number and time; each said as truncated with its line. A whole file
// that only lacks its last line break reads without a word.
TEST(TriggerFile, ACutLastLineIsSaidNotAnError) {
  const std::string two(kMrk, sizeof(kMrk) - 1);
  const TriggerFile in_time = ParseMrk(two + "3\t3960", "f.MRK");
  ASSERT_EQ(in_time.events.size(), 2u);
  ASSERT_EQ(in_time.warnings.size(), 1u) << test::JoinedWarnings(in_time.warnings);
  EXPECT_EQ(in_time.warnings[0].kind, "truncated");
  EXPECT_NE(in_time.warnings[0].message.find("line 3: the file ends inside it"), std::string::npos)
      << in_time.warnings[0].message;
  EXPECT_EQ(in_time.warnings[0].count.value_or(0), 1u);

  const TriggerFile in_position =
      ParseMrk(two + "3\t396019.5\t[2110]\t-17,N\t11,E\t196,V\t22.56", "f.MRK");
  ASSERT_EQ(in_position.events.size(), 3u);
  EXPECT_EQ(in_position.events[2].sequence, 3);
  EXPECT_FALSE(in_position.events[2].latitude_deg);
  EXPECT_TRUE(test::AnyWarningContains(in_position.warnings, "read as far as it goes"))
      << test::JoinedWarnings(in_position.warnings);

  const std::string whole = two.substr(0, two.size() - 1);
  EXPECT_TRUE(ParseMrk(whole, "f.MRK").warnings.empty());
  EXPECT_THROW(ParseMrk("1\t39x0\t[2110]\n" + two, "f.MRK"), IoError);  // not the last line

  const TriggerFile csv = ParseTriggerCsv("image,t\nA,1\nB,", "f.csv");
  ASSERT_EQ(csv.events.size(), 1u);
  EXPECT_TRUE(test::AnyWarningContains(csv.warnings, "line 3: the file ends inside it"))
      << test::JoinedWarnings(csv.warnings);
  EXPECT_EQ(ParseTriggerCsv("image,t\nA,1\nB,2", "f.csv").events.size(), 2u);
}

TEST(TriggerFileReal, AutelEvoIIMrk) {
  SHUTTERLAB_REAL_DATA(path, "incoming/autel_mrk_helenenschacht/101FTASK_Timestamp.mrk");
  const TriggerFile f = ReadTriggerFile(path);
  EXPECT_EQ(f.format, "mrk");
  ASSERT_EQ(f.events.size(), 176u);  // PROVENANCE.md: 176 lines, MAX_0002..MAX_0177
  EXPECT_EQ(f.events.front().sequence, 2);
  EXPECT_EQ(f.events.back().sequence, 177);
  EXPECT_EQ(UtcText(UtcFromGpsNs(f.events.front().t_ns)), "2022-05-25 10:17:50.242");
  EXPECT_DOUBLE_EQ(*f.events.front().latitude_deg, 47.6436873208);
  EXPECT_DOUBLE_EQ(*f.events.back().height_m, 513.090);
  // PROVENANCE.md: median photo interval 1.502 s, min 1.134, max 15.38.
  std::vector<double> gaps;
  for (size_t i = 1; i < f.events.size(); ++i)
    gaps.push_back((f.events[i].t_ns - f.events[i - 1].t_ns) * 1e-9);
  EXPECT_NEAR(*std::min_element(gaps.begin(), gaps.end()), 1.134, 5e-4);
  EXPECT_NEAR(*std::max_element(gaps.begin(), gaps.end()), 15.38, 5e-3);
  EXPECT_TRUE(f.warnings.empty()) << test::JoinedWarnings(f.warnings);
}

TEST(TriggerFile, ReadsPlainAndNamedCsvOnTheLogClockOrUtc) {
  test::TempDir dir;
  const TriggerFile bare = ReadTriggerFile(test::WriteText(dir, "bare.csv", "1.5\n3.25\n"));
  EXPECT_EQ(bare.clock, TriggerClock::kLog);
  ASSERT_EQ(bare.events.size(), 2u);
  EXPECT_EQ(bare.events[1].t_ns, 3'250'000'000);
  EXPECT_TRUE(bare.events[0].name.empty());

  const TriggerFile named =
      ReadTriggerFile(test::WriteText(dir, "named.csv", "# c\nimage,t\nA.JPG,2\n"));
  EXPECT_EQ(named.events[0].name, "A.JPG");
  EXPECT_EQ(named.events[0].t_ns, 2'000'000'000);

  // The SIYI flight's image_metadata.csv layout: PX4 boot time in us wins over the UTC columns.
  const std::string siyi =
      "utc,timestamp,utc_usec,lat,lon,alt_msl,image\n"
      "2026-01-13 03:04:17.875381+00:00,182092193,1768273457875381,14.5,121.3,386.7,IMG_0001.jpg\n";
  const TriggerFile px4 = ReadTriggerFile(test::WriteText(dir, "siyi.csv", siyi));
  EXPECT_EQ(px4.clock, TriggerClock::kLog);
  EXPECT_EQ(px4.events[0].t_ns, 182'092'193'000);
  EXPECT_EQ(px4.events[0].name, "IMG_0001.jpg");

  const TriggerFile utc = ReadTriggerFile(
      test::WriteText(dir, "utc.csv", "name,utc\nB.jpg,2026-01-13T03:04:17.875381+01:00\n"));
  EXPECT_EQ(utc.clock, TriggerClock::kUtc);
  EXPECT_EQ(UtcText(utc.events[0].t_ns), "2026-01-13 02:04:17.875");
}

TEST(TriggerFile, CsvErrorsNameTheLine) {
  test::TempDir dir;
  const auto message = [&](const std::string& text) {
    try {
      ReadTriggerFile(test::WriteText(dir, "bad.csv", text));
    } catch (const IoError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("image,t\nA,1\nB,x\n").find("bad.csv:3: bad time 'x'"), std::string::npos);
  EXPECT_NE(message("image,when\nA,1\n").find("bad.csv:1: the header names no time column"),
            std::string::npos);
  EXPECT_NE(message("1,2,3\n").find("bad.csv:1: expected 't' or 'image,t'"), std::string::npos);
  EXPECT_NE(message("t\n").find("no trigger times"), std::string::npos);
  EXPECT_NE(message("image,t\nA,1,2\n").find("bad.csv:2: expected 2 fields, got 3"),
            std::string::npos);
}

TEST(TriggerFile, ReadsTheCameraEventsOfAULog) {
  test::TempDir dir;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 200; ++i) samples.push_back({1'000'000 + i * 5'000'000LL, {0, 0, 0}});
  const std::vector<CameraEvent> events = {{200'000'000, 7, ""}, {600'000'000, 8, ""}};
  WriteULog(dir / "f.ulg", GyroTrace(samples), events);
  const TriggerFile f = ReadTriggerFile(dir / "f.ulg");
  EXPECT_EQ(f.format, "ulog");
  EXPECT_EQ(f.clock, TriggerClock::kLog);
  ASSERT_EQ(f.events.size(), 2u);
  EXPECT_EQ(f.events[1].t_ns, 600'000'000);
  EXPECT_EQ(f.events[1].sequence, 8);
  EXPECT_NE(f.source.find("camera_capture"), std::string::npos) << f.source;
}

}  // namespace
}  // namespace shutterlab
