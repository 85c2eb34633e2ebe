#include "estimate/paper/analyze.h"

#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/flight_log_io.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/estimate/paper/paper_fixtures.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::ConstantRateLog;
using test::RateForGroundSmear;

constexpr int64_t kDtNs = test::kLogDtNs;  // 1 kHz
constexpr double kAltitudeM = 50.0;        // test::MappingRig's
constexpr double kReadoutS = 0.030;        // test::MappingRig's
// D_paper interpolates the window's ends, so a constant rate gives w * readout up to rounding.
constexpr double kPaperTolM = 1e-9;

// The mapping camera (1280x960, f 1100 px, 30 ms, 50 m), the default limits and triggers.
AnalyzeOptions BaseOptions() {
  AnalyzeOptions options;
  options.rig = test::MappingRig();
  return options;
}

TEST(Analyze, ConstantRateGivesPaperDistortionAndFlagsAboveTheLimit) {
  const double omega = RateForGroundSmear(0.07);  // between the 5 cm and 10 cm limits
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(omega, 0, 0), 10.0);
  AnalyzeOptions options = BaseOptions();
  options.triggers = {{"moving", SecondsToNs(6.0)},
                      {"still", SecondsToNs(1.0)},
                      {"late", SecondsToNs(9.99)},
                      {"early", SecondsToNs(-1.0)}};
  const AnalyzeResult result = Analyze(log, options);
  ASSERT_TRUE(result.bias_from_still);
  EXPECT_NEAR(result.bias_rad_s.norm(), 0.0, 1e-12);
  ASSERT_EQ(result.images.size(), 4u);
  const ImageResult& moving = result.images[0];
  ASSERT_TRUE(moving.in_trace);
  EXPECT_NEAR(moving.d_paper_m, kAltitudeM * std::tan(omega * kReadoutS), kPaperTolM);
  EXPECT_NEAR(moving.d_paper_m, 0.07, kPaperTolM);
  EXPECT_EQ(moving.dominant_axis, 0);
  EXPECT_TRUE(moving.flagged[0]);
  EXPECT_FALSE(moving.flagged[1]);
  const ImageResult& still = result.images[1];
  ASSERT_TRUE(still.in_trace);
  EXPECT_EQ(still.d_paper_m, 0.0);
  EXPECT_NEAR(still.d_full_m, 0.0, 1e-9);  // ray casting rounds
  EXPECT_FALSE(still.flagged[0]);
  // The readout of these runs past either end of the trace: reported, not thrown.
  EXPECT_FALSE(result.images[2].in_trace);
  EXPECT_FALSE(result.images[3].in_trace);
  EXPECT_EQ(result.verdict.images_in_trace, 2u);
  EXPECT_DOUBLE_EQ(result.verdict.share_percent[0], 50.0);
  EXPECT_DOUBLE_EQ(result.verdict.share_percent[1], 0.0);
  EXPECT_EQ(result.verdict.axis_to_stabilise, 0);
  // What-if, recomputed: 10 ms readout -> 2.3 cm; half altitude -> 3.5 cm; both under 5 cm.
  EXPECT_DOUBLE_EQ(result.verdict.share_fast_readout_percent[0], 0.0);
  EXPECT_DOUBLE_EQ(result.verdict.share_half_altitude_percent[0], 0.0);
  EXPECT_NE(result.verdict.line.find("50.0% over 5 cm"), std::string::npos) << result.verdict.line;
  ASSERT_TRUE(result.flight.has_value());
  EXPECT_EQ(result.flight->rows.size(), 2u);
}

// At 50 Hz a 30 ms readout holds one or two samples: the images are refused as flight's rows are,
// not given a D of 0, and the verdict says what the rate allows; a 100 ms readout is judged.
TEST(Analyze, ImagesWhoseReadoutHoldsTooFewSamplesAreNotJudged) {
  FlightLog log;
  std::vector<GyroSample> samples;
  for (int k = 0; k < 1000; ++k)  // 20 s at 50 Hz, turning about x after 6 s
    samples.push_back({static_cast<int64_t>(k) * 20'000'000,
                       Eigen::Vector3d(k >= 300 ? RateForGroundSmear(0.07) : 0.0, 0, 0)});
  log.gyro = GyroTrace(samples);
  log.format = "gyro.csv";
  AnalyzeOptions options = BaseOptions();
  options.every_s = 2.0;
  const AnalyzeResult refused = Analyze(log, options);
  ASSERT_FALSE(refused.images.empty());
  for (const ImageResult& image : refused.images) {
    if (!image.in_trace) continue;
    EXPECT_TRUE(image.too_few_samples) << image.name;
    EXPECT_FALSE(image.judged());
  }
  EXPECT_EQ(refused.verdict.images_in_trace, 0u);
  EXPECT_GT(refused.verdict.images_too_few_samples, 0u);
  EXPECT_EQ(refused.verdict.line.rfind("verdict: no image can be judged: at 50 Hz the 30 ms "
                                       "readout holds at most two samples; it must be longer "
                                       "than 40 ms",
                                       0),
            0u)
      << refused.verdict.line;
  EXPECT_NE(AnalyzeReport(refused).find("too few samples in the readout"), std::string::npos);
  options.rig.shutter.readout_s = 0.100;
  const AnalyzeResult judged = Analyze(log, options);
  EXPECT_EQ(judged.verdict.images_too_few_samples, 0u);
  EXPECT_EQ(judged.verdict.images_in_trace, refused.verdict.images_too_few_samples);
  // Its what-if of a 10 ms readout cannot be judged at 50 Hz either: said, not given as 0 %.
  EXPECT_TRUE(judged.verdict.share_fast_readout_percent.empty());
  EXPECT_NE(judged.verdict.line.find("with a 10 ms readout: too few samples at 50 Hz to judge"),
            std::string::npos)
      << judged.verdict.line;
}

TEST(Analyze, FlagIsStrictlyAboveTheLimit) {
  // Just under and just over 5 cm.
  for (const double d_m : {0.0499, 0.0501}) {
    const FlightLog log = ConstantRateLog(Eigen::Vector3d(0, RateForGroundSmear(d_m), 0), 8.0);
    AnalyzeOptions options = BaseOptions();
    options.triggers = {{"a", SecondsToNs(6.0)}};
    const AnalyzeResult result = Analyze(log, options);
    ASSERT_TRUE(result.images[0].in_trace);
    EXPECT_EQ(result.images[0].dominant_axis, 1);
    EXPECT_EQ(result.images[0].flagged[0], d_m > 0.05) << d_m;
  }
}

TEST(Analyze, FullDistortionOfPurePitchIsFocalTimesTangent) {
  // A short frame keeps off-axis terms (y^2/f^2 < 0.1 %, x^2/f^2 < 0.4 %) small, so the column
  // through the principal point decides: D = f tan(w * readout * (h-1)/h) from row 0 to the last.
  constexpr double kRelTol = 0.01;
  const double omega = 0.5;
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(omega, 0, 0), 8.0);
  AnalyzeOptions options = BaseOptions();
  options.rig.camera.width = 129;
  options.rig.camera.height = 64;
  options.rig.camera.cx = 64.0;
  options.rig.camera.cy = 31.5;
  options.triggers = {{"a", SecondsToNs(6.0)}};
  const AnalyzeResult result = Analyze(log, options);
  const ImageResult& image = result.images[0];
  ASSERT_TRUE(image.in_trace);
  const double expected_px = 1100.0 * std::tan(omega * kReadoutS * 63.0 / 64.0);
  EXPECT_NEAR(image.d_full_px, expected_px, kRelTol * expected_px);
  EXPECT_NEAR(image.d_full_m, image.d_full_px * kAltitudeM / 1100.0, 1e-12);
}

TEST(Analyze, FullDistortionOfRollIsTheAngleTimesTheCornerRadius) {
  // With fx = fy, K Rz(a) K^-1 turns the image about the principal point: the last row moves by
  // 2 sin(a/2) times its distance from the centre against row 0 (the reference), largest at the
  // corner columns, which the coarse grid includes. 0.5 %: small-angle second-order terms.
  constexpr double kRelTol = 0.005;
  const double omega = 0.5;
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(0, 0, omega), 8.0);
  AnalyzeOptions options = BaseOptions();
  options.triggers = {{"a", SecondsToNs(6.0)}};
  const AnalyzeResult result = Analyze(log, options);
  const double angle = omega * kReadoutS * 959.0 / 960.0;
  const double expected_px = 2.0 * std::sin(0.5 * angle) * std::hypot(639.5, 479.5);
  EXPECT_NEAR(result.images[0].d_full_px, expected_px, kRelTol * expected_px);
  EXPECT_EQ(result.images[0].dominant_axis, 2);
}

TEST(Analyze, FullDistortionCountsTheDeclaredVelocity) {
  // No rotation, 10 m/s along camera x: the ground moves v * (t_last - t_0) between the first and
  // last rows, so D_full = v * readout * (h - 1) / h on the ground; the paper's model sees nothing.
  const FlightLog log = ConstantRateLog(Eigen::Vector3d::Zero(), 8.0);
  AnalyzeOptions options = BaseOptions();
  options.rig.velocity_mps = Eigen::Vector3d(10.0, 0, 0);
  options.triggers = {{"a", SecondsToNs(6.0)}};
  const AnalyzeResult result = Analyze(log, options);
  const double h = options.rig.camera.height;
  ASSERT_TRUE(result.images[0].in_trace);
  EXPECT_NEAR(result.images[0].d_full_m, 10.0 * kReadoutS * (h - 1) / h, 1e-9);
  EXPECT_EQ(result.images[0].d_paper_m, 0.0);
}

TEST(Analyze, FullDistortionCountsLensDistortion) {
  // A pitch shifts the image; under distortion k1 = -0.2 the shift spans fewer pixels off-centre
  // and the rows' displacements differ: the renderer's model sees it, the paper's model does not.
  // (A roll about the optical axis would not do: radial distortion commutes with it.)
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(RateForGroundSmear(0.07), 0, 0), 8.0);
  AnalyzeOptions options = BaseOptions();
  options.triggers = {{"a", SecondsToNs(6.0)}};
  const AnalyzeResult pinhole = Analyze(log, options);
  options.rig.camera.distortion = BrownConrady{{-0.2, 0, 0, 0, 0}};
  const AnalyzeResult barrel = Analyze(log, options);
  EXPECT_EQ(pinhole.images[0].d_paper_m, barrel.images[0].d_paper_m);
  EXPECT_GT(std::abs(barrel.images[0].d_full_px / pinhole.images[0].d_full_px - 1.0), 0.03);
}

TEST(Analyze, CamFromGyroMapsTheLogsAxesToTheCamera) {
  // Gyro z is camera x under this R_CG (a cyclic permutation).
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(0, 0, RateForGroundSmear(0.07)), 8.0);
  AnalyzeOptions options = BaseOptions();
  options.rig.cam_from_gyro << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  options.triggers = {{"a", SecondsToNs(6.0)}};
  const AnalyzeResult result = Analyze(log, options);
  EXPECT_EQ(result.images[0].dominant_axis, 0);
  EXPECT_NEAR(result.images[0].d_paper_m, 0.07, kPaperTolM);
}

TEST(Analyze, LogAltitudeWhenAsked) {
  FlightLog log = ConstantRateLog(Eigen::Vector3d(RateForGroundSmear(0.07), 0, 0), 8.0);
  log.altitude_above_ground_m = 2.0 * kAltitudeM;
  AnalyzeOptions options = BaseOptions();
  options.triggers = {{"a", SecondsToNs(6.0)}};
  EXPECT_NEAR(Analyze(log, options).images[0].d_paper_m, 0.07, kPaperTolM);
  options.use_log_altitude = true;
  const AnalyzeResult result = Analyze(log, options);
  EXPECT_EQ(result.altitude_source, "log");
  // D_paper is linear in the altitude: tan of the same angle.
  EXPECT_NEAR(result.images[0].d_paper_m, 0.14, 2 * kPaperTolM);
}

TEST(Analyze, LatencyShiftsTheExposure) {
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(RateForGroundSmear(0.07), 0, 0), 8.0);
  AnalyzeOptions options = BaseOptions();
  options.triggers = {{"a", SecondsToNs(3.5)}};
  options.trigger_latency_s = 1.0;  // exposed in the motion, not in the still lead-in
  const AnalyzeResult result = Analyze(log, options);
  EXPECT_EQ(result.images[0].t_ns, SecondsToNs(4.5));
  EXPECT_NEAR(result.images[0].d_paper_m, 0.07, kPaperTolM);
}

TEST(Analyze, EverySimulatesTriggersAndNoTriggersGivesNoImages) {
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(0.01, 0, 0), 9.5);
  AnalyzeOptions options = BaseOptions();
  EXPECT_TRUE(Analyze(log, options).images.empty());
  options.every_s = 2.0;
  const AnalyzeResult result = Analyze(log, options);
  ASSERT_EQ(result.images.size(), 4u);  // floor(9.5 / 2)
  EXPECT_EQ(result.images[3].t_ns, SecondsToNs(6.0));
  EXPECT_EQ(result.images[0].name, "IMG_0001");
}

TEST(Analyze, NoStillSegmentMeansZeroBias) {
  // A sinusoid never rests; the analysis still runs, on zero bias.
  std::vector<GyroSample> samples;
  for (int64_t k = 0; k < 8000; ++k) {
    const double t = k * 1e-3;
    samples.push_back({k * kDtNs, Eigen::Vector3d(std::sin(3 * t), std::cos(5 * t), 0.3)});
  }
  FlightLog log;
  log.gyro = GyroTrace(std::move(samples));
  AnalyzeOptions options = BaseOptions();
  options.every_s = 1.0;
  const AnalyzeResult result = Analyze(log, options);
  EXPECT_FALSE(result.bias_from_still);
  EXPECT_EQ(result.bias_rad_s, Eigen::Vector3d::Zero());
  ASSERT_TRUE(result.flight.has_value());
  EXPECT_EQ(result.images.size(), 7u);
}

TEST(Analyze, EstimateBiasFalseKeepsTheRatesAsGiven) {
  // A constant 0.01 rad/s everywhere: with estimation the still lead-in reads it as bias and the
  // image sees nothing; without, the image sees the rate itself.
  const double omega = 0.01;
  std::vector<GyroSample> samples;
  for (int64_t k = 0; k <= 8000; ++k) samples.push_back({k * kDtNs, Eigen::Vector3d(omega, 0, 0)});
  FlightLog log;
  log.gyro = GyroTrace(std::move(samples));
  AnalyzeOptions options = BaseOptions();
  options.triggers = {{"a", SecondsToNs(6.0)}};
  const AnalyzeResult estimated = Analyze(log, options);
  ASSERT_TRUE(estimated.bias_from_still);
  EXPECT_NEAR(estimated.bias_rad_s.x(), omega, 1e-12);
  EXPECT_NEAR(estimated.images[0].d_paper_m, 0.0, 1e-9);
  options.estimate_bias = false;
  const AnalyzeResult raw = Analyze(log, options);
  EXPECT_FALSE(raw.bias_estimated);
  EXPECT_FALSE(raw.bias_from_still);
  EXPECT_EQ(raw.bias_rad_s, Eigen::Vector3d::Zero());
  EXPECT_NEAR(raw.images[0].d_paper_m, kAltitudeM * std::tan(omega * kReadoutS), kPaperTolM);
  EXPECT_NE(AnalyzeReport(raw).find("bias: zero (not estimated)"), std::string::npos);
}

TEST(Analyze, CameraEventsAreTheDefaultTriggers) {
  FlightLog log = ConstantRateLog(Eigen::Vector3d(RateForGroundSmear(0.07), 0, 0), 8.0);
  log.camera_events = {{SecondsToNs(5.0), 7, "camera_capture"},
                       {SecondsToNs(5.0), 7, "camera_trigger"},
                       {SecondsToNs(6.0), 8, "camera_capture"}};
  const AnalyzeResult result = Analyze(log, BaseOptions());
  ASSERT_EQ(result.images.size(), 2u);  // the most frequent kind only
  EXPECT_EQ(result.images[1].name, "IMG_8");
}

TEST(Analyze, KeepsTheTracesItsImagesCameFrom) {
  // A bias the still lead-in finds, a rate about gyro z that R_CG makes camera x, and the log's
  // altitude: the kept traces are in camera axes, without the bias, at the altitude used.
  const Eigen::Vector3d bias_gyro(0.002, -0.001, 0.003);
  const FlightLog constant = ConstantRateLog(Eigen::Vector3d(0, 0, RateForGroundSmear(0.07)), 8.0);
  // White noise on every sample: the lead-in and the rotation are equally quiet, and the still
  // search takes the one with the smaller mean (noise-free, rounding would decide).
  constexpr double kNoiseRadS = 1e-3;
  // The bias is the mean over ~4000 still samples: 6 standard errors.
  constexpr double kBiasTolRadS = 6 * kNoiseRadS / 63.0;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, kNoiseRadS);
  std::vector<GyroSample> samples = constant.gyro.samples();
  for (GyroSample& s : samples) {
    s.omega_rad_s += bias_gyro + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  }
  FlightLog log = constant;
  log.gyro = GyroTrace(std::move(samples));
  log.altitude_above_ground_m = 2.0 * kAltitudeM;
  AnalyzeOptions options = BaseOptions();
  options.rig.cam_from_gyro << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  options.use_log_altitude = true;
  options.triggers = {{"a", SecondsToNs(6.0)}};
  const AnalyzeResult result = Analyze(log, options);
  ASSERT_TRUE(result.bias_from_still);
  ASSERT_NE(result.traces, nullptr);
  const AnalyzeTraces& traces = *result.traces;
  const auto& logged = log.gyro.samples();
  ASSERT_EQ(traces.camera_rates.size(), logged.size());
  ASSERT_EQ(traces.angles.size(), logged.size());
  for (size_t k = 0; k < logged.size(); ++k) {
    ASSERT_EQ(traces.camera_rates[k].t_ns, logged[k].t_ns);
    ASSERT_EQ(
        traces.camera_rates[k].omega_rad_s,
        Eigen::Vector3d(options.rig.cam_from_gyro * logged[k].omega_rad_s - result.bias_rad_s))
        << k;
  }
  // The image's range is the kept angles' change over its readout (6.000 to 6.030 s: samples; the
  // rate stays far above the noise, so the angle rises monotonically).
  const ImageResult& image = result.images[0];
  ASSERT_TRUE(image.in_trace);
  const size_t begin = log.gyro.LowerBound(image.t_ns);
  const size_t end = log.gyro.LowerBound(image.t_ns + SecondsToNs(kReadoutS));
  EXPECT_DOUBLE_EQ(
      image.range_arcsec[0],
      (traces.angles.angle_rad[0][end] - traces.angles.angle_rad[0][begin]) * kArcsecPerRad);
  // The full model's motion: the rig analysed, the bias back in gyro axes.
  const TrueModel& model = traces.motion.model();
  EXPECT_EQ(result.altitude_m, 2.0 * kAltitudeM);
  EXPECT_EQ(model.rig.altitude_m, result.altitude_m);
  EXPECT_EQ(model.rig.time_offset_s, 0.0);
  EXPECT_LT((model.gyro_bias_rad_s - bias_gyro).norm(), kBiasTolRadS);
  // A copy of the result shares the traces rather than copying them.
  const AnalyzeResult copy = result;
  EXPECT_EQ(copy.traces.get(), result.traces.get());
}

TEST(Analyze, AllanDeviationOnTheStillSegmentWhenAsked) {
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(RateForGroundSmear(0.07), 0, 0), 8.0);
  AnalyzeOptions options = BaseOptions();
  EXPECT_FALSE(Analyze(log, options).allan.has_value());
  options.allan = true;
  const AnalyzeResult still = Analyze(log, options);
  ASSERT_TRUE(still.bias_from_still);
  ASSERT_TRUE(still.allan.has_value());
  ASSERT_FALSE(still.allan->empty());
  EXPECT_TRUE(still.allan_on_still);
  // The longest cluster time grows with the record: the still lead-in (4 s) is half the whole log
  // (8 s, without a bias search), so its longest tau is shorter.
  options.estimate_bias = false;
  const AnalyzeResult whole = Analyze(log, options);
  ASSERT_TRUE(whole.allan.has_value());
  EXPECT_FALSE(whole.allan_on_still);
  EXPECT_LT(still.allan->tau_s.back(), whole.allan->tau_s.back());
}

TEST(Analyze, RealBetaflightLogEveryTwoSeconds) {
  SHUTTERLAB_REAL_DATA(path, "gyro/betaflight_blackbox/btfl_001.bbl");
  const FlightLog log = ReadFlightLog(path);
  AnalyzeOptions options = BaseOptions();
  options.every_s = 2.0;
  const AnalyzeResult result = Analyze(log, options);
  const auto& s = log.gyro.samples();
  const double duration_s = (s.back().t_ns - s.front().t_ns) * 1e-9;
  EXPECT_EQ(result.images.size(), static_cast<size_t>(std::floor(duration_s / 2.0)));
  ASSERT_TRUE(result.flight.has_value());
  size_t in_trace = 0;
  for (const ImageResult& image : result.images) {
    if (!image.in_trace) continue;
    ++in_trace;
    EXPECT_TRUE(std::isfinite(image.d_paper_m) && image.d_paper_m >= 0) << image.name;
    EXPECT_TRUE(std::isfinite(image.d_full_m) && image.d_full_m >= 0) << image.name;
  }
  EXPECT_EQ(in_trace, result.images.size());
  EXPECT_EQ(result.format, "betaflight");
}

TEST(Analyze, WritesImagesCsvAndExcludeList) {
  const FlightLog log = ConstantRateLog(Eigen::Vector3d(RateForGroundSmear(0.07), 0, 0), 8.0);
  AnalyzeOptions options = BaseOptions();
  options.triggers = {{"IMG_A", SecondsToNs(6.0)}, {"IMG_B", SecondsToNs(1.0)}};
  const AnalyzeResult result = Analyze(log, options);
  test::TempDir dir;
  WriteAnalyzeOutputs(dir / "out", result);
  EXPECT_EQ(ReadFileToString(dir / "out/exclude.txt"), "IMG_A\n");
  const std::string csv = ReadFileToString(dir / "out/images.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "name,t,D_paper_m,D_full_m,flag_0.05,flag_0.1,dominant_axis");
}

TEST(TriggersOnLogClock, NamesTriggersAndPlacesGpsTimesThroughTheLogsFixes) {
  TriggerFile csv;
  csv.clock = TriggerClock::kLog;
  csv.events = {{3'000'000'000, -1, "DSC01", {}, {}, {}}, {4'000'000'000, -1, "", {}, {}, {}}};
  const FlightLog no_gps;
  const auto named = TriggersOnLogClock(csv, no_gps, "t.csv");
  ASSERT_EQ(named.size(), 2u);
  EXPECT_EQ(named[0].name, "DSC01");
  EXPECT_EQ(named[1].name, "IMG_0002");
  EXPECT_EQ(named[1].t_ns, 4'000'000'000);

  // MRK: GPS time. The log's clock is UTC - 1e18 ns; GPS is 18 s ahead of UTC (2022).
  TriggerFile mrk;
  mrk.clock = TriggerClock::kGps;
  const int64_t gps_ns = GpsNsFromWeek(2211, 296288.242869);
  mrk.events = {{gps_ns, 12, "", {}, {}, {}}};
  EXPECT_THROW(TriggersOnLogClock(mrk, no_gps, "f.MRK"), IoError);
  FlightLog log;
  const int64_t utc_ns = UtcFromGpsNs(gps_ns);
  log.utc_fixes = {{utc_ns - 1'000'000'000'000'000'000 - 5'000'000'000, utc_ns - 5'000'000'000},
                   {utc_ns - 1'000'000'000'000'000'000 + 5'000'000'000, utc_ns + 5'000'000'000}};
  const auto placed = TriggersOnLogClock(mrk, log, "f.MRK");
  EXPECT_EQ(placed[0].name, "IMG_12");
  EXPECT_EQ(placed[0].t_ns, utc_ns - 1'000'000'000'000'000'000);
}

TEST(AnalyzeOptions, CheckRejectsNonsense) {
  AnalyzeOptions options = BaseOptions();
  options.limits_m = {-0.05};
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = BaseOptions();
  options.rig.shutter.readout_s = 0.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  EXPECT_EQ(LimitKey(0.05), "0.05");
  EXPECT_EQ(LimitKey(0.1), "0.1");
}

}  // namespace
}  // namespace shutterlab
