#pragma once
// Gyroflow's text IMU log, `.gcsv` (https://docs.gyroflow.xyz, "gcsv format";
// https://github.com/gyroflow/gyroflow-docs/blob/main/docs/logging/gcsv.md):
//
//   GYROFLOW IMU LOG            (or CAMERA IMU LOG)
//   version,1.3
//   id,...  orientation,XYZ  note,...  fwversion,...  timestamp,...  vendor,...  videofilename,...
//   lensprofile,...  lens_info,...  frame_readout_time,15.23  frame_readout_direction,0
//   tscale,0.001                t * tscale = seconds
//   gscale,0.00122173           g * gscale = rad/s
//   ascale,...  mscale,...      (optional; accelerometer / magnetometer, not used here)
//   t,gx,gy,gz[,ax,ay,az[,mx,my,mz]]
//   rows...
//
// Orientation. Gyroflow's reference parser (AdrianEddy/telemetry-parser, src/tags_impl.rs,
// `Vector3::orient`) builds output axis i from character i of the string: 'X'/'Y'/'Z' take input
// x/y/z, lowercase takes it negated. So "yXz" means out = (-in.y, in.x, -in.z). The result is in
// Gyroflow's own IMU frame; the same parser (src/gyroflow/gcsv.rs) assumes "xzY" when a file has no
// orientation line, and so do we.

#include "sim/gyro_source.h"
#include "sim/gyro_trace.h"
#include "sim/log_warning.h"
#include "sim/logs/raw_csv.h"
#include "sim/readout_direction.h"
#include "sim/text_file.h"

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

struct GcsvLog {
  // Seconds (t * tscale) and rad/s (g * gscale), with `orientation` applied: the axes Gyroflow
  // would use.
  GyroTrace trace;
  std::string orientation = "XYZ";        // as applied (the file's, or the default "xzY")
  std::optional<double> frame_readout_s;  // frame_readout_time (Gyroflow writes milliseconds)
  // frame_readout_direction: top to bottom also when absent. Gyroflow's codes 0/1/2/3 (and
  // 180/270/90) and names (TopToBottom, ...) are mapped.
  ReadoutDirection frame_readout_direction = ReadoutDirection::kTopToBottom;
  double tscale = 0.001;
  double gscale = 1.0;
  // Every "key,value" line of the header block in file order, scales and orientation included.
  std::vector<std::pair<std::string, std::string>> header;
  // e.g. a defaulted orientation; and a `gap` warning for each "gap,T_S,LOST,KIND" header line,
  // the dropouts a logger wrote into its own header (shutterlab record does).
  std::vector<LogWarning> warnings;
};

// Reads a .gcsv. Throws IoError "PATH:LINE: problem" for a missing first line, a header that ends
// before the column line, a missing or non-positive tscale / gscale, a bad orientation string, a
// column line not starting t,gx,gy,gz, a row whose column count differs from the column line's, a
// non-numeric or non-finite field, or a decreasing timestamp; but a last line without its line
// break that does not read is the file cut inside it: left out, with a `truncated` warning.
GcsvLog ReadGcsv(const std::string& path);
// The same as a stream: the header block is read at once (its errors thrown here), the samples a
// block at a time as the chunks are taken. log.trace stays empty. path names the file in messages.
struct GcsvStream {
  GcsvLog log;
  std::unique_ptr<GyroSource> samples;
};
// chunk_samples bounds each chunk.
GcsvStream OpenGcsv(TextBlocks blocks, const std::string& path,
                    size_t chunk_samples = FillingSource::kDefaultChunkSamples);

struct GcsvWriteOptions {
  std::string id = "shutterlab";
  // Written to the header; rates are mapped through its inverse so that ReadGcsv gives back the
  // trace's own axes.
  std::string orientation = "XYZ";
  // Unit of the t column: tscale 1, 0.001, 1e-06 or 1e-09; times are written exactly.
  TimeUnit time_unit = TimeUnit::kMicroseconds;
  // 0: rates written as shortest round-trip decimals in rad/s with gscale 1 (lossless).
  // > 0: rates quantised to integer multiples of gscale rad/s, as a logger would write them.
  double gscale = 0.0;
  std::optional<double> frame_readout_s;  // written as frame_readout_time in ms when set
  ReadoutDirection frame_readout_direction = ReadoutDirection::kTopToBottom;
  // Further "key,value" header lines (note, vendor, lensprofile, ...), written as given.
  std::vector<std::pair<std::string, std::string>> extra_header;
  void Check() const;  // throws std::invalid_argument naming the first bad field
};

// The header of a .gcsv up to and including its column line "t,gx,gy,gz", as WriteGcsv writes it:
// for writers that stream the rows themselves (record/). Checks the options.
std::string GcsvHeaderText(const GcsvWriteOptions& options);

// Writes a .gcsv whole or not at all (IoError on failure).
void WriteGcsv(const std::string& path, const GyroTrace& trace,
               const GcsvWriteOptions& options = {});

// The signed permutation M of an orientation string: out = M * in (see the note at the top).
// Throws std::invalid_argument unless the string is three of xXyYzZ naming each axis once.
Eigen::Matrix3d GcsvOrientationMatrix(const std::string& orientation);

}  // namespace shutterlab
