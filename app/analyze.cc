// `shutterlab analyze LOG`: per-image rolling-shutter distortion from a real flight log, with the
// flight table for the camera's readout and a verdict (estimate/analyze.h).
// `shutterlab analyze --photos DIR [LOG]`: the same for a folder of photos, read with their
// metadata (render/photo_set.h, estimate/paper/photo_analysis.h).

#include "estimate/paper/analyze.h"

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/paper/flight.h"
#include "estimate/paper/photo_analysis.h"
#include "estimate/paper/photo_flight.h"
#include "estimate/report/analysis_json.h"
#include "estimate/report/analyze_report.h"
#include "estimate/report/photo_json.h"
#include "render/image_io.h"
#include "render/lens_profile.h"
#include "render/photo_set.h"
#include "render/pictures.h"
#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/trigger_file.h"
#include "sim/sensor_pair.h"
#include "sim/units.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab::app {
namespace {

struct AnalyzeCommand {
  std::string log_path;
  std::string format = "auto";
  int log_index = -1;
  int range_dps = 250;
  ColumnFlags column_flags;  // --time-unit, --columns, --delimiter, --rate-unit
  std::string camera_path;
  std::string lens_profile_path;
  std::string readout = "30ms";
  double altitude_m = 50.0;
  double focal_px = 1100.0;
  std::string size = "1280x960";
  std::string triggers_path;
  std::string second_path;
  std::string every;
  std::string latency = "0";
  std::vector<std::string> limits{"5cm", "10cm"};
  double noise_allowance_arcsec = 20.0;
  std::string out_dir;
  std::string scene_path;
  std::string photos_dir;
  std::string photo_utc_offset;
  bool json = false;
  bool altitude_given = false;
  bool readout_given = false;
  bool focal_given = false;
};

RigModel RigFromFlags(const AnalyzeCommand& command) {
  RigModel rig;
  const size_t x = command.size.find_first_of("xX");
  int width = 0, height = 0;
  try {
    SHUTTERLAB_CHECK(x != std::string::npos) << "";
    width = std::stoi(command.size.substr(0, x));
    height = std::stoi(command.size.substr(x + 1));
  } catch (const std::exception&) {
    throw std::invalid_argument("--size must be WxH, e.g. 1280x960 (got '" + command.size + "')");
  }
  rig.camera.width = width;
  rig.camera.height = height;
  rig.camera.fx = rig.camera.fy = command.focal_px;
  rig.camera.cx = 0.5 * (width - 1);
  rig.camera.cy = 0.5 * (height - 1);
  rig.shutter.readout_s = ParseDurationS(command.readout);
  rig.altitude_m = command.altitude_m;
  return rig;
}

// What the user gave that wins over the photos' own values: --camera's focal length and readout,
// --readout, --focal-px and --altitude (the flags over the camera file).
PhotoSetOptions PhotoOptionsFromFlags(const AnalyzeCommand& command) {
  PhotoSetOptions options;
  if (!command.camera_path.empty()) {
    const RigModel rig = ReadRigModel(command.camera_path);
    options.readout_s = rig.shutter.readout_s;
    options.readout_origin = ReadoutOrigin::kCameraFile;
    options.readout_text = "camera.json " + command.camera_path;
    options.focal_px = 0.5 * (rig.camera.fx + rig.camera.fy);
    options.focal_text = "camera.json " + command.camera_path;
  }
  if (command.readout_given) {
    options.readout_s = ParseDurationS(command.readout);
    options.readout_origin = ReadoutOrigin::kUser;
    options.readout_text = "--readout " + command.readout;
  }
  if (command.focal_given) {
    options.focal_px = command.focal_px;
    options.focal_text = "--focal-px";
  }
  if (command.altitude_given) options.altitude_m = command.altitude_m;
  if (!command.lens_profile_path.empty())
    options.lens_profile = ReadLensProfile(command.lens_profile_path);
  return options;
}

// analyze's options from the flags; the triggers come later (they need the log). *lens: the lens
// profile's use, when --lens-profile is given (its lens, and its readout unless --readout was
// typed).
AnalyzeOptions AnalyzeOptionsFromFlags(const AnalyzeCommand& command,
                                       std::optional<LensProfileUse>* lens) {
  AnalyzeOptions options;
  if (!command.camera_path.empty()) {
    options.rig = ReadRigModel(command.camera_path);
    if (command.altitude_given) options.rig.altitude_m = command.altitude_m;
  } else {
    options.rig = RigFromFlags(command);
  }
  if (lens && !command.lens_profile_path.empty()) {
    *lens = ScaleLensProfile(ReadLensProfile(command.lens_profile_path), options.rig.camera.width,
                             options.rig.camera.height);
    ApplyLensProfile(&**lens, &options.rig, command.readout_given);
    for (const std::string& note : (*lens)->notes) std::cerr << "note: " << note << "\n";
  }
  options.limits_m.clear();
  for (const std::string& text : command.limits) options.limits_m.push_back(ParseLengthM(text));
  options.noise_allowance_arcsec = command.noise_allowance_arcsec;
  // --altitude wins, then camera.json; without either the log's height above ground beats 50 m.
  options.use_log_altitude = !command.altitude_given && command.camera_path.empty();
  if (!command.every.empty()) options.every_s = ParseDurationS(command.every);
  options.trigger_latency_s = ParseDurationS(command.latency);
  // The report's charts, shading, histograms and pictures, and its Allan deviation.
  if (!command.out_dir.empty()) options.plots = AnalyzePlotOptions{};
  options.allan = !command.out_dir.empty();
  return options;
}

FlightLogReadOptions ReadOptionsFromFlags(const AnalyzeCommand& command) {
  FlightLogReadOptions read;
  read.format = ParseLogFormat(command.format);
  read.log_index = command.log_index;
  read.raw.range_dps = command.range_dps;
  command.column_flags.Apply(&read);
  read.Check();
  return read;
}

std::optional<TriggerFile> TriggersFromFlags(const AnalyzeCommand& command) {
  if (command.triggers_path.empty()) return std::nullopt;
  TriggerFile triggers = ReadTriggerFile(command.triggers_path);
  PrintLogWarnings(command.triggers_path, triggers.warnings);
  return triggers;
}

// What reading the trigger file lost, named by the file: it goes with the log's warnings into the
// outputs (printed on stderr already, when it was read).
std::vector<LogWarning> TriggerWarnings(const std::optional<TriggerFile>& triggers,
                                        const std::string& path) {
  std::vector<LogWarning> warnings;
  if (!triggers) return warnings;
  const std::string name = std::filesystem::path(path).filename().string();
  for (LogWarning w : triggers->warnings) {
    w.message = "trigger file " + name + ": " + w.message;
    warnings.push_back(std::move(w));
  }
  return warnings;
}

// The image triggers of a trigger file on the log's clock, and what they are (options).
void SetTriggers(const TriggerFile& triggers, const FlightLog& log, const std::string& path,
                 AnalyzeOptions* options) {
  options->triggers = TriggersOnLogClock(triggers, log, path);
  options->triggers_source =
      "trigger file " + std::filesystem::path(path).filename().string() + ": " + triggers.source;
}

// LOG and --second's LOG2, opened for the streamed analysis's passes (a log on a pipe copied once
// to a temporary file that every pass reads).
struct AnalyzedLogs {
  ReopenableFile first;
  std::optional<ReopenableFile> second;
  explicit AnalyzedLogs(const AnalyzeCommand& command) : first(command.log_path) {
    if (!command.second_path.empty()) second.emplace(command.second_path);
  }
  // After the last pass: it read the logs as the first did (IoError otherwise).
  void CheckUnchanged() const {
    first.CheckUnchanged();
    if (second) second->CheckUnchanged();
  }
};

// With --second, the pair as AnalyzeStream reads it, fused on the first log's clock
// (FitPairInPasses; the still segment that weighs the fusion searched on the first log), fused
// chunk by chunk each time the analysis opens it. The same pair and fused samples as
// FuseSensorPair on the logs read whole.
AnalyzeLogSource PairStreamSource(const AnalyzeCommand& command, const FlightLogReadOptions& read,
                                  const std::optional<TriggerFile>& triggers, FlightLogStream first,
                                  const AnalyzedLogs& logs, std::optional<SensorPair>* pair) {
  FlightLog first_log = first.log;
  auto fitted = std::make_shared<const PairInPasses>(
      FitPairInPasses(logs.first, *logs.second, read, std::move(first), std::nullopt));
  *pair = fitted->pair;
  // The fused log: the first's metadata, both logs' warnings, the fused samples.
  FlightLog fused = std::move(first_log);
  fused.warnings = fitted->warnings;
  AnalyzeLogSource source;
  source.open = [fused, fitted] {
    FlightLogStream stream;
    stream.log = fused;
    stream.gyro = fitted->OpenFused();
    stream.audit_warnings = false;  // both logs' audits are in fused.warnings
    return stream;
  };
  source.more_warnings = TriggerWarnings(triggers, command.triggers_path);
  return source;
}

// The log as AnalyzeStream reads it: first is its first stream, already opened (its metadata
// read); each later pass opens the log again. Prints the log's warnings when it has been read
// through; the trigger file's go after them. With --second, the pair fused (PairStreamSource).
AnalyzeLogSource StreamSource(const AnalyzeCommand& command, const FlightLogReadOptions& read,
                              const std::optional<TriggerFile>& triggers, FlightLogStream first,
                              const AnalyzedLogs& logs, std::optional<SensorPair>* pair) {
  if (!command.second_path.empty())
    return PairStreamSource(command, read, triggers, std::move(first), logs, pair);
  auto first_left = std::make_shared<std::optional<FlightLogStream>>(std::move(first));
  AnalyzeLogSource source;
  source.open = [first_left, file = logs.first, &read] {
    if (!*first_left) return OpenFlightLog(file, read);
    FlightLogStream stream = std::move(**first_left);
    first_left->reset();
    return stream;
  };
  source.more_warnings = TriggerWarnings(triggers, command.triggers_path);
  source.on_read = [&command](const std::vector<LogWarning>& warnings) {
    PrintLogWarnings(command.log_path, warnings);
  };
  return source;
}

// The log analysed as a stream (AnalyzeStream), in bounded memory whatever its length: what
// `analyze LOG` does for every log, from a file or a pipe, with --out too (the report draws
// bounded plots).
AnalyzeResult AnalyzeStreamed(const AnalyzeCommand& command, const FlightLogReadOptions& read,
                              const std::optional<TriggerFile>& triggers, AnalyzeOptions options,
                              std::optional<SensorPair>* pair) {
  // Opened once for the triggers (a GPS-timed file needs the log's GPS fixes); that stream is
  // the analysis's first.
  const AnalyzedLogs logs(command);
  FlightLogStream first =
      OpenFlightLogShowingProgress(logs.first.Open(), command.log_path, read, "analyze");
  if (triggers) SetTriggers(*triggers, first.log, command.triggers_path, &options);
  const AnalyzeLogSource source =
      StreamSource(command, read, triggers, std::move(first), logs, pair);
  Progress progress("analyze", 1000);
  options.progress = [&progress](double f) { progress.Update(static_cast<size_t>(f * 1000)); };
  AnalyzeResult result = AnalyzeStream(source, options);
  logs.CheckUnchanged();
  // The flight table's own warnings join the log's on stderr, as they do in the --json's list.
  if (result.flight) PrintLogWarnings(command.log_path, result.flight->warnings);
  return result;
}

AnalyzeReportOptions ReportFromFlags(const AnalyzeCommand& command) {
  SHUTTERLAB_CHECK(command.scene_path.empty() || !command.out_dir.empty())
      << "--scene is for the report: give --out DIR too";
  AnalyzeReportOptions report;
  report.log_name = std::filesystem::path(command.log_path).filename().string();
  if (!command.scene_path.empty()) {
    report.scene = ToRgb8(ReadImage(command.scene_path));
    report.scene_name = std::filesystem::path(command.scene_path).filename().string();
  }
  return report;
}

// The photos placed and analysed on the LOG, read as a stream in bounded memory whatever its
// length.
PhotoFlightResult PhotosOnLog(const AnalyzeCommand& command, const FlightLogReadOptions& read,
                              const PhotoSet& set, const std::optional<TriggerFile>& triggers,
                              const PhotoFlightOptions& options, std::optional<SensorPair>* pair) {
  const TriggerFile* trigger_file = triggers ? &*triggers : nullptr;
  const AnalyzedLogs logs(command);
  FlightLogStream first =
      OpenFlightLogShowingProgress(logs.first.Open(), command.log_path, read, "analyze");
  const FlightLog metadata = first.log;  // the samples stay in the stream
  const AnalyzeLogSource source =
      StreamSource(command, read, triggers, std::move(first), logs, pair);
  try {
    PhotoFlightResult result =
        AnalyzePhotoFlightStream(set, metadata, source, trigger_file, options);
    logs.CheckUnchanged();
    if (result.log.flight) PrintLogWarnings(command.log_path, result.log.flight->warnings);
    return result;
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(command.log_path + ": " + e.what());
  }
}

// --photos DIR [LOG]: the photos alone (translation from their speed), or placed on the log.
void RunPhotos(const AnalyzeCommand& command) {
  PhotoSetOptions read = PhotoOptionsFromFlags(command);
  read.Check();
  PhotoFlightOptions options;
  options.analyze = AnalyzeOptionsFromFlags(command, nullptr);
  options.lens_profile = read.lens_profile;
  options.photos.limits_m = options.analyze.limits_m;
  options.rig_given = !command.camera_path.empty();
  options.altitude_given = command.altitude_given;
  options.readout_given = command.readout_given;
  if (!command.photo_utc_offset.empty()) {
    options.clock.camera_utc_offset_s = ParseUtcOffset(command.photo_utc_offset);
    SHUTTERLAB_CHECK(options.clock.camera_utc_offset_s)
        << "--photo-utc-offset must be +HH:MM or -HH:MM (got '" << command.photo_utc_offset << "')";
  }
  SHUTTERLAB_CHECK(command.every.empty())
      << "--every is for a log alone: the photos are the triggers";
  options.Check();
  const std::optional<FlightLogReadOptions> log_read =
      command.log_path.empty() ? std::nullopt
                               : std::optional<FlightLogReadOptions>(ReadOptionsFromFlags(command));
  const std::optional<TriggerFile> triggers = TriggersFromFlags(command);
  SHUTTERLAB_CHECK(!triggers || log_read) << "--triggers places photos on a LOG: give the LOG too";
  AnalyzeReportOptions report = ReportFromFlags(command);
  PhotoSet set;
  {
    Progress progress("photos", 1000);
    read.progress = [&progress](double f) { progress.Update(static_cast<size_t>(f * 1000)); };
    set = ReadPhotoSet(command.photos_dir, read);
  }
  if (read.lens_profile && !log_read) {
    // What the profile gave the photos (scaled to the first photo with a size; with a LOG the
    // analysed camera's notes are printed instead).
    for (const PhotoRecord& r : set.photos) {
      if (!r.ok() || r.metadata.width <= 0 || r.metadata.height <= 0) continue;
      const LensProfileUse use =
          ScaleLensProfile(*read.lens_profile, r.metadata.width, r.metadata.height);
      for (const std::string& note : use.notes) std::cerr << "note: " << note << "\n";
      break;
    }
  }
  if (!log_read) {
    const PhotoAnalysis analysis = AnalyzePhotos(set, options.photos);
    if (!command.out_dir.empty()) WritePhotoOutputs(command.out_dir, set, analysis);
    if (command.json) {
      std::cout << JsonText(PhotoAnalysisToJson(set, analysis)) << "\n";
    } else {
      std::cout << PhotoAnalysisReport(set, analysis);
    }
    return;
  }
  Progress progress("analyze", 1000);
  options.analyze.progress = [&progress](double f) {
    progress.Update(static_cast<size_t>(f * 1000));
  };
  std::optional<SensorPair> pair;
  const PhotoFlightResult result = PhotosOnLog(command, *log_read, set, triggers, options, &pair);
  if (result.lens) {
    for (const std::string& note : result.lens->notes) std::cerr << "note: " << note << "\n";
  }
  if (!command.out_dir.empty()) {
    WriteAnalyzeOutputs(command.out_dir, result.log);
    report.camera_source = result.camera_source;
    AnalyzeReportPage(result.analyzed, result.log, report).Write(command.out_dir + "/report.html");
    WritePhotoOutputs(command.out_dir, set, result.photos);  // its exclude.txt replaces analyze's
  }
  if (command.json) {
    nlohmann::json json = AnalyzeToJson(result.log);
    if (pair) json["pair"] = SensorPairToJson(*pair, command.second_path);
    if (result.lens) json["lens_profile"] = LensProfileUseJson(*result.lens);
    json["photos"] = PhotoAnalysisToJson(set, result.photos);
    json["photos"]["camera_source"] = result.camera_source;
    std::cout << JsonText(json) << "\n";
  } else {
    if (pair) std::cout << SensorPairText(*pair, command.log_path, command.second_path) << "\n";
    std::cout << AnalyzeReport(result.log) << "\ncamera analysed: " << result.camera_source
              << "\n\n"
              << PhotoAnalysisReport(set, result.photos);
  }
}

void Run(const AnalyzeCommand& command) {
  if (!command.photos_dir.empty()) return RunPhotos(command);
  SHUTTERLAB_CHECK(!command.log_path.empty()) << "give a LOG, or --photos DIR";
  std::optional<LensProfileUse> lens;
  AnalyzeOptions options = AnalyzeOptionsFromFlags(command, &lens);
  const FlightLogReadOptions read = ReadOptionsFromFlags(command);
  options.Check();  // before the (possibly long) read
  const std::optional<TriggerFile> triggers = TriggersFromFlags(command);
  const AnalyzeReportOptions report = ReportFromFlags(command);
  std::optional<SensorPair> pair;
  AnalyzeResult result;
  try {
    result = AnalyzeStreamed(command, read, triggers, options, &pair);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(command.log_path + ": " + e.what());
  }
  if (!command.out_dir.empty()) {
    WriteAnalyzeOutputs(command.out_dir, result);
    AnalyzeReportPage(options, result, report).Write(command.out_dir + "/report.html");
  }
  if (command.json) {
    auto json = AnalyzeToJson(result);
    if (pair) json["pair"] = SensorPairToJson(*pair, command.second_path);
    if (lens) json["lens_profile"] = LensProfileUseJson(*lens);
    std::cout << JsonText(json) << "\n";
  } else {
    if (pair) std::cout << SensorPairText(*pair, command.log_path, command.second_path) << "\n";
    std::cout << AnalyzeReport(result);
  }
}

const CommandRegistration kAnalyzeRegistration(80, [](CLI::App& app) {
  auto* cmd = app.add_subcommand("analyze",
                                 "per-image rolling-shutter distortion from a flight log (ULog, "
                                 "DataFlash, blackbox, GoPro MP4, gyro.csv, any CSV by --columns)");
  auto command = std::make_shared<AnalyzeCommand>();
  CheckLogPath(cmd->add_option("LOG", command->log_path,
                               "flight or gyro log (optional with --photos; - = stdin)"));
  cmd->add_option("--photos", command->photos_dir,
                  "a folder of photos (or one photo): per-photo distortion from their metadata; "
                  "without LOG the translation part from the recorded flight speed, with LOG "
                  "each photo placed on the log's clock (--triggers, the log's camera events, or "
                  "the capture times through the log's GPS time)");
  cmd->add_option("--photo-utc-offset", command->photo_utc_offset,
                  "the photos' camera clock zone, e.g. +08:00 (else EXIF OffsetTimeOriginal, the "
                  "offset fitted to the log's events, or the one zone that fits the log)");
  cmd->add_option(
         "--format", command->format,
         "auto, ulog, dataflash, blackbox, gopro, gyro.csv, gcsv, raw, gyro_dump (columns: set by "
         "--columns)")
      ->capture_default_str();
  cmd->add_option("--log-index", command->log_index,
                  "blackbox: which log of the file (-1 = longest)")
      ->capture_default_str();
  cmd->add_option("--range", command->range_dps, "raw counts: full-scale range, deg/s")
      ->capture_default_str();
  command->column_flags.Add(cmd);
  cmd->add_option("--camera", command->camera_path, "camera.json (docs/FORMATS.md rig/1)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--lens-profile", command->lens_profile_path,
                  "Gyroflow lens profile (JSON): its lens, scaled to the image size, and its "
                  "readout where it states one (unless --readout is given); with --photos also "
                  "each photo's focal length and readout")
      ->check(CLI::ExistingFile);
  auto* readout = cmd->add_option("--readout", command->readout,
                                  "rolling-shutter readout without --camera (s, ms, us); with "
                                  "--photos it overrides the readout table")
                      ->capture_default_str();
  auto* altitude =
      cmd->add_option("--altitude", command->altitude_m,
                      "height above flat ground, m (overrides camera.json; default: the log's "
                      "altitude above ground when it has one, else 50)")
          ->capture_default_str();
  auto* focal = cmd->add_option("--focal-px", command->focal_px,
                                "focal length without --camera, pixels (with --photos: overrides "
                                "the photos' own)")
                    ->capture_default_str();
  cmd->add_option("--size", command->size, "image size WxH without --camera")
      ->capture_default_str();
  cmd->add_option("--triggers", command->triggers_path,
                  "when the photos were taken, by content: DJI/Autel .MRK (GPS time, placed "
                  "through the log's GPS fixes), a log's camera events (ULog, DataFlash CAM/TRIG), "
                  "or CSV 'image,t' / 't' (s on the log clock; a header may name t_ms, t_us, "
                  "timestamp, utc_usec or utc instead)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--second", command->second_path,
                  "a second sensor's log on the same clock (record --device twice): fused with the "
                  "first, the mounting fitted from the motion")
      ->check(CLI::ExistingFile);
  cmd->add_option("--every", command->every,
                  "simulated triggers at this cadence (e.g. 2s); with --triggers or --every the "
                  "log's camera events are not used");
  cmd->add_option("--latency", command->latency, "trigger-to-exposure latency (s, ms, us)")
      ->capture_default_str();
  cmd->add_option("--limit", command->limits, "ground limits, e.g. 5cm,10cm")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--noise-allowance", command->noise_allowance_arcsec,
                  "flight table: added to each threshold for the gyro's own noise, arcsec")
      ->capture_default_str();
  cmd->add_option("--out", command->out_dir,
                  "write DIR/images.csv, DIR/exclude.txt and DIR/report.html (with --photos: "
                  "DIR/photos.csv, exclude.txt, image_list.txt, colmap_image_list.txt)");
  cmd->add_option("--scene", command->scene_path,
                  "nadir image for the report's worst-image pictures (with --out)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", command->json, "print JSON (docs/FORMATS.md `analyze`)");
  return std::function<void()>([command, altitude, readout, focal] {
    command->altitude_given = altitude->count() > 0;
    command->readout_given = readout->count() > 0;
    command->focal_given = focal->count() > 0;
    Run(*command);
  });
});

}  // namespace
}  // namespace shutterlab::app
