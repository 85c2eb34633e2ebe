#pragma once
// `shutterlab analyze`'s flags and what they make: the library's options (the rig, the analysis,
// the photos, the log pipeline's input, the trigger file, the report).

#include "app/trace_options.h"
#include "estimate/paper/analyze.h"
#include "estimate/paper/log_pipeline.h"
#include "estimate/paper/photo_flight.h"
#include "estimate/report/analyze_report.h"
#include "io/lens_profile.h"
#include "io/photo_set.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab::app {

// Set by CLI11 (AddAnalyzeFlags), read by the converters below.
struct AnalyzeFlags {
  std::string log_path;
  std::string format = "auto";
  int log_index = -1;
  int range_dps = 250;
  ColumnFlags column_flags;  // --time-unit, --columns, --delimiter, --rate-unit
  std::string camera_path;
  std::string lens_profile_path;
  double readout_ms = 30.0;
  double altitude_m = 50.0;
  double focal_px = 1100.0;
  std::string size = "1280x960";
  std::string triggers_path;
  std::string
      triggers_clock_path;  // --triggers-clock: the gyro log whose clock the triggers are on
  std::string second_path;
  bool sync_second = false;
  double every_s = std::numeric_limits<double>::quiet_NaN();  // NaN: not given
  double latency_s = 0.0;
  std::vector<double> limits_m{0.05, 0.10};
  double noise_allowance_arcsec = 20.0;
  std::string out_dir;
  std::vector<std::string> export_formats;  // --export: with --photos and --out
  std::string scene_path;
  std::string photos_dir;
  std::string photo_utc_offset;
  double speed_m_s = std::numeric_limits<double>::quiet_NaN();           // NaN: the photos' own
  double ground_elevation_m = std::numeric_limits<double>::quiet_NaN();  // NaN: not given
  bool recursive = false;
  bool zero_bias = false;
  std::string bias;  // --bias A:B; empty: the log's longest still stretch (--auto-bias)
  bool auto_bias = false;
  bool json = false;
  bool altitude_given = false;
  bool readout_given = false;
  bool focal_given = false;
  bool size_given = false;
};

// Adds every flag to the subcommand; the function returned, called once parsing succeeded, notes
// which of --altitude, --readout, --focal-px and --size were typed.
std::function<void()> AddAnalyzeFlags(CLI::App* command, AnalyzeFlags* flags);

// analyze's options from the flags (the triggers come with the log). *lens: the lens profile's
// use, when --lens-profile is given (its lens, and its readout unless --readout was typed); its
// notes are printed.
AnalyzeOptions AnalyzeOptionsFromFlags(const AnalyzeFlags& flags,
                                       std::optional<LensProfileUse>* lens);
// --photos: the photo folder's reading (*read, checked) and the analysis of the photos, checked.
PhotoFlightOptions PhotoFlightOptionsFromFlags(const AnalyzeFlags& flags, PhotoSetOptions* read);
// LOG (with --second) as the log pipeline reads it.
LogInput InputFromFlags(const AnalyzeFlags& flags);
// The trigger file, read (its warnings printed first, under its name); nullopt without one.
std::optional<TriggerInput> TriggersFromFlags(const AnalyzeFlags& flags);
// The report's options: the log's name and --scene.
AnalyzeReportOptions ReportFromFlags(const AnalyzeFlags& flags);

}  // namespace shutterlab::app
