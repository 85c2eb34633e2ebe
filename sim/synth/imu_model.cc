#include "sim/synth/imu_model.h"

#include "sim/check.h"
#include "sim/logs/raw_csv.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {
namespace {

// The sensor's output register is int16.
constexpr double kMinCount = -32768.0;
constexpr double kMaxCount = 32767.0;

bool FiniteVector(const Eigen::Vector3d& v) { return v.allFinite(); }

}  // namespace

NoiseSource::NoiseSource(uint64_t seed, uint64_t stream) {
  // seed_seq spreads (seed, stream) over the whole engine state, so nearby seeds and streams
  // give unrelated sequences; its algorithm is fixed by the standard.
  std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32),
                    static_cast<uint32_t>(stream), static_cast<uint32_t>(stream >> 32),
                    0x5eed5eedu};
  engine_.seed(seq);
}

double NoiseSource::Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

double NoiseSource::Normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  // Box-Muller (Box & Muller 1958); 1 - u keeps the logarithm's argument in (0, 1].
  const double u1 = 1.0 - Uniform();
  const double u2 = Uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double phase = 2.0 * kPi * u2;
  spare_ = r * std::sin(phase);
  has_spare_ = true;
  return r * std::cos(phase);
}

ImuErrorModel ImuErrorModel::Ideal() {
  ImuErrorModel m;
  m.noise_density_rad_s_sqrt_hz = 0.0;
  m.bias_instability_rad_s = 0.0;
  m.rate_random_walk_rad_s2_sqrt_hz = 0.0;
  m.bias_rad_s.setZero();
  m.scale_error.setZero();
  m.misalignment_rad.setZero();
  m.quantize = false;
  m.saturate = false;
  m.timestamp_jitter_s = 0.0;
  m.gap_period_s = 0.0;
  m.gap_duration_s = 0.0;
  return m;
}

Eigen::Matrix3d ImuErrorModel::SensorFromBody() const {
  Eigen::Matrix3d t = misalignment_rad;
  for (int i = 0; i < 3; ++i) t(i, i) = 1.0 + scale_error[i];
  return t;
}

double ImuErrorModel::LsbPerDps() const { return RawSensitivityLsbPerDps(range_dps); }

void ImuErrorModel::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(noise_density_rad_s_sqrt_hz) && noise_density_rad_s_sqrt_hz >= 0)
      << "noise density must be >= 0 rad/s/sqrt(Hz), got " << noise_density_rad_s_sqrt_hz;
  SHUTTERLAB_CHECK(std::isfinite(bias_instability_rad_s) && bias_instability_rad_s >= 0)
      << "bias instability must be >= 0 rad/s, got " << bias_instability_rad_s;
  SHUTTERLAB_CHECK(std::isfinite(bias_correlation_s) && bias_correlation_s > 0)
      << "bias correlation time must be > 0 s, got " << bias_correlation_s;
  SHUTTERLAB_CHECK(std::isfinite(rate_random_walk_rad_s2_sqrt_hz) &&
                   rate_random_walk_rad_s2_sqrt_hz >= 0)
      << "rate random walk must be >= 0 rad/s^2/sqrt(Hz), got " << rate_random_walk_rad_s2_sqrt_hz;
  SHUTTERLAB_CHECK(FiniteVector(bias_rad_s)) << "constant bias must be finite";
  SHUTTERLAB_CHECK(FiniteVector(scale_error) && (scale_error.array() > -0.5).all() &&
                   (scale_error.array() < 0.5).all())
      << "scale error must lie in (-0.5, 0.5), got " << scale_error.transpose();
  SHUTTERLAB_CHECK(misalignment_rad.allFinite() && misalignment_rad.diagonal().isZero(0.0) &&
                   misalignment_rad.cwiseAbs().maxCoeff() < 0.2)
      << "misalignment must have a zero diagonal and entries below 0.2 rad";
  SHUTTERLAB_CHECK(range_dps == 250 || range_dps == 500 || range_dps == 1000 || range_dps == 2000)
      << "gyro range must be 250, 500, 1000 or 2000 deg/s, got " << range_dps;
  SHUTTERLAB_CHECK(std::isfinite(timestamp_jitter_s) && timestamp_jitter_s >= 0)
      << "timestamp jitter must be >= 0 s, got " << timestamp_jitter_s;
  SHUTTERLAB_CHECK(std::isfinite(gap_period_s) && gap_period_s >= 0)
      << "gap period must be >= 0 s (0 = no gaps), got " << gap_period_s;
  if (gap_period_s > 0) {
    SHUTTERLAB_CHECK(std::isfinite(gap_duration_s) && gap_duration_s > 0 &&
                     gap_duration_s < gap_period_s)
        << "gap duration must lie in (0, gap period = " << gap_period_s << " s), got "
        << gap_duration_s;
  }
}

ImuSimulator::ImuSimulator(const ImuErrorModel& model, double rate_hz, NoiseSource noise)
    : model_(model), sensor_from_body_(model.SensorFromBody()), noise_(std::move(noise)) {
  model_.Check();
  SHUTTERLAB_CHECK(std::isfinite(rate_hz) && rate_hz > 0) << "rate must be > 0 Hz";
  const double dt_s = 1.0 / rate_hz;
  white_std_rad_s_ = model_.noise_density_rad_s_sqrt_hz * std::sqrt(rate_hz);
  // Exact discretisation of db/dt = -b/tau + w keeps the stationary std at bias_instability.
  gm_phi_ = std::exp(-dt_s / model_.bias_correlation_s);
  gm_drive_rad_s_ = model_.bias_instability_rad_s * std::sqrt(1.0 - gm_phi_ * gm_phi_);
  rrw_step_rad_s_ = model_.rate_random_walk_rad_s2_sqrt_hz * std::sqrt(dt_s);
  lsb_per_dps_ = model_.LsbPerDps();
  // The same expression as ReadRawCsv's, so that raw counts read back bit-exactly.
  rad_s_per_count_ = kRadPerDeg / lsb_per_dps_;
  gm_bias_rad_s_ = model_.bias_instability_rad_s > 0
                       ? Eigen::Vector3d(model_.bias_instability_rad_s * noise_.Normal3())
                       : Eigen::Vector3d::Zero();
}

Eigen::Vector3d ImuSimulator::Measure(const Eigen::Vector3d& true_omega_rad_s) {
  Eigen::Vector3d omega = sensor_from_body_ * true_omega_rad_s + model_.bias_rad_s;
  // Draw every stream only when it is on, so that an ideal model consumes no randomness; the
  // order of draws is fixed (white, Gauss-Markov, random walk) for reproducibility.
  if (white_std_rad_s_ > 0) omega += white_std_rad_s_ * noise_.Normal3();
  if (model_.bias_instability_rad_s > 0) {
    gm_bias_rad_s_ = gm_phi_ * gm_bias_rad_s_ + gm_drive_rad_s_ * noise_.Normal3();
    omega += gm_bias_rad_s_;
  }
  if (rrw_step_rad_s_ > 0) {
    rrw_bias_rad_s_ += rrw_step_rad_s_ * noise_.Normal3();
    omega += rrw_bias_rad_s_;
  }
  for (int a = 0; a < 3; ++a) {
    const double counts = omega[a] / kRadPerDeg * lsb_per_dps_;
    double out_counts = model_.quantize ? std::round(counts) : counts;
    if (model_.saturate && (out_counts < kMinCount || out_counts > kMaxCount)) {
      out_counts = std::clamp(out_counts, kMinCount, kMaxCount);
      ++saturated_;
    }
    // Convert back only when something changed, so that an unclipped, unquantised rate stays
    // bit-exact.
    if (out_counts != counts) omega[a] = out_counts * rad_s_per_count_;
  }
  return omega;
}

}  // namespace shutterlab
