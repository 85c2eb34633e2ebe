#include "io/rig_dataset.h"

#include "io/image_io.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "sim/trace_audit.h"

#include <algorithm>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// Whether the dataset is a video (every line leaves ref empty), after checking that every line
// agrees and every image it names is there.
bool CheckFrameImages(const RigDataset& dataset) {
  const std::vector<FrameEntry>& entries = dataset.frames;
  const bool video = entries.front().ref.empty();
  for (size_t i = 0; i < entries.size(); ++i) {
    // frames.csv: a header line, then one frame a line.
    const long line = static_cast<long>(i) + 2;
    if (entries[i].ref.empty() != video) {
      throw IoError(IoMessage(dataset.frames_path, line,
                              video ? "a ref image in a video dataset (line 2 has none)"
                                    : "no ref image (a video dataset leaves ref empty on every "
                                      "line, line 2 has one)"));
    }
    std::vector<std::string> images = {entries[i].image};
    if (!video) images.push_back(entries[i].ref);
    for (const std::string& name : images) {
      if (name.empty() || !fs::is_regular_file(dataset.dir / name)) {
        throw IoError(IoMessage(dataset.frames_path, line, "image '" + name + "' not found"));
      }
    }
  }
  return video;
}

}  // namespace

cv::Mat ReadMask(const std::string& path, int width, int height) {
  if (!fs::is_regular_file(path)) throw IoError(IoMessage(path, 0, "mask not found"));
  const cv::Mat image = ReadImage(path);
  if (image.cols != width || image.rows != height) {
    throw IoError(IoMessage(path, 0,
                            "mask is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + ", the camera " +
                                std::to_string(width) + "x" + std::to_string(height)));
  }
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  const size_t colours = std::min<size_t>(channels.size(), 3);
  for (size_t c = 1; c < colours; ++c) {
    if (cv::countNonZero(channels[c] != channels[0]) > 0) {
      throw IoError(IoMessage(path, 0, "mask has colours (it must be grey: non-zero = use)"));
    }
  }
  cv::Mat mask = channels[0] != 0;  // CV_8U 0 / 255
  if (cv::countNonZero(mask) == 0) {
    throw IoError(IoMessage(path, 0, "mask leaves no pixel to use (non-zero = use)"));
  }
  return mask;
}

std::map<int64_t, Eigen::Quaterniond> ReadImageOrientation(const std::string& path) {
  const std::string text = ReadFileToString(path);
  LineCursor lines(text);
  std::vector<std::string_view> fields;
  const std::optional<std::string_view> header = lines.Next();
  if (!header) throw IoError(IoMessage(path, 1, "empty file"));
  SplitFields(*header, ',', &fields);
  const char* names[5] = {"frame", "iori_w", "iori_x", "iori_y", "iori_z"};
  int column[5];
  for (int k = 0; k < 5; ++k) {
    const auto it = std::find(fields.begin(), fields.end(), names[k]);
    if (it == fields.end()) {
      throw IoError(IoMessage(path, 1, std::string("no column '") + names[k] + "' in the header"));
    }
    column[k] = static_cast<int>(it - fields.begin());
  }
  std::map<int64_t, Eigen::Quaterniond> out;
  while (const std::optional<std::string_view> line = lines.Next()) {
    if (line->empty()) continue;
    SplitFields(*line, ',', &fields);
    const long at = lines.line_number();
    const auto field = [&](int k) {
      return column[k] < static_cast<int>(fields.size()) ? fields[column[k]] : std::string_view();
    };
    if (field(1).empty()) continue;  // no IORI near this frame
    const std::optional<int64_t> frame = ParseInt(field(0));
    if (!frame) throw IoError(IoMessage(path, at, "frame is not an integer"));
    double q[4];
    for (int k = 0; k < 4; ++k) {
      const std::optional<double> v = ParseDouble(field(k + 1));
      if (!v) throw IoError(IoMessage(path, at, std::string(names[k + 1]) + " is not a number"));
      q[k] = *v;
    }
    const Eigen::Quaterniond quaternion(q[0], q[1], q[2], q[3]);
    if (!(quaternion.norm() > 0.5)) throw IoError(IoMessage(path, at, "not a unit quaternion"));
    out[*frame] = quaternion.normalized();
  }
  return out;
}

RigDataset ReadRigDataset(const std::string& dataset_dir) {
  RigDataset dataset;
  dataset.dir = fs::path(dataset_dir);
  if (!fs::is_directory(dataset.dir)) {
    throw IoError(IoMessage(dataset_dir, 0, "not a dataset folder"));
  }
  dataset.camera_path = (dataset.dir / "camera.json").string();
  dataset.gyro_path = (dataset.dir / "gyro.csv").string();
  dataset.frames_path = (dataset.dir / "frames.csv").string();
  for (const std::string& path : {dataset.camera_path, dataset.gyro_path, dataset.frames_path}) {
    if (!fs::is_regular_file(path)) throw IoError(IoMessage(path, 0, "missing"));
  }
  dataset.declared = ReadRigModel(dataset.camera_path);
  dataset.gyro = ReadGyroCsv(dataset.gyro_path);
  if (dataset.gyro.size() < 2) {
    throw IoError(IoMessage(dataset.gyro_path, 0, "fewer than two samples"));
  }
  dataset.frames = ReadFramesCsv(dataset.frames_path);
  if (dataset.frames.empty()) throw IoError(IoMessage(dataset.frames_path, 0, "no frames"));
  dataset.video = CheckFrameImages(dataset);
  const fs::path orientation = dataset.dir / "image_orientation.csv";
  if (fs::is_regular_file(orientation)) {
    dataset.image_orientation = ReadImageOrientation(orientation.string());
  }
  if (!dataset.declared.mask.empty()) {
    dataset.mask = ReadMask((dataset.dir / dataset.declared.mask).string(),
                            dataset.declared.camera.width, dataset.declared.camera.height);
  }
  dataset.gyro_warnings = AuditTrace(dataset.gyro);
  return dataset;
}

}  // namespace shutterlab
