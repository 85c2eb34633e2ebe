#pragma once
// The paper's analyses as docs/FORMATS.md's JSON (`noise`, `accuracy`, `flight`, `analyze`): the
// results stay typed in estimate/paper; their JSON is written here, at the edge.

#include "estimate/paper/accuracy.h"
#include "estimate/paper/analyze.h"
#include "estimate/paper/flight.h"
#include "estimate/paper/noise.h"
#include "io/warnings_io.h"  // WarningsToJson
#include "record/recording.h"
#include "sim/log_warning.h"
#include "sim/sensor_pair.h"

#include <nlohmann/json.hpp>

#include <vector>

namespace shutterlab {

// docs/FORMATS.md `noise` JSON, plus extra keys: per axis sigma_rms_arcsec, bias_rad_s and, when
// the Allan deviation was computed, arw_deg_sqrt_h, arw_rad_s_sqrt_hz, bias_instability_deg_h,
// bias_instability_tau_s, bias_instability_upper_bound; top level windows, samples, rate_hz. Keys
// in the contract's order (ordered_json), as `noise --json` has always printed them.
nlohmann::ordered_json NoiseToJson(const NoiseResult& result);

// docs/FORMATS.md `accuracy` JSON, plus extra keys per rotation (theta_vector_arcsec,
// theta_so3_arcsec, t_start_s, t_end_s) and top level (average_samples, difference_mean_arcsec,
// difference_std_arcsec, noise_level_rad_s, enter_rad_s, exit_rad_s, skipped_t_s). Keys in the
// contract's order (ordered_json), as `accuracy --json` has always printed them.
nlohmann::ordered_json AccuracyToJson(const AccuracyResult& result);

// docs/FORMATS.md `flight` JSON (plus per-axis percentages, window counts and the bias).
nlohmann::json FlightToJson(const FlightResult& result);

// The two-sensor fusion (sim/sensor_pair.h): {"second_log": PATH, "paired", "unpaired",
// "mounting_fitted", "mounting_angle_deg", "mounting_signal_ratio", "a_from_b" (3x3 row-major),
// "weights_first" [x, y, z], "weights_from_still", "difference_rms_rad_s"}.
nlohmann::ordered_json SensorPairToJson(const SensorPair& pair, const std::string& second_path);
// Noise of a pair: SensorPairToJson plus "first", "second" (NoiseToJson) and "gain"
// ({"sigma_vs_first": [x, y, z], "sigma_vs_second", "arw_vs_first", "arw_vs_second"}).
nlohmann::ordered_json NoisePairToJson(const SensorPair& pair, const std::string& second_path,
                                       const NoiseResult& first, const NoiseResult& second,
                                       const NoiseResult& fused);

// `record --json` (docs/FORMATS.md "Recorder output"): the summary of a recording.
nlohmann::ordered_json RecordSummaryToJson(const RecordSummary& summary,
                                           const std::string& triggers_path);

// docs/FORMATS.md `analyze` JSON (plus bias, verdict and per-image detail).
nlohmann::json AnalyzeToJson(const AnalyzeResult& result);

// What neither the user nor the file gave (analyze's, flight's, noise's and accuracy's
// `assumptions`): [{"what", "taken", "why", "give"}, ...].
nlohmann::json AssumptionsToJson(const std::vector<Assumption>& assumptions);

}  // namespace shutterlab
