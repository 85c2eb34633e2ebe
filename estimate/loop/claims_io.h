#pragma once
// The claims of import.json (`shutterlab import`, docs/FORMATS.md "Video datasets") that validate
// can test, read at the edge into typed effect values.

#include "model/effects.h"

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// One claim of import.json that a fit tests (EffectSpec::claim names it).
struct SourceClaim {
  std::string what;                     // import.json's name: readout_s, gyro_to_camera, ...
  std::string status;                   // import.json's status ("source claim", ...); "" if none
  Effect effect = Effect::kTimeOffset;  // the effect fitted to test it
  EffectValue value;                    // the value the source states, in the effect's shape
};

// The effect whose fit tests an import.json claim (EffectSpec::claim); nullopt for the others.
std::optional<Effect> EffectForClaim(const std::string& what);

// The testable claims of import_json_path, in the file's order, read and checked before any work is
// done (a broken file is named at once, not after minutes of measuring); none when the file does
// not exist or has no "claims". Each claim is an object with a string "what", "status" a string
// when present, and a "value" of the effect's docs/FORMATS.md shape (model/effect_io.h
// EffectValueFromJson: gyro_to_camera a 3x3 array of numbers, readout_s and time_offset_s numbers,
// direction a row-order word). Claims no effect tests (intrinsics, say) are left out. Throws
// IoError naming the path, the claim's number and the problem.
std::vector<SourceClaim> ReadSourceClaims(const std::string& import_json_path);

}  // namespace shutterlab
