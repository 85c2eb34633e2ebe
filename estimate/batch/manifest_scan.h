#pragma once
// `batch --scan DIR`: a folder tree (a card's dump, a survey archive) turned into a manifest for a
// person to review before running it: every rig dataset (a folder with camera.json and frames.csv
// or gyro.csv), phone clip (gyro.txt, framestamp.txt, frames/), GoPro MP4, photo folder (with the
// one log beside it, and a DJI .MRK trigger file, when there is one) and flight log, each found by
// its content, not its name.

#include <string>

namespace shutterlab {

struct ManifestScan {
  std::string toml;  // the manifest, paths relative to the scanned folder
  size_t logs = 0, photo_folders = 0, paired = 0, clips = 0, datasets = 0;
};

// Scans `dir` (its subfolders too; hidden ones and a batch's own output, a folder holding
// items/ID/made.json, are skipped). Ids are the items' paths with '/' as '_', made unique; the
// group is the first folder under `dir` when an item lies deeper. Throws IoError when dir cannot
// be read.
ManifestScan ScanForManifest(const std::string& dir);

}  // namespace shutterlab
