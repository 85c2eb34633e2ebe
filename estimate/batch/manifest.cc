#include "estimate/batch/manifest.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <toml++/toml.h>

namespace shutterlab {
namespace fs = std::filesystem;

const char* BatchJobName(BatchJob job) {
  switch (job) {
    case BatchJob::kImport:
      return "import";
    case BatchJob::kAnalyze:
      return "analyze";
    case BatchJob::kPhotos:
      return "photos";
    case BatchJob::kValidate:
      return "validate";
    case BatchJob::kCorrect:
      return "correct";
    case BatchJob::kExport:
      return "export";
  }
  return "?";
}

namespace {

constexpr BatchJob kAllJobs[] = {BatchJob::kImport,   BatchJob::kAnalyze, BatchJob::kPhotos,
                                 BatchJob::kValidate, BatchJob::kCorrect, BatchJob::kExport};
const char* const kExportFormats[] = {"colmap",    "odm",   "kalibr", "gyroflow",
                                      "metashape", "pix4d", "vins"};

// What a path key must name: a file, a folder, or either (a photo folder may be one photo; a
// clip is a GoPro .mp4 or a phone clip's folder).
enum class PathKind { kFile, kFolder, kEither };
struct PathKey {
  const char* key;
  std::string BatchItem::*field;
  PathKind kind;
  bool per_item;  // an input of one flight: not allowed in [defaults]
};
const PathKey kPathKeys[] = {
    {"log", &BatchItem::log, PathKind::kFile, true},
    {"photos", &BatchItem::photos, PathKind::kEither, true},
    {"clip", &BatchItem::clip, PathKind::kEither, true},
    {"dataset", &BatchItem::dataset, PathKind::kFolder, true},
    {"triggers", &BatchItem::triggers, PathKind::kFile, true},
    {"camera", &BatchItem::camera, PathKind::kFile, false},
    {"lens_profile", &BatchItem::lens_profile, PathKind::kFile, false},
};
const char* const kOtherKeys[] = {"id",   "group",  "readout",     "altitude",  "limit",
                                  "jobs", "export", "start_frame", "max_frames"};

class ManifestReader {
 public:
  ManifestReader(std::string path) : path_(std::move(path)) {
    folder_ = fs::absolute(fs::path(path_)).parent_path();
  }

  [[noreturn]] void Fail(const toml::node& node, const std::string& problem) const {
    throw IoError(IoMessage(path_, static_cast<long>(node.source().begin.line), problem));
  }
  [[noreturn]] void Fail(long line, const std::string& problem) const {
    throw IoError(IoMessage(path_, line, problem));
  }

  std::string String(const toml::node& node, const std::string& key) const {
    const auto value = node.value<std::string>();
    if (!node.is_string() || !value) Fail(node, "'" + key + "' must be a string (in quotes)");
    return *value;
  }

  std::vector<std::string> StringList(const toml::node& node, const std::string& key) const {
    if (node.is_string()) return {String(node, key)};
    const toml::array* array = node.as_array();
    if (!array) Fail(node, "'" + key + "' must be a string or a list of strings");
    std::vector<std::string> values;
    for (const toml::node& element : *array) values.push_back(String(element, key));
    return values;
  }

  // A whole number of at least `least`.
  long Count(const toml::node& node, const std::string& key, long least) const {
    const auto value = node.value_exact<int64_t>();
    if (!value || *value < least)
      Fail(node, "'" + key + "' must be a whole number of at least " + std::to_string(least) +
                     " (no quotes)");
    return static_cast<long>(*value);
  }

  double Quantity(const toml::node& node, const std::string& key, const char* unit,
                  const char* bare_means) const {
    try {
      return ParseQuantity(String(node, key), unit, key, bare_means);
    } catch (const std::invalid_argument& e) {
      Fail(node, WithoutCheckLocation(e.what()));
    }
  }

  std::string ExistingPath(const toml::node& node, const PathKey& key) const {
    const std::string text = String(node, key.key);
    if (text.empty()) Fail(node, std::string("'") + key.key + "' is empty");
    const fs::path path = fs::path(text).is_absolute() ? fs::path(text) : folder_ / text;
    std::error_code error;
    const fs::file_status status = fs::status(path, error);
    if (!fs::exists(status)) {
      Fail(node, std::string(key.key) + " '" + text + "' does not exist (" + path.string() +
                     "; relative paths are read from the manifest's folder)");
    }
    if (key.kind == PathKind::kFile && !fs::is_regular_file(status))
      Fail(node, std::string(key.key) + " '" + text + "' is not a file");
    if (key.kind == PathKind::kFolder && !fs::is_directory(status))
      Fail(node, std::string(key.key) + " '" + text + "' is not a folder");
    return path.lexically_normal().string();
  }

  // One key of [defaults] or of an [[item]] into item; `jobs_given` says whether it set jobs.
  void ReadKey(const std::string& key, const toml::node& node, bool in_defaults, BatchItem* item,
               bool* jobs_given) const {
    for (const PathKey& path_key : kPathKeys) {
      if (key != path_key.key) continue;
      if (in_defaults && path_key.per_item)
        Fail(node, "'" + key + "' is one flight's input: give it in each [[item]], not [defaults]");
      item->*path_key.field = ExistingPath(node, path_key);
      return;
    }
    if (key == "id") {
      if (in_defaults) Fail(node, "'id' names one item: give it in each [[item]]");
      item->id = String(node, key);
    } else if (key == "group") {
      item->group = String(node, key);
    } else if (key == "readout") {
      item->readout_s = Quantity(node, key, "s", "ms");
      if (!(item->readout_s > 0 && item->readout_s < 1))
        Fail(node, "'readout' must be above 0 and below 1 s (a rolling shutter's readout)");
    } else if (key == "altitude") {
      item->altitude_m = Quantity(node, key, "m", "m");
      if (!(item->altitude_m > 0)) Fail(node, "'altitude' must be above 0 m");
    } else if (key == "limit") {
      item->limits_m.clear();
      const toml::array* array = node.as_array();
      if (array) {
        for (const toml::node& element : *array)
          item->limits_m.push_back(Quantity(element, key, "m", "cm"));
      } else {
        item->limits_m.push_back(Quantity(node, key, "m", "cm"));
      }
      for (const double limit : item->limits_m)
        if (!(limit > 0)) Fail(node, "every 'limit' must be above 0 m");
    } else if (key == "start_frame" || key == "max_frames") {
      if (in_defaults)
        Fail(node, "'" + key + "' chooses one clip's frames: give it in its [[item]]");
      (key == "start_frame" ? item->start_frame : item->max_frames) =
          Count(node, key, key == "start_frame" ? 0 : 1);
    } else if (key == "jobs") {
      item->jobs = Jobs(node);
      *jobs_given = true;
    } else if (key == "export") {
      item->exports = StringList(node, key);
      for (const std::string& format : item->exports) {
        if (std::find_if(std::begin(kExportFormats), std::end(kExportFormats),
                         [&](const char* f) { return format == f; }) == std::end(kExportFormats))
          Fail(node, "unknown export format '" + format + "' (" + ExportFormatList() + ")");
      }
    } else {
      Fail(node, "unknown key '" + key + "' (" + KeyList() + ")");
    }
  }

  std::vector<BatchJob> Jobs(const toml::node& node) const {
    std::set<BatchJob> jobs;
    for (const std::string& name : StringList(node, "jobs")) {
      const auto* job = std::find_if(std::begin(kAllJobs), std::end(kAllJobs),
                                     [&](BatchJob j) { return name == BatchJobName(j); });
      if (job == std::end(kAllJobs)) Fail(node, "unknown job '" + name + "' (" + JobList() + ")");
      jobs.insert(*job);
    }
    return {jobs.begin(), jobs.end()};
  }

  // The jobs an item runs: those given (a clip's import added: it is how a clip becomes a
  // dataset) or those its inputs call for, each checked against the inputs it needs.
  void SettleJobs(BatchItem* item, bool jobs_given) const {
    const bool has_dataset = !item->dataset.empty() || !item->clip.empty();
    if (!item->clip.empty() && !item->dataset.empty())
      Fail(item->line, "item '" + item->id + "' gives both a clip and a dataset: give one");
    if (!jobs_given) {
      item->jobs.clear();
      if (has_dataset)
        item->jobs = {BatchJob::kValidate};
      else if (!item->photos.empty())
        item->jobs = {BatchJob::kPhotos};
      else if (!item->log.empty())
        item->jobs = {BatchJob::kAnalyze};
      else
        Fail(item->line, "item '" + item->id + "' has no input: give log, photos, clip or dataset");
    }
    if (item->clip.empty() && (item->start_frame >= 0 || item->max_frames >= 0))
      Fail(item->line,
           "item '" + item->id +
               "': start_frame and max_frames choose a clip's frames, and it has no clip");
    if (!item->clip.empty() && item->jobs.front() != BatchJob::kImport)
      item->jobs.insert(item->jobs.begin(), BatchJob::kImport);
    const auto has = [&](BatchJob job) {
      return std::find(item->jobs.begin(), item->jobs.end(), job) != item->jobs.end();
    };
    const auto need = [&](bool ok, BatchJob job, const std::string& what) {
      if (!ok)
        Fail(item->line, "item '" + item->id + "': job '" + BatchJobName(job) + "' needs " + what);
    };
    if (has(BatchJob::kAnalyze)) need(!item->log.empty(), BatchJob::kAnalyze, "a log");
    if (has(BatchJob::kPhotos)) need(!item->photos.empty(), BatchJob::kPhotos, "photos");
    if (has(BatchJob::kValidate)) need(has_dataset, BatchJob::kValidate, "a dataset or a clip");
    if (has(BatchJob::kCorrect)) {
      need((!item->photos.empty() && !item->log.empty()) ||
               (has_dataset && has(BatchJob::kValidate)),
           BatchJob::kCorrect, "photos with their log, or a dataset or clip with the validate job");
    }
    if (has(BatchJob::kExport)) {
      need(has(BatchJob::kPhotos) || has(BatchJob::kValidate), BatchJob::kExport,
           "the photos or the validate job (it exports what they found)");
      need(!item->exports.empty(), BatchJob::kExport,
           "export = [\"odm\", ...] (" + ExportFormatList() + ")");
    }
  }

  static std::string JobList() {
    std::string list;
    for (BatchJob job : kAllJobs)
      list += (list.empty() ? "" : ", ") + std::string(BatchJobName(job));
    return list;
  }
  static std::string ExportFormatList() {
    std::string list;
    for (const char* format : kExportFormats)
      list += (list.empty() ? "" : ", ") + std::string(format);
    return list;
  }
  static std::string KeyList() {
    std::string list;
    for (const PathKey& key : kPathKeys) list += (list.empty() ? "" : ", ") + std::string(key.key);
    for (const char* key : kOtherKeys) list += ", " + std::string(key);
    return list;
  }

  BatchManifest Read() {
    const std::string text = ReadFileToString(path_);
    toml::table root;
    try {
      root = toml::parse(text, path_);
    } catch (const toml::parse_error& e) {
      Fail(static_cast<long>(e.source().begin.line), std::string(e.description()));
    }
    BatchItem defaults;
    defaults.readout_s = defaults.altitude_m = std::numeric_limits<double>::quiet_NaN();
    bool default_jobs = false;
    const toml::array* items = nullptr;
    for (auto&& [key, node] : root) {
      if (key == "defaults") {
        const toml::table* table = node.as_table();
        if (!table) Fail(node, "[defaults] must be a table");
        for (auto&& [k, v] : *table)
          ReadKey(std::string(k.str()), v, true, &defaults, &default_jobs);
      } else if (key == "item") {
        items = node.as_array();
        if (!items || !items->is_array_of_tables()) Fail(node, "items are [[item]] tables");
      } else {
        Fail(node, "unknown table '" + std::string(key.str()) +
                       "' (a manifest holds [defaults] and [[item]]s)");
      }
    }
    if (!items || items->empty())
      Fail(1, "no [[item]]: a manifest lists its flights as [[item]] tables");
    BatchManifest manifest;
    manifest.path = path_;
    std::map<std::string, long> ids;
    for (const toml::node& node : *items) {
      BatchItem item = defaults;
      item.line = static_cast<long>(node.source().begin.line);
      bool jobs_given = default_jobs;
      for (auto&& [k, v] : *node.as_table())
        ReadKey(std::string(k.str()), v, false, &item, &jobs_given);
      CheckId(item, &ids);
      SettleJobs(&item, jobs_given);
      manifest.items.push_back(std::move(item));
    }
    return manifest;
  }

  void CheckId(const BatchItem& item, std::map<std::string, long>* ids) const {
    if (item.id.empty()) Fail(item.line, "an [[item]] without an id (id = \"2026-11-03_field7\")");
    const bool plain = std::all_of(item.id.begin(), item.id.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
    });
    if (!plain || item.id[0] == '.' || item.id.size() > 200)
      Fail(item.line, "id '" + item.id +
                          "' must be letters, digits, '.', '_' or '-' (it names a folder), not "
                          "starting with '.'");
    const auto [at, inserted] = ids->emplace(item.id, item.line);
    if (!inserted)
      Fail(item.line,
           "id '" + item.id + "' is given twice (line " + std::to_string(at->second) + " too)");
  }

 private:
  std::string path_;
  fs::path folder_;
};

}  // namespace

BatchManifest ReadBatchManifest(const std::string& path) { return ManifestReader(path).Read(); }

std::vector<std::string> BatchItemInputFiles(const BatchItem& item) {
  std::vector<std::string> files;
  for (const PathKey& key : kPathKeys) {
    const std::string& path = item.*key.field;
    if (path.empty()) continue;
    if (fs::is_directory(path)) {
      for (const auto& entry : fs::recursive_directory_iterator(path)) {
        if (entry.is_regular_file()) files.push_back(entry.path().string());
      }
    } else {
      files.push_back(path);
    }
  }
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());
  return files;
}

}  // namespace shutterlab
