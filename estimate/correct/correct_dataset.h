#pragma once
// `shutterlab correct DATASET --out DIR`: every frame of a rig dataset (docs/FORMATS.md "Rig
// dataset", still or video) corrected to the global-shutter view from the pose at a reference
// instant, through the same camera (render/rs_correct.h), with the declared model plus what a
// validation report identified (estimate/correct/correction_model.h).
//
// DIR is again a rig dataset (docs/FORMATS.md "Correction output"):
//   camera.json     the model corrected with, readout_s 0 (a global shutter)
//   gyro.csv        the logged gyro with the model's gyro scale, bias and clock rate applied, so
//                   that camera.json declares the whole model
//   frames.csv      each corrected frame at its reference instant, the image under the input's
//                   relative path; still datasets corrected to row 0 keep their references
//   <image paths>   the corrected images: the input's format, bit depth, JPEG quality, EXIF and
//                   XMP, with Xmp.shutterlab.* saying how they were corrected
//   <ref paths>     the references, copied (still datasets corrected to row 0)
//   masks/<image path>.png        one bit a pixel, set (read back as 255) where the pixel has a
//                                 source in the frame (and camera.json's mask, moved with the
//                                 frame, allows it), 0 where not
//   camera_mask.png               camera.json's mask as it was, when it names one
//   colmap/image_list.txt         the corrected images for COLMAP (--image_path DIR,
//                                 --ImageReader.mask_path DIR/masks)
//   odm/images/                   an OpenDroneMap project's images (links or copies) with their
//                                 NAME_mask.png
//   overview.png                  a few frames, rolling shutter beside corrected
//   correct.json                  what was done, per frame D before and predicted after
// A folder of photos with its flight log (estimate/correct/photo_input.h) is corrected the same
// way, as stills: DIR holds the corrected photos under their names, camera.json, gyro.csv (the
// log's trace) and frames.csv (no references), masks and lists.
// Stills use the ground plane at the altitude for translation; video is rotation only unless a
// depth is given. Frames run in parallel; an image already in DIR is kept (resumed) unless force;
// every file is written whole or not at all; the input is never modified.

#include "estimate/correct/correct_summary.h"
#include "estimate/correct/correction_model.h"
#include "estimate/correct/photo_input.h"
#include "estimate/correct/residual_prediction.h"
#include "render/rs_correct.h"
#include "sim/log_warning.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

struct CorrectOptions {
  std::string dataset_dir;  // a rig dataset, or with `photos` the folder of photos
  // correct --photos DIR LOG: the log, the triggers and the camera of the photos in dataset_dir.
  // Their triggers are on the log's clock: the model's time_offset_s is not applied (said), and
  // without a gyro bias in the model the log's still segment gives it (said).
  std::optional<PhotoInputOptions> photos;
  std::string out_dir;
  std::string report_path;  // a validation report (validate --report); "" for the declared model
  // Effects set on top of camera.json and the report, "NAME=VALUE" as `render --inject` takes them
  // (a readout from a datasheet, a mounting measured on the bench).
  std::vector<std::string> effects;
  CorrectionReference reference = CorrectionReference::kFirstRow;
  // Video: the scene plane's depth, m, for translation (the camera.json velocity); stills use the
  // altitude. Without it video is rotation only.
  std::optional<double> depth_m;
  Interpolation interpolation = Interpolation::kBilinear;
  CorrectionMapOptions map;
  ResidualPredictionOptions prediction;
  // The gyro's white-noise density, rad/s/sqrt(Hz); estimated from gyro.csv when absent.
  std::optional<double> gyro_noise_rad_s_sqrt_hz;
  bool force = false;        // rewrite corrected images that DIR already holds
  bool check_truth = false;  // rendered datasets: measure the result against truth/ (row 0)
  // Where check_truth reads each frame's NNNN_disp.exr (photos: NNNN is the photo's index in the
  // folder); "": DATASET/truth.
  std::string truth_dir;
  int jobs = 0;          // frames at once; 0: the hardware's threads, at most 4
  bool pictures = true;  // overview.png
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// progress(done, total) after each frame; called from worker threads one at a time.
using CorrectProgress = std::function<void(size_t done, size_t total)>;

// Reads and checks everything before writing; bad input throws IoError / std::invalid_argument
// with one line naming the file and problem. DIR may not be the dataset itself.
CorrectSummary CorrectDataset(const CorrectOptions& options, const CorrectProgress& progress = {});

// The measurement against the truth (TruthResidual) of one corrected frame's map.
TruthResidual MeasureAgainstTruth(const CorrectionMap& map, const cv::Mat& truth_field);

}  // namespace shutterlab
