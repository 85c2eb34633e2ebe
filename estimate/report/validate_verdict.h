#pragma once
// What `validate` found, in plain words: the first thing its page and its table say. What the data
// show, how sure that is, and what to do about it.

#include "estimate/loop/validation_result.h"

#include <nlohmann/json_fwd.hpp>

#include <string>
#include <vector>

namespace shutterlab {

struct ValidationVerdict {
  // kOk: the declared model explains the data; kAttention: it does not, and the effects found
  // say why (put them in camera.json); kProblem: the data cannot settle the camera's effects (an
  // image that does not follow the gyro, a residual nothing explains).
  enum class Level { kOk, kAttention, kProblem };
  Level level = Level::kOk;
  std::string headline;               // one sentence: what the data show
  std::vector<std::string> findings;  // the effects with their standard errors, the claims
  std::string certainty;              // how sure, and which standard errors
  std::vector<std::string> actions;   // what to do
};
const char* VerdictLevelName(ValidationVerdict::Level level);

ValidationVerdict MakeVerdict(const ValidationResult& result);

// The verdict as the report JSON's "verdict" and as lines for a person.
nlohmann::json VerdictToJson(const ValidationVerdict& verdict);
std::string VerdictText(const ValidationVerdict& verdict);

}  // namespace shutterlab
