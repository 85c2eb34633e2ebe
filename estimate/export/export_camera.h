#pragma once
// What `shutterlab export` carries into another tool, read from any of shutterlab's results: a
// validation report (the fitted model, each effect's standard error), a camera.json (a rig
// dataset's, a correction's) or a folder that holds one, or an `analyze --photos --json` result
// (the photos' own camera: size, focal length, readout, speed).
//
// Every quantity is in shutterlab's conventions (docs/FORMATS.md): OpenCV intrinsics with the
// centre of the top-left pixel at (0, 0); a frame's time is its first row read's, and row v is
// read v * readout_s / height later; gyro clock = camera clock + time_offset_s; w_C = R_CG w_G.
// Each exporter converts to its tool's conventions and says how (estimate/export/exports.h).

#include "model/effects.h"
#include "model/truth_model.h"

#include <nlohmann/json_fwd.hpp>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// A photo of an `analyze --photos` result, as the tools list their images.
struct ExportPhoto {
  std::string name;  // file name, relative to the photo folder
  std::string path;  // as the result gives it
  int width = 0, height = 0;
  std::optional<double> readout_s;  // the photo's readout, when known
  std::optional<double> speed_m_s;  // its recorded ground speed, when known
  std::optional<double> focal_mm;   // EXIF FocalLength, when written
  // EXIF FocalPlaneXResolution in pixels per mm, when written.
  std::optional<double> focal_plane_px_per_mm;
  // ISO 8601: "2024-07-16T09:41:37.250Z" when the camera's zone is known, the camera clock's face
  // without a zone ("2024-07-16T09:41:37.250") when not, "" when the photo has no capture time.
  std::string capture_time;
  bool flagged = false;  // over a limit in the analysis (the exclude list)
};

struct ExportCamera {
  std::string source;       // what it was read from, for the side notes: "validation report X"
  std::string make, model;  // the camera's, when the source names them; "" otherwise
  // The rig (intrinsics, lens, readout and direction, mounting R_CG, time offset) and the gyro's
  // scale, bias and clock rate.
  TrueModel truth;
  bool readout_known = true;  // false: no readout anywhere in the source (a photo of no table row)
  // false: the source relates no gyro to the camera (photos alone): the mounting and the time
  // offset are not known, whatever truth.rig holds.
  bool gyro_known = true;
  // The standard errors the source gives, where the exported value has one: time_offset and
  // readout_time (s), clock_rate (ppm); NaN where the data did not determine it.
  std::optional<double> time_offset_stderr_s, readout_stderr_s, clock_rate_stderr_ppm;
  // Every effect the source fitted (a validation report's), its value and standard errors in the
  // value's shape (std::monostate where there are none: no covariance in the report, or a readout
  // direction): the side note lists
  // them all, since no target file has a place for them (Metashape's calibration file and OPF's
  // calibrated cameras carry no uncertainty; docs/exports.md).
  struct Fitted {
    std::string name, unit;  // docs/FORMATS.md's effect name and its value's unit
    EffectValue value, stderr_value;
  };
  std::vector<Fitted> fitted;
  // The values the data did not determine, by effect name (time_offset, readout_time,
  // readout_direction, gyro_to_camera), with why: a fitted value whose standard error is not a
  // number, a declared value (import.json's claim) the report's claims contradict, or a guess or
  // an inference of the importer's that they could not test. An export refuses them unless
  // --force.
  std::map<std::string, std::string> undetermined;
  // What every export's side note says besides its own conversions: the source's own statements
  // (import.json's "source claim") that the report could not test, exported as stated.
  std::vector<std::string> notes;
  std::vector<ExportPhoto> photos;  // an `analyze --photos` result's, in its order
  // The photos' camera came from a camera.json or a lens profile, not from their metadata.
  bool camera_given = false;
  // A correction's per-image masks (its output folder's masks/: IMAGE.png, 0 where a pixel has no
  // source, COLMAP's mask_path naming), as the source folder gives them; "" when none.
  std::string masks_dir;
  // A correction of photos: the folder of the corrected images alone (correct.json's image_root),
  // COLMAP's --image_path, which the masks' names are relative to; "" when none.
  std::string images_dir;
};

// Reads path by its content: a JSON file with "format": "validation/1" (a report, whose
// "fitted_model" it needs), "format": "rig/1" (camera.json), or a "photos" list (analyze
// --photos --json, with or without a LOG); a folder holding camera.json (a rig dataset, a
// correction's output). Throws IoError("PATH: problem") naming what it could not use.
ExportCamera ReadExportSource(const std::string& path);

// The camera of an `analyze --photos --json` result's "photos" list (analyze --photos --export
// hands it over in memory): the first photo with a size and a focal length, every readable photo
// listed. source names it in the side notes and errors; throws IoError when no photo has both.
ExportCamera ExportCameraFromPhotos(const nlohmann::json& photos, const std::string& source);

}  // namespace shutterlab
