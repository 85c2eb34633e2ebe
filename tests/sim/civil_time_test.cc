#include "sim/civil_time.h"

#include <gtest/gtest.h>

#include <string>

namespace shutterlab {
namespace {

TEST(CivilTime, DaysFromCivilKnownDates) {
  EXPECT_EQ(DaysFromCivil(1970, 1, 1), 0);
  EXPECT_EQ(DaysFromCivil(2000, 3, 1), 11017);  // after a century leap day
  EXPECT_EQ(DaysFromCivil(1969, 12, 31), -1);
  EXPECT_EQ(DaysFromCivil(1980, 1, 6) * kSecondsPerDay, kGpsEpochUnixS);
}

TEST(CivilTime, ParsesExifDateTimeWithFractionAndOffset) {
  std::string problem;
  const auto face = ParseExifDateTime("2024:07:16 09:41:37", "25", "+08:00", &problem);
  ASSERT_TRUE(face) << problem;
  EXPECT_EQ(face->face_ns, 1721122897LL * kNsPerSecond + 250'000'000);  // python calendar.timegm
  EXPECT_DOUBLE_EQ(face->resolution_s, 0.01);
  ASSERT_TRUE(face->utc_offset_s);
  EXPECT_EQ(*face->utc_offset_s, 8 * 3600);
  EXPECT_EQ(*face->UtcNs(), face->face_ns - 8LL * 3600 * kNsPerSecond);
  EXPECT_EQ(UtcText(*face->UtcNs()), "2024-07-16 01:41:37.250");
  EXPECT_EQ(UtcOffsetText(-5 * 3600 - 1800), "-05:30");
}

TEST(CivilTime, NoFractionNoOffsetMeansOneSecondAndNoUtc) {
  std::string problem;
  const auto face = ParseExifDateTime("2024-07-16T09:41:37", "", "", &problem);
  ASSERT_TRUE(face) << problem;
  EXPECT_DOUBLE_EQ(face->resolution_s, 1.0);
  EXPECT_FALSE(face->UtcNs());
}

TEST(CivilTime, RejectsBlankAndBadFaces) {
  const char* bad[][3] = {{"    :  :     :  :  ", "", ""},
                          {"2024:13:16 09:41:37", "", ""},
                          {"2024:07:16 09:41", "", ""},
                          {"2024:07:16 09:41:37", "1a", ""},
                          {"2024:07:16 09:41:37", "", "+8"}};
  for (const auto& b : bad) {
    std::string problem;
    EXPECT_FALSE(ParseExifDateTime(b[0], b[1], b[2], &problem)) << b[0] << " " << b[1] << b[2];
    EXPECT_NE(problem.find('\''), std::string::npos) << "the problem quotes the text: " << problem;
  }
}

TEST(CivilTime, GpsToUtcCountsLeapSeconds) {
  // The Autel MRK's first row: GPS week 2211, 296288.242869 s of week -> UTC 2022-05-25
  // 10:17:50.243 (GPS - UTC = 18 s since 2017).
  const int64_t gps_ns = GpsNsFromWeek(2211, 296288.242869);
  EXPECT_EQ(gps_ns % kNsPerSecond, 242'869'000);
  EXPECT_EQ(UtcText(UtcFromGpsNs(gps_ns)), "2022-05-25 10:17:50.242");
  EXPECT_EQ(LeapSecondsAtUtc(1483228799LL * kNsPerSecond), 17);  // 2016-12-31 23:59:59
  EXPECT_EQ(LeapSecondsAtUtc(1483228800LL * kNsPerSecond), 18);  // 2017-01-01
  EXPECT_EQ(UtcFromGpsNs(0), kGpsEpochUnixS * kNsPerSecond);
}

}  // namespace
}  // namespace shutterlab
