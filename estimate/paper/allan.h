#pragma once
// Allan deviation of gyro rates (overlapping estimator) and the noise coefficients read off it.
//
// Reference: IEEE Std 952-1997 (Annex C, Allan variance of fibre-optic gyros) and
// El-Sheimy, Hou, Niu, "Analysis and modeling of inertial sensors using Allan variance",
// IEEE Trans. Instrum. Meas. 57(1), 2008: angle random walk N is the value of the -1/2 slope line
// at tau = 1 s; bias instability B is the flat minimum of the curve divided by sqrt(2 ln2 / pi)
// = 0.664.

#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab {

// Cluster sizes m (in samples) for a record of n_rates rate samples: log-spaced with
// points_per_decade per decade, from 1 up to floor(n_rates * max_fraction) (tau from one sample
// period to a tenth of the record by default), without repeats. Empty when n_rates * max_fraction
// < 1.
std::vector<size_t> AllanClusterSizes(size_t n_rates, int points_per_decade = 10,
                                      double max_fraction = 0.1);

// Overlapping Allan deviation in the angle (phase) form, rad/s, one value per cluster size m:
//   sigma^2(tau) = sum_{k=0}^{L-2m-1} (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2 / (2 tau^2 (L -
//   2m)), tau = m * tau0_s,
// where theta (L entries, rad) is the integrated rate: theta_k = sum_{i<k} rate_i * tau0, so L rate
// samples' angle has L+1 entries. O(L) per m. Requires L >= 2m + 1 for every m.
std::vector<double> OverlappingAllanDeviation(const std::vector<double>& angle_rad, double tau0_s,
                                              const std::vector<size_t>& cluster_sizes);

// Brute-force twin from the rates, O(n * m) per m: the textbook definition with cluster means
// ybar_k = mean(rate_k .. rate_{k+m-1}), sigma^2 = mean over k of (ybar_{k+m} - ybar_k)^2 / 2.
std::vector<double> OverlappingAllanDeviationBruteForce(const std::vector<double>& rate_rad_s,
                                                        const std::vector<size_t>& cluster_sizes);

// Noise coefficients of one axis read off its Allan curve.
struct AllanCoefficients {
  // Angle random walk N: the -1/2 slope line's value at tau = 1 s. rad/s/sqrt(Hz) = rad/sqrt(s).
  double arw_rad_s_sqrt_hz = 0.0;
  double arw_deg_sqrt_h = 0.0;  // the same in deg/sqrt(h): N * 180/pi * 60
  // Bias instability B = (minimum of the curve) / 0.664, in deg/h, and the tau of that minimum.
  double bias_instability_deg_h = 0.0;
  double bias_instability_tau_s = 0.0;
  // True when the minimum is not a floor: it is the longest tau, or (record length known) it lies
  // within 3 standard errors of the white-noise line N / sqrt(tau). The record is then too short to
  // see the flat part and B is only an upper bound.
  bool bias_instability_upper_bound = false;
};

// Reads N and B off a curve (tau_s ascending, adev_rad_s > 0 where defined). N: the -1/2 line
// fitted (in log space, weighted by the number of clusters ~ 1/m) through the first run of points
// whose local log-log slope is within 0.15 of -1/2; when no point qualifies, the point whose slope
// is nearest -1/2. record_s: the record's length, for the standard error of each point (white
// noise: relative error 1/sqrt(3 record/tau), from the overlapping estimator's ~1.5 record/tau
// degrees of freedom); 0 when unknown.
AllanCoefficients ReadAllanCoefficients(const std::vector<double>& tau_s,
                                        const std::vector<double>& adev_rad_s,
                                        double record_s = 0.0);

// Per-axis Allan curves of a trace segment, with their coefficients.
struct AllanResult {
  double tau0_s = 0.0;                // the sample period used: the trace's median interval
  std::vector<double> tau_s;          // ascending
  std::vector<double> adev_rad_s[3];  // x, y, z (gyro axes), rad/s
  AllanCoefficients axes[3];
  // Why there is no result though the segment is long enough (empty when there is one, or when
  // it is too short): the estimator needs a positive sample period.
  std::string not_computed;
  bool empty() const { return tau_s.empty(); }
};

// Allan deviation of the rates of samples [first, size) of the trace. Timestamps are taken as
// uniform at the median interval tau0 (the estimator needs it); each sample's contribution to the
// angle uses its own interval, so jitter and logging gaps enter as they do in the per-axis angles.
// A constant bias does not change the result. Returns an empty result when the segment holds
// fewer than 20 rates (no tau with at least a few clusters), and an empty one with not_computed
// said when the median interval is 0 (most samples share the time of the one before).
AllanResult AllanAnalysis(const GyroTrace& trace, size_t first = 0, int points_per_decade = 10);

// AllanAnalysis on a segment that arrives a sample at a time (a log too long to hold), in memory
// bounded whatever its length. What AllanAnalysis reads off the whole segment first must be given:
// its sample count, median interval, and the mean rate it removes (of the samples after the
// first). The taus are AllanAnalysis's. Cluster sizes up to kAllanExactClusterMax samples are
// OverlappingAllanDeviation's sums, the same terms in the same order (equal to the bit for equal
// inputs); a longer cluster m averages every s-th term, s = ceil(m / kAllanSparseTerms), and so
// differs from the overlapping estimate by a small part of the estimate's own scatter.
inline constexpr size_t kAllanExactClusterMax = 1024;
inline constexpr size_t kAllanSparseTerms = 256;
class AllanStream {
 public:
  AllanStream(size_t samples, int64_t median_interval_ns, const Eigen::Vector3d& mean_rad_s,
              int points_per_decade = 10);
  // The segment's next sample (time order).
  void Add(const GyroSample& sample);
  // After the segment's last sample (throws std::invalid_argument when fewer or more came than
  // announced).
  AllanResult Finish() const;

 private:
  // A cluster size longer than kAllanExactClusterMax: the angle at the indices its terms need.
  struct Sparse {
    size_t m = 0, stride = 0, phase = 0;                  // phase: the current index modulo stride
    size_t mid_phase = 0, end_phase = 0;                  // m and 2m modulo stride
    std::vector<std::array<double, 3>> at_start, at_mid;  // rings: indices = 0 and = m (mod s)
    std::array<double, 3> sum{};
    size_t terms = 0;
  };
  size_t samples_;
  double tau0_s_;
  Eigen::Vector3d mean_rad_s_;
  std::vector<size_t> sizes_;
  bool no_sample_period_ = false;  // the median interval was 0: no result, and Finish says so
  size_t dense_ = 0;               // sizes_[0, dense_) are exact
  std::vector<std::array<double, 3>> dense_sums_;
  std::vector<std::array<double, 3>> ring_;  // the last 2 m + 1 angles of the longest exact m
  std::vector<Sparse> sparse_;
  size_t added_ = 0;
  int64_t previous_t_ns_ = 0;
  std::array<double, 3> angle_{};
};

// CSV for --allan: header "tau_s,adev_x,adev_y,adev_z", one line per tau, rad/s.
std::string AllanCsv(const AllanResult& result);

}  // namespace shutterlab
