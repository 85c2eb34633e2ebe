#pragma once
// Deterministic synthetic gyro traces: an analytic motion (sim/synth/motion.h) seen through an IMU
// error model (sim/synth/imu_model.h) and a logger (timestamp jitter, periodic gaps).
//
// Sample k is taken at the nominal instant t0_ns + round(k * 1e9 / rate_hz) (computed from k, never
// accumulated), where the true rate is evaluated; its logged timestamp adds the jitter. Everything
// random comes from NoiseSource streams of the seed: one for the motion, one for each sensor's
// noise and one for each sensor's timing, so that changing a logger setting does not change the
// noise, and a second sensor sees the same motion with independent errors.
//
// What the defaults give (3000 Hz, +-250 deg/s, seed-dependent, see tests/sim/synth/synth_test.cc):
//  - still: the paper's Table 1 statistic (120-sample windows of the per-axis integrated angle,
//    bias from the first 5 s) has mean sigma ~1.1" and mean range ~4.3" per axis (noise
//    density 7.0e-5 rad/s/sqrt(Hz)).
//  - flight (120 s, 50 m, 20" allowance): flagged shares per axis, 10 ms / 20 ms windows, of
//    21-31 % / 50-60 % at 5 cm and 9-14 % / 23-33 % at 10 cm over seeds 1-5 (seed 1: 21 / 54 and
//    9 / 23 %); the paper's flight had 25 / 56 % and 11 / 25 %.

#include "sim/gyro_trace.h"
#include "sim/logs/gyro_io.h"
#include "sim/synth/imu_model.h"
#include "sim/synth/motion.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct SynthOptions {
  MotionProfile profile = MotionProfile::kStill;
  double rate_hz = 3000.0;  // sampling rate, Hz (the paper's logger ran the MPU-9250 at 2-4 kHz)
  // Length, s; the trace holds floor(duration_s * rate_hz) + 1 samples (fewer with gaps).
  // 0 picks the profile's default: still 60 s, flight 120 s, steps the natural length
  // (lead + each turn and the still after it).
  double duration_s = 0.0;
  uint64_t seed = 1;   // every random draw derives from it (std::mt19937_64, never random_device)
  double t0_s = 0.0;   // time of the first sample, s (gyro clock)
  ImuErrorModel imu;   // sensor errors, range and logger timing; Ideal() for a perfect sensor
  StepsOptions steps;  // used by the steps profile
  FlightMotionOptions flight;  // used by the flight profile

  void Check() const;  // throws std::invalid_argument naming the first bad field
  // The duration actually used, s (resolves duration_s = 0).
  double DurationS() const;
  // Samples on the nominal grid, gaps included.
  int64_t NominalSampleCount() const;
  // Nominal instant of sample k, ns.
  int64_t NominalTimeNs(int64_t k) const;
};

// The analytic motion of these options (its OmegaRadS(t_s) takes t_s since t0_s).
Motion MakeMotion(const SynthOptions& options);

// The logged trace of sensor `sensor` (0 = the first, 1 = the paper's second gyro, ...): the
// motion through the error model, with jitter and gaps. saturated_values (optional) receives how
// many rate values the range clipped.
GyroTrace SynthesizeTrace(const SynthOptions& options, int sensor = 0,
                          size_t* saturated_values = nullptr);

// The noiseless truth: the exact body rate at every nominal instant (no gaps, no jitter, no sensor
// error). Integrating it (OrientationTrace) gives the true orientation; for steps, also see
// MakeMotion(options).turns() and Motion::WorldFromBody.
GyroTrace SynthesizeTruth(const SynthOptions& options);

// Where and how `shutterlab synth` writes.
struct SynthOutputOptions {
  std::string out_path;   // first sensor
  std::string out2_path;  // second sensor (same motion, independent noise); empty for none
  // kGyroCsv (docs/FORMATS.md gyro.csv, seconds and rad/s) or kRaw (the paper's logger: header
  // t,gx,gy,gz, int16 counts of imu.range_dps, time in time_unit; read back with --raw --range
  // --time-unit).
  LogFormat format = LogFormat::kGyroCsv;
  TimeUnit time_unit = TimeUnit::kSeconds;  // raw only
  // Instead of the above: a PX4 ULog flight log (sim/logs/ulog_write.h), with a camera_capture
  // event every trigger_every_s (0: none) from one interval after the first sample, and the
  // altitude above ground when given. ULog times must be positive: start with t0_s > 0.
  bool ulog = false;
  double trigger_every_s = 0.0;
  std::optional<double> altitude_m;

  void Check() const;
};

struct SynthSummary {
  size_t samples = 0;           // samples in the first sensor's trace
  size_t gaps = 0;              // logging gaps in it (GyroTrace::sampling)
  double duration_s = 0.0;      // its time span, s
  size_t saturated_values = 0;  // rate values clipped at the range, both sensors
  std::vector<StepTurn> turns;  // steps: the true turns
};

// Synthesises the trace(s) and writes them, each file whole or not at all (when the second file
// cannot be written the first is removed again). Throws IoError / std::invalid_argument.
SynthSummary WriteSynthetic(const SynthOptions& options, const SynthOutputOptions& output);

}  // namespace shutterlab
