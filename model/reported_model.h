#pragma once
// A validation report read back (docs/FORMATS.md "Validation report", validation/1): what
// `correct --report` corrects with and what `export` carries. Its writer is
// estimate/report/loop_json.h; the reader lives with the model it reads, so that every tool that
// takes a report (and the fuzz target of this reader) needs the model alone.

#include "model/effects.h"
#include "model/truth_model.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct ReportedEffect {
  Effect effect = Effect::kTimeOffset;
  EffectValue value;  // docs/FORMATS.md value
  // EffectSpec's parameters (deltas from the declared model) and their covariance; empty in a
  // report that does not carry them.
  Eigen::VectorXd parameters;
  Eigen::MatrixXd covariance;
};

// One of validate's tested claims (a source's declared value, import.json's "claims"), as words.
struct ReportedClaim {
  std::string claim;    // import.json's name: readout_s, time_offset_s, gyro_to_camera, direction
  std::string effect;   // the effect fitted to test it: readout_time, time_offset, ...
  std::string status;   // import.json's status: "source claim", "guess", ...
  std::string verdict;  // "claim holds: ...", "claim contradicted: ...", "not determined: ..."
};

struct ReportedModel {
  std::vector<ReportedEffect> effects;  // in the report's order
  // The declared model plus every effect, as the loop fitted it ("fitted_model"); absent from
  // reports of other tools or older versions.
  std::optional<TrueModel> fitted;
  double noise_px = 0.0;
  bool unexplained = false;
  double after_rms_px = 0.0, after_max_px = 0.0;
  std::vector<ReportedClaim> claims;  // empty where nothing was claimed
};
// Reads a validation report; throws IoError("PATH: problem").
ReportedModel ReadValidationReport(const std::string& path);

}  // namespace shutterlab
