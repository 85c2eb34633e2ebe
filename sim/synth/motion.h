#pragma once
// Analytic body motions for synthetic gyro traces: the true body rate w(t) at any instant, so that
// tests have exact ground truth.
//
// Time t_s is in seconds since the first sample of the trace. Rates are rad/s about the body axes,
// which are the ideal sensor axes (the sensor's own errors are in sim/synth/imu_model.h).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab {

enum class MotionProfile {
  kStill,   // no rotation at all
  kSteps,   // a total station: n turns of a fixed angle about one axis, still in between
  kFlight,  // a multirotor: attitude wobble, wind gusts, motor harmonics, frame resonance
};

// "still", "steps", "flight"; throws std::invalid_argument otherwise.
MotionProfile ParseMotionProfile(const std::string& name);
const char* MotionProfileName(MotionProfile profile);

// The source paper's accuracy test on a total station: still, turn, still, turn, ...
struct StepsOptions {
  int turns = 5;           // number of turns, all the same way
  double angle_deg = 1.0;  // angle of each turn, deg (negative turns the other way)
  // Turn axis in body (= ideal sensor) axes; normalised on use. The default is not aligned with any
  // sensor axis (it is the direction of the paper's Table 3 example, before [-51,-41,-23]" and
  // after [3433,-340,757]"), so every axis sees part of each turn.
  Eigen::Vector3d axis{0.951, -0.094, 0.210};
  // Each turn lasts a duration drawn uniformly from [turn_min_s, turn_max_s] (seeded), s.
  double turn_min_s = 0.2;
  double turn_max_s = 0.3;
  double lead_still_s =
      6.0;               // still before the first turn, s (covers the default 5 s bias segment)
  double still_s = 3.0;  // still after each turn, s

  void Check() const;  // throws std::invalid_argument naming the first bad field
};

// A multirotor in hover / slow flight. All rate amplitudes are deg/s, frequencies Hz.
// The defaults give flagged shares near the source paper's flight (50 m altitude, 20" allowance):
// see sim/synth/synth.h.
struct FlightMotionOptions {
  double lead_still_s = 6.0;  // on the ground, motors off, s (covers the default 5 s bias segment)
  double spin_up_s = 1.0;  // all motion ramps smoothly from zero over this time after the lead, s
  // Slow attitude wobble: a sum of sinusoids from 0.2 to 2.5 Hz per axis whose amplitude follows a
  // slowly varying activity level; RMS rate per roll / pitch axis (yaw gets 0.6 of it), deg/s.
  double wobble_rms_dps = 2.2;
  // Wind gusts: Gaussian rate pulses (0.08-0.35 s wide) at random instants, this many per second
  // on average, peak rate log-uniform in [gust_min_dps, gust_max_dps], mostly roll / pitch.
  double gusts_per_s = 0.7;
  double gust_min_dps = 4.0;
  double gust_max_dps = 50.0;
  // Motor harmonics: the rotor frequency sweeps motor_hz +- motor_sweep_hz (throttle); the first
  // harmonic has amplitude vibration_dps per axis (times 0.5-1.5 with throttle), the second 0.4 of
  // it.
  double motor_hz = 140.0;
  double motor_sweep_hz = 25.0;
  double vibration_dps = 3.0;
  // Frame resonance at resonance_hz whose amplitude comes and goes between 0 and resonance_dps.
  double resonance_hz = 95.0;
  double resonance_dps = 4.0;

  void Check() const;  // throws std::invalid_argument naming the first bad field
};

// One turn of the steps profile: the rate is axis * (angle_rad / duration_s) * (1 - cos(2 pi tau /
// duration_s)) for tau = t_s - start_s in [0, duration_s] (a Hann pulse: the rate and the angular
// acceleration are continuous), zero outside; it integrates to exactly angle_rad about axis.
struct StepTurn {
  double start_s;
  double duration_s;
  double angle_rad;
  Eigen::Vector3d axis;  // unit vector, body axes
};

class Motion {
 public:
  Motion() = default;  // still
  static Motion Still() { return Motion(); }
  // seed draws the turn durations.
  static Motion Steps(const StepsOptions& options, uint64_t seed);
  // seed draws the wobble, gusts and vibration phases; duration_s bounds where gusts are placed.
  static Motion Flight(const FlightMotionOptions& options, double duration_s, uint64_t seed);

  MotionProfile profile() const { return profile_; }

  // True body rate at t_s (seconds since the first sample), rad/s, body axes.
  Eigen::Vector3d OmegaRadS(double t_s) const;

  // Length of the motion as designed, s: steps: lead + turns and the still after each; flight:
  // the duration it was built for; still: 0 (any length).
  double natural_duration_s() const { return natural_duration_s_; }

  // Steps: the turns, in order (empty for the other profiles).
  const std::vector<StepTurn>& turns() const { return turns_; }

  // Exact world_from_body at t_s, identity at t_s = 0. Still and steps only (rotations about one
  // fixed axis have a closed form); throws std::invalid_argument for flight, whose truth is the
  // SO(3) integration of the noiseless trace (SynthesizeTruth + OrientationTrace).
  Eigen::Quaterniond WorldFromBody(double t_s) const;

 private:
  struct Sinusoid {  // amplitude * sin(2 pi freq t + phase)
    double amplitude;
    double freq_hz;
    double phase_rad;
  };
  struct Gust {
    double center_s;
    double width_s;
    Eigen::Vector3d peak_rad_s;
  };
  Eigen::Vector3d FlightOmegaRadS(double t_s) const;

  MotionProfile profile_ = MotionProfile::kStill;
  double natural_duration_s_ = 0.0;
  std::vector<StepTurn> turns_;
  // Flight components (times relative to the end of the lead).
  FlightMotionOptions flight_;
  std::vector<Sinusoid> envelope_;
  std::vector<Sinusoid> wobble_[3];
  std::vector<Gust> gusts_;  // sorted by center
  double motor_sweep_freq_hz_ = 0.0, motor_sweep_phase_rad_ = 0.0;
  double throttle_freq_hz_ = 0.0, throttle_phase_rad_ = 0.0;
  double burst_freq_hz_ = 0.0, burst_phase_rad_ = 0.0;
  Eigen::Vector3d harmonic1_[2], harmonic2_[2], resonance_[2];  // [0] sin, [1] cos weights, rad/s
};

}  // namespace shutterlab
