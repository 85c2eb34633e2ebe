#pragma once
// A gyro error model (MEMS rate gyro read by a logger) and the seeded noise source it draws from.
//
// measured = Q(Sat(T * true + b_const + b_gm(t) + b_rrw(t) + n_white)), with
//   T = diag(1 + scale_error) + misalignment_rad   (sensor_from_body, small terms)
//   b_gm   first-order Gauss-Markov bias (bias instability), b_rrw a random walk (rate random
//   walk), n_white white rate noise (angle random walk), Sat/Q the sensor's int16 output register.
// Conventions follow the Kalibr/basalt IMU noise model: a continuous density sigma_c (per sqrt(Hz))
// becomes a per-sample std sigma_c * sqrt(rate_hz) (white) or sigma_c * sqrt(dt) per step (walk).

#include <Eigen/Core>

#include <cstdint>
#include <random>

namespace shutterlab {

// Standard normal and uniform draws from a seeded std::mt19937_64. The transforms are written out
// here (Box-Muller on 53-bit uniforms) rather than taken from std::normal_distribution, whose
// algorithm differs between standard libraries: a seed gives the same trace on every platform.
class NoiseSource {
 public:
  // Stream s of seed: independent generators for the motion, each sensor, and the timing.
  NoiseSource(uint64_t seed, uint64_t stream);
  double Uniform();  // in [0, 1)
  double Normal();   // mean 0, std 1
  Eigen::Vector3d Normal3() { return {Normal(), Normal(), Normal()}; }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// Every field has its unit in the name or comment. Default-constructed, the model resembles an
// InvenSense MPU-9250 at +-250 deg/s as logged by the source paper's Raspberry Pi logger at 2-4
// kHz; the white-noise density is calibrated so that a still trace at 3000 Hz gives the paper's
// Table 1 (120-sample windows of the integrated angle: mean sigma ~1.1", mean range ~4.3").
struct ImuErrorModel {
  // White rate noise (angle random walk), rad/s/sqrt(Hz). Per-sample std = density * sqrt(rate_hz);
  // the integrated angle over T seconds then has std density * sqrt(T) rad.
  double noise_density_rad_s_sqrt_hz = 7.0e-5;  // 0.0040 deg/s/sqrt(Hz)
  // Bias instability as a first-order Gauss-Markov process per axis: stationary std (rad/s) and
  // correlation time (s). Its Allan deviation peaks at about 0.62 * std near tau = 1.9 * time.
  double bias_instability_rad_s = 5e-5;  // ~10 deg/h
  double bias_correlation_s = 100.0;
  // Rate random walk, rad/s^2/sqrt(Hz) (= rad/s per sqrt(s)): the bias wanders by this * sqrt(T).
  double rate_random_walk_rad_s2_sqrt_hz = 2e-5;
  // Constant bias (zero-rate offset) per sensor axis, rad/s.
  Eigen::Vector3d bias_rad_s{0.0105, -0.0070, 0.0044};  // ~0.6, -0.4, 0.25 deg/s
  // Scale-factor error per axis, dimensionless: measured_i = (1 + scale_error_i) * true_i.
  // (docs/FORMATS.md gyro_scale s_i, "true = s_i * logged", is 1 / (1 + scale_error_i).)
  Eigen::Vector3d scale_error{0.004, -0.003, 0.002};
  // Axis misalignment / cross-axis sensitivity, rad: entry (i, j), i != j, is the sensitivity of
  // sensor axis i to a rate about body axis j. The diagonal must be zero (scale goes above).
  Eigen::Matrix3d misalignment_rad = (Eigen::Matrix3d() << 0.0, 1.0e-3, -0.5e-3,  //
                                      -0.8e-3, 0.0, 0.7e-3,                       //
                                      0.4e-3, -0.6e-3, 0.0)
                                         .finished();
  // Full-scale range, deg/s: 250, 500, 1000 or 2000 (131, 65.5, 32.8, 16.4 LSB per deg/s).
  int range_dps = 250;
  // Round each rate to the nearest count (LSB) of the range: the logged value is count / LSB.
  bool quantize = true;
  // Clip to the int16 register, [-32768, 32767] counts (about +-range_dps).
  bool saturate = true;
  // Logger timing. The sensor samples on its own regular clock; the logged timestamp differs from
  // the sampling instant by a zero-mean Gaussian of this std, s (clipped to just under half a
  // period so that timestamps stay ordered).
  double timestamp_jitter_s = 0.0;
  // Periodic logging gaps: every gap_period_s after the first sample the logger stops for
  // gap_duration_s while it writes its buffer; samples whose instant falls in
  // [t0 + m * gap_period_s, t0 + m * gap_period_s + gap_duration_s), m >= 1, are lost.
  // gap_period_s = 0 disables gaps.
  double gap_period_s = 0.0;
  double gap_duration_s = 0.0;

  // A perfect sensor: no noise, bias, scale, misalignment, quantisation, saturation, jitter or
  // gaps.
  static ImuErrorModel Ideal();

  // sensor_from_body = diag(1 + scale_error) + misalignment_rad.
  Eigen::Matrix3d SensorFromBody() const;
  // Sensitivity of the range, LSB per deg/s.
  double LsbPerDps() const;

  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Applies an ImuErrorModel to true rates sampled at a fixed rate, one sample after the other.
// Holds the drifting bias states; draws only from its own NoiseSource, so two simulators with
// different streams give independent noise on the same motion (the paper's two-gyro idea).
class ImuSimulator {
 public:
  // rate_hz: sampling rate the noise densities are discretised with. The Gauss-Markov bias starts
  // from its stationary distribution, the rate random walk from zero.
  ImuSimulator(const ImuErrorModel& model, double rate_hz, NoiseSource noise);

  // The logged rate (rad/s, sensor axes) for the true body rate (rad/s) at the next sample.
  Eigen::Vector3d Measure(const Eigen::Vector3d& true_omega_rad_s);

  // Number of rate values clipped by saturation so far.
  size_t saturated_values() const { return saturated_; }

 private:
  ImuErrorModel model_;
  Eigen::Matrix3d sensor_from_body_;
  NoiseSource noise_;
  double white_std_rad_s_;
  double gm_phi_;          // exp(-dt / tau)
  double gm_drive_rad_s_;  // std of the Gauss-Markov innovation per step
  double rrw_step_rad_s_;  // std of the random-walk step per sample
  double lsb_per_dps_;
  double rad_s_per_count_;
  Eigen::Vector3d gm_bias_rad_s_;
  Eigen::Vector3d rrw_bias_rad_s_ = Eigen::Vector3d::Zero();
  size_t saturated_ = 0;
};

}  // namespace shutterlab
