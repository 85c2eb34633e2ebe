#pragma once
// One reader for a rig dataset folder (docs/FORMATS.md "Rig dataset"), still or video: camera.json,
// gyro.csv and frames.csv read and checked once, every image frames.csv names checked to be there,
// and the gyro audited like any log (sim/trace_audit.h). validate starts here for both kinds.

#include "io/frames_csv.h"
#include "model/camera.h"
#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <filesystem>
#include <map>
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
  // camera.json's `mask` (ReadMask), CV_8U 0 / 255 (255 = may be used); empty when it names none.
  cv::Mat mask;
  // image_orientation.csv (ReadImageOrientation): the stabiliser's IORI per frame id; empty when
  // the dataset has none.
  std::map<int64_t, Eigen::Quaterniond> image_orientation;
};

// image_orientation.csv (docs/FORMATS.md "Import output", written by import for a GoPro clip with
// IORI): for each frame id that has one, the IORI quaternion as the camera wrote it (w, x, y, z;
// its axes and sense are not documented: validate tests which reading explains the images).
// Lines without IORI are left out. Throws IoError naming the file and line for a header without
// frame and iori_w..iori_z, a malformed number or a zero quaternion.
std::map<int64_t, Eigen::Quaterniond> ReadImageOrientation(const std::string& path);

// A mask image (docs/FORMATS.md camera.json `mask`; validate --mask, import --mask) for a camera of
// width x height: one channel (or colour channels that are all equal, a grey picture saved as RGB;
// an alpha channel is ignored), any depth; non-zero = may be used. Returns CV_8U 0 / 255. Throws
// IoError naming the file for a missing or unreadable file, another size, colours that differ, or
// a mask with no usable pixel.
cv::Mat ReadMask(const std::string& path, int width, int height);

// Reads and checks the folder. Throws IoError naming the file (and frames.csv line) for a missing
// folder or file, a malformed file, a gyro.csv of fewer than two samples, no frames, a frames.csv
// that mixes still and video lines, an image it names that is not there, or a bad mask.
RigDataset ReadRigDataset(const std::string& dataset_dir);

}  // namespace shutterlab
