#include "estimate/loop/image_orientation.h"

#include "estimate/loop/effect_model.h"
#include "sim/integrate.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <cmath>
#include <limits>
#include <optional>

namespace shutterlab {
namespace {

// One tested pair: the declared gyro's rotation between the frames' middle rows (camera axes),
// the image's (from the consensus), and the two frames' written quaternions.
struct PairRotation {
  Eigen::Matrix3d gyro;  // R_e^T R_l
  Eigen::Vector3d theta_image;
  Eigen::Quaterniond q_earlier, q_later;
};

std::vector<PairRotation> PairRotations(const TrueModel& declared, const GyroTrace& gyro,
                                        const std::vector<FramePoints>& pairs,
                                        const std::vector<FrameConsensus>& consensus,
                                        const std::map<int64_t, Eigen::Quaterniond>& iori) {
  std::vector<GyroSample> rates = gyro.samples();
  for (GyroSample& s : rates) s.omega_rad_s = declared.CamRate(s.omega_rad_s);
  const OrientationTrace orientation{GyroTrace(std::move(rates))};
  const double mid_row = 0.5 * (declared.rig.camera.height - 1);
  std::vector<PairRotation> out;
  for (size_t k = 0; k < pairs.size() && k < consensus.size(); ++k) {
    const FramePoints& pair = pairs[k];
    if (!pair.earlier || !consensus[k].determined) continue;
    const auto e = iori.find(pair.earlier->frame), l = iori.find(pair.frame);
    if (e == iori.end() || l == iori.end()) continue;
    const int64_t t_e = pair.earlier->t_first_row_ns, t_l = pair.t_first_row_ns;
    const double off_e = declared.RowGyroOffsetS(t_e, mid_row);
    const double off_l = declared.RowGyroOffsetS(t_l, mid_row);
    PairRotation r;
    try {
      r.gyro = (orientation.WorldFromBodyAt(t_e, off_e).conjugate() *
                orientation.WorldFromBodyAt(t_l, off_l))
                   .normalized()
                   .toRotationMatrix();
    } catch (const std::out_of_range&) {
      continue;
    }
    const double dt_s = (t_l - t_e) * 1e-9 + off_l - off_e;
    r.theta_image = LogSO3(Eigen::Quaterniond(r.gyro)) + consensus[k].delta_omega_rad_s * dt_s;
    r.q_earlier = e->second;
    r.q_later = l->second;
    out.push_back(r);
  }
  return out;
}

// theta_S of one pair under a reading.
Eigen::Vector3d ModelRotation(const ImageOrientationCheck& reading, const PairRotation& r) {
  const Eigen::Matrix3d s_e = CamFromImage(reading, r.q_earlier);
  const Eigen::Matrix3d s_l = CamFromImage(reading, r.q_later);
  return LogSO3(Eigen::Quaterniond(s_e.transpose() * r.gyro * s_l).normalized());
}

}  // namespace

Eigen::Matrix3d CamFromImage(const ImageOrientationCheck& reading, const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d m = q.normalized().toRotationMatrix();
  return reading.axes * (reading.inverse ? m.transpose() : m) * reading.axes.transpose();
}

ImageOrientationCheck TestImageOrientation(const TrueModel& declared, const GyroTrace& gyro,
                                           const std::vector<FramePoints>& pairs,
                                           const std::vector<FrameConsensus>& consensus,
                                           const std::map<int64_t, Eigen::Quaterniond>& iori) {
  ImageOrientationCheck check;
  check.present = !iori.empty();
  if (!check.present) return check;
  const std::vector<PairRotation> rotations = PairRotations(declared, gyro, pairs, consensus, iori);
  check.pairs_tested = static_cast<int>(rotations.size());
  if (rotations.size() < 3) {
    check.verdict = "not determined: " + std::to_string(rotations.size()) +
                    " pair(s) with the stabiliser's rotation (IORI) and a determined consensus";
    return check;
  }
  double baseline = 0.0;
  for (const PairRotation& r : rotations) {
    baseline += (r.theta_image - LogSO3(Eigen::Quaterniond(r.gyro))).squaredNorm();
  }
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Matrix3d& axes : AxisRotations()) {
    for (bool inverse : {false, true}) {
      ImageOrientationCheck reading;
      reading.axes = axes;
      reading.inverse = inverse;
      double sum = 0.0;
      for (const PairRotation& r : rotations) {
        sum += (r.theta_image - ModelRotation(reading, r)).squaredNorm();
      }
      if (sum < best) {
        best = sum;
        check.axes = axes;
        check.inverse = inverse;
      }
    }
  }
  check.share = baseline > 0 ? std::max(0.0, 1.0 - best / baseline) : 0.0;
  std::vector<double> gains;
  for (const PairRotation& r : rotations) {
    const double model = ModelRotation(check, r).norm();
    if (model > 0) gains.push_back(r.theta_image.norm() / model);
  }
  check.gain = gains.empty() ? 0.0 : Median(gains);
  check.verdict = "not judged: the images have not been screened under the best reading";
  return check;
}

void JudgeImageOrientation(const GyroFollowCheck& raw, const GyroFollowCheck& applied,
                           ImageOrientationCheck* check) {
  check->raw_gain = raw.determined ? raw.gain : std::numeric_limits<double>::quiet_NaN();
  check->applied_gain =
      applied.determined ? applied.gain : std::numeric_limits<double>::quiet_NaN();
  check->applied_pairs = applied.pairs_tested;
  if (applied.determined) {
    // Closer to 1 on a log scale: a gain of 0.5 and one of 2 are as far off.
    const bool closer =
        !raw.determined || std::abs(std::log(applied.gain)) < std::abs(std::log(raw.gain));
    check->holds = applied.follows && closer;
  } else {  // the camera so turned moves too little to test: the rotations' own test
    check->holds = check->share >= kMinImageOrientationShare && check->gain >= kMinGain &&
                   check->gain <= 1.0 / kMinGain;
  }
  const std::string numbers =
      "with the best of its 48 readings (axes and sense) applied, the image turns " +
      (applied.determined
           ? FormatNumber("%.2f", applied.gain) +
                 "x as fast as the gyro turned by it says (median over " +
                 std::to_string(applied.pairs_tested) + " pairs)"
           : FormatNumber("%.2f", check->gain) +
                 "x as the reading's rotation says (too little motion left for the screening's "
                 "test)") +
      (raw.determined ? ", against " + FormatNumber("%.2f", raw.gain) + "x for the gyro alone"
                      : std::string()) +
      "; the reading explains " + FormatNumber("%.0f", 100 * check->share) +
      " % of how the image's rotation departs from the gyro's";
  check->verdict =
      (check->holds ? "the stabiliser's rotation (IORI) holds, and is applied: "
                    : "the stabiliser's rotation (IORI) does not explain the images: ") +
      numbers;
}

std::vector<size_t> ApplyImageOrientation(const ImageOrientationCheck& reading,
                                          const std::map<int64_t, Eigen::Quaterniond>& iori,
                                          std::vector<FramePoints>* pairs) {
  std::vector<FramePoints> kept;
  std::vector<size_t> removed;
  for (size_t k = 0; k < pairs->size(); ++k) {
    FramePoints& pair = (*pairs)[k];
    const auto l = iori.find(pair.frame);
    const auto e = pair.earlier ? iori.find(pair.earlier->frame) : iori.end();
    if (l == iori.end() || e == iori.end()) {
      removed.push_back(k);
      continue;
    }
    pair.cam_from_image = CamFromImage(reading, l->second);
    pair.earlier->cam_from_image = CamFromImage(reading, e->second);
    kept.push_back(std::move(pair));
  }
  *pairs = std::move(kept);
  return removed;
}

}  // namespace shutterlab
