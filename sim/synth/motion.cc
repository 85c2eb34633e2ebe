#include "sim/synth/motion.h"

#include "sim/check.h"
#include "sim/so3.h"
#include "sim/synth/imu_model.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {
namespace {

// Random-stream ids (NoiseSource) of the motion; sensors use others (sim/synth/synth.cc).
constexpr uint64_t kStepsStream = 1;
constexpr uint64_t kFlightStream = 2;

// A Gaussian pulse is negligible beyond this many widths (exp(-0.5 * 6^2) ~ 1.5e-8 of its peak).
constexpr double kGustReachWidths = 6.0;
constexpr double kGustMaxWidthS = 0.35;
constexpr double kGustMinWidthS = 0.08;

double LogUniform(NoiseSource& rng, double lo, double hi) {
  return lo * std::exp(rng.Uniform() * std::log(hi / lo));
}

// 0 before t = 0, 1 after t = 1, C1-smooth in between.
double SmoothStep(double t) {
  if (t <= 0.0) return 0.0;
  if (t >= 1.0) return 1.0;
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace

MotionProfile ParseMotionProfile(const std::string& name) {
  const std::string n = ToLower(name);
  if (n == "still") return MotionProfile::kStill;
  if (n == "steps") return MotionProfile::kSteps;
  if (n == "flight") return MotionProfile::kFlight;
  SHUTTERLAB_CHECK(false) << "unknown motion profile '" << name << "' (still, steps, flight)";
  return MotionProfile::kStill;
}

const char* MotionProfileName(MotionProfile profile) {
  switch (profile) {
    case MotionProfile::kStill:
      return "still";
    case MotionProfile::kSteps:
      return "steps";
    case MotionProfile::kFlight:
      return "flight";
  }
  return "?";
}

void StepsOptions::Check() const {
  SHUTTERLAB_CHECK(turns >= 1 && turns <= 100000) << "turns must be 1..100000, got " << turns;
  SHUTTERLAB_CHECK(std::isfinite(angle_deg) && angle_deg != 0.0 && std::abs(angle_deg) <= 180.0)
      << "turn angle must be nonzero and at most 180 deg, got " << angle_deg;
  SHUTTERLAB_CHECK(axis.allFinite() && axis.norm() > 1e-9) << "turn axis must be a nonzero vector";
  SHUTTERLAB_CHECK(std::isfinite(turn_min_s) && std::isfinite(turn_max_s) && turn_min_s > 0 &&
                   turn_max_s >= turn_min_s)
      << "turn duration must satisfy 0 < min <= max, got " << turn_min_s << ".." << turn_max_s
      << " s";
  SHUTTERLAB_CHECK(std::isfinite(lead_still_s) && lead_still_s >= 0)
      << "lead still time must be >= 0 s, got " << lead_still_s;
  SHUTTERLAB_CHECK(std::isfinite(still_s) && still_s >= 0)
      << "still time between turns must be >= 0 s, got " << still_s;
}

void FlightMotionOptions::Check() const {
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0; };
  SHUTTERLAB_CHECK(non_negative(lead_still_s)) << "flight lead still time must be >= 0 s";
  SHUTTERLAB_CHECK(non_negative(spin_up_s)) << "flight spin-up time must be >= 0 s";
  SHUTTERLAB_CHECK(non_negative(wobble_rms_dps)) << "wobble RMS must be >= 0 deg/s";
  SHUTTERLAB_CHECK(non_negative(gusts_per_s) && gusts_per_s <= 100)
      << "gusts per second must be 0..100";
  SHUTTERLAB_CHECK(std::isfinite(gust_min_dps) && gust_min_dps > 0 &&
                   gust_max_dps >= gust_min_dps && std::isfinite(gust_max_dps))
      << "gust peak rates must satisfy 0 < min <= max deg/s";
  SHUTTERLAB_CHECK(non_negative(motor_hz) && non_negative(motor_sweep_hz) &&
                   motor_sweep_hz <= motor_hz)
      << "motor frequency must be >= 0 Hz with a sweep no larger than itself";
  SHUTTERLAB_CHECK(non_negative(vibration_dps)) << "vibration amplitude must be >= 0 deg/s";
  SHUTTERLAB_CHECK(non_negative(resonance_hz) && non_negative(resonance_dps))
      << "frame resonance frequency and amplitude must be >= 0";
}

Motion Motion::Steps(const StepsOptions& options, uint64_t seed) {
  options.Check();
  Motion m;
  m.profile_ = MotionProfile::kSteps;
  NoiseSource rng(seed, kStepsStream);
  const Eigen::Vector3d axis = options.axis.normalized();
  double t_s = options.lead_still_s;
  for (int i = 0; i < options.turns; ++i) {
    const double duration_s =
        options.turn_min_s + (options.turn_max_s - options.turn_min_s) * rng.Uniform();
    m.turns_.push_back({t_s, duration_s, options.angle_deg * kRadPerDeg, axis});
    t_s += duration_s + options.still_s;
  }
  m.natural_duration_s_ = t_s;
  return m;
}

Motion Motion::Flight(const FlightMotionOptions& options, double duration_s, uint64_t seed) {
  options.Check();
  SHUTTERLAB_CHECK(std::isfinite(duration_s) && duration_s >= 0)
      << "flight duration must be >= 0 s";
  Motion m;
  m.profile_ = MotionProfile::kFlight;
  m.flight_ = options;
  m.natural_duration_s_ = duration_s;
  NoiseSource rng(seed, kFlightStream);
  // Activity level exp(0.5 * s(t)), s a sum of three slow sinusoids of unit RMS: calm and busy
  // stretches of tens of seconds, the level ranging about 0.4..2.5.
  for (int j = 0; j < 3; ++j) {
    m.envelope_.push_back(
        {0.5 * std::sqrt(2.0 / 3.0), LogUniform(rng, 0.015, 0.1), kTwoPi * rng.Uniform()});
  }
  // Wobble: six sinusoids per axis, random weights normalised to the requested RMS.
  for (int axis = 0; axis < 3; ++axis) {
    const double rms_rad_s = options.wobble_rms_dps * kRadPerDeg * (axis == 2 ? 0.6 : 1.0);
    std::vector<Sinusoid>& w = m.wobble_[axis];
    double sum_sq = 0.0;
    for (int j = 0; j < 6; ++j) {
      const double weight = 0.2 + rng.Uniform();
      w.push_back({weight, LogUniform(rng, 0.2, 2.5), kTwoPi * rng.Uniform()});
      sum_sq += 0.5 * weight * weight;
    }
    for (Sinusoid& s : w) s.amplitude *= sum_sq > 0 ? rms_rad_s / std::sqrt(sum_sq) : 0.0;
  }
  // Gusts: a Poisson process over the flight (after the lead).
  const double flight_s = std::max(0.0, duration_s - options.lead_still_s);
  if (options.gusts_per_s > 0) {
    double t_s = 0.0;
    while (true) {
      t_s += -std::log(1.0 - rng.Uniform()) / options.gusts_per_s;
      if (t_s >= flight_s) break;
      Eigen::Vector3d dir(rng.Normal(), rng.Normal(), 0.5 * rng.Normal());
      dir.normalize();
      const double peak_rad_s =
          LogUniform(rng, options.gust_min_dps, options.gust_max_dps) * kRadPerDeg;
      const double width_s = LogUniform(rng, kGustMinWidthS, kGustMaxWidthS);
      m.gusts_.push_back({t_s, width_s, peak_rad_s * dir});
    }
  }
  // Vibration: per-axis amplitude (0.5..1 of the nominal) and phase of each harmonic, split into
  // sin / cos weights so that evaluation needs one sin/cos of the rotor phase.
  m.motor_sweep_freq_hz_ = LogUniform(rng, 0.03, 0.08);
  m.motor_sweep_phase_rad_ = kTwoPi * rng.Uniform();
  m.throttle_freq_hz_ = LogUniform(rng, 0.05, 0.12);
  m.throttle_phase_rad_ = kTwoPi * rng.Uniform();
  m.burst_freq_hz_ = LogUniform(rng, 0.08, 0.2);
  m.burst_phase_rad_ = kTwoPi * rng.Uniform();
  const auto weights = [&rng](double amplitude_rad_s, Eigen::Vector3d* sin_w,
                              Eigen::Vector3d* cos_w) {
    for (int axis = 0; axis < 3; ++axis) {
      const double a = amplitude_rad_s * (0.5 + 0.5 * rng.Uniform());
      const double phase = kTwoPi * rng.Uniform();
      (*sin_w)[axis] = a * std::cos(phase);
      (*cos_w)[axis] = a * std::sin(phase);
    }
  };
  weights(options.vibration_dps * kRadPerDeg, &m.harmonic1_[0], &m.harmonic1_[1]);
  weights(0.4 * options.vibration_dps * kRadPerDeg, &m.harmonic2_[0], &m.harmonic2_[1]);
  weights(options.resonance_dps * kRadPerDeg, &m.resonance_[0], &m.resonance_[1]);
  return m;
}

Eigen::Vector3d Motion::OmegaRadS(double t_s) const {
  switch (profile_) {
    case MotionProfile::kStill:
      return Eigen::Vector3d::Zero();
    case MotionProfile::kSteps: {
      // Turns are sorted by start: find the last one starting at or before t_s.
      auto it = std::upper_bound(turns_.begin(), turns_.end(), t_s,
                                 [](double t, const StepTurn& turn) { return t < turn.start_s; });
      if (it == turns_.begin()) return Eigen::Vector3d::Zero();
      const StepTurn& turn = *(it - 1);
      const double tau_s = t_s - turn.start_s;
      if (tau_s > turn.duration_s) return Eigen::Vector3d::Zero();
      const double rate =
          turn.angle_rad / turn.duration_s * (1.0 - std::cos(kTwoPi * tau_s / turn.duration_s));
      return rate * turn.axis;
    }
    case MotionProfile::kFlight:
      return FlightOmegaRadS(t_s);
  }
  return Eigen::Vector3d::Zero();
}

Eigen::Vector3d Motion::FlightOmegaRadS(double t_s) const {
  const double u = t_s - flight_.lead_still_s;  // time since the motors started
  if (u <= 0.0) return Eigen::Vector3d::Zero();
  const double ramp = flight_.spin_up_s > 0 ? SmoothStep(u / flight_.spin_up_s) : 1.0;

  double level = 0.0;
  for (const Sinusoid& s : envelope_)
    level += s.amplitude * std::sin(kTwoPi * s.freq_hz * u + s.phase_rad);
  const double activity = std::exp(level);
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  for (int axis = 0; axis < 3; ++axis) {
    for (const Sinusoid& s : wobble_[axis]) {
      omega[axis] += s.amplitude * std::sin(kTwoPi * s.freq_hz * u + s.phase_rad);
    }
  }
  omega *= activity;

  // Gusts whose centre lies within reach of u.
  const double reach_s = kGustReachWidths * kGustMaxWidthS;
  auto it = std::lower_bound(gusts_.begin(), gusts_.end(), u - reach_s,
                             [](const Gust& g, double t) { return g.center_s < t; });
  for (; it != gusts_.end() && it->center_s <= u + reach_s; ++it) {
    const double z = (u - it->center_s) / it->width_s;
    if (std::abs(z) < kGustReachWidths) omega += std::exp(-0.5 * z * z) * it->peak_rad_s;
  }

  // Rotor phase: integral of 2 pi (f0 + df sin(2 pi fs u + p)) du, in closed form.
  const double sweep = kTwoPi * motor_sweep_freq_hz_;
  const double rotor_phase =
      kTwoPi * flight_.motor_hz * u -
      (sweep > 0
           ? kTwoPi * flight_.motor_sweep_hz / sweep *
                 (std::cos(sweep * u + motor_sweep_phase_rad_) - std::cos(motor_sweep_phase_rad_))
           : 0.0);
  const double throttle =
      1.0 + 0.5 * std::sin(kTwoPi * throttle_freq_hz_ * u + throttle_phase_rad_);
  const double s1 = std::sin(rotor_phase), c1 = std::cos(rotor_phase);
  const double s2 = 2.0 * s1 * c1, c2 = c1 * c1 - s1 * s1;
  omega += throttle *
           (s1 * harmonic1_[0] + c1 * harmonic1_[1] + s2 * harmonic2_[0] + c2 * harmonic2_[1]);
  const double b = 0.5 + 0.5 * std::sin(kTwoPi * burst_freq_hz_ * u + burst_phase_rad_);
  const double resonance_phase = kTwoPi * flight_.resonance_hz * u;
  omega += b * b *
           (std::sin(resonance_phase) * resonance_[0] + std::cos(resonance_phase) * resonance_[1]);
  return ramp * omega;
}

Eigen::Quaterniond Motion::WorldFromBody(double t_s) const {
  SHUTTERLAB_CHECK(profile_ != MotionProfile::kFlight)
      << "the flight motion has no closed-form orientation; integrate the truth trace";
  // All turns share one body-fixed axis, so the rotations commute and R(t) = Exp(axis * angle(t)).
  double angle_rad = 0.0;
  for (const StepTurn& turn : turns_) {
    const double tau_s = t_s - turn.start_s;
    if (tau_s <= 0.0) break;
    if (tau_s >= turn.duration_s) {
      angle_rad += turn.angle_rad;
    } else {
      const double x = tau_s / turn.duration_s;  // integral of the Hann pulse up to tau
      angle_rad += turn.angle_rad * (x - std::sin(kTwoPi * x) / kTwoPi);
    }
  }
  if (turns_.empty()) return Eigen::Quaterniond::Identity();
  return ExpSO3(angle_rad * turns_.front().axis);
}

}  // namespace shutterlab
