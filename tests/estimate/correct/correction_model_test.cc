#include "estimate/correct/correction_model.h"

#include "estimate/correct/residual_prediction.h"
#include "render/rs_warp.h"
#include "sim/units.h"
#include "tests/render/render_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace shutterlab {
namespace {

// White noise of density `density` at 1 kHz on a still stretch of `still_s`, then a slow swing.
GyroTrace NoisyTrace(double density, double still_s, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, density / std::sqrt(1e-3));
  std::vector<GyroSample> samples;
  for (int k = 0; k < 20000; ++k) {
    const double t = k * 1e-3;
    const double swing = t < still_s ? 0.0 : 0.5 * std::sin(2 * M_PI * 0.7 * (t - still_s));
    samples.push_back({k * 1'000'000LL, Eigen::Vector3d(swing + normal(rng),
                                                        0.3 * swing + normal(rng), normal(rng))});
  }
  return GyroTrace(std::move(samples));
}

TEST(EstimateGyroNoise, ReadsTheDensityOnTheStillSegmentOrFromSecondDifferences) {
  constexpr double kDensity = 7e-5;  // rad/s/sqrt(Hz), an MPU-9250's
  const GyroNoiseEstimate still = EstimateGyroNoise(NoisyTrace(kDensity, 6.0, 1));
  EXPECT_NEAR(still.rad_s_sqrt_hz, kDensity, 0.05 * kDensity) << still.source;
  EXPECT_NE(still.source.find("still segment"), std::string::npos) << still.source;
  // Moving from the start: the second differences, which a slow motion barely touches.
  const GyroNoiseEstimate moving = EstimateGyroNoise(NoisyTrace(kDensity, 0.0, 2));
  EXPECT_NEAR(moving.rad_s_sqrt_hz, kDensity, 0.1 * kDensity) << moving.source;
  EXPECT_NE(moving.source.find("second differences"), std::string::npos) << moving.source;
}

TEST(BuildCorrectionModel, TakesTheFittedModelAndRefusesAnotherCamera) {
  const RigModel declared = test::SmallRig(96, 72);
  ReportedModel report;
  report.fitted = TrueModel{};
  report.fitted->rig = declared;
  report.fitted->rig.time_offset_s = 0.003;
  report.fitted->gyro_scale = Eigen::Vector3d(1.02, 1.0, 0.98);
  ReportedEffect effect;
  effect.effect = Effect::kTimeOffset;
  effect.value = 0.003;
  effect.covariance = Eigen::MatrixXd::Constant(1, 1, 1e-8);
  report.effects.push_back(effect);
  const CorrectionModel model = BuildCorrectionModel(declared, report, "r.json");
  EXPECT_EQ(model.model.rig.time_offset_s, 0.003);
  EXPECT_EQ(model.model.gyro_scale, report.fitted->gyro_scale);
  ASSERT_EQ(model.uncertainty.size(), 1u);
  EXPECT_EQ(model.uncertainty[0].covariance(0, 0), 1e-8);
  report.fitted->rig.camera.width = 128;
  EXPECT_THROW(BuildCorrectionModel(declared, report, "r.json"), std::invalid_argument);
  // Without fitted_model the effects' values are applied to camera.json, and it is said.
  report.fitted.reset();
  const CorrectionModel applied = BuildCorrectionModel(declared, report, "r.json");
  EXPECT_EQ(applied.model.rig.time_offset_s, 0.003);
  EXPECT_FALSE(applied.notes.empty());
}

// A report whose effect no device has (a gyro 90 % off in scale about z) corrects nothing: it is
// refused in one line naming the report, the effect and the bound, whatever tool wrote it.
TEST(BuildCorrectionModel, RefusesAnEffectNoDeviceHas) {
  const RigModel declared = test::SmallRig(96, 72);
  ReportedModel report;
  ReportedEffect scale;
  scale.effect = Effect::kGyroScale;
  scale.value = Eigen::Vector3d(1.0, 1.0, 0.1);
  report.effects.push_back(scale);
  try {
    BuildCorrectionModel(declared, report, "r.json");
    ADD_FAILURE() << "an impossible gyro scale was taken";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("r.json: gyro_scale axis z at 0.1, outside 0.9 ... 1.1"), std::string::npos)
        << what;
    EXPECT_NE(what.find("give the values to use with --effect NAME=VALUE"), std::string::npos)
        << what;
  }
  report.effects[0].value = Eigen::Vector3d(1.0, 1.0, 1.02);  // 2 %: a real part's
  EXPECT_NO_THROW(BuildCorrectionModel(declared, report, "r.json"));
  // A device camera.json says differs: its own bounds hold instead.
  RigModel wide = declared;
  wide.bounds["gyro_scale"] = {0.05, 1.5};
  report.effects[0].value = Eigen::Vector3d(1.0, 1.0, 0.1);
  EXPECT_NO_THROW(BuildCorrectionModel(wide, report, "r.json"));
}

TEST(PredictResidual, ACertainModelLeavesNothingAndDBeforeIsTheFramesDistortion) {
  const RigModel rig = test::SmallRig(160, 120);
  const GyroTrace gyro = test::ConstantRateTrace(Eigen::Vector3d(0.4, -0.6, 0.9));
  CorrectionModel model;
  model.model.rig = rig;
  CorrectionSetting setting;
  setting.plane_depth_m = rig.altitude_m;
  const ResidualPrediction certain = PredictResidual(model, gyro, SecondsToNs(0.5), setting);
  EXPECT_LT(certain.d_after_px, 1e-5) << "the fixed point is solved to 1e-6 px";
  EXPECT_EQ(certain.draws, 32);
  // D before against the renderer's truth field's D (every pixel; the prediction's grid is 33x25).
  const FrameGeometry geometry(rig.camera, rig.altitude_m,
                               CameraMotion(gyro, model.model).Frame(SecondsToNs(0.5)),
                               cv::Size(400, 300));
  EXPECT_NEAR(certain.d_before_px, FrameDistortionPx(DisplacementField(geometry)), 0.02);
  // Its one draw standing for all 32 against all 32 drawn: a covariance of zero draws the model
  // itself every time, through the random draws.
  CorrectionModel drawn_each_time = model;
  drawn_each_time.uncertainty.push_back({Effect::kReadoutTime, Eigen::MatrixXd::Zero(1, 1)});
  const ResidualPrediction twin = PredictResidual(drawn_each_time, gyro, SecondsToNs(0.5), setting);
  EXPECT_EQ(twin.draws, certain.draws);
  EXPECT_EQ(twin.d_after_px, certain.d_after_px);
  EXPECT_EQ(twin.d_after_p90_px, certain.d_after_p90_px);
  EXPECT_EQ(twin.rms_after_px, certain.rms_after_px);
  EXPECT_EQ(twin.d_before_px, certain.d_before_px);
  // A readout uncertain by 10 %: something is left, more at the 90th percentile than the median.
  model.uncertainty.push_back({Effect::kReadoutTime, Eigen::MatrixXd::Constant(1, 1, 4e-6)});
  const ResidualPrediction uncertain = PredictResidual(model, gyro, SecondsToNs(0.5), setting);
  EXPECT_GT(uncertain.d_after_px, 0.02 * certain.d_before_px);
  EXPECT_GT(uncertain.d_after_p90_px, uncertain.d_after_px);
  EXPECT_LT(uncertain.d_after_p90_px, 0.3 * certain.d_before_px);
  // Each draw's poses at the rows the grid reads only, against every row: the same numbers, for
  // both reference rows. The gyro's noise is on (drawn alike on both sides, at the rows read).
  model.gyro_noise_rad_s_sqrt_hz = 2e-3;
  for (const CorrectionReference reference :
       {CorrectionReference::kFirstRow, CorrectionReference::kMidReadout}) {
    setting.reference = reference;
    ResidualPredictionOptions every_row;
    every_row.every_row = true;
    const ResidualPrediction fast = PredictResidual(model, gyro, SecondsToNs(0.5), setting);
    const ResidualPrediction slow =
        PredictResidual(model, gyro, SecondsToNs(0.5), setting, every_row);
    EXPECT_GT(fast.d_after_px, uncertain.d_after_px) << "the noise adds to what is left";
    EXPECT_EQ(fast.draws, slow.draws);
    EXPECT_EQ(fast.d_after_px, slow.d_after_px);
    EXPECT_EQ(fast.d_after_p90_px, slow.d_after_p90_px);
    EXPECT_EQ(fast.rms_after_px, slow.rms_after_px);
  }
  // A model without uncertainty draws itself: each draw turns the model's one frame by its own
  // noise, against each draw's poses at every row computed afresh.
  CorrectionModel noise_only = model;
  noise_only.uncertainty.clear();
  ResidualPredictionOptions every_row;
  every_row.every_row = true;
  const ResidualPrediction fast = PredictResidual(noise_only, gyro, SecondsToNs(0.5), setting);
  const ResidualPrediction slow =
      PredictResidual(noise_only, gyro, SecondsToNs(0.5), setting, every_row);
  EXPECT_GT(fast.d_after_px, 10 * certain.d_after_px) << "the noise is left";
  EXPECT_EQ(fast.draws, slow.draws);
  EXPECT_EQ(fast.d_after_px, slow.d_after_px);
  EXPECT_EQ(fast.d_after_p90_px, slow.d_after_p90_px);
  EXPECT_EQ(fast.rms_after_px, slow.rms_after_px);
  // The caller's frame of the model (a correction's) stands for the one computed inside, with and
  // without an uncertainty to draw; the frame given is the one used (a frame of twice the rate
  // doubles D before); a trace that misses the readout is refused as without a frame.
  for (const CorrectionModel* m : {&noise_only, &model}) {
    const FrameMotion frame = CameraMotion(gyro, m->model).Frame(SecondsToNs(0.5));
    const ResidualPrediction inside = PredictResidual(*m, gyro, SecondsToNs(0.5), setting);
    const ResidualPrediction given =
        PredictResidual(*m, gyro, SecondsToNs(0.5), setting, {}, &frame);
    EXPECT_EQ(given.draws, inside.draws);
    EXPECT_EQ(given.d_before_px, inside.d_before_px);
    EXPECT_EQ(given.d_after_px, inside.d_after_px);
    EXPECT_EQ(given.d_after_p90_px, inside.d_after_p90_px);
    EXPECT_EQ(given.rms_after_px, inside.rms_after_px);
    const FrameMotion faster =
        CameraMotion(test::ConstantRateTrace(Eigen::Vector3d(0.8, -1.2, 1.8)), m->model)
            .Frame(SecondsToNs(0.5));
    EXPECT_NEAR(PredictResidual(*m, gyro, SecondsToNs(0.5), setting, {}, &faster).d_before_px,
                2 * inside.d_before_px, 0.05 * inside.d_before_px);
    const GyroTrace before_readout = GyroAround(gyro, 0, SecondsToNs(0.45));
    EXPECT_THROW(PredictResidual(*m, before_readout, SecondsToNs(0.5), setting), std::out_of_range);
    EXPECT_THROW(PredictResidual(*m, before_readout, SecondsToNs(0.5), setting, {}, &frame),
                 std::out_of_range);
  }
}

// The noise walk drawn at a few rows has, at each and on each axis alone, the variance
// density^2 |t_v - t_start| (t the rows' gyro-clock times under the model); rows on one side share
// their steps (the covariance of two is the nearer one's variance), the two sides and the three
// axes are independent. Top to bottom, and bottom to top on a clock 300 ppm fast. 40000 walks:
// each variance to 0.7 % (one sigma); a walk that forgot where its last step ended would give row
// 100 the variance 90 rows' steps (from 90) plus 50 (from 50), not 50.
TEST(GyroNoiseAnglesRad, TheWalkAtTheRowsReadHasTheVarianceOfEveryRowsSteps) {
  for (const bool bottom_to_top : {false, true}) {
    TrueModel model;
    model.rig = test::SmallRig(8, 101);
    model.rig.shutter.readout_s = 0.1;  // 1 ms from row to row
    if (bottom_to_top) {
      model.rig.shutter.direction = ReadoutDirection::kBottomToTop;
      model.clock_rate_ppm = 300.0;
    }
    const int64_t t_first_row_ns = SecondsToNs(0.5);
    const int marked[6] = {0, 10, 50, 51, 90, 100};
    std::vector<bool> rows(101, false);
    for (int v : marked) rows[v] = true;
    const double density = 0.01;
    std::mt19937_64 rng(3);
    const int walks = 40000;
    using Moments = Eigen::Matrix<double, 6, 6>;
    Moments per_axis[3] = {Moments::Zero(), Moments::Zero(), Moments::Zero()};
    double cross_axis = 0.0;  // x against y at row 100
    for (int i = 0; i < walks; ++i) {
      const std::vector<Eigen::Vector3d> a =
          GyroNoiseAnglesRad(model, t_first_row_ns, 50, density, rows, &rng);
      ASSERT_EQ(a.size(), 101u);
      EXPECT_EQ(a[50], Eigen::Vector3d::Zero());
      EXPECT_EQ(a[30], Eigen::Vector3d::Zero()) << "an unmarked row";
      for (int axis = 0; axis < 3; ++axis) {
        Eigen::Matrix<double, 6, 1> x;
        for (int k = 0; k < 6; ++k) x[k] = a[marked[k]][axis];
        per_axis[axis] += x * x.transpose() / walks;
      }
      cross_axis += a[100].x() * a[100].y() / walks;
    }
    const auto variance = [&](int row) {
      return density * density *
             std::abs(model.RowGyroOffsetS(t_first_row_ns, row) -
                      model.RowGyroOffsetS(t_first_row_ns, 50));
    };
    for (int axis = 0; axis < 3; ++axis) {
      const Moments& m = per_axis[axis];
      for (int k : {0, 1, 3, 4, 5}) {
        EXPECT_NEAR(m(k, k), variance(marked[k]), 0.03 * variance(marked[k]))
            << "row " << marked[k] << ", axis " << axis << ", bottom to top " << bottom_to_top;
      }
      EXPECT_NEAR(m(0, 1), variance(10), 0.03 * variance(10)) << "steps shared";
      EXPECT_NEAR(m(4, 5), variance(90), 0.03 * variance(90)) << "steps shared";
      EXPECT_NEAR(m(0, 5), 0.0, 0.03 * variance(0)) << "independent sides";
    }
    EXPECT_NEAR(cross_axis, 0.0, 0.03 * variance(100)) << "independent axes";
  }
}

}  // namespace
}  // namespace shutterlab
