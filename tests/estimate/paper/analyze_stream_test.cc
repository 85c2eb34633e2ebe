// AnalyzeStream against its brute-force twin: Analyze on the same log held whole. The streamed
// analysis forms the same sums in the same order, so everything it reports is equal to the bit.

#include "estimate/paper/analyze.h"
#include "estimate/paper/photo_flight.h"
#include "io/photo_set.h"
#include "sim/civil_time.h"
#include "sim/gyro_source.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/trigger_file.h"
#include "sim/trace_audit.h"
#include "sim/units.h"
#include "tests/estimate/paper/paper_fixtures.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// The log as AnalyzeStream reads it: its metadata, and its samples in chunks of chunk_samples
// (a few put chunk edges inside every readout).
AnalyzeLogSource SourceOf(const FlightLog& log, size_t chunk_samples, int* opened = nullptr) {
  AnalyzeLogSource source;
  source.open = [&log, chunk_samples, opened] {
    if (opened) ++*opened;
    FlightLogStream stream;
    stream.log = log;
    stream.log.gyro = GyroTrace();
    stream.gyro = std::make_unique<TraceSource>(log.gyro, chunk_samples);
    return stream;
  };
  return source;
}

// The log as ReadFlightLog gives it: the audit's warnings after the reader's.
FlightLog Audited(FlightLog log) {
  for (LogWarning& w : AuditTrace(log.gyro)) log.warnings.push_back(std::move(w));
  return log;
}

void ExpectSameImages(const std::vector<ImageResult>& streamed,
                      const std::vector<ImageResult>& whole) {
  ASSERT_EQ(streamed.size(), whole.size());
  for (size_t i = 0; i < whole.size(); ++i) {
    const ImageResult& s = streamed[i];
    const ImageResult& w = whole[i];
    SCOPED_TRACE(w.name);
    EXPECT_EQ(s.name, w.name);
    EXPECT_EQ(s.trigger_t_ns, w.trigger_t_ns);
    EXPECT_EQ(s.t_ns, w.t_ns);
    EXPECT_EQ(s.in_trace, w.in_trace);
    EXPECT_EQ(s.too_few_samples, w.too_few_samples);
    EXPECT_EQ(s.d_paper_m, w.d_paper_m);
    EXPECT_EQ(s.d_full_m, w.d_full_m);
    EXPECT_EQ(s.d_full_px, w.d_full_px);
    EXPECT_EQ(s.range_arcsec, w.range_arcsec);
    EXPECT_EQ(s.dominant_axis, w.dominant_axis);
    EXPECT_EQ(s.flagged, w.flagged);
  }
}

void ExpectSameResult(const AnalyzeResult& s, const AnalyzeResult& w) {
  EXPECT_EQ(s.format, w.format);
  EXPECT_EQ(s.gyro_source, w.gyro_source);
  EXPECT_EQ(s.samples, w.samples);
  EXPECT_EQ(s.duration_s, w.duration_s);
  EXPECT_EQ(s.rate_hz, w.rate_hz);
  EXPECT_EQ(s.gaps, w.gaps);
  ASSERT_EQ(s.log_warnings.size(), w.log_warnings.size());
  for (size_t i = 0; i < w.log_warnings.size(); ++i)
    EXPECT_EQ(WarningLine(s.log_warnings[i]), WarningLine(w.log_warnings[i]));
  EXPECT_EQ(s.bias_estimated, w.bias_estimated);
  EXPECT_EQ(s.bias_from_still, w.bias_from_still);
  EXPECT_EQ(s.still_segment.begin_s, w.still_segment.begin_s);
  EXPECT_EQ(s.still_segment.end_s, w.still_segment.end_s);
  EXPECT_EQ(s.bias_rad_s, w.bias_rad_s);
  EXPECT_EQ(s.trigger_source, w.trigger_source);
  EXPECT_EQ(s.altitude_m, w.altitude_m);
  EXPECT_EQ(s.altitude_source, w.altitude_source);
  EXPECT_EQ(s.flight_problem, w.flight_problem);
  ASSERT_EQ(s.flight.has_value(), w.flight.has_value());
  if (w.flight) {
    EXPECT_EQ(FlightTable(*s.flight), FlightTable(*w.flight));
  }
  ExpectSameImages(s.images, w.images);
  EXPECT_EQ(s.verdict.images_in_trace, w.verdict.images_in_trace);
  EXPECT_EQ(s.verdict.images_too_few_samples, w.verdict.images_too_few_samples);
  EXPECT_EQ(s.verdict.share_percent, w.verdict.share_percent);
  EXPECT_EQ(s.verdict.axis_to_stabilise, w.verdict.axis_to_stabilise);
  EXPECT_EQ(s.verdict.share_fast_readout_percent, w.verdict.share_fast_readout_percent);
  EXPECT_EQ(s.verdict.share_half_altitude_percent, w.verdict.share_half_altitude_percent);
  EXPECT_EQ(s.verdict.line, w.verdict.line);
  EXPECT_EQ(AnalyzeReport(s), AnalyzeReport(w));
  EXPECT_EQ(s.traces, nullptr);
  // What a report draws.
  EXPECT_EQ(s.allan_on_still, w.allan_on_still);
  ASSERT_EQ(s.allan.has_value(), w.allan.has_value());
  if (w.allan) {
    EXPECT_EQ(s.allan->tau0_s, w.allan->tau0_s);
    EXPECT_EQ(s.allan->tau_s, w.allan->tau_s);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(s.allan->adev_rad_s[a], w.allan->adev_rad_s[a]);
      EXPECT_EQ(s.allan->axes[a].arw_deg_sqrt_h, w.allan->axes[a].arw_deg_sqrt_h);
      EXPECT_EQ(s.allan->axes[a].bias_instability_deg_h, w.allan->axes[a].bias_instability_deg_h);
    }
  }
  ASSERT_EQ(s.plots != nullptr, w.plots != nullptr);
  if (w.plots) {
    EXPECT_EQ(s.plots->t_s, w.plots->t_s);
    EXPECT_EQ(s.plots->rate_deg_s, w.plots->rate_deg_s);
    EXPECT_EQ(s.plots->angle_deg, w.plots->angle_deg);
    ASSERT_EQ(s.plots->worst.size(), w.plots->worst.size());
    for (size_t i = 0; i < w.plots->worst.size(); ++i) {
      EXPECT_EQ(s.plots->worst[i].image, w.plots->worst[i].image);
      const FrameMotion& sf = s.plots->worst[i].frame;
      const FrameMotion& wf = w.plots->worst[i].frame;
      ASSERT_EQ(sf.world_from_cam.size(), wf.world_from_cam.size());
      for (size_t row = 0; row < wf.world_from_cam.size(); ++row) {
        ASSERT_EQ(sf.world_from_cam[row], wf.world_from_cam[row]) << row;
        ASSERT_EQ(sf.cam_center_m[row], wf.cam_center_m[row]) << row;
      }
      EXPECT_EQ(sf.world_from_ref, wf.world_from_ref);
    }
  }
  if (w.flight) {
    ASSERT_EQ(s.flight->summary.has_value(), w.flight->summary.has_value());
    if (w.flight->summary) {
      const FlightWindowSummary& ss = *s.flight->summary;
      const FlightWindowSummary& ws = *w.flight->summary;
      EXPECT_EQ(ss.windows, ws.windows);
      ASSERT_EQ(ss.flagged.size(), ws.flagged.size());
      for (size_t l = 0; l < ws.flagged.size(); ++l)
        EXPECT_EQ(ss.flagged[l].intervals(), ws.flagged[l].intervals());
      for (int a = 0; a < 3; ++a) EXPECT_TRUE(ss.range_arcsec[a] == ws.range_arcsec[a]);
    }
  }
}

// 12 s at 1 kHz: still with noise and a bias for 4 s, then a wobble about every axis with noise.
FlightLog WobblyLog() {
  std::mt19937 rng(15);
  std::normal_distribution<double> noise(0.0, 2e-3);
  const Eigen::Vector3d bias(0.004, -0.003, 0.002);
  FlightLog log = test::StillThenRateLog(
      12.0, [](double) { return Eigen::Vector3d::Zero(); }, "wobble");
  std::vector<GyroSample> samples = log.gyro.samples();
  for (GyroSample& s : samples) {
    const double t_s = s.t_ns * 1e-9;
    if (t_s > 4.0)
      s.omega_rad_s = Eigen::Vector3d(0.3 * std::sin(7 * t_s), 0.2 * std::cos(11 * t_s), 0.1 * t_s);
    for (int a = 0; a < 3; ++a) s.omega_rad_s[a] += bias[a] + noise(rng);
  }
  log.gyro = GyroTrace(std::move(samples));
  return log;
}

// The camera turned against the gyro, images out of time order, two outside the log, a latency.
AnalyzeOptions TurnedCameraOptions() {
  AnalyzeOptions options;
  options.rig = test::MappingRig();
  options.rig.camera.width = 320;  // a smaller grid keeps D_full cheap
  options.rig.camera.height = 240;
  options.rig.camera.cx = 159.5;
  options.rig.camera.cy = 119.5;
  options.rig.cam_from_gyro =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  options.trigger_latency_s = 0.0013;
  // The report's plots: 12,000 samples cut to 300 buckets' envelopes, two worst images' frames.
  options.plots = AnalyzePlotOptions{300, 2};
  options.allan = true;
  for (const double t_s : {9.5, 1.0, 6.02, 4.7, 11.99, -0.5, 7.25, 6.0, 10.0101})
    options.triggers.push_back({"t" + std::to_string(t_s), SecondsToNs(t_s)});
  return options;
}

TEST(AnalyzeStream, EqualsTheWholeTraceAnalysisToTheBit) {
  const FlightLog log = WobblyLog();
  const AnalyzeOptions options = TurnedCameraOptions();
  const AnalyzeResult whole = Analyze(Audited(log), options);
  ASSERT_TRUE(whole.bias_from_still);
  ASSERT_TRUE(whole.flight.has_value());
  ASSERT_GT(whole.verdict.images_in_trace, 5u);
  ASSERT_EQ(whole.plots->t_s.size(), 600u);
  ASSERT_EQ(whole.plots->worst.size(), 2u);
  ASSERT_TRUE(whole.allan_on_still);
  ASSERT_FALSE(whole.allan->empty());
  // The Allan deviation is AllanAnalysis's on the still segment's rates: its clusters are all
  // exact here, and only the mean it removes is formed in another order.
  const GyroTrace& rates = whole.traces->camera_rates;
  const auto [begin, end] = SamplesInSegment(rates, whole.still_segment);
  const AllanResult held = AllanAnalysis(GyroTrace(
      std::vector<GyroSample>(rates.samples().begin() + begin, rates.samples().begin() + end)));
  ASSERT_EQ(whole.allan->tau_s, held.tau_s);
  ASSERT_GT(held.adev_rad_s[0][0], 1e-4);  // the still segment holds noise
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < held.tau_s.size(); ++i)
      EXPECT_NEAR(whole.allan->adev_rad_s[a][i], held.adev_rad_s[a][i],
                  1e-9 * held.adev_rad_s[a][i]);
  }
  ASSERT_FALSE(whole.flight->summary->flagged[0].intervals().empty());
  for (const size_t chunk : {size_t{5}, size_t{61}, size_t{4096}}) {
    SCOPED_TRACE("chunk " + std::to_string(chunk));
    int opened = 0;
    ExpectSameResult(AnalyzeStream(SourceOf(log, chunk, &opened), options), whole);
    EXPECT_EQ(opened, 7);  // five still passes, the sampling and the analysis
  }
}

// Progress runs from the first pass to the last, never back: each of the seven passes moves it.
TEST(AnalyzeStream, ProgressMovesThroughEveryPass) {
  const FlightLog log = WobblyLog();
  AnalyzeOptions options = TurnedCameraOptions();
  std::vector<double> fractions;
  options.progress = [&fractions](double f) { fractions.push_back(f); };
  AnalyzeStream(SourceOf(log, 4096), options);
  ASSERT_FALSE(fractions.empty());
  EXPECT_LT(fractions.front(), 1.0 / 7);
  EXPECT_EQ(fractions.back(), 1.0);
  for (size_t i = 1; i < fractions.size(); ++i) EXPECT_GE(fractions[i], fractions[i - 1]) << i;
  for (int pass = 0; pass < 7; ++pass) {
    // Some report inside each pass's share.
    EXPECT_TRUE(std::any_of(fractions.begin(), fractions.end(),
                            [pass](double f) { return f > pass / 7.0 && f <= (pass + 1) / 7.0; }))
        << "pass " << pass;
  }
}

TEST(AnalyzeStream, EqualsTheWholeTraceWithoutStillSegmentEveryTriggersAndShortReadout) {
  // No still stretch (zero bias), simulated triggers, a readout shorter than the what-if's 10 ms.
  const FlightLog moving = test::StillThenRateLog(
      6.0, [](double t_s) { return Eigen::Vector3d(0.2 + std::sin(3 * t_s), 0.1, -0.05 * t_s); },
      "moving");
  FlightLog log = moving;
  std::vector<GyroSample> samples(moving.gyro.samples().begin() + 4500,
                                  moving.gyro.samples().end());
  log.gyro = GyroTrace(std::move(samples));
  AnalyzeOptions options = TurnedCameraOptions();
  options.triggers.clear();
  options.every_s = 0.25;
  options.rig.shutter.readout_s = 0.004;
  const AnalyzeResult whole = Analyze(Audited(log), options);
  ASSERT_FALSE(whole.bias_from_still);
  ExpectSameResult(AnalyzeStream(SourceOf(log, 5), options), whole);
  // Without the bias search: two passes.
  options.estimate_bias = false;
  options.what_if = false;
  int opened = 0;
  ExpectSameResult(AnalyzeStream(SourceOf(log, 64, &opened), options),
                   Analyze(Audited(log), options));
  EXPECT_EQ(opened, 2);
}

TEST(AnalyzeStream, EqualsTheWholeTraceWithCameraEventsLogAltitudeAndGaps) {
  FlightLog log = WobblyLog();
  // Two gaps (a warning each way) and the log's own camera events and altitude.
  std::vector<GyroSample> samples;
  for (const GyroSample& s : log.gyro.samples()) {
    const double t_s = s.t_ns * 1e-9;
    if ((t_s > 7.1 && t_s < 7.3) || (t_s > 9.0 && t_s < 9.05)) continue;
    samples.push_back(s);
  }
  log.gyro = GyroTrace(std::move(samples));
  for (int k = 0; k < 8; ++k)
    log.camera_events.push_back({SecondsToNs(4.5 + 0.9 * k), 100 + k, "CAM"});
  log.camera_events.push_back({SecondsToNs(5.0), -1, "TRIG"});
  log.altitude_above_ground_m = 37.5;
  log.altitude_source = "median CAM.RelAlt";
  AnalyzeOptions options = TurnedCameraOptions();
  options.triggers.clear();
  options.use_log_altitude = true;
  const AnalyzeResult whole = Analyze(Audited(log), options);
  ASSERT_EQ(whole.altitude_source, "log");
  ASSERT_GT(whole.gaps, 0u);
  ExpectSameResult(AnalyzeStream(SourceOf(log, 11), options), whole);
}

TEST(AnalyzeStream, TooFewSamplesAndTooShortLogsAsTheWholeTrace) {
  FlightLog log;
  std::vector<GyroSample> samples;
  for (int k = 0; k < 400; ++k)  // 8 s at 50 Hz
    samples.push_back(
        {static_cast<int64_t>(k) * 20'000'000, Eigen::Vector3d(k >= 300 ? 0.05 : 0.0, 0, 0)});
  log.gyro = GyroTrace(samples);
  AnalyzeOptions options = TurnedCameraOptions();
  ExpectSameResult(AnalyzeStream(SourceOf(log, 9), options), Analyze(log, options));
  log.gyro = GyroTrace(std::vector<GyroSample>(samples.begin(), samples.begin() + 1));
  EXPECT_THROW(Analyze(log, options), std::invalid_argument);
  EXPECT_THROW(AnalyzeStream(SourceOf(log, 9), options), std::invalid_argument);
}

// `analyze --photos DIR LOG` streamed (AnalyzePhotoFlightStream: the log's metadata places the
// photos, AnalyzeStream analyses them) against the log read whole (AnalyzePhotoFlight). Nine
// photos from a camera clock at UTC+08:00, off by a few ms: seven paired with the log's camera
// events through its GPS time (one exposed too late for its readout to fit in the log), two
// without an event placed by their capture time.
TEST(AnalyzeStream, PhotoFlightEqualsTheWholeLogToTheBit) {
  constexpr int64_t kUtcAtLogZeroNs = 1'721'091'600'000'000'000;  // 2024-07-16 01:00:00 UTC
  constexpr int64_t kZoneNs = 8 * 3'600'000'000'000LL;
  FlightLog log = WobblyLog();
  for (int k = 0; k <= 12; ++k)
    log.utc_fixes.push_back({k * kNsPerSecond, kUtcAtLogZeroNs + k * kNsPerSecond});
  std::vector<int64_t> exposures_ns;
  for (int k = 0; k < 8; ++k) exposures_ns.push_back(SecondsToNs(4.3 + 0.9 * k));
  exposures_ns.push_back(SecondsToNs(11.995));
  const int error_ms[9] = {3, -2, 5, 0, 1, -4, 2, 0, 6};
  PhotoSet set;
  for (size_t k = 0; k < exposures_ns.size(); ++k) {
    if (k != 6 && k != 7)
      log.camera_events.push_back({exposures_ns[k], static_cast<int64_t>(k), "camera_capture"});
    PhotoMetadata m;
    m.width = 320;
    m.height = 240;
    m.focal_length_35mm = 24.0;
    m.relative_altitude_m = 60.0;
    m.speed_m_s = Eigen::Vector3d(5.0, 1.0, 0.0);
    ClockFace face;
    face.face_ns = kUtcAtLogZeroNs + exposures_ns[k] + kZoneNs + error_ms[k] * 1'000'000LL;
    face.resolution_s = 1e-3;
    m.capture_time = face;
    set.photos.push_back(MakePhotoRecord("/p/DJI_000" + std::to_string(k + 1) + ".JPG", m, {}));
  }
  PhotoFlightOptions options;
  options.analyze = TurnedCameraOptions();
  options.analyze.rig.shutter.readout_s = 0.02;
  options.readout_given = true;
  const PhotoFlightResult whole = AnalyzePhotoFlight(set, Audited(log), nullptr, options);
  ASSERT_EQ(whole.clock.paired, 7u) << whole.clock.method;
  ASSERT_EQ(whole.log.images.size(), 9u) << whole.clock.method;
  ASSERT_EQ(whole.log.verdict.images_in_trace, 8u);
  ASSERT_TRUE(whole.log.bias_from_still);
  FlightLog metadata = log;
  metadata.gyro = GyroTrace();
  const PhotoFlightResult streamed =
      AnalyzePhotoFlightStream(set, metadata, SourceOf(log, 61), nullptr, options);
  ExpectSameResult(streamed.log, whole.log);
  EXPECT_EQ(streamed.camera_source, whole.camera_source);
  EXPECT_EQ(streamed.clock.method, whole.clock.method);
  EXPECT_EQ(streamed.clock.clock_offset_s, whole.clock.clock_offset_s);
  ASSERT_EQ(streamed.photos.photos.size(), whole.photos.photos.size());
  for (size_t i = 0; i < whole.photos.photos.size(); ++i) {
    const PhotoResult& s = streamed.photos.photos[i];
    const PhotoResult& w = whole.photos.photos[i];
    SCOPED_TRACE(w.name);
    EXPECT_EQ(s.placement.t_ns, w.placement.t_ns);
    EXPECT_EQ(s.placement.residual_s, w.placement.residual_s);
    EXPECT_EQ(s.d_rotation_px, w.d_rotation_px);
    EXPECT_EQ(s.d_rotation_m, w.d_rotation_m);
    EXPECT_EQ(s.d_paper_m, w.d_paper_m);
    EXPECT_EQ(s.flagged, w.flagged);
  }
  EXPECT_EQ(PhotoAnalysisReport(set, streamed.photos), PhotoAnalysisReport(set, whole.photos));
}

// Photos that record no flight speed take the log's at their placed time: 3 m/s north and 4 m/s
// east for the first two, 6 m/s east for the third; with a 20 ms readout D's translation part is
// 10 and 12 cm. A photo that records its speed keeps its own.
TEST(AnalyzeStream, PhotosWithoutASpeedTakeTheLogs) {
  FlightLog log = WobblyLog();
  for (int64_t t_ns = 0; t_ns <= 12 * kNsPerSecond; t_ns += kNsPerSecond / 10) {
    const Eigen::Vector3d ned =
        t_ns < 6 * kNsPerSecond ? Eigen::Vector3d(3.0, 4.0, -1.0) : Eigen::Vector3d(0.0, 6.0, 0.0);
    log.velocity.push_back({t_ns, ned});
  }
  log.velocity_source = "test.v";
  PhotoSet set;
  PhotoSetOptions read;
  read.readout_s = 0.02;
  for (int k = 0; k < 4; ++k) {
    log.camera_events.push_back({SecondsToNs(2.5 + 2.0 * k), k, "camera_capture"});
    PhotoMetadata m;
    m.width = 320;
    m.height = 240;
    m.focal_length_35mm = 24.0;
    m.relative_altitude_m = 60.0;
    if (k == 3) m.speed_m_s = Eigen::Vector3d(1.0, 0.0, 0.0);
    if (k == 2) m.gimbal = AttitudeDeg{0.0, -90.0, 0.0};  // nadir, the image's top to the north
    set.photos.push_back(MakePhotoRecord("/p/DJI_000" + std::to_string(k + 1) + ".JPG", m, read));
  }
  PhotoFlightOptions options;
  options.analyze = TurnedCameraOptions();
  options.analyze.rig.shutter.readout_s = 0.02;
  options.readout_given = true;
  const PhotoFlightResult result = AnalyzePhotoFlight(set, Audited(log), nullptr, options);
  ASSERT_EQ(result.clock.paired, 4u) << result.clock.method;
  const double expected_m_s[] = {5.0, 5.0, 6.0, 1.0};
  for (size_t k = 0; k < 4; ++k) {
    const PhotoRecord& r = result.set.photos[k];
    SCOPED_TRACE(r.name);
    ASSERT_TRUE(r.ground_speed_m_s.has_value());
    EXPECT_NEAR(*r.ground_speed_m_s, expected_m_s[k], 1e-12);
    EXPECT_EQ(r.speed_source == "the log's test.v at the photo's time", k < 3) << r.speed_source;
    EXPECT_EQ(std::count(r.missing.begin(), r.missing.end(), "flight speed"), 0);
    ASSERT_TRUE(result.photos.photos[k].d_translation_m.has_value());
    EXPECT_NEAR(*result.photos.photos[k].d_translation_m, expected_m_s[k] * 0.02, 1e-12);
  }
  EXPECT_NEAR(*result.set.photos[2].course_deg, 90.0, 1e-9);
  // The log's speed is split by the nadir gimbal like a photo's own: flown east, the image's right,
  // the ground moves to the left, all across the readout.
  const PhotoResult& split = result.photos.photos[2];
  ASSERT_TRUE(split.across_readout_px.has_value());
  EXPECT_NEAR(*split.across_readout_px, -*split.d_translation_px, 1e-9);
  EXPECT_NEAR(*split.along_readout_px, 0.0, 1e-9);
  EXPECT_FALSE(result.photos.photos[0].along_readout_px.has_value()) << "no gimbal: no split";
  EXPECT_FALSE(set.photos[0].ground_speed_m_s.has_value()) << "the set given is left as it was";
}

// The same on real bytes: the three DJI photos named by a trigger file on the PX4 log's clock
// (they were not taken on that flight: this checks the streamed analysis against the whole read,
// not the photos' truth), the log's gaps included.
TEST(AnalyzeStream, PhotoFlightOfRealPhotosOnARealLogEqualsTheWholeLog) {
  SHUTTERLAB_REAL_DATA(photos, "incoming/dji_fc8482_clusterodm");
  SHUTTERLAB_REAL_DATA(path, "gyro/px4_ulog/sample.ulg");
  // The reader's own warnings; the trace audit's are added by each analysis.
  FlightLogStream read = OpenFlightLog(path);
  FlightLog log = std::move(read.log);
  log.gyro = ReadAllSamples(read.gyro.get());
  for (LogWarning& w : read.gyro->Warnings()) log.warnings.push_back(std::move(w));
  const PhotoSet set = ReadPhotoSet(photos);
  const TriggerFile triggers = ParseTriggerCsv(
      "image,t\ntest-photo-1.jpg,112.7\ntest-photo-2.jpg,117.614\ntest-photo-3.jpg,160.3\n",
      "t.csv");
  PhotoFlightOptions options;
  options.analyze = TurnedCameraOptions();
  const PhotoFlightResult whole = AnalyzePhotoFlight(set, Audited(log), &triggers, options);
  ASSERT_EQ(whole.log.images.size(), 3u);
  ASSERT_GT(whole.log.gaps, 0u);
  FlightLog metadata = log;
  metadata.gyro = GyroTrace();
  // Each pass opens the file again, as the command does: the reader's own two passes each time.
  AnalyzeLogSource source;
  int opened = 0;
  source.open = [&path, &opened] {
    ++opened;
    return OpenFlightLog(path);
  };
  const PhotoFlightResult streamed =
      AnalyzePhotoFlightStream(set, metadata, source, &triggers, options);
  EXPECT_GE(opened, 2);
  ExpectSameResult(streamed.log, whole.log);
  EXPECT_EQ(streamed.camera_source, whole.camera_source);
  EXPECT_EQ(PhotoAnalysisReport(set, streamed.photos), PhotoAnalysisReport(set, whole.photos));
}

}  // namespace
}  // namespace shutterlab
