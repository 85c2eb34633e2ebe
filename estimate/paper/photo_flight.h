#pragma once
// `analyze --photos DIR LOG`: a folder of photos and the flight log that flew them. Each photo is
// placed on the log's clock (estimate/paper/photo_clock.h), `analyze` looks at the gyro during its
// readout (estimate/paper/analyze.h: the rotation part), and the photo keeps the translation part
// from its recorded speed beside it (estimate/paper/photo_analysis.h).
//
// The camera analysed is the photos' own when no camera.json is given: the most common image size,
// focal length and readout among the photos (the readout table's included, and said); a camera
// without a known readout is analysed at AnalyzeOptions::rig's readout (the 30 ms default) and
// the result says so. The altitude: --altitude, else camera.json's, else the log's height above
// ground, else the photos' median height above take-off, else the rig's.

#include "estimate/paper/analyze.h"
#include "estimate/paper/photo_analysis.h"
#include "estimate/paper/photo_clock.h"
#include "io/lens_profile.h"
#include "io/photo_set.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/trigger_file.h"

#include <optional>
#include <string>

namespace shutterlab {

struct PhotoFlightOptions {
  // Limits, noise allowance, latency, progress, report series; its rig is the camera when
  // rig_given (camera.json), its altitude when altitude_given, its readout when readout_given.
  AnalyzeOptions analyze;
  bool rig_given = false, altitude_given = false, readout_given = false;
  PhotoAnalysisOptions photos;  // its limits are analyze's
  PhotoClockOptions clock;
  // --lens-profile: scaled to the analysed camera and put into its rig (ApplyLensProfile; its
  // readout unless readout_given).
  std::optional<LensProfile> lens_profile;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct PhotoFlightResult {
  // The photos as analysed: the set given, where a placed photo that records no flight speed (and
  // no --speed) has the log's velocity at its placed time (speed_source says so).
  PhotoSet set;
  PhotoClock clock;
  AnalyzeOptions analyzed;             // what Analyze was given: the photos' camera, their times
  AnalyzeResult log;                   // analyze on the placed photos (images named by the photos)
  PhotoAnalysis photos;                // per photo: placement, rotation (from log) and translation
  std::string camera_source;           // where the analysed camera came from, for a person
  std::optional<LensProfileUse> lens;  // the lens profile as the rig took it
};

// The most common camera among the readable photos with a size and a focal length (image size,
// focal length to 0.1 px and readout) into *rig: its size, focal length, principal point at the
// centre, and its readout unless readout_given (the rig's is kept then, and when no photo has
// one). *source says which camera it was and where each value came from; rig is left as it is
// when no photo gives its size and focal length.
void CameraFromPhotos(const PhotoSet& set, bool readout_given, RigModel* rig, std::string* source);

// triggers: a trigger file, or null for the log's camera events.
PhotoFlightResult AnalyzePhotoFlight(const PhotoSet& set, const FlightLog& log,
                                     const TriggerFile* triggers,
                                     const PhotoFlightOptions& options);

// The same on a log too long to hold, in memory bounded whatever its length: metadata is the log
// without its samples (FlightLogStream::log: the camera events and GPS fixes place the photos),
// source gives the samples to AnalyzeStream with the photos as its triggers. The result is
// AnalyzePhotoFlight's on the log read whole, to the bit, but for AnalyzeResult::traces (null; the
// report draws AnalyzeResult::plots, the same either way).
PhotoFlightResult AnalyzePhotoFlightStream(const PhotoSet& set, const FlightLog& metadata,
                                           const AnalyzeLogSource& source,
                                           const TriggerFile* triggers,
                                           const PhotoFlightOptions& options);

}  // namespace shutterlab
