#pragma once
// What `correct` did (estimate/correct/correct_dataset.h CorrectDataset): per frame the reference
// instant, the map, the predicted residual and, on rendered data, the residual against the truth.
// Apart from the correction so that its outputs (estimate/correct/correct_io.h) read it.

#include "estimate/correct/correction_model.h"
#include "estimate/correct/residual_prediction.h"
#include "sim/log_warning.h"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

// A corrected frame measured against the renderer's exact truth (truth/NNNN_disp.exr): the
// remaining displacement r(p) = q + d(q) - p of each output pixel p with a source, q its source in
// the map that was used and d the true displacement at q (bilinear in the field).
struct TruthResidual {
  double rms_px = 0.0, max_px = 0.0;
  double d_px = 0.0;         // docs/FORMATS.md D of r
  double d_before_px = 0.0;  // D of the truth field itself: the frame before correction
  size_t pixels = 0;
};

struct CorrectedFrame {
  int64_t frame = 0;
  std::string source_image;  // the input's relative path (photos: the file's name)
  std::string image;         // DIR's relative path: the input's (photos: images/NAME)
  // The translation corrected: the velocity in the frame's world (camera axes at row 0), m/s, and
  // for a person what of the motion was corrected and from what.
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  std::string translation;
  int64_t t_first_row_ns = 0;  // input frames.csv (camera clock)
  int64_t t_reference_ns = 0;  // the corrected image's instant: DIR's frames.csv t_first_row
  double reference_row = 0.0;  // image row captured at that instant
  bool kept = false;           // DIR already held it (resumed, not rewritten)
  int cell_px = 0;             // correction map grid
  double map_error_px = 0.0;   // its estimated interpolation error
  double no_source_fraction = 0.0;
  ResidualPrediction residual;  // the model's share (its uncertainty and the gyro's noise)
  // Predicted D after, median and 90th percentile: the model's share plus the map's (its
  // interpolation may add twice its checked error to a column's diameter).
  double predicted_d_after_px = 0.0, predicted_d_after_p90_px = 0.0;
  std::optional<TruthResidual> truth;
  std::vector<std::string> notes;  // what the image's metadata could not carry
};

struct CorrectSummary {
  std::string dataset, out_dir, report_path;
  bool video = false;
  bool photos = false;  // a folder of photos with its log
  CorrectionModel model;
  CorrectionSetting setting;
  // for a person: "ground plane at 50 m, velocity ...", "rotation only: ..."; photos: per photo in
  // each frame's translation
  std::string translation;
  std::string image_root;              // DIR's folder of the corrected images ("": DIR itself)
  double m_per_px = 0.0;               // ground metres per pixel at the altitude (D on the ground)
  std::vector<CorrectedFrame> frames;  // frames.csv order, corrected ones
  std::vector<std::pair<int64_t, std::string>> skipped;  // frame and why
  std::vector<std::string> notes;
  std::vector<LogWarning> warnings;  // the dataset's gyro.csv audit
};

}  // namespace shutterlab
