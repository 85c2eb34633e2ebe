#include "render/rig_dataset.h"

#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/trace_audit.h"

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
  dataset.gyro_warnings = AuditTrace(dataset.gyro);
  return dataset;
}

}  // namespace shutterlab
