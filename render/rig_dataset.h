#pragma once
// One reader for a rig dataset folder (docs/FORMATS.md "Rig dataset"), still or video: camera.json,
// gyro.csv and frames.csv read and checked once, every image frames.csv names checked to be there,
// and the gyro audited like any log (sim/trace_audit.h). validate starts here for both kinds.

#include "render/camera.h"
#include "render/frames_csv.h"
#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <filesystem>
#include <string>
#include <vector>

namespace shutterlab {

struct RigDataset {
  std::filesystem::path dir;
  std::string camera_path, gyro_path, frames_path;  // for messages
  RigModel declared;                                // camera.json
  GyroTrace gyro;                                   // gyro.csv
  std::vector<FrameEntry> frames;                   // frames.csv, in file order (line = index + 2)
  // A video dataset leaves `ref` empty on every line (import, render of a clip); a still one names
  // a reference image on every line.
  bool video = false;
  std::vector<LogWarning> gyro_warnings;  // AuditTrace of gyro.csv
};

// Reads and checks the folder. Throws IoError naming the file (and frames.csv line) for a missing
// folder or file, a malformed file, a gyro.csv of fewer than two samples, no frames, a frames.csv
// that mixes still and video lines, or an image it names that is not there.
RigDataset ReadRigDataset(const std::string& dataset_dir);

}  // namespace shutterlab
