#include "estimate/paper/allan.h"

#include "sim/check.h"
#include "sim/integrate.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {
namespace {

// Why a segment long enough has no Allan deviation.
constexpr const char* kNoSamplePeriod =
    "the median sample interval is 0 (most samples share the time of the one before: see "
    "duplicate_time), and the Allan deviation needs a positive sample period";

// sigma(tau) of bias instability (flicker rate noise) flattens at sqrt(2 ln2 / pi) B (IEEE 952,
// C.4).
constexpr double kFlickerFloorFactor = 0.664;
// A point belongs to the white-noise (-1/2) region when its local slope is this close to -1/2.
constexpr double kWhiteSlopeTolerance = 0.15;
// A minimum within this many standard errors of the white-noise line is not a floor.
constexpr double kFloorSigmas = 3.0;

}  // namespace

std::vector<size_t> AllanClusterSizes(size_t n_rates, int points_per_decade, double max_fraction) {
  SHUTTERLAB_CHECK(points_per_decade >= 1) << "Allan: points per decade must be at least 1";
  SHUTTERLAB_CHECK(max_fraction > 0.0 && max_fraction <= 0.5)
      << "Allan: the longest tau must be a fraction in (0, 0.5] of the record";
  std::vector<size_t> sizes;
  const double m_max = std::floor(static_cast<double>(n_rates) * max_fraction);
  for (int j = 0;; ++j) {
    const double m = std::round(std::pow(10.0, static_cast<double>(j) / points_per_decade));
    if (m > m_max) break;
    const size_t mi = static_cast<size_t>(m);
    if (sizes.empty() || mi > sizes.back()) sizes.push_back(mi);
  }
  return sizes;
}

std::vector<double> OverlappingAllanDeviation(const std::vector<double>& angle_rad, double tau0_s,
                                              const std::vector<size_t>& cluster_sizes) {
  SHUTTERLAB_CHECK(tau0_s > 0.0 && std::isfinite(tau0_s))
      << "Allan: sample period must be positive";
  const size_t length = angle_rad.size();
  std::vector<double> adev;
  adev.reserve(cluster_sizes.size());
  for (const size_t m : cluster_sizes) {
    SHUTTERLAB_CHECK(m >= 1 && length >= 2 * m + 1)
        << "Allan: cluster of " << m << " samples needs at least " << 2 * m + 1 << " angles, have "
        << length;
    const size_t terms = length - 2 * m;
    double sum = 0.0;
    for (size_t k = 0; k < terms; ++k) {
      // Second difference of the angle = m tau0 times the difference of adjacent cluster means.
      const double d = angle_rad[k + 2 * m] - 2.0 * angle_rad[k + m] + angle_rad[k];
      sum += d * d;
    }
    const double tau_s = static_cast<double>(m) * tau0_s;
    adev.push_back(std::sqrt(sum / (2.0 * tau_s * tau_s * static_cast<double>(terms))));
  }
  return adev;
}

std::vector<double> OverlappingAllanDeviationBruteForce(const std::vector<double>& rate_rad_s,
                                                        const std::vector<size_t>& cluster_sizes) {
  const size_t n = rate_rad_s.size();
  std::vector<double> adev;
  for (const size_t m : cluster_sizes) {
    SHUTTERLAB_CHECK(m >= 1 && n >= 2 * m)
        << "Allan: cluster of " << m << " samples needs " << 2 * m << " rates, have " << n;
    auto cluster_mean = [&](size_t k) {
      double s = 0.0;
      for (size_t i = k; i < k + m; ++i) s += rate_rad_s[i];
      return s / static_cast<double>(m);
    };
    double sum = 0.0;
    size_t count = 0;
    for (size_t k = 0; k + 2 * m <= n; ++k, ++count) {
      const double d = cluster_mean(k + m) - cluster_mean(k);
      sum += d * d;
    }
    adev.push_back(std::sqrt(sum / (2.0 * static_cast<double>(count))));
  }
  return adev;
}

AllanCoefficients ReadAllanCoefficients(const std::vector<double>& tau_s,
                                        const std::vector<double>& adev_rad_s, double record_s) {
  SHUTTERLAB_CHECK(tau_s.size() == adev_rad_s.size())
      << "Allan: tau and deviation differ in length";
  AllanCoefficients out;
  // Only strictly positive, finite points have a place on a log-log plot (a noiseless axis gives
  // 0).
  std::vector<double> log_tau, log_adev, tau;
  for (size_t i = 0; i < tau_s.size(); ++i) {
    if (adev_rad_s[i] > 0.0 && std::isfinite(adev_rad_s[i]) && tau_s[i] > 0.0) {
      log_tau.push_back(std::log(tau_s[i]));
      log_adev.push_back(std::log(adev_rad_s[i]));
      tau.push_back(tau_s[i]);
    }
  }
  const size_t n = log_tau.size();
  if (n == 0) return out;

  // Bias instability: the flat minimum.
  const size_t i_min = std::min_element(log_adev.begin(), log_adev.end()) - log_adev.begin();
  out.bias_instability_deg_h =
      std::exp(log_adev[i_min]) / kFlickerFloorFactor * kDegPerRad * 3600.0;
  out.bias_instability_tau_s = tau[i_min];

  // Angle random walk: local slopes by differences over the neighbours.
  if (n == 1) {
    out.arw_rad_s_sqrt_hz = std::exp(log_adev[0] + 0.5 * log_tau[0]);
  } else {
    std::vector<double> slope(n);
    for (size_t i = 0; i < n; ++i) {
      const size_t a = i == 0 ? 0 : i - 1;
      const size_t b = i + 1 == n ? n - 1 : i + 1;
      slope[i] = (log_adev[b] - log_adev[a]) / (log_tau[b] - log_tau[a]);
    }
    size_t begin = n, end = n;
    for (size_t i = 0; i < n; ++i) {
      const bool white = std::abs(slope[i] + 0.5) <= kWhiteSlopeTolerance;
      if (white && begin == n) begin = i;
      if (!white && begin != n) {
        end = i;
        break;
      }
    }
    if (begin == n) {  // no white-noise region: the nearest point to a -1/2 slope
      begin = 0;
      for (size_t i = 1; i < n; ++i) {
        if (std::abs(slope[i] + 0.5) < std::abs(slope[begin] + 0.5)) begin = i;
      }
      end = begin + 1;
    }
    // Weights ~ the number of independent clusters (~ 1/tau): short taus are the precise ones.
    double sum_w = 0.0, sum = 0.0;
    for (size_t i = begin; i < end; ++i) {
      const double w = 1.0 / tau[i];
      sum_w += w;
      sum += w * (log_adev[i] + 0.5 * log_tau[i]);  // log of the -1/2 line's value at tau = 1 s
    }
    out.arw_rad_s_sqrt_hz = std::exp(sum / sum_w);
  }
  out.arw_deg_sqrt_h = out.arw_rad_s_sqrt_hz * kDegPerRad * 60.0;  // sqrt(3600 s) = 60 sqrt(s)

  out.bias_instability_upper_bound = (i_min + 1 == n);
  if (record_s > 0.0) {
    const double white_line = out.arw_rad_s_sqrt_hz / std::sqrt(tau[i_min]);
    const double relative_error = 1.0 / std::sqrt(3.0 * record_s / tau[i_min]);
    // A floor lies above the white-noise line; a minimum on it (within its scatter) is white noise
    // that has not yet met the floor.
    if (std::abs(std::exp(log_adev[i_min]) / white_line - 1.0) <= kFloorSigmas * relative_error) {
      out.bias_instability_upper_bound = true;
    }
  }
  return out;
}

AllanResult AllanAnalysis(const GyroTrace& trace, size_t first, int points_per_decade) {
  AllanResult result;
  if (first >= trace.size()) return result;
  const size_t n_rates = trace.size() - first - 1;  // the first sample has no interval before it
  const std::vector<size_t> sizes = AllanClusterSizes(n_rates, points_per_decade);
  if (sizes.empty()) return result;
  if (trace.sampling().median_interval_ns <= 0) {
    result.not_computed = kNoSamplePeriod;
    return result;
  }
  result.tau0_s = trace.sampling().median_interval_ns * 1e-9;
  // Remove the segment's mean rate first: the angle stays near zero (no precision lost to drift)
  // and the result does not depend on a constant bias even where logging gaps make the sampling
  // uneven.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t i = first + 1; i < trace.size(); ++i) mean += trace[i].omega_rad_s;
  mean /= static_cast<double>(n_rates);
  const PerAxisAngles angles = IntegratePerAxis(trace, mean, first);
  for (const size_t m : sizes) result.tau_s.push_back(static_cast<double>(m) * result.tau0_s);
  for (int a = 0; a < 3; ++a) {
    result.adev_rad_s[a] = OverlappingAllanDeviation(angles.angle_rad[a], result.tau0_s, sizes);
    result.axes[a] = ReadAllanCoefficients(result.tau_s, result.adev_rad_s[a],
                                           static_cast<double>(n_rates) * result.tau0_s);
  }
  return result;
}

AllanStream::AllanStream(size_t samples, int64_t median_interval_ns,
                         const Eigen::Vector3d& mean_rad_s, int points_per_decade)
    : samples_(samples), tau0_s_(median_interval_ns * 1e-9), mean_rad_s_(mean_rad_s) {
  if (samples_ < 2) return;  // no rate: an empty result, as AllanAnalysis gives
  sizes_ = AllanClusterSizes(samples_ - 1, points_per_decade);
  if (sizes_.empty()) return;
  if (tau0_s_ <= 0.0) {  // Add then does nothing, and Finish says why
    sizes_.clear();
    no_sample_period_ = true;
    return;
  }
  while (dense_ < sizes_.size() && sizes_[dense_] <= kAllanExactClusterMax) ++dense_;
  dense_sums_.assign(dense_, {0.0, 0.0, 0.0});
  if (dense_ > 0) ring_.assign(2 * sizes_[dense_ - 1] + 1, {0.0, 0.0, 0.0});
  for (size_t i = dense_; i < sizes_.size(); ++i) {
    Sparse sparse;
    sparse.m = sizes_[i];
    sparse.stride = (sparse.m + kAllanSparseTerms - 1) / kAllanSparseTerms;
    sparse.mid_phase = sparse.m % sparse.stride;
    sparse.end_phase = (2 * sparse.m) % sparse.stride;
    sparse.at_start.resize(2 * sparse.m / sparse.stride + 2);
    sparse.at_mid.resize(sparse.m / sparse.stride + 2);
    sparse_.push_back(std::move(sparse));
  }
}

void AllanStream::Add(const GyroSample& sample) {
  const size_t j = added_++;
  if (sizes_.empty()) return;
  // IntegratePerAxis with the mean as the bias: angle_j = sum over i <= j of (w_i - mean) dt_i.
  if (j > 0) {
    const double dt_s = (sample.t_ns - previous_t_ns_) * 1e-9;
    for (int a = 0; a < 3; ++a) angle_[a] += (sample.omega_rad_s[a] - mean_rad_s_[a]) * dt_s;
  }
  previous_t_ns_ = sample.t_ns;
  // OverlappingAllanDeviation's term k = j - 2m, for every exact m it is complete for.
  if (dense_ > 0) {
    const size_t size = ring_.size();
    ring_[j % size] = angle_;
    for (size_t i = 0; i < dense_ && 2 * sizes_[i] <= j; ++i) {
      const size_t m = sizes_[i];
      const std::array<double, 3>& mid = ring_[(j - m) % size];
      const std::array<double, 3>& start = ring_[(j - 2 * m) % size];
      for (int a = 0; a < 3; ++a) {
        const double d = angle_[a] - 2.0 * mid[a] + start[a];
        dense_sums_[i][a] += d * d;
      }
    }
  }
  // The longer clusters: the terms whose start index is a multiple of the stride.
  for (Sparse& sparse : sparse_) {
    const size_t s = sparse.stride;
    if (sparse.phase == 0) sparse.at_start[(j / s) % sparse.at_start.size()] = angle_;
    if (sparse.phase == sparse.mid_phase && j >= sparse.m)
      sparse.at_mid[((j - sparse.m) / s) % sparse.at_mid.size()] = angle_;
    if (sparse.phase == sparse.end_phase && j >= 2 * sparse.m) {
      const size_t k = j - 2 * sparse.m;  // a multiple of s
      const std::array<double, 3>& start = sparse.at_start[(k / s) % sparse.at_start.size()];
      const std::array<double, 3>& mid = sparse.at_mid[(k / s) % sparse.at_mid.size()];
      for (int a = 0; a < 3; ++a) {
        const double d = angle_[a] - 2.0 * mid[a] + start[a];
        sparse.sum[a] += d * d;
      }
      ++sparse.terms;
    }
    if (++sparse.phase == s) sparse.phase = 0;
  }
}

AllanResult AllanStream::Finish() const {
  SHUTTERLAB_CHECK(added_ == samples_)
      << "Allan: " << added_ << " samples came of the " << samples_ << " announced";
  AllanResult result;
  if (no_sample_period_) result.not_computed = kNoSamplePeriod;
  if (sizes_.empty()) return result;
  result.tau0_s = tau0_s_;
  for (const size_t m : sizes_) result.tau_s.push_back(static_cast<double>(m) * tau0_s_);
  for (size_t i = 0; i < sizes_.size(); ++i) {
    const double tau_s = result.tau_s[i];
    const bool exact = i < dense_;
    const double terms =
        static_cast<double>(exact ? samples_ - 2 * sizes_[i] : sparse_[i - dense_].terms);
    const std::array<double, 3>& sum = exact ? dense_sums_[i] : sparse_[i - dense_].sum;
    for (int a = 0; a < 3; ++a)
      result.adev_rad_s[a].push_back(std::sqrt(sum[a] / (2.0 * tau_s * tau_s * terms)));
  }
  for (int a = 0; a < 3; ++a) {
    result.axes[a] = ReadAllanCoefficients(result.tau_s, result.adev_rad_s[a],
                                           static_cast<double>(samples_ - 1) * tau0_s_);
  }
  return result;
}

std::string AllanCsv(const AllanResult& result) {
  std::string out = "tau_s,adev_x,adev_y,adev_z\n";
  for (size_t i = 0; i < result.tau_s.size(); ++i) {
    AppendDouble(result.tau_s[i], &out);
    for (int a = 0; a < 3; ++a) {
      out += ',';
      AppendDouble(result.adev_rad_s[a][i], &out);
    }
    out += '\n';
  }
  return out;
}

}  // namespace shutterlab
