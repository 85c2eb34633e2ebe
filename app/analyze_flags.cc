#include "app/analyze_flags.h"

#include "app/trace_options.h"
#include "io/image_io.h"
#include "render/pictures.h"
#include "sim/bias.h"
#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/trigger_file.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <cmath>
#include <filesystem>
#include <iostream>

namespace shutterlab::app {
namespace {

RigModel RigFromFlags(const AnalyzeFlags& flags) {
  RigModel rig;
  const size_t x = flags.size.find_first_of("xX");
  int width = 0, height = 0;
  try {
    SHUTTERLAB_CHECK(x != std::string::npos) << "";
    width = std::stoi(flags.size.substr(0, x));
    height = std::stoi(flags.size.substr(x + 1));
  } catch (const std::exception&) {
    throw std::invalid_argument("--size must be WxH, e.g. 1280x960 (got '" + flags.size + "')");
  }
  rig.camera.width = width;
  rig.camera.height = height;
  rig.camera.fx = rig.camera.fy = flags.focal_px;
  rig.camera.cx = 0.5 * (width - 1);
  rig.camera.cy = 0.5 * (height - 1);
  rig.shutter.readout_s = ConvertUnit(flags.readout_ms, "ms", "s");
  rig.altitude_m = flags.altitude_m;
  return rig;
}

// What the user gave that wins over the photos' own values: --camera's focal length and readout,
// --readout, --focal-px and --altitude (the flags over the camera file).
PhotoSetOptions PhotoOptionsFromFlags(const AnalyzeFlags& flags) {
  PhotoSetOptions options;
  if (!flags.camera_path.empty()) {
    const RigModel rig = ReadRigModel(flags.camera_path);
    options.readout_s = rig.shutter.readout_s;
    options.readout_origin = ReadoutOrigin::kCameraFile;
    options.readout_text = "camera.json " + flags.camera_path;
    options.focal_px = 0.5 * (rig.camera.fx + rig.camera.fy);
    options.focal_text = "camera.json " + flags.camera_path;
    options.camera = rig.camera;
  }
  if (flags.readout_given) {
    options.readout_s = ConvertUnit(flags.readout_ms, "ms", "s");
    options.readout_origin = ReadoutOrigin::kUser;
    options.readout_text = "--readout " + QuantityText(flags.readout_ms, "ms");
  }
  if (flags.focal_given) {
    options.focal_px = flags.focal_px;
    options.focal_text = "--focal-px";
    options.camera.reset();  // its focal length is not the one given
  }
  if (flags.altitude_given) options.altitude_m = flags.altitude_m;
  if (!std::isnan(flags.speed_m_s)) options.speed_m_s = flags.speed_m_s;
  if (!std::isnan(flags.ground_elevation_m)) options.ground_elevation_m = flags.ground_elevation_m;
  options.recursive = flags.recursive;
  if (!flags.lens_profile_path.empty())
    options.lens_profile = ReadLensProfile(flags.lens_profile_path);
  return options;
}

// Without --camera: what was taken for the camera, its readout and its lens, and how to give them.
void AddCameraAssumptions(const AnalyzeFlags& flags, const RigModel& rig, bool readout_from_profile,
                          std::vector<Assumption>* assumptions) {
  const PinholeCamera& camera = rig.camera;
  const bool profile = !flags.lens_profile_path.empty();  // its focal length, at the image size
  if (!flags.size_given || (!flags.focal_given && !profile)) {
    assumptions->push_back({"camera",
                            std::to_string(camera.width) + " x " + std::to_string(camera.height) +
                                " px, f " + FormatNumber("%g", camera.fx) + " px",
                            "", "--camera camera.json, or --size and --focal-px"});
  }
  if (!flags.readout_given && !readout_from_profile) {
    assumptions->push_back(
        {"readout", FormatNumber("%g ms", flags.readout_ms),
         profile ? "the lens profile states none" : "",
         profile ? "--readout or --camera" : "--readout, --camera or --lens-profile"});
  }
  if (!profile) {
    assumptions->push_back(
        {"lens", "no distortion", "", "--lens-profile (a Gyroflow profile) or --camera"});
  }
}

FlightLogReadOptions ReadOptionsFromFlags(const AnalyzeFlags& flags) {
  FlightLogReadOptions read;
  read.format = ParseLogFormat(flags.format);
  read.log_index = flags.log_index;
  read.raw.range_dps = flags.range_dps;
  flags.column_flags.Apply(&read);
  read.Check();
  return read;
}

}  // namespace

AnalyzeOptions AnalyzeOptionsFromFlags(const AnalyzeFlags& flags,
                                       std::optional<LensProfileUse>* lens) {
  AnalyzeOptions options;
  if (!flags.camera_path.empty()) {
    options.rig = ReadRigModel(flags.camera_path);
    if (flags.altitude_given) options.rig.altitude_m = flags.altitude_m;
  } else {
    options.rig = RigFromFlags(flags);
  }
  bool readout_from_profile = false;
  if (lens && !flags.lens_profile_path.empty()) {
    *lens = ScaleLensProfile(ReadLensProfile(flags.lens_profile_path), options.rig.camera.width,
                             options.rig.camera.height);
    ApplyLensProfile(&**lens, &options.rig, flags.readout_given);
    readout_from_profile = (*lens)->readout && (*lens)->readout->readout_s;
    for (const std::string& note : (*lens)->notes) std::cerr << "note: " << note << "\n";
  }
  if (flags.camera_path.empty())
    AddCameraAssumptions(flags, options.rig, readout_from_profile, &options.assumptions);
  options.limits_m = flags.limits_m;
  options.noise_allowance_arcsec = flags.noise_allowance_arcsec;
  // --altitude wins, then camera.json; without either the log's height above ground beats 50 m.
  options.use_log_altitude = !flags.altitude_given && flags.camera_path.empty();
  if (!std::isnan(flags.every_s)) {
    SHUTTERLAB_CHECK(flags.every_s > 0)
        << "--every " << QuantityText(flags.every_s, "s")
        << " would judge no image: give a cadence above 0 s, e.g. 2s";
    options.every_s = flags.every_s;
  }
  options.trigger_latency_s = flags.latency_s;
  options.estimate_bias = !flags.zero_bias;
  if (!flags.bias.empty()) options.bias_segment = ParseBiasSegment(flags.bias);
  // The report's charts, shading, histograms and pictures, and its Allan deviation.
  if (!flags.out_dir.empty()) options.plots = AnalyzePlotOptions{};
  options.allan = !flags.out_dir.empty();
  return options;
}

std::optional<TriggerInput> TriggersFromFlags(const AnalyzeFlags& flags) {
  if (flags.triggers_path.empty()) return std::nullopt;
  TriggerInput triggers{ReadTriggerFile(flags.triggers_path), flags.triggers_path};
  PrintLogWarnings(flags.triggers_path, triggers.file.warnings);
  if (!flags.triggers_clock_path.empty()) {
    // Both gyros read whole: the alignment correlates them over every lag.
    const GyroTrace log_gyro = ReadFlightLog(flags.log_path, ReadOptionsFromFlags(flags)).gyro;
    const GyroTrace clock_gyro = ReadFlightLog(flags.triggers_clock_path).gyro;
    const std::string clock_name = std::filesystem::path(flags.triggers_clock_path).filename();
    try {
      const GyroSync sync =
          MoveTriggersToLogClock(log_gyro, clock_gyro, clock_name, &triggers.file);
      // On stderr: the warnings' stream, which --json leaves free of its document.
      std::fprintf(stderr,
                   "triggers: on %s's clock; log clock = its clock %+.6f s (+- %.2f ms), from "
                   "the motion (peak correlation %.2f)\n",
                   clock_name.c_str(), -sync.offset_s, sync.offset_stderr_s * 1e3,
                   sync.peak_correlation);
    } catch (const std::invalid_argument& e) {
      throw IoError(flags.triggers_clock_path + ": cannot put the triggers on " + flags.log_path +
                    "'s clock: " + WithoutCheckLocation(e.what()));
    }
  }
  return triggers;
}

LogInput InputFromFlags(const AnalyzeFlags& flags) {
  LogInput input;
  input.path = flags.log_path;
  input.read = ReadOptionsFromFlags(flags);
  input.second_path = flags.second_path;
  input.second_own_clock = flags.sync_second;
  return input;
}

AnalyzeReportOptions ReportFromFlags(const AnalyzeFlags& flags) {
  SHUTTERLAB_CHECK(flags.scene_path.empty() || !flags.out_dir.empty())
      << "--scene is for the report: give --out DIR too";
  AnalyzeReportOptions report;
  report.log_name = std::filesystem::path(flags.log_path).filename().string();
  if (!flags.scene_path.empty()) {
    report.scene = ToRgb8(ReadImage(flags.scene_path));
    report.scene_name = std::filesystem::path(flags.scene_path).filename().string();
  }
  return report;
}

PhotoFlightOptions PhotoFlightOptionsFromFlags(const AnalyzeFlags& flags, PhotoSetOptions* read) {
  *read = PhotoOptionsFromFlags(flags);
  read->Check();
  PhotoFlightOptions options;
  options.analyze = AnalyzeOptionsFromFlags(flags, nullptr);
  options.analyze.assumptions.clear();  // the photos say their camera (PhotoFlightResult)
  options.lens_profile = read->lens_profile;
  options.photos.limits_m = options.analyze.limits_m;
  options.rig_given = !flags.camera_path.empty();
  options.altitude_given = flags.altitude_given;
  options.readout_given = flags.readout_given;
  if (!flags.photo_utc_offset.empty()) {
    options.clock.camera_utc_offset_s = ParseUtcOffset(flags.photo_utc_offset);
    SHUTTERLAB_CHECK(options.clock.camera_utc_offset_s)
        << "--photo-utc-offset must be +HH:MM or -HH:MM (got '" << flags.photo_utc_offset << "')";
  }
  SHUTTERLAB_CHECK(std::isnan(flags.every_s))
      << "--every is for a log alone: the photos are the triggers";
  options.Check();
  return options;
}

namespace {

// --photos and the options only it reads (each refused without it: silently ignored, a given
// value would look used).
void AddPhotoFlags(CLI::App* command, AnalyzeFlags* flags) {
  CLI::Option* photos = command->add_option(
      "--photos", flags->photos_dir,
      "a folder of photos (or one photo): per-photo distortion from their metadata; "
      "without LOG the translation part from the recorded flight speed, with LOG "
      "each photo placed on the log's clock (--triggers, the log's camera events, or "
      "the capture times through the log's GPS time)");
  AddQuantityOption(command, "--speed", &flags->speed_m_s, "m/s", "m/s",
                    "--photos: the ground speed of every photo, over their metadata's (for "
                    "photos that do not record it)")
      ->needs(photos);
  AddQuantityOption(command, "--ground-elevation", &flags->ground_elevation_m, "m", "m",
                    "--photos: the ground's elevation (the take-off point's) in the photos' "
                    "absolute altitude's datum: a photo with no height above take-off is then "
                    "flown at its absolute (or GPS) altitude minus this")
      ->default_str("")
      ->needs(photos);
  command
      ->add_flag("--recursive", flags->recursive,
                 "--photos: read the folder's subfolders too (a card's DCIM/100MEDIA, ...)")
      ->needs(photos);
  command
      ->add_option("--photo-utc-offset", flags->photo_utc_offset,
                   "the photos' camera clock zone, e.g. +08:00 (else EXIF OffsetTimeOriginal, the "
                   "offset fitted to the log's events, or the one zone that fits the log)")
      ->needs(photos);
  command
      ->add_option("--export", flags->export_formats,
                   "with --photos and --out: also the photos' camera for these tools, each in "
                   "DIR/export_FORMAT/ (colmap, odm, kalibr, gyroflow, metashape, pix4d, vins; as "
                   "shutterlab export)")
      ->delimiter(',')
      ->needs(photos);
}

}  // namespace

std::function<void()> AddAnalyzeFlags(CLI::App* command, AnalyzeFlags* flags) {
  CheckLogPath(command->add_option("LOG", flags->log_path,
                                   "flight or gyro log (optional with --photos; - = stdin)"));
  AddPhotoFlags(command, flags);
  AddFormatOption(command, &flags->format);
  command
      ->add_option("--log-index", flags->log_index,
                   "blackbox: which log of the file (-1 = longest)")
      ->capture_default_str();
  AddRangeOption(command, &flags->range_dps);
  flags->column_flags.Add(command);
  command->add_option("--camera", flags->camera_path, "camera.json (docs/FORMATS.md rig/1)")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--lens-profile", flags->lens_profile_path,
                   "Gyroflow lens profile (JSON): its lens, scaled to the image size, and its "
                   "readout where it states one (unless --readout is given); with --photos also "
                   "each photo's focal length and readout")
      ->check(CLI::ExistingFile);
  auto* readout = AddQuantityOption(command, "--readout", &flags->readout_ms, "ms", "ms",
                                    "rolling-shutter readout without --camera; with --photos it "
                                    "overrides the readout table");
  auto* altitude = AddQuantityOption(command, "--altitude", &flags->altitude_m, "m", "m",
                                     "height above flat ground (overrides camera.json; default: "
                                     "the log's altitude above ground when it has one, else 50m)");
  auto* focal = command
                    ->add_option("--focal-px", flags->focal_px,
                                 "focal length without --camera, pixels (with --photos: overrides "
                                 "the photos' own)")
                    ->capture_default_str();
  auto* size = command->add_option("--size", flags->size, "image size WxH without --camera")
                   ->capture_default_str();
  command
      ->add_option(
          "--triggers", flags->triggers_path,
          "when the photos were taken, by content: DJI/Autel .MRK (GPS time, placed "
          "through the log's GPS fixes), a log's camera events (ULog, DataFlash CAM/TRIG), "
          "or CSV 'image,t' / 't' (s on the log clock; a header may name t_ms, t_us, "
          "timestamp, utc_usec or utc instead)")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--triggers-clock", flags->triggers_clock_path,
                   "GYROLOG: the --triggers times are on this gyro log's clock (record's triggers "
                   "file: its .gcsv), not LOG's; put on LOG's by aligning the two gyros from the "
                   "motion (as sync)")
      ->check(CLI::ExistingFile)
      ->needs("--triggers");
  command
      ->add_option(
          "--second", flags->second_path,
          "a second sensor's log on the same clock (record --device twice): fused with the "
          "first, the mounting fitted from the motion")
      ->check(CLI::ExistingFile);
  AddSyncSecond(command, &flags->sync_second);
  AddQuantityOption(command, "--every", &flags->every_s, "s", "s",
                    "simulated triggers at this cadence, e.g. 2s; with --triggers or --every "
                    "the log's camera events are not used");
  AddQuantityOption(command, "--latency", &flags->latency_s, "s", "ms",
                    "trigger-to-exposure latency");
  AddQuantityListOption(command, "--limit", &flags->limits_m, "m", "cm",
                        "ground limits, e.g. 5cm,10cm");
  AddQuantityOption(command, "--noise-allowance", &flags->noise_allowance_arcsec, "arcsec",
                    "arcsec", "flight table: added to each threshold for the gyro's own noise");
  command->add_option("--out", flags->out_dir,
                      "write DIR/images.csv, DIR/exclude.txt and DIR/report.html (with --photos: "
                      "DIR/photos.csv, exclude.txt, image_list.txt, colmap_image_list.txt)");
  command
      ->add_option("--scene", flags->scene_path,
                   "nadir image for the report's worst-image pictures (with --out)")
      ->check(CLI::ExistingFile);
  // The bias options of flight, noise and accuracy; the default differs, said in the help: a
  // flight log seldom starts with 5 s of stillness, so analyze searches for its still stretch.
  auto* zero = command->add_flag(
      "--zero-bias", flags->zero_bias,
      "take the logged rates as bias-free, as flight --zero-bias does (flight-controller logs, "
      "calibrated at arming); default: --auto-bias");
  auto* given = command->add_option(
      "--bias", flags->bias,
      "still segment for the bias, A:B after the first sample (0:5s, 2s:7s), instead of the "
      "search (--auto-bias)");
  auto* automatic = command->add_flag(
      "--auto-bias", flags->auto_bias,
      "the bias of the log's longest still stretch (the default for analyze; zero, and said, "
      "when it has none)");
  zero->excludes(given)->excludes(automatic);
  given->excludes(automatic);
  command->add_flag("--json", flags->json, "print JSON (docs/FORMATS.md `analyze`)");
  return [flags, altitude, readout, focal, size] {
    flags->altitude_given = altitude->count() > 0;
    flags->readout_given = readout->count() > 0;
    flags->focal_given = focal->count() > 0;
    flags->size_given = size->count() > 0;
  };
}

}  // namespace shutterlab::app
