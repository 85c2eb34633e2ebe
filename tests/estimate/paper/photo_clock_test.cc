#include "estimate/paper/photo_clock.h"

#include "sim/civil_time.h"
#include "sim/logs/trigger_file.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// The log's clock starts 2024-07-16 01:00:00 UTC; its GPS fixes run from 1 s to 200 s.
constexpr int64_t kUtcAtLogZeroNs = 1'721'091'600'000'000'000;
constexpr int64_t kHourNs = 3'600'000'000'000;
constexpr int64_t kMs = 1'000'000;

FlightLog LogWithGps() {
  FlightLog log;
  for (int k = 1; k <= 200; ++k) {
    const int64_t t = k * kNsPerSecond;
    log.utc_fixes.push_back({t, kUtcAtLogZeroNs + t});
  }
  return log;
}

// Ten exposures 2 s apart (one 0.3 s late) from 20 s on the log clock.
std::vector<int64_t> EventTimes() {
  std::vector<int64_t> t;
  for (int k = 0; k < 10; ++k)
    t.push_back(20 * kNsPerSecond + k * 2 * kNsPerSecond + (k == 4 ? 300 * kMs : 0));
  return t;
}

// A photo whose camera clock shows UTC + zone + error at the exposure, to the ms.
PhotoRecord StampedPhoto(const std::string& name, int64_t utc_ns, int64_t zone_ns, int64_t error_ns,
                         bool write_zone = false) {
  PhotoMetadata m;
  m.width = 100;
  m.height = 100;
  ClockFace face;
  face.face_ns = utc_ns + zone_ns + error_ns;
  face.resolution_s = 1e-3;
  if (write_zone) face.utc_offset_s = static_cast<int>(zone_ns / kNsPerSecond);
  m.capture_time = face;
  return MakePhotoRecord("/p/" + name, m, {});
}

// The camera clock is UTC+08:00 and off by these ms; the pairing must remove the common part and
// leave the rest as residuals.
const int64_t kErrorsMs[10] = {3, -2, 5, 0, 1, -4, 2, 0, 6, -1};

TEST(PlacePhotos, PairsByCaptureTimeWithTheLogsEventsAndReportsTheResidual) {
  FlightLog log = LogWithGps();
  const std::vector<int64_t> t = EventTimes();
  for (size_t k = 0; k < t.size(); ++k)
    log.camera_events.push_back({t[k], static_cast<int64_t>(k), "camera_capture"});
  PhotoSet set;
  // Photos 1..9 (the first exposure has no photo), numbered unlike the log's sequence.
  for (size_t k = 1; k < t.size(); ++k) {
    set.photos.push_back(StampedPhoto("DJI_0" + std::to_string(100 + k) + ".JPG",
                                      kUtcAtLogZeroNs + t[k], 8 * kHourNs, kErrorsMs[k] * kMs));
  }
  const PhotoClock clock = PlacePhotos(set, log, nullptr, {});
  ASSERT_EQ(clock.paired, 9u) << clock.method;
  // The fitted offset is +08:00 plus the median error (1 ms, the 5th of the nine sorted).
  std::vector<int64_t> errors(kErrorsMs + 1, kErrorsMs + 10);
  std::sort(errors.begin(), errors.end());
  const int64_t median_ms = errors[4];
  ASSERT_TRUE(clock.clock_offset_s);
  EXPECT_NEAR(*clock.clock_offset_s, 8 * 3600 + median_ms * 1e-3, 1e-9);
  double sum_sq = 0;
  for (size_t i = 0; i < set.photos.size(); ++i) {
    const PhotoPlacement& p = clock.placements[i];
    ASSERT_TRUE(p.t_ns) << p.problem;
    EXPECT_EQ(*p.t_ns, t[i + 1]) << set.photos[i].name;
    ASSERT_TRUE(p.residual_s);
    EXPECT_NEAR(*p.residual_s, (kErrorsMs[i + 1] - median_ms) * 1e-3, 1e-9);
    sum_sq += std::pow((kErrorsMs[i + 1] - median_ms) * 1e-3, 2);
  }
  EXPECT_NEAR(*clock.residual_rms_s, std::sqrt(sum_sq / 9), 1e-12);
  EXPECT_NE(clock.method.find("by capture time"), std::string::npos) << clock.method;
  EXPECT_NE(clock.method.find("UTC+08:00"), std::string::npos) << clock.method;
}

TEST(PlacePhotos, WholeSecondCaptureTimesStillPickTheRightEvents) {
  FlightLog log = LogWithGps();
  const std::vector<int64_t> t = EventTimes();
  for (size_t k = 0; k < t.size(); ++k)
    log.camera_events.push_back({t[k], static_cast<int64_t>(k), "camera_capture"});
  PhotoSet set;
  for (size_t k = 0; k < t.size(); ++k) {
    PhotoRecord r =
        StampedPhoto("P" + std::to_string(k) + ".jpg", kUtcAtLogZeroNs + t[k], -5 * kHourNs, 0);
    ClockFace& face = *r.metadata.capture_time;
    face.face_ns -= face.face_ns % kNsPerSecond;  // EXIF without SubSecTimeOriginal
    face.resolution_s = 1.0;
    set.photos.push_back(r);
  }
  const PhotoClock clock = PlacePhotos(set, log, nullptr, {});
  ASSERT_EQ(clock.paired, 10u) << clock.method;
  for (size_t k = 0; k < t.size(); ++k) {
    EXPECT_EQ(*clock.placements[k].t_ns, t[k]);
    EXPECT_LE(std::abs(*clock.placements[k].residual_s), 0.5 + 1e-9);
  }
}

// A log without GPS time (a gyro recorder's, an indoor flight): the capture times are matched on
// the log's own clock. The camera clock runs an arbitrary 1.2e9 s + 17.25 s ahead of the log's
// boot clock and off by kErrorsMs. The first exposure has no photo and the 7th photo's event was
// not logged: eight pairs, residuals the errors less their median, and the 7th photo placed by
// its capture time through the fitted offset. One shift over pairs eight photos too (the cadence is
// regular): the 5th exposure's 0.3 s lateness makes that rival pair less tightly, and decides.
TEST(PlacePhotos, WithoutGpsTimeCaptureTimesAreMatchedOnTheLogsClock) {
  FlightLog log;  // no utc_fixes
  const std::vector<int64_t> t = EventTimes();
  for (size_t k = 0; k < t.size(); ++k) {
    if (k != 6) log.camera_events.push_back({t[k], static_cast<int64_t>(k), "camera_capture"});
  }
  constexpr int64_t kCameraAheadNs = 1'200'000'017'250'000'000;
  PhotoSet set;
  for (size_t k = 1; k < t.size(); ++k)
    set.photos.push_back(
        StampedPhoto("P" + std::to_string(k) + ".jpg", t[k], kCameraAheadNs, kErrorsMs[k] * kMs));
  const PhotoClock clock = PlacePhotos(set, log, nullptr, {});
  ASSERT_EQ(clock.paired, 8u) << clock.method;
  ASSERT_EQ(clock.placed, 9u) << clock.method;
  std::vector<int64_t> errors;
  for (size_t k = 1; k < t.size(); ++k) {
    if (k != 6) errors.push_back(kErrorsMs[k]);
  }
  std::sort(errors.begin(), errors.end());
  const double median_ms = 0.5 * (errors[3] + errors[4]);
  ASSERT_TRUE(clock.clock_offset_s);
  EXPECT_EQ(clock.clock_offset_to, "log clock");
  EXPECT_NEAR(*clock.clock_offset_s, kCameraAheadNs * 1e-9 + median_ms * 1e-3, 1e-6);
  for (size_t i = 0; i < set.photos.size(); ++i) {
    const size_t k = i + 1;
    const PhotoPlacement& p = clock.placements[i];
    ASSERT_TRUE(p.t_ns) << p.problem;
    if (k == 6) {
      EXPECT_FALSE(p.residual_s);
      EXPECT_NEAR((*p.t_ns - t[k]) * 1e-9, (kErrorsMs[k] - median_ms) * 1e-3, 1e-9);
      EXPECT_NE(p.method.find("offset to the log's clock"), std::string::npos)
          << "[" << p.method << "]";
      continue;
    }
    EXPECT_EQ(*p.t_ns, t[k]) << set.photos[i].name;
    ASSERT_TRUE(p.residual_s);
    EXPECT_NEAR(*p.residual_s, (kErrorsMs[k] - median_ms) * 1e-3, 1e-9);
  }
  EXPECT_NE(clock.method.find("by capture time on the log's clock"), std::string::npos)
      << clock.method;
}

// Real: the SIYI ZR10 flight's image_metadata.csv (215 rows 3 s apart, PX4 boot time and UTC) with
// its image names removed, and four of its photos (EXIF DateTimeOriginal, whole seconds, UTC).
// On the log's clock alone the four capture times fit the regular rows at every 3 s shift: said,
// nothing guessed. With the log's GPS time (here the CSV's own boot time against UTC) the nearest
// time zone decides and each photo pairs with the row the CSV names it on; IMG_0050's residual is
// -0.99 s, the others' within 20 ms (SOURCES.md: the rows were assigned at a 3 s cadence).
TEST(PlacePhotosReal, SiyiPhotosByCaptureTimeAlone) {
  SHUTTERLAB_REAL_DATA(dir, "images/siyi_zr10");
  TriggerFile rows = ReadTriggerFile(dir + "/image_metadata.csv");
  ASSERT_EQ(rows.clock, TriggerClock::kLog);
  ASSERT_EQ(rows.events.size(), 215u);
  std::map<std::string, int64_t> named;
  for (TriggerEvent& e : rows.events) named[e.name] = e.t_ns, e.name.clear();
  const PhotoSet set = ReadPhotoSet(dir);
  ASSERT_EQ(set.photos.size(), 4u);
  const PhotoClock alone = PlacePhotos(set, FlightLog{}, &rows, {});
  EXPECT_EQ(alone.placed, 0u) << alone.method;
  EXPECT_NE(alone.method.find("fit the events as well at several offsets"), std::string::npos)
      << alone.method;
  EXPECT_NE(alone.placements[0].problem.find("several offsets"), std::string::npos)
      << alone.placements[0].problem;

  // The log's GPS time: the CSV's utc_usec against its boot time.
  FlightLog log;
  const std::string csv = ReadFileToString(dir + "/image_metadata.csv");
  LineCursor cursor(csv);
  std::vector<std::string_view> fields;
  cursor.Next();  // header: utc,timestamp,utc_usec,...
  while (const auto line = cursor.Next()) {
    SplitFields(*line, ',', &fields);
    log.utc_fixes.push_back({*ParseInt(fields[1]) * 1000, *ParseInt(fields[2]) * 1000});
  }
  const PhotoClock clock = PlacePhotos(set, log, &rows, {});
  EXPECT_EQ(clock.clock_offset_to, "UTC");
  ASSERT_EQ(clock.placed, 4u) << clock.method;
  EXPECT_EQ(clock.paired, 4u) << clock.method;
  for (size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(set.photos[i].name);
    const double off_s = (*clock.placements[i].t_ns - named.at(set.photos[i].name)) * 1e-9;
    EXPECT_EQ(off_s, 0.0);
    EXPECT_NEAR(*clock.placements[i].residual_s, i == 0 ? -0.99 : 0.0, 0.02);
  }
}

TEST(PlacePhotos, MrkPairsByPhotoNumberAndGpsTime) {
  FlightLog log = LogWithGps();
  const std::vector<int64_t> t = EventTimes();
  TriggerFile mrk;
  mrk.format = "mrk";
  mrk.clock = TriggerClock::kGps;
  for (size_t k = 0; k < t.size(); ++k) {
    TriggerEvent e;
    e.sequence = static_cast<int64_t>(k) + 1;
    // GPS time = UTC + 18 s (2024); GPS ns since its epoch.
    e.t_ns = kUtcAtLogZeroNs + t[k] + 18 * kNsPerSecond - kGpsEpochUnixS * kNsPerSecond;
    mrk.events.push_back(e);
  }
  PhotoSet set;
  set.photos.push_back(StampedPhoto("DJI_0003.JPG", kUtcAtLogZeroNs + t[2], 0, 40 * kMs));
  set.photos.push_back(StampedPhoto("DJI_0007.JPG", kUtcAtLogZeroNs + t[6], 0, 20 * kMs));
  set.photos.push_back(StampedPhoto("DJI_0099.JPG", kUtcAtLogZeroNs + 150 * kNsPerSecond, 0, 0));
  const PhotoClock clock = PlacePhotos(set, log, &mrk, {});
  EXPECT_EQ(clock.paired, 2u);
  EXPECT_EQ(*clock.placements[0].t_ns, t[2]);
  EXPECT_EQ(*clock.placements[1].t_ns, t[6]);
  EXPECT_NE(clock.placements[0].method.find("#3, by photo number"), std::string::npos)
      << clock.placements[0].method;
  EXPECT_NEAR(std::abs(*clock.placements[0].residual_s), 0.010, 1e-9);  // 40 vs 20 ms: +-10 ms
  // No MRK line: placed by its capture time with the fitted offset (30 ms).
  ASSERT_TRUE(clock.placements[2].t_ns) << clock.placements[2].problem;
  EXPECT_NEAR((*clock.placements[2].t_ns - 150 * kNsPerSecond) * 1e-9, -0.030, 1e-6);
  EXPECT_FALSE(clock.placements[2].residual_s);
}

TEST(PlacePhotos, WithoutEventsByCaptureTimeAndTheZone) {
  const FlightLog log = LogWithGps();
  PhotoSet written;  // OffsetTimeOriginal +02:00 in the file
  written.photos.push_back(
      StampedPhoto("a.jpg", kUtcAtLogZeroNs + 30 * kNsPerSecond, 2 * kHourNs, 0, true));
  PhotoClock clock = PlacePhotos(written, log, nullptr, {});
  ASSERT_TRUE(clock.placements[0].t_ns) << clock.placements[0].problem;
  EXPECT_NEAR(static_cast<double>(*clock.placements[0].t_ns - 30 * kNsPerSecond), 0.0, 2.0);
  EXPECT_NE(clock.placements[0].method.find("OffsetTimeOriginal"), std::string::npos);

  // No zone anywhere: the one quarter hour (+05:30) that puts both photos inside the 200 s log.
  PhotoSet unzoned;
  const int64_t zone = 5 * kHourNs + kHourNs / 2;
  unzoned.photos.push_back(StampedPhoto("b.jpg", kUtcAtLogZeroNs + 30 * kNsPerSecond, zone, 0));
  unzoned.photos.push_back(StampedPhoto("c.jpg", kUtcAtLogZeroNs + 90 * kNsPerSecond, zone, 0));
  clock = PlacePhotos(unzoned, log, nullptr, {});
  ASSERT_EQ(clock.placed, 2u) << clock.placements[0].problem;
  EXPECT_NEAR(static_cast<double>(*clock.placements[1].t_ns - 90 * kNsPerSecond), 0.0, 2.0);
  EXPECT_NE(clock.placements[0].method.find("UTC+05:30"), std::string::npos)
      << clock.placements[0].method;

  // --photo-utc-offset wins; a log without GPS time places nothing and says why.
  PhotoClockOptions given;
  given.camera_utc_offset_s = 5 * 3600;
  clock = PlacePhotos(unzoned, log, nullptr, given);
  EXPECT_NEAR((*clock.placements[0].t_ns - 30 * kNsPerSecond) * 1e-9, 1800.0, 1e-6);
  clock = PlacePhotos(unzoned, FlightLog{}, nullptr, {});
  EXPECT_EQ(clock.placed, 0u);
  EXPECT_NE(clock.placements[0].problem.find("no GPS time"), std::string::npos)
      << clock.placements[0].problem;
}

}  // namespace
}  // namespace shutterlab
