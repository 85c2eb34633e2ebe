#pragma once
// The model `correct` corrects with: the declared camera.json, plus the effects a validation report
// identified (model/effects.h), their uncertainty (each effect's parameter covariance), and the
// gyro's white-noise density. The uncertainty is what the residual prediction draws from
// (estimate/correct/residual_prediction.h).

#include "model/camera.h"
#include "model/effects.h"
#include "model/reported_model.h"
#include "model/truth_model.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// One effect's uncertainty: the covariance of its EffectSpec parameters (deltas around the fitted
// value, as EffectSpec::apply_delta takes them).
struct EffectUncertainty {
  Effect effect = Effect::kTimeOffset;
  Eigen::MatrixXd covariance;
};

struct CorrectionModel {
  TrueModel model;              // declared plus the identified effects
  std::vector<Effect> effects;  // what the report identified, in its order
  std::vector<EffectUncertainty> uncertainty;
  // White noise of the gyro, rad/s/sqrt(Hz) (the angle's random walk), and where it came from.
  double gyro_noise_rad_s_sqrt_hz = 0.0;
  std::string gyro_noise_source;
  std::vector<std::string> notes;  // for a person: what was assumed or could not be used
};

// The declared model alone, or with a report: its fitted_model when it has one (checked to be
// for a camera of the declared size), else declared + each effect's value (clock_rate's companion
// offset is not in a report without fitted_model: said in notes). Effects without a covariance add
// no uncertainty (said in notes). Throws std::invalid_argument for a report of another camera.
CorrectionModel BuildCorrectionModel(const RigModel& declared,
                                     const std::optional<ReportedModel>& report,
                                     const std::string& report_path);

// The white-noise density of a gyro trace, rad/s/sqrt(Hz), the largest over the axes: on the
// trace's still segment (sim/still_detect.h) the rate's standard deviation times sqrt(median
// interval); without one, 1.4826 MAD of the rate's second differences / sqrt(6) (white noise of
// sigma gives second differences of variance 6 sigma^2) times the same, an overestimate where the
// motion has energy near the sample rate (vibration is motion, not noise, and the gyro measures
// it). 0 for fewer than 8 samples.
struct GyroNoiseEstimate {
  double rad_s_sqrt_hz = 0.0;
  std::string source;  // for a person: which of the two, over which span
};
GyroNoiseEstimate EstimateGyroNoise(const GyroTrace& gyro);

}  // namespace shutterlab
