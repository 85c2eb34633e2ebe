#include "render/survey_score.h"

#include "io/colmap_model.h"
#include "io/image_io.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

double Rms(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return values.empty() ? 0.0 : std::sqrt(sum / values.size());
}

// truth/photos.csv: each photo's name and middle-row pose, by the header's column names.
std::vector<SurveyTruth::Photo> ReadTruthPhotos(const std::string& path) {
  const std::string text = ReadFileToString(path);
  std::vector<SurveyTruth::Photo> photos;
  std::map<std::string, size_t> column;
  std::vector<std::string_view> fields;
  size_t start = 0;
  long number = 0;
  while (start < text.size()) {
    const size_t end = std::min(text.find('\n', start), text.size());
    std::string_view line(text.data() + start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    start = end + 1;
    ++number;
    if (line.empty()) continue;
    SplitFields(line, ',', &fields);
    if (column.empty()) {
      for (size_t k = 0; k < fields.size(); ++k) column[std::string(fields[k])] = k;
      for (const char* need : {"photo", "x_m", "y_m", "z_m", "qw", "qx", "qy", "qz"}) {
        if (!column.count(need)) {
          throw IoError(
              IoMessage(path, 1, std::string("no column ") + need + " (a survey's photos.csv)"));
        }
      }
      continue;
    }
    if (fields.size() < column.size()) {
      throw IoError(IoMessage(path, number,
                              "has " + std::to_string(fields.size()) + " fields, the header " +
                                  std::to_string(column.size())));
    }
    const auto value = [&](const char* name) {
      const size_t k = column.at(name);
      const std::optional<double> v = ParseDouble(fields[k]);
      if (!v) throw IoError(IoMessage(path, number, std::string(name) + " is not a number"));
      return *v;
    };
    SurveyTruth::Photo p;
    p.name = std::string(fields[column.at("photo")]);
    p.mid.center_m = Eigen::Vector3d(value("x_m"), value("y_m"), value("z_m"));
    p.mid.world_from_cam = Eigen::Quaterniond(value("qw"), value("qx"), value("qy"), value("qz"))
                               .normalized()
                               .toRotationMatrix();
    photos.push_back(std::move(p));
  }
  return photos;
}

}  // namespace

SurveyTruth ReadSurveyTruth(const std::string& survey_dir) {
  const fs::path truth_dir = fs::path(survey_dir) / "truth";
  SurveyTruth truth;
  truth.photos = ReadTruthPhotos((truth_dir / "photos.csv").string());
  const std::string json_path = (truth_dir / "terrain.json").string();
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(ReadFileToString(json_path));
    Terrain& t = truth.terrain;
    t.west_m = json.at("west_m").get<double>();
    t.north_m = json.at("north_m").get<double>();
    t.cell_m = json.at("cell_m").get<double>();
    const double offset_m = json.at("offset_m").get<double>();
    const double scale_m = json.at("scale_m").get<double>();
    const std::string heights = (truth_dir / json.at("heights").get<std::string>()).string();
    const cv::Mat values = ReadImage(heights);
    if (values.type() != CV_16UC1 || values.rows < 2 || values.cols < 2) {
      throw IoError(IoMessage(heights, 0, "the heights must be a 16-bit grey image, 2x2 or more"));
    }
    values.convertTo(t.height_m, CV_64F, scale_m, offset_m);
    cv::minMaxLoc(t.height_m, &t.min_m, &t.max_m);
  } catch (const nlohmann::json::exception& e) {
    throw IoError(IoMessage(json_path, 0, std::string("not a survey's terrain.json: ") + e.what()));
  }
  return truth;
}

ReconstructionScore ScoreReconstruction(const SurveyTruth& truth, const std::string& model_dir) {
  const ColmapModel model = ReadColmapTextModel(model_dir);
  ReconstructionScore score;
  score.photos = truth.photos.size();
  score.mean_reprojection_error_px = model.MeanReprojectionErrorPx();
  score.points = model.points.size();
  std::map<std::string, size_t> index;
  for (size_t k = 0; k < truth.photos.size(); ++k) index[truth.photos[k].name] = k;
  std::vector<const ColmapImage*> estimated(truth.photos.size(), nullptr);
  for (const ColmapImage& image : model.images) {
    const auto it = index.find(fs::path(image.name).filename().string());
    if (it == index.end()) {
      score.notes.push_back(image.name + ": not a photo of the survey (left out)");
      continue;
    }
    if (estimated[it->second]) {
      score.notes.push_back(image.name + ": a second image of " + it->first + " (the first kept)");
      continue;
    }
    estimated[it->second] = &image;
  }
  Eigen::Matrix3Xd from(3, 0), to(3, 0);
  for (size_t k = 0; k < truth.photos.size(); ++k) {
    score.per_photo.push_back({truth.photos[k].name, estimated[k] != nullptr, 0.0, 0.0, 0.0});
    if (!estimated[k]) continue;
    ++score.registered;
    from.conservativeResize(3, from.cols() + 1);
    to.conservativeResize(3, to.cols() + 1);
    from.col(from.cols() - 1) = estimated[k]->CenterM();
    to.col(to.cols() - 1) = truth.photos[k].mid.center_m;
  }
  if (score.registered < 3) {
    score.notes.push_back(std::to_string(score.registered) +
                          " photo(s) registered: 3 are needed to align the model to the truth");
    return score;
  }
  // Cameras on one line leave the roll about it to the noise: the centres' errors still hold,
  // the orientations' and the points' would not.
  const Eigen::Matrix3Xd centred = to.colwise() - to.rowwise().mean();
  const Eigen::Vector3d spread = Eigen::JacobiSVD<Eigen::Matrix3Xd>(centred).singularValues();
  const bool on_a_line = spread(1) < 1e-3 * spread(0);
  // Umeyama's similarity: to ~ s R from + t.
  const Eigen::Matrix4d align = Eigen::umeyama(from, to, true);
  score.alignment_scale = align.block<3, 3>(0, 0).col(0).norm();
  const Eigen::Matrix3d rotation = align.block<3, 3>(0, 0) / score.alignment_scale;
  const auto aligned = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(align.block<3, 3>(0, 0) * x + align.block<3, 1>(0, 3));
  };
  std::vector<double> horizontal, vertical, orientation;
  for (size_t k = 0; k < truth.photos.size(); ++k) {
    if (!estimated[k]) continue;
    PhotoScore& p = score.per_photo[k];
    const Eigen::Vector3d error = aligned(estimated[k]->CenterM()) - truth.photos[k].mid.center_m;
    p.horizontal_error_m = std::hypot(error.x(), error.y());
    p.vertical_error_m = error.z();
    const Eigen::Matrix3d turn =
        truth.photos[k].mid.world_from_cam.transpose() * rotation * estimated[k]->WorldFromCam();
    p.orientation_error_deg = on_a_line ? kNan : Eigen::AngleAxisd(turn).angle() * kDegPerRad;
    horizontal.push_back(p.horizontal_error_m);
    vertical.push_back(p.vertical_error_m);
    orientation.push_back(p.orientation_error_deg);
  }
  score.horizontal_rms_m = Rms(horizontal);
  score.vertical_rms_m = Rms(vertical);
  score.orientation_rms_deg = Rms(orientation);
  if (on_a_line) {
    score.notes.push_back(
        "the registered cameras lie on one line: the alignment's roll about it is undetermined, "
        "so the orientation and point errors are left out (fly two lines)");
    score.point_median_m = score.point_rms_m = score.orientation_rms_deg = kNan;
    return score;
  }
  std::vector<double> heights;
  for (const ColmapPoint& point : model.points) {
    const Eigen::Vector3d x = aligned(point.xyz);
    const std::optional<double> ground = truth.terrain.HeightAt(x.x(), x.y());
    if (ground) heights.push_back(std::abs(x.z() - *ground));
  }
  score.points_on_terrain = heights.size();
  score.point_rms_m = Rms(heights);
  score.point_median_m = heights.empty() ? 0.0 : Median(heights);
  if (score.registered < score.photos) {
    score.notes.push_back(std::to_string(score.photos - score.registered) +
                          " photo(s) not registered");
  }
  return score;
}

}  // namespace shutterlab
