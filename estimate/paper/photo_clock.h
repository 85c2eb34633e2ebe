#pragma once
// Places each photo of a folder on a flight log's clock, so that `analyze` can look at the gyro
// during its readout.
//
// The photo's exposure is an event: a trigger file's line (sim/logs/trigger_file.h: .MRK, CSV, a
// log's camera events) or, without one, the log's own camera events. Photos are paired with
// events, first rule that applies:
//  1. by name, when the events name their images;
//  2. by number, for an .MRK: its first column is the photo's number (DJI_0123.JPG <-> 123);
//  3. by capture time, when the photos have one: the camera clock's offset is the difference that
//     most photo-event pairs share (votes in 0.5 s bins, each photo matched to the nearest event
//     within its capture time's resolution / 2 + 0.5 s), refined to the median of the matched
//     pairs. Against UTC when the events have a UTC time (UTC or GPS times, or log times through
//     the log's GPS fixes, sim/logs/log_clock.h): the offset is then the camera's time zone and
//     error. Else against the log's own clock (a log without GPS time): the offset is then
//     anything, and the pattern of the capture times against the events' decides;
//  4. in order, when there are as many photos as events.
// A paired photo's time is its event's (exposure of row 0, as analyze takes a trigger). Its
// residual is the capture time less the camera clock's offset less the event's time on the same
// base: what the pairing could not explain (EXIF's whole seconds alone give up to +-0.5 s).
//
// A photo without an event is placed by its capture time: with an offset to the log's clock
// fitted above, capture time - offset; else when the log has GPS time, capture time - camera
// clock offset -> UTC -> log clock. The offset is the one fitted above, else
// PhotoClockOptions::camera_utc_offset_s, else EXIF OffsetTimeOriginal, else the one whole
// quarter hour (a time zone) that puts every photo inside the log's GPS span; with several, the
// photos are not placed and the problem says to give --photo-utc-offset. Such a placement has no
// residual: its uncertainty is the capture time's resolution.

#include "estimate/paper/photo_analysis.h"
#include "io/photo_set.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/trigger_file.h"

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct PhotoClockOptions {
  // The camera clock's zone, seconds east of UTC (--photo-utc-offset); wins over the photos'
  // OffsetTimeOriginal and over the search.
  std::optional<int> camera_utc_offset_s;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct PhotoClock {
  std::vector<PhotoPlacement> placements;                // one per photo, same order
  std::string method;                                    // for a person: how the photos were placed
  std::optional<double> clock_offset_s;                  // camera clock - clock_offset_to, s
  std::string clock_offset_to;                           // "UTC" or "log clock" (no GPS time)
  std::optional<double> residual_rms_s, residual_max_s;  // over the pairs with both times
  size_t paired = 0, placed = 0;
};

// triggers: a trigger file, or null for the log's own camera events. Reads the log's camera events
// and GPS fixes, never its samples: a streamed log's metadata (FlightLogStream::log) serves.
PhotoClock PlacePhotos(const PhotoSet& set, const FlightLog& log, const TriggerFile* triggers,
                       const PhotoClockOptions& options);

}  // namespace shutterlab
