#include "estimate/correct/correction_model.h"

#include "model/effect_io.h"
#include "sim/check.h"
#include "sim/still_detect.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {

CorrectionModel BuildCorrectionModel(const RigModel& declared,
                                     const std::optional<ReportedModel>& report,
                                     const std::string& report_path) {
  CorrectionModel out;
  out.model.rig = declared;
  if (!report) return out;
  if (report->fitted) {
    const PinholeCamera& fitted = report->fitted->rig.camera;
    SHUTTERLAB_CHECK(fitted.width == declared.camera.width &&
                     fitted.height == declared.camera.height)
        << report_path << ": the report's model is for a " << fitted.width << "x" << fitted.height
        << " camera, the dataset's is " << declared.camera.width << "x" << declared.camera.height;
    out.model = *report->fitted;
  } else {
    out.notes.push_back(report_path +
                        ": no fitted_model (a report of another tool or an older version): the "
                        "declared model plus each effect's value");
  }
  for (const ReportedEffect& e : report->effects) {
    // A value no device has explains a residual but corrects nothing (validate's verdict says
    // what it points to); from a report of any tool, so checked here, not read from a key.
    const std::string outside = OutOfBounds(e.effect, e.value, &declared);
    SHUTTERLAB_CHECK(outside.empty())
        << report_path << ": " << Spec(e.effect).name << " " << outside
        << ": it is no correction; give the values to use with --effect NAME=VALUE instead";
    out.effects.push_back(e.effect);
    if (!report->fitted) {
      ApplyInjection(Injection{e.effect, e.value}, &out.model);
      if (e.effect == Effect::kClockRate) {
        out.notes.push_back(report_path +
                            ": clock_rate's own time offset is not in the report: taken as 0");
      }
    }
    const int n = Spec(e.effect).parameter_count;
    if (n == 0) continue;  // readout_direction: a discrete choice, no spread
    if (e.covariance.rows() == n && e.covariance.allFinite()) {
      out.uncertainty.push_back({e.effect, e.covariance});
    } else {
      out.notes.push_back(report_path + ": " + Spec(e.effect).name +
                          " has no covariance: its uncertainty is left out of the prediction");
    }
  }
  out.model.Check();
  return out;
}

GyroNoiseEstimate EstimateGyroNoise(const GyroTrace& gyro) {
  const std::vector<GyroSample>& s = gyro.samples();
  GyroNoiseEstimate out;
  if (s.size() < 8 || gyro.sampling().median_interval_ns <= 0) {
    out.source = "too few samples: taken as 0";
    return out;
  }
  const double root_dt = std::sqrt(gyro.sampling().median_interval_ns * 1e-9);
  try {
    const StillSegment still = DetectStillSegment(gyro);
    const size_t n = still.end_sample - still.first_sample;
    if (n >= 8) {
      double sigma = 0.0;
      for (int axis = 0; axis < 3; ++axis) {
        double sum = 0.0, sum_sq = 0.0;
        for (size_t k = still.first_sample; k < still.end_sample; ++k) {
          sum += s[k].omega_rad_s[axis];
          sum_sq += s[k].omega_rad_s[axis] * s[k].omega_rad_s[axis];
        }
        const double mean = sum / n;
        sigma = std::max(sigma, std::sqrt(std::max(0.0, sum_sq / n - mean * mean)));
      }
      out.rad_s_sqrt_hz = sigma * root_dt;
      out.source = FormatNumber("gyro.csv's still segment %.1f", still.segment.begin_s) +
                   FormatNumber("..%.1f s after its first sample", still.segment.end_s);
      return out;
    }
  } catch (const std::invalid_argument&) {
    // no still segment: the second differences below
  }
  double sigma = 0.0;
  std::vector<double> second(s.size() - 2);
  for (int axis = 0; axis < 3; ++axis) {
    for (size_t k = 1; k + 1 < s.size(); ++k) {
      second[k - 1] = std::abs(s[k + 1].omega_rad_s[axis] - 2 * s[k].omega_rad_s[axis] +
                               s[k - 1].omega_rad_s[axis]);
    }
    // The median absolute second difference (its median is ~0): 1.4826 MAD is sigma of a normal.
    sigma = std::max(sigma, 1.4826 * UpperMedian(second) / std::sqrt(6.0));
  }
  out.rad_s_sqrt_hz = sigma * root_dt;
  out.source =
      "gyro.csv's second differences (no still segment: motion near the sample rate counts too)";
  return out;
}

}  // namespace shutterlab
