#pragma once
// How much distortion a correction leaves, predicted from the model's uncertainty: the
// displacement D of docs/FORMATS.md "Frame distortion D" of the frame before correction (under the
// model), and of the corrected frame against the true global-shutter view, over draws of the truth
// around the model.
//
// For an output pixel p the correction reads the rolling-shutter image at q = S(p), the source
// under the model (render/rs_correct.h). Were the truth T, q would show what the true reference
// view shows at F_T(q), T's forward map; the corrected frame is displaced by r(p) = F_T(S(p)) - p
// against that view. Each draw takes T = the model plus, per effect, a normal draw of its fitted
// parameters (the report's covariance), and the gyro's white noise integrated along the readout
// (an independent random walk per camera axis, zero at the reference row, of variance density
// squared per second). D after is r's D; with the model itself as the truth r is 0 (the map's own
// interpolation error is not in it: CorrectionMap::estimated_error_px).

#include "estimate/correct/correction_model.h"
#include "render/rs_correct.h"
#include "sim/gyro_trace.h"

#include <cstdint>
#include <optional>
#include <random>
#include <vector>

namespace shutterlab {

// How a frame is corrected.
struct CorrectionSetting {
  CorrectionReference reference = CorrectionReference::kFirstRow;
  // The scene plane's depth in the frame's world (stills: the ground at the altitude); nullopt:
  // rotation only.
  std::optional<double> plane_depth_m;
};

struct ResidualPredictionOptions {
  int draws = 32;         // draws of the truth
  int grid_columns = 33;  // output pixels on a grid, borders included
  int grid_rows = 25;
  uint64_t seed = 1;  // with the frame's time: the same draws on every run
  // Each draw's poses at every row, not only at the rows the grid reads, and its rates integrated
  // afresh even where they are the model's: the same numbers, slower (the brute-force twin of the
  // tests). The gyro's noise is drawn at the rows read either way (GyroNoiseAnglesRad's own test
  // checks its walk).
  bool every_row = false;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct ResidualPrediction {
  double d_before_px = 0.0;     // the uncorrected frame's D under the model
  double d_after_px = 0.0;      // median over draws of the corrected frame's D
  double d_after_p90_px = 0.0;  // its 90th percentile
  double rms_after_px = 0.0;    // median over draws of r's root mean square
  int draws = 0;                // draws whose truth covered the frame (and so counted)
};

// The gyro's white noise integrated along a frame's readout, drawn at the rows marked in `rows`
// (one flag a row; the others stay zero): per camera axis a random walk that is zero at start_row
// and has, at row v, the variance density^2 |t_v - t_start| (rad^2), t_v the row's gyro-clock time
// under `model`; the walk's steps on either side of start_row are independent.
std::vector<Eigen::Vector3d> GyroNoiseAnglesRad(const TrueModel& model, int64_t t_first_row_ns,
                                                int start_row, double density_rad_s_sqrt_hz,
                                                const std::vector<bool>& rows,
                                                std::mt19937_64* rng);

// gyro: the logged trace around the frame (a second either side is plenty: it is integrated once
// where a draw needs it, and again for each draw whose mounting, gyro scale or bias differs from
// the model's). model_frame: the model's poses of the frame (CameraMotion::Frame), when the caller
// has them (a correction's, integrated from an earlier sample of the same log: the same to
// rounding); computed here when null. Throws std::out_of_range when the model's readout of the
// frame lies outside the trace, given a frame or not.
ResidualPrediction PredictResidual(const CorrectionModel& model, const GyroTrace& gyro,
                                   int64_t t_first_row_ns, const CorrectionSetting& setting,
                                   const ResidualPredictionOptions& options = {},
                                   const FrameMotion* model_frame = nullptr);

}  // namespace shutterlab
