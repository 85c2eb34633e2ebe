// shutterlab synth: deterministic synthetic gyro traces (still, total-station steps, multirotor
// flight) through an IMU error model. Thin: fills SynthOptions, calls WriteSynthetic, prints.

#include "sim/synth/synth.h"

#include "app/command.h"
#include "app/trace_options.h"
#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
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
  std::string format = "gyro.csv";  // the readers' name (sim/logs/log_format.h); "csv" too
  bool raw = false;
  std::string time_unit = "s";
  double altitude_m = 0.0;
  bool ideal = false;
  bool no_quantize = false;
  bool no_saturate = false;
  std::vector<double> const_bias, scale_error, misalignment, axis, turn_time;
  double lead_s = 6.0;
  CLI::Option* lead_option = nullptr;  // given: sets both profiles' lead
  CLI::Option* t0_option = nullptr;    // not given with ulog: 1 s
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
  // A ULog's clock counts from boot and never reads 0 (docs/FORMATS.md): start it a second in.
  if (o.output.ulog && o.t0_option->count() == 0) s.t0_s = 1.0;
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
    SHUTTERLAB_CHECK(o.turn_time.size() == 2) << "--turn-time takes MIN,MAX, e.g. 1s,2s";
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
                                     const char* unit, const char* bare_means,
                                     const std::string& help) {
    auto* option = AddQuantityOption(cmd, name, &(p->given.*field), unit, bare_means, help);
    p->model_overrides.emplace_back(option,
                                    [p, field](ImuErrorModel& m) { m.*field = p->given.*field; });
  };
  model_option("--noise-density", &ImuErrorModel::noise_density_rad_s_sqrt_hz, "rad/s/rtHz",
               "rad/s/rtHz", "white rate noise (angle random walk)");
  model_option("--bias-instability", &ImuErrorModel::bias_instability_rad_s, "rad/s", "rad/s",
               "Gauss-Markov bias std");
  model_option("--bias-tau", &ImuErrorModel::bias_correlation_s, "s", "s",
               "Gauss-Markov bias correlation time");
  model_option("--rate-random-walk", &ImuErrorModel::rate_random_walk_rad_s2_sqrt_hz,
               "rad/s^2/rtHz", "rad/s^2/rtHz", "rate random walk");
  model_option("--jitter", &ImuErrorModel::timestamp_jitter_s, "s", "us", "timestamp jitter std");
  model_option("--gap-period", &ImuErrorModel::gap_period_s, "s", "s",
               "a logging gap every this long (0: none)");
  model_option("--gap-duration", &ImuErrorModel::gap_duration_s, "s", "ms",
               "length of each logging gap");
  auto* option = AddQuantityListOption(cmd, "--const-bias", &p->const_bias, "rad/s", "deg/s",
                                       "constant bias X,Y,Z (default ~0.6,-0.4,0.25deg/s)")
                     ->expected(3);
  p->model_overrides.emplace_back(option,
                                  [p](ImuErrorModel& m) { m.bias_rad_s = Triple(p->const_bias); });
  option = TripleOption(cmd, "--scale-error", &p->scale_error,
                        "scale error X,Y,Z, dimensionless: measured = (1 + e) * true");
  p->model_overrides.emplace_back(
      option, [p](ImuErrorModel& m) { m.scale_error = Triple(p->scale_error); });
  option = AddQuantityListOption(cmd, "--misalignment", &p->misalignment, "rad", "mrad",
                                 "cross-axis sensitivity XY,XZ,YX,YZ,ZX,ZY (entry ij: sensor "
                                 "axis i sees this much of the rate about body axis j)")
               ->expected(6);
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
  AddQuantityOption(cmd, "--trigger-every", &o->output.trigger_every_s, "s", "s",
                    "ulog: a camera_capture event every this long (0: none)");
  AddQuantityOption(cmd, "--altitude", &o->altitude_m, "m", "m",
                    "ulog: altitude above ground, written as vehicle_local_position.dist_bottom");
  cmd->add_option("--format", o->format,
                  "gyro.csv (s, rad/s; csv too), raw (int16 counts) or ulog (a PX4 flight log "
                  "that every command reads): the names every command's --format reads")
      ->capture_default_str();
  cmd->add_flag("--raw", o->raw, "shorthand for --format raw");
  cmd->add_option("--time-unit", o->time_unit,
                  "raw format: unit of the time column (s, ms, us, ns)")
      ->capture_default_str();
  // Sampling.
  AddQuantityOption(cmd, "--rate", &s.rate_hz, "Hz", "Hz", "sampling rate");
  AddQuantityOption(cmd, "--duration", &s.duration_s, "s", "s",
                    "length (0: still 60s, flight 120s, steps as many as the turns need)");
  cmd->add_option("--seed", s.seed, "random seed (same seed, same bytes)")->capture_default_str();
  o->t0_option = AddQuantityOption(cmd, "--t0", &s.t0_s, "s", "s",
                                   "time of the first sample (ulog: 1s unless given, a ULog's "
                                   "clock starts at boot and never reads 0)");
  AddRangeOption(cmd, &s.imu.range_dps,
                 "gyro full-scale range (250, 500, 1000, 2000deg/s = 131, 65.5, 32.8, 16.4 LSB "
                 "per deg/s): sets quantisation and saturation");
  // Sensor errors.
  cmd->add_flag("--ideal", o->ideal,
                "perfect sensor: no noise, bias, scale, misalignment, quantisation, saturation, "
                "jitter or gaps (the error options below still apply)");
  AddSensorErrorOptions(cmd, o.get());
  // Motion.
  o->lead_option = AddQuantityOption(cmd, "--lead", &o->lead_s, "s", "s",
                                     "steps / flight: still time before the motion");
  cmd->add_option("--turns", s.steps.turns, "steps: number of turns")->capture_default_str();
  AddQuantityOption(cmd, "--angle", &s.steps.angle_deg, "deg", "deg", "steps: angle of each turn");
  TripleOption(cmd, "--axis", &o->axis, "steps: turn axis X,Y,Z in sensor axes (normalised)");
  AddQuantityListOption(cmd, "--turn-time", &o->turn_time, "s", "s",
                        "steps: each turn lasts MIN,MAX (uniform)")
      ->expected(2);
  AddQuantityOption(cmd, "--still", &s.steps.still_s, "s", "s",
                    "steps: still time after each turn");
  AddQuantityOption(cmd, "--wobble", &s.flight.wobble_rms_dps, "deg/s", "deg/s",
                    "flight: attitude wobble RMS rate");
  AddQuantityOption(cmd, "--gusts", &s.flight.gusts_per_s, "Hz", "Hz",
                    "flight: wind gusts per second");
  AddQuantityOption(cmd, "--gust-max", &s.flight.gust_max_dps, "deg/s", "deg/s",
                    "flight: largest gust peak rate");
  AddQuantityOption(cmd, "--vibration", &s.flight.vibration_dps, "deg/s", "deg/s",
                    "flight: motor harmonic amplitude");
  AddQuantityOption(cmd, "--resonance", &s.flight.resonance_dps, "deg/s", "deg/s",
                    "flight: frame resonance amplitude");
  return std::function<void()>([o] { Run(*o); });
});

}  // namespace
}  // namespace shutterlab::app
