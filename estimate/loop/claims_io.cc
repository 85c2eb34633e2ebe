#include "estimate/loop/claims_io.h"

#include "model/effect_io.h"
#include "sim/check.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <stdexcept>

namespace shutterlab {

using nlohmann::json;

std::optional<Effect> EffectForClaim(const std::string& what) {
  for (const EffectSpec& spec : AllEffects()) {
    if (!spec.claim.empty() && spec.claim == what) return spec.effect;
  }
  return std::nullopt;
}

std::vector<SourceClaim> ReadSourceClaims(const std::string& path) {
  std::vector<SourceClaim> claims;
  if (!std::filesystem::is_regular_file(path)) return claims;
  json record;
  try {
    record = json::parse(ReadFileToString(path));
  } catch (const json::exception& e) {
    throw IoError(IoMessage(path, 0, std::string("not JSON: ") + e.what()));
  }
  if (!record.is_object() || !record.contains("claims")) return claims;
  if (!record["claims"].is_array()) throw IoError(IoMessage(path, 0, "\"claims\" is not an array"));
  for (size_t k = 0; k < record["claims"].size(); ++k) {
    const json& claim = record["claims"][k];
    const std::string where = "claim " + std::to_string(k + 1) + ": ";
    if (!claim.is_object() || !claim.contains("what") || !claim["what"].is_string()) {
      throw IoError(IoMessage(path, 0, where + "not an object with a string \"what\""));
    }
    if (claim.contains("status") && !claim["status"].is_string()) {
      throw IoError(IoMessage(path, 0, where + "\"status\" is not a string"));
    }
    SourceClaim out;
    out.what = claim["what"].get<std::string>();
    const std::optional<Effect> effect = EffectForClaim(out.what);
    if (!effect) continue;  // a claim validate cannot test (exposure, say)
    out.effect = *effect;
    out.status = claim.value("status", "");
    const json value = claim.value("value", json());
    try {
      out.value = EffectValueFromJson(*effect, value, out.what);
    } catch (const std::invalid_argument&) {
      throw IoError(
          IoMessage(path, 0, where + "\"" + out.what + "\" has an unusable value " + value.dump()));
    }
    claims.push_back(std::move(out));
  }
  return claims;
}

}  // namespace shutterlab
