#include "sim/sensor_pair.h"

#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <cmath>
#include <vector>

namespace shutterlab {

void SensorPairOptions::Check() const {
  const Eigen::Matrix3d& r = a_from_b_prior;
  SHUTTERLAB_CHECK((r * r.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
                   std::abs(r.determinant() - 1.0) < 1e-6)
      << "the mounting prior must be a rotation";
  if (still) {
    SHUTTERLAB_CHECK(still->end_s > still->begin_s) << "the still segment is empty";
  }
}

namespace {

struct Pairs {
  std::vector<size_t> a_index;
  std::vector<Eigen::Vector3d> a, b;
};

// Each sample of a with b's nearest sample within half of b's median interval.
Pairs PairSamples(const GyroTrace& a, const GyroTrace& b, size_t* unpaired) {
  Pairs pairs;
  const int64_t half_ns = std::max<int64_t>(b.sampling().median_interval_ns / 2, 1);
  size_t j = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const int64_t t = a[i].t_ns;
    while (j + 1 < b.size() && std::llabs(b[j + 1].t_ns - t) <= std::llabs(b[j].t_ns - t)) ++j;
    if (std::llabs(b[j].t_ns - t) <= half_ns) {
      pairs.a_index.push_back(i);
      pairs.a.push_back(a[i].omega_rad_s);
      pairs.b.push_back(b[j].omega_rad_s);
    } else {
      ++*unpaired;
    }
  }
  return pairs;
}

Eigen::Vector3d Mean(const std::vector<Eigen::Vector3d>& v) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

// Kabsch: the rotation R minimising sum |(a - mean a) - R (b - mean b)|^2; *ratio the fit's
// signal-to-residual measure; *residual_var the per-axis residual variance.
Eigen::Matrix3d FitMounting(const Pairs& pairs, double* ratio, double* residual_var) {
  const Eigen::Vector3d mean_a = Mean(pairs.a), mean_b = Mean(pairs.b);
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero(), cov_a = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < pairs.a.size(); ++k) {
    const Eigen::Vector3d da = pairs.a[k] - mean_a, db = pairs.b[k] - mean_b;
    h += db * da.transpose();
    cov_a += da * da.transpose();
  }
  const double n = static_cast<double>(pairs.a.size());
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d r = svd.matrixV() * d * svd.matrixU().transpose();
  double residual = 0;
  for (size_t k = 0; k < pairs.a.size(); ++k) {
    residual += ((pairs.a[k] - mean_a) - r * (pairs.b[k] - mean_b)).squaredNorm();
  }
  *residual_var = residual / (3 * n);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov_a / n);  // ascending
  *ratio = *residual_var > 0 ? eigen.eigenvalues()[1] / *residual_var : 0.0;
  return r;
}

// Per-axis variance about the mean of v[k] over k in [begin, end).
Eigen::Vector3d Variance(const std::vector<Eigen::Vector3d>& v, size_t begin, size_t end) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum_sq = Eigen::Vector3d::Zero();
  for (size_t k = begin; k < end; ++k) {
    sum += v[k];
    sum_sq += v[k].cwiseProduct(v[k]);
  }
  const double n = static_cast<double>(end - begin);
  return (sum_sq / n - (sum / n).cwiseProduct(sum / n)).cwiseMax(0.0);
}

}  // namespace

SensorPair FuseSensorPair(const GyroTrace& a, const GyroTrace& b,
                          const SensorPairOptions& options) {
  options.Check();
  SHUTTERLAB_CHECK(!a.empty() && !b.empty()) << "both sensors need samples";
  SensorPair result;
  Pairs pairs = PairSamples(a, b, &result.unpaired);
  result.paired = pairs.a.size();
  SHUTTERLAB_CHECK(result.paired >= 10)
      << "the two sensors share only " << result.paired
      << " sample times: are they on one clock? (a pair is within half of the second's interval)";
  double residual_var = 0;
  const Eigen::Matrix3d fitted = FitMounting(pairs, &result.mounting_signal_ratio, &residual_var);
  result.mounting_fitted = result.mounting_signal_ratio > kMountingSignalRatio;
  result.a_from_b = result.mounting_fitted ? fitted : options.a_from_b_prior;
  result.mounting_angle_deg = Eigen::AngleAxisd(result.a_from_b).angle() * 180.0 / kPi;
  for (auto& w : pairs.b) w = result.a_from_b * w;  // b in a's axes from here on
  std::vector<Eigen::Vector3d> diff(pairs.a.size());
  for (size_t k = 0; k < diff.size(); ++k) diff[k] = pairs.a[k] - pairs.b[k];
  result.residual_rms_rad_s = std::sqrt(Variance(diff, 0, diff.size()).mean());
  if (options.still) {
    const int64_t t0 = a.t_begin_ns();
    size_t begin = 0, end = 0;
    for (size_t k = 0; k < pairs.a_index.size(); ++k) {
      const double t_s = (a[pairs.a_index[k]].t_ns - t0) * 1e-9;
      if (t_s < options.still->begin_s) begin = k + 1;
      if (t_s < options.still->end_s) end = k + 1;
    }
    if (end > begin + 100) {
      const Eigen::Vector3d var_a = Variance(pairs.a, begin, end),
                            var_b = Variance(pairs.b, begin, end);
      for (int axis = 0; axis < 3; ++axis) {
        const double total = var_a[axis] + var_b[axis];
        result.weight_a[axis] = total > 0 ? var_b[axis] / total : 0.5;
      }
      result.weights_from_still = true;
    }
  }
  std::vector<GyroSample> fused(pairs.a.size());
  for (size_t k = 0; k < fused.size(); ++k) {
    fused[k].t_ns = a[pairs.a_index[k]].t_ns;
    fused[k].omega_rad_s = result.weight_a.cwiseProduct(pairs.a[k]) +
                           (Eigen::Vector3d::Ones() - result.weight_a).cwiseProduct(pairs.b[k]);
  }
  result.fused = GyroTrace(std::move(fused));
  return result;
}

std::string SensorPairText(const SensorPair& pair, const std::string& a_name,
                           const std::string& b_name) {
  std::string text = "sensor pair: " + a_name + " + " + b_name + ": " +
                     std::to_string(pair.paired) + " samples paired (" +
                     std::to_string(pair.unpaired) + " of the first without a partner)\n";
  text += "  mounting (second into first's axes): ";
  if (pair.mounting_fitted) {
    text += "fitted from the motion, a " + FormatNumber("%.2f", pair.mounting_angle_deg) +
            " deg rotation";
  } else {
    text += "not fitted (the motion is " + FormatNumber("%.1f", pair.mounting_signal_ratio) +
            "x the noise, too little to show it); the given one kept, " +
            FormatNumber("%.2f deg", pair.mounting_angle_deg);
  }
  text += "; [";
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      text += FormatNumber(c == 0 && r == 0 ? "%.4f" : " %.4f", pair.a_from_b(r, c));
    if (r < 2) text += ";";
  }
  text += "]\n";
  text += "  weights of the first per axis " + FormatNumber("%.3f ", pair.weight_a.x()) +
          FormatNumber("%.3f ", pair.weight_a.y()) + FormatNumber("%.3f", pair.weight_a.z()) +
          (pair.weights_from_still ? " (inverse variances over the still segment)"
                                   : " (equal: no still segment)") +
          "; difference rms " + FormatNumber("%.3g deg/s", pair.residual_rms_rad_s * 180.0 / kPi) +
          "\n";
  return text;
}

}  // namespace shutterlab
