// `shutterlab analyze LOG`: per-image rolling-shutter distortion from a real flight log, with the
// flight table for the camera's readout and a verdict (estimate/paper/analyze.h).
// `shutterlab analyze --photos DIR [LOG]`: the same for a folder of photos, read with their
// metadata (io/photo_set.h, estimate/paper/photo_analysis.h).

#include "app/analyze_flags.h"
#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"
#include "estimate/export/exports.h"
#include "estimate/paper/log_pipeline.h"
#include "estimate/paper/photo_analysis.h"
#include "estimate/report/analysis_json.h"
#include "estimate/report/analyze_report.h"
#include "estimate/report/photo_json.h"
#include "estimate/report/photo_report.h"
#include "io/photo_set.h"
#include "sim/check.h"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab::app {
namespace {

// The paths of files named in a folder, for SayWritten.
std::vector<std::string> InDir(const std::string& dir, const std::vector<std::string>& names) {
  std::vector<std::string> paths;
  for (const std::string& name : names) paths.push_back(dir + "/" + name);
  return paths;
}

// --export: the photos' camera in each tool's files, all made in memory first, so that a format
// that refuses (pix4d: a fisheye) or is unknown stops the command before anything is written.
std::vector<std::pair<std::string, ExportOutput>> PhotoExports(const AnalyzeFlags& flags,
                                                               const nlohmann::json& photos) {
  std::vector<std::pair<std::string, ExportOutput>> exports;
  if (flags.export_formats.empty()) return exports;
  SHUTTERLAB_CHECK(!flags.out_dir.empty()) << "--export writes into --out DIR: give --out";
  const ExportCamera camera =
      ExportCameraFromPhotos(photos, "analyze --photos " + flags.photos_dir);
  for (const std::string& name : flags.export_formats) {
    const ExportFormat& format = FindExportFormat(name);
    try {
      exports.emplace_back(format.name, format.write(camera, {}));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--export ") + format.name + ": " + e.what() +
                                  " (nothing written; shutterlab export takes --force)");
    }
  }
  return exports;
}

// Writes each export into DIR/export_FORMAT/ and says what it wrote, a line a folder.
void WritePhotoExports(const std::string& dir,
                       const std::vector<std::pair<std::string, ExportOutput>>& exports) {
  for (const auto& [name, output] : exports) {
    const std::string folder = dir + "/export_" + name;
    SayWritten(folder, WriteExport(output, folder));
  }
}

// --photos DIR [LOG]: the photos alone (translation from their speed), or placed on the log.
void RunPhotos(const AnalyzeFlags& flags) {
  PhotoSetOptions read;
  const PhotoFlightOptions options = PhotoFlightOptionsFromFlags(flags, &read);
  const std::optional<LogInput> log =
      flags.log_path.empty() ? std::nullopt : std::optional<LogInput>(InputFromFlags(flags));
  const std::optional<TriggerInput> triggers = TriggersFromFlags(flags);
  SHUTTERLAB_CHECK(!triggers || log) << "--triggers places photos on a LOG: give the LOG too";
  AnalyzeReportOptions report = ReportFromFlags(flags);
  PhotoSet set;
  {
    Progress progress("photos", 1000);
    read.progress = [&progress](double f) { progress.Update(static_cast<size_t>(f * 1000)); };
    set = ReadPhotoSet(flags.photos_dir, read);
  }
  if (set.in_subfolders > 0) {
    std::cerr << "note: " << flags.photos_dir << ": " << set.in_subfolders
              << " photos in its subfolders were not read (give --recursive to read them)\n";
  }
  // What the profile gave the photos; with a LOG the analysed camera's notes are printed instead.
  if (read.lens_profile && !log) {
    for (const std::string& note : LensProfileNotes(set, *read.lens_profile))
      std::cerr << "note: " << note << "\n";
  }
  if (!log) {
    const PhotoAnalysis analysis = AnalyzePhotos(set, options.photos);
    const auto exports = PhotoExports(flags, PhotoAnalysisToJson(set, analysis)["photos"]);
    if (!flags.out_dir.empty()) {
      WritePhotoOutputs(flags.out_dir, set, analysis);
      PhotoReportPage(set, analysis).Write(flags.out_dir + "/report.html");
      SayWritten(flags.out_dir, InDir(flags.out_dir, {"report.html", "photos.csv", "exclude.txt",
                                                      "image_list.txt", "colmap_image_list.txt"}));
      WritePhotoExports(flags.out_dir, exports);
    }
    if (flags.json) {
      std::cout << JsonText(PhotoAnalysisToJson(set, analysis)) << "\n";
    } else {
      std::cout << PhotoAnalysisReport(set, analysis);
    }
    return;
  }
  PipelinePrinter printer;
  const PhotosOnLogRun run = RunPhotosOnLog(*log, set, options, triggers, printer.Events());
  printer.Done();
  const PhotoFlightResult& result = run.result;
  const std::optional<SensorPair>& pair = run.pair;
  const PhotoSet& analysed = result.set;  // with the log's speeds where the photos record none
  const auto exports = PhotoExports(flags, PhotoAnalysisToJson(analysed, result.photos)["photos"]);
  if (result.lens) {
    for (const std::string& note : result.lens->notes) std::cerr << "note: " << note << "\n";
  }
  if (!flags.out_dir.empty()) {
    WriteAnalyzeOutputs(flags.out_dir, result.log);
    report.camera_source = result.camera_source;
    AnalyzeReportPage(result.analyzed, result.log, report).Write(flags.out_dir + "/report.html");
    WritePhotoOutputs(flags.out_dir, analysed,
                      result.photos);  // its exclude.txt replaces analyze's
    SayWritten(flags.out_dir,
               InDir(flags.out_dir, {"report.html", "images.csv", "photos.csv", "exclude.txt",
                                     "image_list.txt", "colmap_image_list.txt"}));
    WritePhotoExports(flags.out_dir, exports);
  }
  if (flags.json) {
    nlohmann::json json = AnalyzeToJson(result.log);
    if (pair) json["pair"] = SensorPairToJson(*pair, flags.second_path);
    if (result.lens) json["lens_profile"] = LensProfileUseJson(*result.lens);
    json["photos"] = PhotoAnalysisToJson(analysed, result.photos);
    json["photos"]["camera_source"] = result.camera_source;
    std::cout << JsonText(json) << "\n";
  } else {
    if (pair) std::cout << SensorPairText(*pair, flags.log_path, flags.second_path) << "\n";
    std::cout << AnalyzeReport(result.log) << "\ncamera analysed: " << result.camera_source
              << "\n\n"
              << PhotoAnalysisReport(analysed, result.photos);
  }
}

void Run(const AnalyzeFlags& flags) {
  if (!flags.photos_dir.empty()) return RunPhotos(flags);
  SHUTTERLAB_CHECK(!flags.log_path.empty()) << "give a LOG, or --photos DIR";
  std::optional<LensProfileUse> lens;
  const AnalyzeOptions options = AnalyzeOptionsFromFlags(flags, &lens);
  const LogInput input = InputFromFlags(flags);
  options.Check();  // before the trigger file and the (possibly long) read
  const std::optional<TriggerInput> triggers = TriggersFromFlags(flags);
  const AnalyzeReportOptions report = ReportFromFlags(flags);
  PipelinePrinter printer;
  const AnalyzeRun run = RunAnalyze(input, options, triggers, printer.Events());
  printer.Done();
  const AnalyzeResult& result = run.result;
  if (!flags.out_dir.empty()) {
    WriteAnalyzeOutputs(flags.out_dir, result);
    AnalyzeReportPage(options, result, report).Write(flags.out_dir + "/report.html");
    SayWritten(flags.out_dir, InDir(flags.out_dir, {"report.html", "images.csv", "exclude.txt"}));
  }
  if (flags.json) {
    auto json = AnalyzeToJson(result);
    if (run.pair) json["pair"] = SensorPairToJson(*run.pair, flags.second_path);
    if (lens) json["lens_profile"] = LensProfileUseJson(*lens);
    std::cout << JsonText(json) << "\n";
  } else {
    if (run.pair) {
      std::cout << SensorPairText(*run.pair, flags.log_path, flags.second_path) << "\n";
    }
    std::cout << AnalyzeReport(result);
  }
}

const CommandRegistration kAnalyzeRegistration(80, [](CLI::App& app) {
  auto* cmd = app.add_subcommand("analyze",
                                 "per-image rolling-shutter distortion from a flight log (ULog, "
                                 "DataFlash, blackbox, GoPro MP4, gyro.csv, any CSV by --columns)");
  auto flags = std::make_shared<AnalyzeFlags>();
  const std::function<void()> typed = AddAnalyzeFlags(cmd, flags.get());
  return std::function<void()>([flags, typed] {
    typed();
    Run(*flags);
  });
});

}  // namespace
}  // namespace shutterlab::app
