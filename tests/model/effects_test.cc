#include "model/effects.h"

#include "model/effect_io.h"
#include "tests/model/model_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// A model with every effect's field away from its default, so that a delta on any of them shows.
TrueModel Base() {
  TrueModel model;
  model.rig = test::SmallRig(64, 48);
  ApplyInjection("time_offset=4ms", &model);
  ApplyInjection("gyro_to_camera=0,-1,0,1,0,0,0,0,1", &model);
  ApplyInjection("gyro_scale=1.01,0.99,1.02", &model);
  ApplyInjection("gyro_bias=0.001rad/s,-0.002rad/s,0.003rad/s", &model);
  ApplyInjection("velocity=5m/s,1m/s,0", &model);
  ApplyInjection("lens_distortion=-0.1,0.02", &model);
  ApplyInjection("clock_rate=30ppm", &model);
  return model;
}

// The model as the table sees it: every effect's value.
std::vector<EffectValue> Values(const TrueModel& model) {
  std::vector<EffectValue> out;
  for (const EffectSpec& spec : AllEffects()) out.push_back(spec.value(model));
  return out;
}

// Largest difference between two values of the same shape; infinity where the shapes or the
// directions differ.
double Difference(const EffectValue& a, const EffectValue& b) {
  const double inf = std::numeric_limits<double>::infinity();
  if (a.index() != b.index()) return inf;
  if (const double* x = std::get_if<double>(&a)) return std::abs(*x - std::get<double>(b));
  if (const auto* v = std::get_if<Eigen::Vector3d>(&a)) {
    return (*v - std::get<Eigen::Vector3d>(b)).cwiseAbs().maxCoeff();
  }
  if (const auto* m = std::get_if<Eigen::Matrix3d>(&a)) {
    return (*m - std::get<Eigen::Matrix3d>(b)).cwiseAbs().maxCoeff();
  }
  if (const auto* c = std::get_if<LensDistortion>(&a)) {
    const LensDistortion& d = std::get<LensDistortion>(b);
    if (c->index() != d.index()) return inf;
    const auto coeffs = [](const LensDistortion& lens) -> std::vector<double> {
      if (const auto* b = std::get_if<BrownConrady>(&lens))
        return {b->coeffs.begin(), b->coeffs.end()};
      const Fisheye& f = std::get<Fisheye>(lens);
      return {f.coeffs().begin(), f.coeffs().end()};
    };
    const std::vector<double> x = coeffs(*c), y = coeffs(d);
    double worst = 0.0;
    for (size_t i = 0; i < x.size(); ++i) worst = std::max(worst, std::abs(x[i] - y[i]));
    return worst;
  }
  return a == b ? 0.0 : inf;  // directions, std::monostate
}

double Difference(const std::vector<EffectValue>& a, const std::vector<EffectValue>& b) {
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, Difference(a[i], b[i]));
  return worst;
}

TEST(Effects, EachRoundTripsItsName) {
  ASSERT_EQ(AllEffects().size(), 9u);
  std::set<std::string> names;
  for (size_t i = 0; i < AllEffects().size(); ++i) {
    const EffectSpec& spec = AllEffects()[i];
    EXPECT_EQ(spec.effect, static_cast<Effect>(i)) << spec.name;  // Spec indexes by the enum
    EXPECT_EQ(&Spec(spec.effect), &spec);
    EXPECT_TRUE(ParseEffect(spec.name) == spec.effect) << spec.name;
    EXPECT_EQ(RequireEffect(spec.name, "test"), spec.effect) << spec.name;
    names.insert(spec.name);
    EXPECT_TRUE(spec.step && spec.apply_delta && spec.inject && spec.value && spec.stderr_value)
        << spec.name;
  }
  EXPECT_EQ(names.size(), AllEffects().size());
  // docs/FORMATS.md's names, in its order.
  EXPECT_EQ(Spec(Effect::kTimeOffset).name, "time_offset");
  EXPECT_EQ(Spec(Effect::kReadoutDirection).name, "readout_direction");
  EXPECT_EQ(Spec(Effect::kClockRate).name, "clock_rate");
}

// The physical bounds, known answers on each side: what a real MEMS gyro, camera clock and sensor
// can have is inside; a gyro 90 % off in scale or biased 100 deg/s, a 0.5 s readout, a clock
// 5 % fast are outside, with the axis, the value and the reason. A mounting, a lens and a
// readout direction have no bound.
TEST(Effects, PhysicalBoundsKnownAnswers) {
  const double deg = M_PI / 180.0;
  EXPECT_EQ(OutOfBounds(Effect::kGyroScale, Eigen::Vector3d(1.03, 0.97, 1.0)), "");
  EXPECT_EQ(OutOfBounds(Effect::kGyroScale, Eigen::Vector3d(1.0, 1.0, 0.1)),
            "axis z at 0.1, outside 0.9 ... 1.1: a MEMS gyro's sensitivity is within 3 % of "
            "nominal (MPU-9250 datasheet, sensitivity scale factor tolerance), 10 % allowed");
  EXPECT_EQ(OutOfBounds(Effect::kGyroBias, Eigen::Vector3d(0.5 * deg, -3 * deg, 9 * deg)), "");
  const std::string bias = OutOfBounds(Effect::kGyroBias, Eigen::Vector3d(0, 100 * deg, 0));
  EXPECT_EQ(bias.rfind("axis y at 100 deg/s, outside -10 ... 10 deg/s: ", 0), 0u) << bias;
  EXPECT_EQ(OutOfBounds(Effect::kReadoutTime, 0.0335), "");
  EXPECT_EQ(OutOfBounds(Effect::kReadoutTime, 0.5).rfind("500 ms, outside 0.1 ... 100 ms", 0), 0u);
  EXPECT_EQ(OutOfBounds(Effect::kTimeOffset, -0.0073), "");
  EXPECT_NE(OutOfBounds(Effect::kTimeOffset, 2.5), "");
  EXPECT_EQ(OutOfBounds(Effect::kClockRate, 40.0), "");
  EXPECT_EQ(
      OutOfBounds(Effect::kClockRate, 5e4).rfind("50000 ppm, outside -20000 ... 20000 ppm", 0), 0u);
  EXPECT_EQ(OutOfBounds(Effect::kVelocity, Eigen::Vector3d(12, -3, 0)), "");
  EXPECT_NE(OutOfBounds(Effect::kVelocity, Eigen::Vector3d(0, 0, 250)), "");
  EXPECT_EQ(OutOfBounds(Effect::kGyroToCamera, Eigen::Matrix3d(-Eigen::Matrix3d::Identity())), "");
  EXPECT_FALSE(Spec(Effect::kLensDistortion).bounds.has_value());
  EXPECT_FALSE(Spec(Effect::kReadoutDirection).bounds.has_value());
}

// camera.json's bounds replace an effect's physical ones (a device known to differ), and say so;
// the other effects keep theirs.
TEST(Effects, CameraJsonBoundsReplaceThePhysicalOnes) {
  RigModel rig;
  rig.bounds["gyro_scale"] = {0.05, 2.0};
  EXPECT_EQ(OutOfBounds(Effect::kGyroScale, Eigen::Vector3d(1.0, 1.0, 0.1), &rig), "");
  EXPECT_EQ(OutOfBounds(Effect::kGyroScale, Eigen::Vector3d(1.0, 2.5, 1.0), &rig),
            "axis y at 2.5, outside 0.05 ... 2: camera.json's bounds for gyro_scale");
  rig.bounds["time_offset"] = {-0.002, 0.002};
  EXPECT_EQ(OutOfBounds(Effect::kTimeOffset, 0.004, &rig),
            "4 ms, outside -2 ... 2 ms: camera.json's bounds for time_offset");
  EXPECT_NE(OutOfBounds(Effect::kClockRate, 5e4, &rig), "");
  EXPECT_EQ(BoundedEffectNames(),
            "time_offset, readout_time, gyro_scale, gyro_bias, velocity, clock_rate");
  std::string camera_json_names;
  for (const std::string& name : CameraJsonBoundNames()) {
    camera_json_names += (camera_json_names.empty() ? "" : ", ") + name;
  }
  EXPECT_EQ(camera_json_names, BoundedEffectNames());
}

TEST(Effects, AnUnknownNameFailsNamingIt) {
  EXPECT_FALSE(ParseEffect("warp_speed").has_value());
  EXPECT_FALSE(ParseEffect("").has_value());
  EXPECT_FALSE(ParseEffect("Time_Offset").has_value());
  try {
    RequireEffect("warp_speed", "--candidates");
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--candidates"), std::string::npos) << what;
    EXPECT_NE(what.find("'warp_speed'"), std::string::npos) << what;
    for (const EffectSpec& spec : AllEffects()) {
      EXPECT_NE(what.find(spec.name), std::string::npos) << what;
    }
  }
  try {
    TrueModel model = Base();
    ApplyInjection("warp_speed=9", &model);
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'warp_speed'"), std::string::npos) << e.what();
  }
}

// ApplyInjection sets what the effect's value reads back, in the shape its standard error has.
TEST(Effects, InjectedValueReadsBackInTheStderrShape) {
  const std::vector<std::string> injections = {"time_offset=5ms",
                                               "readout_time=21ms",
                                               "gyro_to_camera=0,0,1,0,1,0,-1,0,0",
                                               "gyro_scale=1.01,0.99,1.0",
                                               "gyro_bias=0.001rad/s,-0.002rad/s,0.003rad/s",
                                               "velocity=5m/s,0,0",
                                               "lens_distortion=-0.1,0.02",
                                               "readout_direction=bottom_to_top",
                                               "clock_rate=-35ppm"};
  ASSERT_EQ(injections.size(), AllEffects().size());
  for (const std::string& text : injections) {
    const Effect effect = *ParseEffect(text.substr(0, text.find('=')));
    const EffectSpec& spec = Spec(effect);
    TrueModel model = Base();
    const EffectValue recorded = ApplyInjection(text, &model).value;
    EXPECT_TRUE(recorded == spec.value(model)) << text;
    EXPECT_TRUE(HasShape(recorded, spec.shape)) << text;
    // The standard error of parameter_count parameters has the value's shape.
    const int n = spec.parameter_count;
    const EffectValue sd = EffectStderr(effect, model, Eigen::MatrixXd::Identity(n, n) * 1e-6);
    if (n == 0) {
      EXPECT_TRUE(std::holds_alternative<std::monostate>(sd)) << text;
      continue;
    }
    EXPECT_LT(Difference(sd, recorded), std::numeric_limits<double>::infinity()) << text;
    EXPECT_THROW(EffectStderr(effect, model, Eigen::MatrixXd::Identity(n + 1, n + 1)),
                 std::invalid_argument)
        << text;
  }
}

// apply_delta reads exactly parameter_count numbers, and each of them moves the model.
TEST(Effects, DeltaUsesExactlyItsParameters) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const EffectSpec& spec : AllEffects()) {
    const int n = spec.parameter_count;
    for (int i = 0; i < n; ++i) {
      std::vector<double> delta(n + 4, nan);  // NaN past the end would show in the model
      std::fill(delta.begin(), delta.begin() + n, 0.0);
      delta[i] = 10 * spec.step(i, 100.0);
      TrueModel model = Base();
      spec.apply_delta(delta.data(), &model);
      const double moved = Difference(Values(model), Values(Base()));
      EXPECT_TRUE(moved > 0 && std::isfinite(moved)) << spec.name << " parameter " << i;
    }
  }
}

TEST(Effects, ZeroDeltaLeavesTheModelUnchanged) {
  for (const EffectSpec& spec : AllEffects()) {
    if (spec.parameter_count == 0) continue;  // readout_direction: a flip, not a delta
    const std::vector<double> zero(spec.parameter_count, 0.0);
    TrueModel model = Base();
    spec.apply_delta(zero.data(), &model);
    EXPECT_TRUE(Values(model) == Values(Base())) << spec.name;
  }
}

TEST(Effects, DeltaThenItsNegationRestoresTheModel) {
  for (const EffectSpec& spec : AllEffects()) {
    std::vector<double> delta, negated;
    for (int i = 0; i < spec.parameter_count; ++i) {
      delta.push_back((i + 3) * spec.step(i, 100.0));
      negated.push_back(-delta.back());
    }
    TrueModel model = Base();
    spec.apply_delta(delta.data(), &model);
    EXPECT_GT(Difference(Values(model), Values(Base())), 0.0) << spec.name;
    spec.apply_delta(negated.data(), &model);  // readout_direction: the second flip
    EXPECT_LT(Difference(Values(model), Values(Base())), 1e-12) << spec.name;
  }
}

}  // namespace
}  // namespace shutterlab
