#pragma once
// What the validation tests (still, foreign and video datasets) share.

#include "estimate/loop/validate.h"

#include <string>

namespace shutterlab::test {

// Acceptance: in identified cases the residual after the loop is at the noise level.
inline constexpr double kAfterOverNoise = 1.5;

// ValidateDataset with its defaults, but no residual images kept (the tests read only numbers).
inline ValidationResult ValidateWithoutResiduals(const std::string& dataset) {
  ValidateOptions options;
  options.keep_residuals = false;
  return ValidateDataset(dataset, options);
}

}  // namespace shutterlab::test
