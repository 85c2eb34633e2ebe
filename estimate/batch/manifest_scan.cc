#include "estimate/batch/manifest_scan.h"

#include "io/photo_set.h"
#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/log_format.h"
#include "sim/text_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <vector>

namespace shutterlab {
namespace fs = std::filesystem;
namespace {

struct FoundItem {
  std::string kind;           // "dataset", "clip", "photos", "log"
  fs::path path;              // relative to the scanned folder
  std::string log, triggers;  // a photo folder's
  size_t photos = 0;
};

bool LooksLikeRawCounts(std::string_view head) {
  LineCursor lines(head.substr(0, head.rfind('\n') + 1));
  size_t rows = 0;
  while (auto line = lines.Next()) {
    if (line->empty()) continue;
    std::vector<std::string_view> fields;
    SplitFields(*line, ',', &fields);
    const bool numbers = fields.size() >= 4 &&
                         std::all_of(fields.begin(), fields.begin() + 4,
                                     [](std::string_view f) { return ParseDouble(f).has_value(); });
    if (!numbers && lines.line_number() > 1) return false;  // line 1 may be a header
    rows += numbers;
    if (rows == 3) return true;
  }
  return rows > 0;
}

// The log format of a file by its first 16 KiB, or nullopt for anything that is not a log. Names
// that are never logs (a camera.json, a page, a picture) are not opened.
std::optional<LogFormat> LogFormatOf(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* never : {".json", ".toml", ".md", ".html", ".png", ".xml", ".mrk", ".pdf",
                            ".yaml", ".txt", ".srt", ".lrf", ".thm", ".mov", ".wav"}) {
    if (ext == never) return std::nullopt;
  }
  if (IsPhotoFileName(path.filename().string())) return std::nullopt;
  std::ifstream file(path, std::ios::binary);
  std::string head(16 * 1024, '\0');
  file.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(file.gcount()));
  if (head.empty()) return std::nullopt;
  try {
    const LogFormat format = DetectFlightLogFormat(head, path.string());
    // Raw counts are the readers' last guess for any text (any header, then rows): here they
    // must look like samples, four numbers or more on each of the first rows after the header.
    if (format == LogFormat::kRaw && !LooksLikeRawCounts(head)) return std::nullopt;
    return format;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

bool IsBatchOutput(const fs::path& dir) {
  std::error_code error;
  if (!fs::is_directory(dir / "items", error)) return false;
  for (const auto& entry : fs::directory_iterator(dir / "items", error))
    if (fs::exists(entry.path() / "made.json")) return true;
  return false;
}

class Scanner {
 public:
  explicit Scanner(fs::path root) : root_(std::move(root)) {}

  void Folder(const fs::path& dir) {
    if (IsBatchOutput(dir)) return;
    const fs::path relative = dir.lexically_relative(root_);
    if (fs::exists(dir / "camera.json") &&
        (fs::exists(dir / "frames.csv") || fs::exists(dir / "gyro.csv"))) {
      found_.push_back({"dataset", relative, "", "", 0});
      return;
    }
    if (fs::exists(dir / "gyro.txt") && fs::exists(dir / "framestamp.txt")) {
      found_.push_back({"clip", relative, "", "", 0});
      return;
    }
    std::vector<fs::path> files, folders;
    for (const auto& entry : fs::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      if (name.empty() || name[0] == '.') continue;
      if (entry.is_directory())
        folders.push_back(entry.path());
      else if (entry.is_regular_file())
        files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    std::sort(folders.begin(), folders.end());
    FoundItem photos{"photos", relative, "", "", 0};
    std::vector<fs::path> logs;
    for (const fs::path& file : files) {
      if (IsPhotoFileName(file.filename().string())) {
        ++photos.photos;
      } else if (file.extension() == ".MRK" || file.extension() == ".mrk") {
        photos.triggers = file.lexically_relative(root_).string();
      } else if (const auto format = LogFormatOf(file)) {
        if (*format == LogFormat::kGoproMp4)
          found_.push_back({"clip", file.lexically_relative(root_), "", "", 0});
        else
          logs.push_back(file);
      }
    }
    // The one log beside a photo folder is its flight's; several are listed alone.
    if (photos.photos > 0) {
      if (logs.size() == 1) {
        photos.log = logs.front().lexically_relative(root_).string();
        logs.clear();
      }
      found_.push_back(photos);
    }
    for (const fs::path& log : logs)
      found_.push_back({"log", log.lexically_relative(root_), "", "", 0});
    for (const fs::path& folder : folders) Folder(folder);
  }

  ManifestScan Manifest() const;

 private:
  fs::path root_;
  std::vector<FoundItem> found_;
};

// A TOML basic string.
std::string Quoted(const std::string& text) {
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

ManifestScan Scanner::Manifest() const {
  ManifestScan scan;
  scan.toml = "# A manifest made by `shutterlab batch --scan " + root_.string() +
              "`: review it (ids, groups, jobs, the camera or\n# lens profile of each drone), then "
              "`shutterlab batch THIS_FILE --out OUT`. Keys: docs/FORMATS.md \"Batch manifest\".\n"
              "# Paths are relative to this file's folder: keep it in the scanned folder.\n\n"
              "[defaults]\nlimit = [\"5cm\", \"10cm\"]\n";
  std::set<std::string> ids;
  for (const FoundItem& item : found_) {
    std::string id = item.path.string();
    if (item.kind == "log" || item.kind == "clip") id = item.path.parent_path() / item.path.stem();
    for (char& c : id) {
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-'))
        c = '_';
    }
    while (!id.empty() && (id[0] == '.' || id[0] == '_')) id.erase(0, 1);
    if (id.empty()) id = "item";
    std::string unique = id;
    for (int n = 2; ids.count(unique); ++n) unique = id + "-" + std::to_string(n);
    ids.insert(unique);
    scan.toml += "\n[[item]]\nid = " + Quoted(unique) + "\n";
    const auto parts = std::distance(item.path.begin(), item.path.end());
    if (parts >= 2) scan.toml += "group = " + Quoted(item.path.begin()->string()) + "\n";
    if (item.kind == "photos") {
      scan.toml += "photos = " + Quoted(item.path.empty() ? "." : item.path.string()) + "  # " +
                   std::to_string(item.photos) + " photos\n";
      if (!item.log.empty()) scan.toml += "log = " + Quoted(item.log) + "\n";
      if (!item.triggers.empty()) scan.toml += "triggers = " + Quoted(item.triggers) + "\n";
      ++scan.photo_folders;
      scan.paired += !item.log.empty();
    } else {
      scan.toml += item.kind + " = " + Quoted(item.path.string()) + "\n";
      ++(item.kind == "log" ? scan.logs : item.kind == "clip" ? scan.clips : scan.datasets);
    }
  }
  return scan;
}

}  // namespace

ManifestScan ScanForManifest(const std::string& dir) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) throw IoError(IoMessage(dir, 0, "is not a folder to scan"));
  Scanner scanner(fs::absolute(dir).lexically_normal());
  try {
    scanner.Folder(fs::absolute(dir).lexically_normal());
  } catch (const fs::filesystem_error& e) {
    throw IoError(IoMessage(e.path1().string(), 0, "cannot be read: " + e.code().message()));
  }
  return scanner.Manifest();
}

}  // namespace shutterlab
