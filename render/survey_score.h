#pragma once
// `shutterlab score SURVEY MODEL`: a reconstruction of a survey's photos (a COLMAP text model,
// io/colmap_model.h) measured against the survey's truth (render/survey.h): what a
// photogrammetry engine made of the photos, in the units a mapper asks about.
//
// The model's frame is its own (any similarity of the world): it is aligned to the truth by the
// similarity (scale, rotation, translation) that best fits the registered cameras' centres to the
// true centres at each photo's middle row (Umeyama's least squares, Eigen::umeyama), the pose a
// photogrammetry tool takes a photo for. Then, per photo: the centre's error, horizontal and
// vertical, and the orientation's (the angle between the aligned and the true camera frames);
// per point: its height above or below the true terrain at its x, y.

#include "render/survey.h"

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// What a survey's truth holds for scoring: the photos (names, middle-row poses) and the terrain.
struct SurveyTruth {
  struct Photo {
    std::string name;
    CameraPose mid;  // the pose at the middle row's instant
  };
  std::vector<Photo> photos;
  Terrain terrain;
};
// Reads SURVEY/truth/photos.csv and terrain.json + terrain.png. Throws IoError naming the file.
SurveyTruth ReadSurveyTruth(const std::string& survey_dir);

struct PhotoScore {
  std::string name;
  bool registered = false;
  double horizontal_error_m = 0.0, vertical_error_m = 0.0;  // aligned centre - true centre
  double orientation_error_deg = 0.0;
};

struct ReconstructionScore {
  size_t photos = 0, registered = 0;
  double mean_reprojection_error_px = 0.0;  // COLMAP's own, over every observation
  double alignment_scale = 0.0;             // metres per model unit
  // Root mean square over the registered photos.
  double horizontal_rms_m = 0.0, vertical_rms_m = 0.0, orientation_rms_deg = 0.0;
  // Points over the terrain: how many, the median and the root mean square of |z - h(x, y)|.
  size_t points = 0, points_on_terrain = 0;
  double point_median_m = 0.0, point_rms_m = 0.0;
  std::vector<PhotoScore> per_photo;  // the truth's order
  std::vector<std::string> notes;     // images the truth does not know, too few registered, ...
};

// Scores a COLMAP text model (image names: the photos' file names, any folder before them is
// dropped) against the truth. Fewer than 3 registered photos cannot be aligned: the score then
// holds only the counts and says so in notes.
ReconstructionScore ScoreReconstruction(const SurveyTruth& truth, const std::string& model_dir);

}  // namespace shutterlab
