#pragma once
// What the validation tests (still, foreign and video datasets) share.

#include "estimate/loop/validate.h"

#include <string>

namespace shutterlab::test {

// Acceptance for "at the noise level": a residual no more than this times the measured noise.
// Identified cases reach it after the loop; a dataset with nothing undeclared, before it.
inline constexpr double kAtNoiseRatio = 1.5;

// ValidateDataset with its defaults, but no residual images kept (the tests read only numbers).
inline ValidationResult ValidateWithoutResiduals(const std::string& dataset) {
  ValidateOptions options;
  options.keep_residuals = false;
  return ValidateDataset(dataset, options);
}

}  // namespace shutterlab::test
