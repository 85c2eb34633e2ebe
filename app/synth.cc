// shutterlab synth: deterministic synthetic gyro traces (still, total-station steps, multirotor
// flight) through an IMU error model. Thin: fills SynthOptions, calls WriteSynthetic, prints.

#include "sim/synth/synth.h"

#include "app/command.h"
#include "sim/check.h"
#include "sim/units.h"

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab::app {
namespace {

struct SynthCliOptions {
  std::string profile = "still";
  SynthOptions synth;
  SynthOutputOptions output;
  std::string format = "csv";
  bool raw = false;
  std::string time_unit = "s";
  double altitude_m = 0.0;
  bool ideal = false;
  bool no_quantize = false;
  bool no_saturate = false;
  std::vector<double> const_bias, scale_error, misalignment, axis, turn_time;
  double lead_s = 6.0;
  CLI::Option* lead_option = nullptr;  // given: sets both profiles' lead
  ImuErrorModel given;  // values of the error options as parsed (defaults when not given)
  // The error-model options, to tell given from defaulted when --ideal resets the model.
  std::vector<std::pair<CLI::Option*, std::function<void(ImuErrorModel&)>>> model_overrides;
};

// A comma-separated X,Y,Z option.
CLI::Option* TripleOption(CLI::App* cmd, const std::string& name, std::vector<double>* values,
                          const std::string& help) {
  return cmd->add_option(name, *values, help)->expected(3)->delimiter(',');
}

Eigen::Vector3d Triple(const std::vector<double>& v) { return {v[0], v[1], v[2]}; }

void Run(SynthCliOptions& o) {
  SynthOptions& s = o.synth;
  s.profile = ParseMotionProfile(o.profile);
  o.output.ulog = !o.raw && o.format == "ulog";
  o.output.format = o.raw           ? LogFormat::kRaw
                    : o.output.ulog ? LogFormat::kGyroCsv
                                    : ParseGyroFormat(o.format);
  if (o.altitude_m > 0.0) o.output.altitude_m = o.altitude_m;
  o.output.time_unit = ParseTimeUnit(o.time_unit);
  // The sensor: the MPU-9250-like default, or a perfect one with --ideal; options given on the
  // command line override either.
  const int range_dps = s.imu.range_dps;
  ImuErrorModel model = o.ideal ? ImuErrorModel::Ideal() : ImuErrorModel();
  model.range_dps = range_dps;
  for (auto& [option, apply] : o.model_overrides) {
    if (option->count() > 0) apply(model);
  }
  s.imu = model;
  if (!o.turn_time.empty()) {
    SHUTTERLAB_CHECK(o.turn_time.size() == 2) << "--turn-time takes MIN,MAX seconds";
    s.steps.turn_min_s = o.turn_time[0];
    s.steps.turn_max_s = o.turn_time[1];
  }
  if (!o.axis.empty()) s.steps.axis = Triple(o.axis);
  if (o.lead_option->count() > 0) s.steps.lead_still_s = s.flight.lead_still_s = o.lead_s;
  s.Check();
  o.output.Check();

  const SynthSummary summary = WriteSynthetic(s, o.output);
  std::printf("wrote %zu samples (%.3f s at %g Hz, %zu gaps, %s) to %s%s%s\n", summary.samples,
              summary.duration_s, s.rate_hz, summary.gaps, MotionProfileName(s.profile),
              o.output.out_path.c_str(), o.output.out2_path.empty() ? "" : " and ",
              o.output.out2_path.c_str());
  if (summary.saturated_values > 0) {
    std::printf("warning: %zu rate values saturated at +-%d deg/s\n", summary.saturated_values,
                s.imu.range_dps);
  }
  for (size_t i = 0; i < summary.turns.size(); ++i) {
    const StepTurn& t = summary.turns[i];
    std::printf("turn %zu: %.6f .. %.6f s, %.6f deg about (%.6f, %.6f, %.6f)\n", i + 1,
                s.t0_s + t.start_s, s.t0_s + t.start_s + t.duration_s, t.angle_rad * 180.0 / kPi,
                t.axis.x(), t.axis.y(), t.axis.z());
  }
}

// The sensor error options beyond --ideal: each, when given, overrides its field of the IMU error
// model. p: a raw pointer in the callbacks, no shared_ptr cycle.
void AddSensorErrorOptions(CLI::App* cmd, SynthCliOptions* p) {
  const auto model_option = [cmd, p](const std::string& name, double ImuErrorModel::*field,
                                     const std::string& help) {
    auto* option = cmd->add_option(name, p->given.*field, help)->capture_default_str();
    p->model_overrides.emplace_back(option,
                                    [p, field](ImuErrorModel& m) { m.*field = p->given.*field; });
  };
  model_option("--noise-density", &ImuErrorModel::noise_density_rad_s_sqrt_hz,
               "white rate noise (angle random walk), rad/s/sqrt(Hz)");
  model_option("--bias-instability", &ImuErrorModel::bias_instability_rad_s,
               "Gauss-Markov bias std, rad/s");
  model_option("--bias-tau", &ImuErrorModel::bias_correlation_s,
               "Gauss-Markov bias correlation time, s");
  model_option("--rate-random-walk", &ImuErrorModel::rate_random_walk_rad_s2_sqrt_hz,
               "rate random walk, rad/s^2/sqrt(Hz)");
  model_option("--jitter", &ImuErrorModel::timestamp_jitter_s, "timestamp jitter std, s");
  model_option("--gap-period", &ImuErrorModel::gap_period_s,
               "a logging gap every this many s (0: none)");
  model_option("--gap-duration", &ImuErrorModel::gap_duration_s, "length of each logging gap, s");
  auto* option = TripleOption(cmd, "--const-bias", &p->const_bias,
                              "constant bias X,Y,Z, rad/s (default ~0.6,-0.4,0.25 deg/s)");
  p->model_overrides.emplace_back(option,
                                  [p](ImuErrorModel& m) { m.bias_rad_s = Triple(p->const_bias); });
  option = TripleOption(cmd, "--scale-error", &p->scale_error,
                        "scale error X,Y,Z, dimensionless: measured = (1 + e) * true");
  p->model_overrides.emplace_back(
      option, [p](ImuErrorModel& m) { m.scale_error = Triple(p->scale_error); });
  option = cmd->add_option("--misalignment", p->misalignment,
                           "cross-axis sensitivity XY,XZ,YX,YZ,ZX,ZY, rad (entry ij: sensor axis i "
                           "sees this much of the rate about body axis j)")
               ->expected(6)
               ->delimiter(',');
  p->model_overrides.emplace_back(option, [p](ImuErrorModel& m) {
    const auto& v = p->misalignment;
    m.misalignment_rad << 0.0, v[0], v[1], v[2], 0.0, v[3], v[4], v[5], 0.0;
  });
  option = cmd->add_flag("--no-quantize", p->no_quantize, "do not round rates to the range's LSB");
  p->model_overrides.emplace_back(option, [](ImuErrorModel& m) { m.quantize = false; });
  option = cmd->add_flag("--no-saturate", p->no_saturate, "do not clip rates at the range");
  p->model_overrides.emplace_back(option, [](ImuErrorModel& m) { m.saturate = false; });
}

const CommandRegistration kSynthRegistration(10, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "synth", "write a deterministic synthetic gyro trace (still, steps, flight) with IMU errors");
  auto o = std::make_shared<SynthCliOptions>();
  SynthOptions& s = o->synth;
  cmd->add_option(
         "PROFILE", o->profile,
         "motion: still | steps (total station: turns about a tilted axis, still between) | "
         "flight (multirotor)")
      ->capture_default_str();
  // Output.
  cmd->add_option("--out", o->output.out_path,
                  "output file (required): gyro.csv, or raw counts with --raw");
  cmd->add_option("--out2", o->output.out2_path,
                  "second sensor's file: same motion, independent noise (the two-gyro idea)");
  cmd->add_option("--trigger-every", o->output.trigger_every_s,
                  "ulog: a camera_capture event every this many seconds (0: none)")
      ->capture_default_str();
  cmd->add_option("--altitude", o->altitude_m,
                  "ulog: altitude above ground, m, written as vehicle_local_position.dist_bottom");
  cmd->add_option("--format", o->format,
                  "csv (gyro.csv: s, rad/s), raw (int16 counts) or ulog (a PX4 flight log that "
                  "every command reads)")
      ->capture_default_str();
  cmd->add_flag("--raw", o->raw, "shorthand for --format raw");
  cmd->add_option("--time-unit", o->time_unit,
                  "raw format: unit of the time column (s, ms, us, ns)")
      ->capture_default_str();
  // Sampling.
  cmd->add_option("--rate", s.rate_hz, "sampling rate, Hz")->capture_default_str();
  cmd->add_option("--duration", s.duration_s,
                  "length, s (0: still 60, flight 120, steps as many as the turns need)")
      ->capture_default_str();
  cmd->add_option("--seed", s.seed, "random seed (same seed, same bytes)")->capture_default_str();
  cmd->add_option("--t0", s.t0_s, "time of the first sample, s")->capture_default_str();
  cmd->add_option("--range", s.imu.range_dps,
                  "gyro full-scale range, deg/s (250, 500, 1000, 2000 = 131, 65.5, 32.8, 16.4 LSB "
                  "per deg/s): sets quantisation and saturation")
      ->capture_default_str();
  // Sensor errors.
  cmd->add_flag("--ideal", o->ideal,
                "perfect sensor: no noise, bias, scale, misalignment, quantisation, saturation, "
                "jitter or gaps (the error options below still apply)");
  AddSensorErrorOptions(cmd, o.get());
  // Motion.
  o->lead_option = cmd->add_option("--lead", o->lead_s,
                                   "steps / flight: still time before the motion, s (default 6)");
  cmd->add_option("--turns", s.steps.turns, "steps: number of turns")->capture_default_str();
  cmd->add_option("--angle", s.steps.angle_deg, "steps: angle of each turn, deg")
      ->capture_default_str();
  TripleOption(cmd, "--axis", &o->axis, "steps: turn axis X,Y,Z in sensor axes (normalised)");
  cmd->add_option("--turn-time", o->turn_time, "steps: each turn lasts MIN,MAX s (uniform)")
      ->expected(2)
      ->delimiter(',');
  cmd->add_option("--still", s.steps.still_s, "steps: still time after each turn, s")
      ->capture_default_str();
  cmd->add_option("--wobble", s.flight.wobble_rms_dps, "flight: attitude wobble RMS rate, deg/s")
      ->capture_default_str();
  cmd->add_option("--gusts", s.flight.gusts_per_s, "flight: wind gusts per second")
      ->capture_default_str();
  cmd->add_option("--gust-max", s.flight.gust_max_dps, "flight: largest gust peak rate, deg/s")
      ->capture_default_str();
  cmd->add_option("--vibration", s.flight.vibration_dps, "flight: motor harmonic amplitude, deg/s")
      ->capture_default_str();
  cmd->add_option("--resonance", s.flight.resonance_dps, "flight: frame resonance amplitude, deg/s")
      ->capture_default_str();
  return std::function<void()>([o] { Run(*o); });
});

}  // namespace
}  // namespace shutterlab::app
