#pragma once
// `analyze --photos DIR [LOG]`: the predicted rolling-shutter distortion of every photo of a
// folder (io/photo_set.h).
//
// Without a log, the translation part only, from the flight speed the photo records, as
// photogrammetry tools model it (OpenDroneMap / OpenSfM's rolling-shutter correction moves each
// row by the camera's velocity times the row's time): a nadir camera over flat ground at height h
// moving at horizontal speed v during a readout of T seconds sees the ground move, between the
// first and the last row, by
//     D_translation_m = v * T            (on the ground)
//     D_translation_px = v * T * f / h   (in the image; f in pixels)
// Along the readout (rows top to bottom, image y down) that motion stretches or compresses the
// photo; across it, it shears it. With the gimbal's attitude (DJI: NED, Z-Y-X yaw, pitch, roll;
// the camera's frame x along the optical axis, y image right, z image down) and its optical axis
// within nadir_tolerance_deg of straight down, the motion is split into those two parts: the ground
// moves by -v along each image axis, R * (0,1,0) (right) and R * (0,0,1) (down). At pitch -90 yaw
// and roll turn about the same axis, so the image's top faces yaw + roll (an Inspire 1 photo at
// yaw 103, roll 168.8 faces 271.8, its airframe's heading). The camera's rotation during the
// readout (usually the larger part) needs a gyro log.
//
// With a log, each photo placed on the log's clock (estimate/paper/photo_clock.h) is analysed by
// `analyze` (estimate/paper/analyze.h) for the rotation; the photo keeps both parts and is
// flagged on their sum, an upper bound of the combined displacement.
//
// Motion blur during the exposure, v * exposure * f / h, is given beside it.

#include "estimate/paper/analyze.h"
#include "io/photo_set.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct PhotoAnalysisOptions {
  std::vector<double> limits_m{0.05, 0.10};  // acceptable displacement on the ground
  // An optical axis further than this from straight down is "oblique" (no along/across split).
  double nadir_tolerance_deg = 10.0;
  // With a log: the rotation part in metres at each photo's own height above the ground (its
  // metadata's), not at the one altitude the log's analysis used for all of them. Off when the
  // user's altitude or camera.json's should win.
  bool rotation_at_each_photo_altitude = false;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Where a photo sits on a log's clock (filled by estimate/paper/photo_clock.h).
struct PhotoPlacement {
  std::optional<int64_t> t_ns;       // exposure of row 0 on the log's clock; empty: not placed
  std::string method;                // e.g. "trigger file (MRK) #123", "log camera event #4"
  std::optional<double> residual_s;  // capture time against the event, after the clock offset
  std::string problem;               // why it was not placed
};

struct PhotoResult {
  std::string name;
  std::string error;  // the file could not be read: nothing below is set
  // Translation only, from the recorded speed (empty when speed, readout, focal or altitude is
  // missing).
  std::optional<double> d_translation_px, d_translation_m;
  // Its parts along the readout (+: the ground moves with the readout, the photo is stretched) and
  // across it (+: to the right), px; only with a nadir gimbal's yaw.
  std::optional<double> along_readout_px, across_readout_px;
  std::optional<double> blur_px;  // v * exposure * f / h
  // With a log: placement and the rotation part (analyze's D_full, D_paper).
  PhotoPlacement placement;
  std::optional<double> d_rotation_px, d_rotation_m, d_paper_m;
  // Flags per limit on the translation (no log) or on rotation + translation (with a log); empty
  // where the part needed is unknown.
  std::vector<std::optional<bool>> flagged;
  // Words a person acts on: "oblique (gimbal pitch -45.0)", "not placed on the log", ...
  std::vector<std::string> notes;
  // Flagged at any limit.
  bool AnyFlagged() const;
};

struct PhotoAnalysis {
  std::string source;  // the folder
  std::vector<double> limits_m;
  bool with_log = false;
  std::vector<PhotoResult> photos;  // one per PhotoSet photo, same order
  // Placement summary with a log: how the photos were placed and how well.
  std::string placement_method;
  std::optional<double> clock_offset_s;  // camera clock - clock_offset_to, where fitted
  std::string clock_offset_to;           // "UTC", or "log clock" for a log without GPS time
  std::optional<double> residual_rms_s, residual_max_s;
  size_t placed = 0;
  // Counts: photos read, with a translation D, flagged per limit, readouts from the table.
  size_t read = 0, predicted = 0, readout_from_table = 0;
  std::vector<size_t> flagged_count;
  size_t excluded = 0;  // what exclude.txt lists: unreadable or flagged at any limit
  std::string verdict;  // one line for a person
};

// The per-photo predictions without a log.
PhotoAnalysis AnalyzePhotos(const PhotoSet& set, const PhotoAnalysisOptions& options);

// With a log: the placements (one per photo, same order) and analyze's result on the placed
// photos (its images named by the photos' names) added to the translation part.
PhotoAnalysis AnalyzePhotosWithLog(const PhotoSet& set, const PhotoAnalysisOptions& options,
                                   const std::vector<PhotoPlacement>& placements,
                                   const AnalyzeResult& log_result);

// The table for a person: camera and readout with their sources, the model, one row a photo,
// what is missing per photo, the verdict.
std::string PhotoAnalysisReport(const PhotoSet& set, const PhotoAnalysis& analysis);

// DIR/photos.csv (one row a photo), DIR/exclude.txt (flagged or unreadable photos' file names, one
// a line), DIR/image_list.txt (the other photos' absolute paths, one a line: OpenSfM's and
// OpenDroneMap's image_list.txt) and DIR/colmap_image_list.txt (their names relative to the photo
// folder: COLMAP's --image_list_path with --image_path DIR). Each written whole; creates DIR.
void WritePhotoOutputs(const std::string& dir, const PhotoSet& set, const PhotoAnalysis& analysis);

}  // namespace shutterlab
