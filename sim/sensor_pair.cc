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

// Per-axis variance about the mean of the vectors added, from their sum and sum of squares.
struct VarianceSum {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum_sq = Eigen::Vector3d::Zero();
  size_t n = 0;
  void Add(const Eigen::Vector3d& v) {
    sum += v;
    sum_sq += v.cwiseProduct(v);
    ++n;
  }
  Eigen::Vector3d Variance() const {
    const double count = static_cast<double>(n);
    return (sum_sq / count - (sum / count).cwiseProduct(sum / count)).cwiseMax(0.0);
  }
};

// Per-axis variance about the mean of v[k] over k in [begin, end).
Eigen::Vector3d Variance(const std::vector<Eigen::Vector3d>& v, size_t begin, size_t end) {
  VarianceSum sum;
  for (size_t k = begin; k < end; ++k) sum.Add(v[k]);
  return sum.Variance();
}

// Inverse-variance weights of a per axis from both sensors' variances over the still segment.
Eigen::Vector3d WeightsOfA(const Eigen::Vector3d& var_a, const Eigen::Vector3d& var_b) {
  Eigen::Vector3d weight_a;
  for (int axis = 0; axis < 3; ++axis) {
    const double total = var_a[axis] + var_b[axis];
    weight_a[axis] = total > 0 ? var_b[axis] / total : 0.5;
  }
  return weight_a;
}

// The fit's signal-to-residual measure: the second-largest variance of a's rates (cov_a / n) over
// the per-axis residual variance.
double MountingSignalRatio(const Eigen::Matrix3d& cov_a, double n, double residual_var) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov_a / n);  // ascending
  return residual_var > 0 ? eigen.eigenvalues()[1] / residual_var : 0.0;
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
  const Eigen::Matrix3d r = KabschRotation(h);
  double residual = 0;
  for (size_t k = 0; k < pairs.a.size(); ++k) {
    residual += ((pairs.a[k] - mean_a) - r * (pairs.b[k] - mean_b)).squaredNorm();
  }
  *residual_var = residual / (3 * n);
  *ratio = MountingSignalRatio(cov_a, n, *residual_var);
  return r;
}

}  // namespace

Eigen::Matrix3d KabschRotation(const Eigen::Matrix3d& h) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixV() * d * svd.matrixU().transpose();
}

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
      result.weight_a = WeightsOfA(Variance(pairs.a, begin, end), Variance(pairs.b, begin, end));
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

namespace {

// b's samples walked alongside a's times as PairSamples walks them: for each time, b's nearest
// sample, when within half of b's median interval.
class PartnerFinder {
 public:
  PartnerFinder(std::unique_ptr<GyroSource> b, int64_t b_median_interval_ns)
      : b_(std::move(b)), half_ns_(std::max<int64_t>(b_median_interval_ns / 2, 1)) {
    SHUTTERLAB_CHECK(HasNext()) << "both sensors need samples";
    current_ = buffer_[next_++];
  }
  // b's rate nearest to t_ns (the times asked in a's order), or null.
  const Eigen::Vector3d* Find(int64_t t_ns) {
    while (HasNext() &&
           std::llabs(buffer_[next_].t_ns - t_ns) <= std::llabs(current_.t_ns - t_ns)) {
      current_ = buffer_[next_++];
    }
    return std::llabs(current_.t_ns - t_ns) <= half_ns_ ? &current_.omega_rad_s : nullptr;
  }

 private:
  bool HasNext() {
    if (next_ < buffer_.size()) return true;
    if (done_) return false;
    next_ = 0;
    done_ = !b_->NextInto(&buffer_);
    return !done_;
  }
  std::unique_ptr<GyroSource> b_;
  int64_t half_ns_;
  std::vector<GyroSample> buffer_;
  size_t next_ = 0;
  bool done_ = false;
  GyroSample current_;
};

// One pass over the pairs, in a's order: visit(a's sample, b's partner rate). Returns the number
// of a's samples without a partner and *a_begin_ns, a's first time; throws when either trace is
// empty.
template <typename Visit>
size_t ForEachPair(const OpenGyroSource& open_a, const OpenGyroSource& open_b,
                   int64_t b_median_interval_ns, const Visit& visit,
                   int64_t* a_begin_ns = nullptr) {
  std::unique_ptr<GyroSource> a = open_a();
  std::vector<GyroSample> chunk;
  SHUTTERLAB_CHECK(a->NextInto(&chunk)) << "both sensors need samples";
  if (a_begin_ns) *a_begin_ns = chunk.front().t_ns;
  PartnerFinder b(open_b(), b_median_interval_ns);
  size_t unpaired = 0;
  do {
    for (const GyroSample& s : chunk) {
      if (const Eigen::Vector3d* partner = b.Find(s.t_ns)) {
        visit(s, *partner);
      } else {
        ++unpaired;
      }
    }
  } while (a->NextInto(&chunk));
  return unpaired;
}

// What the last pass sums for one choice of the mounting: the difference a - a_from_b b over all
// pairs, and both sensors over the still segment's pairs.
struct FusionSums {
  explicit FusionSums(const Eigen::Matrix3d& mounting) : a_from_b(mounting) {}
  Eigen::Matrix3d a_from_b;
  VarianceSum diff, still_a, still_b;
  void Add(const Eigen::Vector3d& a, const Eigen::Vector3d& b, bool still) {
    const Eigen::Vector3d b_in_a = a_from_b * b;
    diff.Add(a - b_in_a);
    if (still) {
      still_a.Add(a);
      still_b.Add(b_in_a);
    }
  }
};

// A fused chunk from each of a's chunks (FusedPairSource).
class FusedSource : public GyroSource {
 public:
  FusedSource(std::unique_ptr<GyroSource> a, std::unique_ptr<GyroSource> b, const SensorPair& pair,
              int64_t b_median_interval_ns)
      : a_(std::move(a)),
        b_(std::move(b), b_median_interval_ns),
        a_from_b_(pair.a_from_b),
        weight_a_(pair.weight_a) {}
  GyroChunk Next() override {
    fused_.clear();
    while (fused_.empty() && a_->NextInto(&chunk_)) {
      for (const GyroSample& s : chunk_) {
        const Eigen::Vector3d* partner = b_.Find(s.t_ns);
        if (!partner) continue;
        const Eigen::Vector3d b_in_a = a_from_b_ * *partner;
        fused_.push_back({s.t_ns, weight_a_.cwiseProduct(s.omega_rad_s) +
                                      (Eigen::Vector3d::Ones() - weight_a_).cwiseProduct(b_in_a)});
      }
    }
    return {fused_.data(), fused_.size()};
  }
  double Fraction() const override { return a_->Fraction(); }

 private:
  std::unique_ptr<GyroSource> a_;
  PartnerFinder b_;
  Eigen::Matrix3d a_from_b_;
  Eigen::Vector3d weight_a_;
  std::vector<GyroSample> chunk_, fused_;
};

}  // namespace

SensorPair FitSensorPair(const OpenGyroSource& open_a, const OpenGyroSource& open_b,
                         int64_t b_median_interval_ns, const SensorPairOptions& options) {
  options.Check();
  SensorPair result;
  // 1: the means, and the pairs in the still segment (by index, as FuseSensorPair counts them).
  Eigen::Vector3d sum_a = Eigen::Vector3d::Zero(), sum_b = Eigen::Vector3d::Zero();
  int64_t a_begin_ns = 0;
  size_t still_begin = 0, still_end = 0;
  const auto sum = [&](const GyroSample& a, const Eigen::Vector3d& b) {
    sum_a += a.omega_rad_s;
    sum_b += b;
    ++result.paired;
    if (!options.still) return;
    const double t_s = (a.t_ns - a_begin_ns) * 1e-9;
    if (t_s < options.still->begin_s) still_begin = result.paired;
    if (t_s < options.still->end_s) still_end = result.paired;
  };
  result.unpaired = ForEachPair(open_a, open_b, b_median_interval_ns, sum, &a_begin_ns);
  SHUTTERLAB_CHECK(result.paired >= 10)
      << "the two sensors share only " << result.paired
      << " sample times: are they on one clock? (a pair is within half of the second's interval)";
  const double n = static_cast<double>(result.paired);
  const Eigen::Vector3d mean_a = sum_a / n, mean_b = sum_b / n;
  // 2: the cross-covariance, and the mounting it fits.
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero(), cov_a = Eigen::Matrix3d::Zero();
  ForEachPair(open_a, open_b, b_median_interval_ns,
              [&](const GyroSample& a, const Eigen::Vector3d& b) {
                const Eigen::Vector3d da = a.omega_rad_s - mean_a, db = b - mean_b;
                h += db * da.transpose();
                cov_a += da * da.transpose();
              });
  const Eigen::Matrix3d fitted = KabschRotation(h);
  // 3: the fit's residual, and the variances under either mounting (the residual decides which).
  double residual = 0;
  FusionSums with_fitted(fitted), with_prior(options.a_from_b_prior);
  size_t k = 0;
  ForEachPair(open_a, open_b, b_median_interval_ns,
              [&](const GyroSample& a, const Eigen::Vector3d& b) {
                residual += ((a.omega_rad_s - mean_a) - fitted * (b - mean_b)).squaredNorm();
                const bool still = k >= still_begin && k < still_end;
                ++k;
                with_fitted.Add(a.omega_rad_s, b, still);
                with_prior.Add(a.omega_rad_s, b, still);
              });
  result.mounting_signal_ratio = MountingSignalRatio(cov_a, n, residual / (3 * n));
  result.mounting_fitted = result.mounting_signal_ratio > kMountingSignalRatio;
  const FusionSums& sums = result.mounting_fitted ? with_fitted : with_prior;
  result.a_from_b = sums.a_from_b;
  result.mounting_angle_deg = Eigen::AngleAxisd(result.a_from_b).angle() * 180.0 / kPi;
  result.residual_rms_rad_s = std::sqrt(sums.diff.Variance().mean());
  if (options.still && still_end > still_begin + 100) {
    result.weight_a = WeightsOfA(sums.still_a.Variance(), sums.still_b.Variance());
    result.weights_from_still = true;
  }
  return result;
}

std::unique_ptr<GyroSource> FusedPairSource(std::unique_ptr<GyroSource> a,
                                            std::unique_ptr<GyroSource> b, const SensorPair& pair,
                                            int64_t b_median_interval_ns) {
  return std::make_unique<FusedSource>(std::move(a), std::move(b), pair, b_median_interval_ns);
}

std::string SensorPairText(const SensorPair& pair, const std::string& a_name,
                           const std::string& b_name) {
  std::string text = "sensor pair: " + a_name + " + " + b_name + ": " +
                     std::to_string(pair.paired) + " samples paired (" +
                     std::to_string(pair.unpaired) + " of the first without a partner)\n";
  if (pair.clock_offset_s) {
    text += "  clock: the second's = the first's " + FormatNumber("%+.6f", *pair.clock_offset_s) +
            " s (+- " + FormatNumber("%.3f", pair.clock_offset_stderr_s * 1e3) +
            " ms), from the motion\n";
  }
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
