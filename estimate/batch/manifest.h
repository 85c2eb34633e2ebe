#pragma once
// A batch manifest (docs/FORMATS.md "Batch manifest"): the flights, clips and datasets of a fleet,
// one [[item]] table each, with [defaults] for every item, in TOML (read by toml++), so that a
// person can write and review it by hand and `batch --scan` can write it for review.

#include <string>
#include <vector>

namespace shutterlab {

// The jobs an item may run, in the order they run (each may read what an earlier one wrote).
enum class BatchJob {
  kImport,    // a clip -> a video rig dataset (import)
  kAnalyze,   // a log alone (analyze LOG)
  kPhotos,    // a folder of photos, with its log when it has one (analyze --photos)
  kValidate,  // a rig dataset, or the clip's import (validate)
  kCorrect,   // the photos with their log, or the dataset with its validation (correct)
  kExport,    // the camera found, in other tools' files (export; analyze --photos --export)
};
const char* BatchJobName(BatchJob job);

struct BatchItem {
  std::string id;     // unique; names the item's folder ([A-Za-z0-9._-], not starting with '.')
  std::string group;  // the drone or camera it belongs to, for the fleet page (may be empty)
  // Inputs, absolute (the manifest's relative paths are read from the manifest's folder); empty
  // when not given.
  std::string log, photos, clip, dataset, triggers, camera, lens_profile;
  // Overrides; NaN / empty when not given.
  double readout_s;
  double altitude_m;
  std::vector<double> limits_m;
  // A clip's frames to import (import's --start-frame, --max-frames); -1 when not given.
  long start_frame = -1, max_frames = -1;
  std::vector<BatchJob> jobs;        // in BatchJob order, no repeats
  std::vector<std::string> exports;  // formats for kExport (shutterlab export --to)
  long line = 0;                     // where its [[item]] starts in the manifest
};

struct BatchManifest {
  std::string path;  // as given
  std::vector<BatchItem> items;
};

// Reads and checks a manifest: unknown keys, a wrong type, a missing or repeated id, a path that
// does not exist, a quantity without its unit, a job the item has no input for, each refused with
// IoError "MANIFEST:LINE: problem" (sim/check.h). Jobs not given are chosen from the inputs:
// a clip: import and validate; a dataset: validate; photos: photos; a log alone: analyze.
BatchManifest ReadBatchManifest(const std::string& path);

// The files an item reads, absolute, sorted: every regular file under each input path (a folder
// whole, its subfolders too).
std::vector<std::string> BatchItemInputFiles(const BatchItem& item);

}  // namespace shutterlab
