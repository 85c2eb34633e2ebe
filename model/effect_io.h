#pragma once
// The edge of the effect table (model/effects.h): effect values as JSON (truth.json, the
// validation report, import.json's claims) and as `render --inject NAME=VALUE` text. Everything
// inside the libraries holds the typed EffectValue; only this file and the report writers spell it
// as JSON.

#include "model/effects.h"
#include "model/truth_model.h"

#include <nlohmann/json.hpp>

#include <string>

namespace shutterlab {

// docs/FORMATS.md's JSON of a value: a number, [x, y, z], a 3x3 matrix as an array of its rows,
// {"k1": .., "k2": ..} (with "p1", "p2", "k3" only where non-zero) or {"model": "fisheye", "k1":
// .., "k2": .., "k3": .., "k4": ..}, a direction word, or null (std::monostate). NaN, a standard
// error the data do not determine, is written as null.
nlohmann::json EffectValueToJson(const EffectValue& value);

// The value of `effect` from docs/FORMATS.md's JSON, the shape EffectValueToJson writes (a number,
// [x, y, z], a 3x3 array of rows, a lens object as camera.json's "distortion", one of the two
// row-order words); import.json's claims are read with it. Throws std::invalid_argument
// "<where>: expected ..., got <JSON>".
EffectValue EffectValueFromJson(Effect effect, const nlohmann::json& json,
                                const std::string& where);

// `render --inject NAME=VALUE`: NAME a docs/FORMATS.md effect name. An effect with a unit takes
// quantities, comma-separated ("time_offset=5ms", "gyro_bias=0.5deg/s,0,0", "clock_rate=30ppm";
// 0 needs no unit, a bare number is refused with what it probably meant). The others take JSON
// ("[1.01,1,1]", "{\"k1\":-0.1}") or comma-separated numbers ("1.01,1,1"; gyro_to_camera: 9
// numbers, row-major; lens_distortion: k1[,k2[,p1,p2[,k3]]], a lens object as camera.json's
// "distortion") or, for readout_direction, a bare word. Numbers may be nested one level
// (gyro_to_camera as JSON rows or flat) and must be finite. Throws std::invalid_argument
// "--inject ..." for a missing '=', an unknown name or a bad value.
Injection ParseInjection(const std::string& name_equals_value);

// A whole true model: {"camera": camera.json's object, "gyro_scale": [3], "gyro_bias_rad_s": [3],
// "clock_rate_ppm": x} (the validation report's "fitted_model"). FromJson throws
// std::invalid_argument "<where>: problem".
nlohmann::json TrueModelToJson(const TrueModel& model);
TrueModel TrueModelFromJson(const nlohmann::json& json, const std::string& where);

// ParseInjection, then the typed ApplyInjection (model/effects.h): the returned injection holds
// the value as truth.json records it. A list of lens coefficients is read in the model's own lens
// model (a fisheye's: k1[,k2[,k3[,k4]]]); a lens object of the other model is refused.
Injection ApplyInjection(const std::string& name_equals_value, TrueModel* model);

}  // namespace shutterlab
