#pragma once
// `shutterlab import SOURCE --out DATASET`: real rolling-shutter footage with its own gyro, turned
// into a video rig dataset (docs/FORMATS.md: camera.json, gyro.csv, frames.csv with `ref` empty,
// images/) plus import.json, which records where every number came from.
//
// Sources:
//  - a GoPro MP4 with a GPMF 'gpmd' track (HERO5 and later): GYRO (SCAL, axis order), SHUT;
//    frames through OpenCV's video reader, times from the MP4 video track's sample table;
//  - a phone clip folder (lhaippp/gyro-video-stabilization layout): gyro.txt (gx,gy,gz,t in rad/s
//    and s), framestamp.txt (start-of-frame time of frame N on line N), gyro_dump.txt (exposure per
//    frame), frames/RE_frame-N.jpg (frame N).
// What the sources do not state (GoPro intrinsics, readout, axis mapping) is declared as a claim or
// a guess and listed in import.json: validate tests it, this importer does not.

#include "sim/gyro_trace.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace shutterlab {

enum class ImportSource { kGoproMp4, kPhoneFolder };

struct ImportOptions {
  std::string source;        // an .mp4 with a gpmd track, or a phone clip folder
  std::string out_dir;       // written whole or not at all
  int64_t max_frames = -1;   // at most this many frames (-1: all)
  int64_t start_frame = -1;  // first frame id to import (-1: the first one); ids as in frames.csv
                             // (GoPro: video frame index from 0; phone: frame number N)
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Recognises SOURCE; throws IoError("SOURCE: problem") saying what was expected otherwise.
ImportSource DetectImportSource(const std::string& source);

// What the GoPro's telemetry holds, in the sensor's x, y, z (GPMF stores the HERO5's as z, x, y).
struct GoproTelemetry {
  GyroTrace gyro;         // movie timeline seconds, rad/s, sensor axes x, y, z
  std::string gyro_name;  // STNM
  std::string axis_order_source;
  std::vector<double> gyro_scale;  // SCAL
  std::vector<size_t> gyro_payload_samples;
  double gyro_rate_hz = 0.0;  // from the linear fit over the track
  double gyro_fit_max_residual_s = 0.0;
  std::vector<double> shutter_s;    // SHUT values (per video frame), empty when absent
  std::vector<double> shutter_t_s;  // their times (their own linear fit)
  std::string device;               // DVNM of the GYRO stream
};
GoproTelemetry ReadGoproTelemetry(const std::string& mp4_path);

// The phone clip's text files.
struct PhoneClip {
  GyroTrace gyro;               // device clock minus time_origin_ns, rad/s, sensor axes
  int64_t time_origin_ns = 0;   // subtracted from every time (whole seconds of the first sample)
  std::vector<int64_t> sof_ns;  // framestamp.txt: sof_ns[N-1] = start of frame N, minus origin
  std::map<int64_t, double> exposure_s;         // gyro_dump.txt: frame N -> exposure time
  double dump_sof_max_diff_s = 0.0;             // largest |SOF in gyro_dump.txt - framestamp.txt|
  std::map<int64_t, std::string> frame_images;  // frame N -> image path (frames/RE_frame-N.*)
};
PhoneClip ReadPhoneClip(const std::string& folder);

struct ImportSummary {
  ImportSource kind = ImportSource::kGoproMp4;
  size_t gyro_samples = 0;
  double gyro_rate_hz = 0.0;
  size_t frames = 0;
  double t_first_s = 0.0, t_last_s = 0.0;  // first and last frame's t_first_row
  nlohmann::json record;                   // what import.json holds
};

// Imports SOURCE into options.out_dir (written under a temporary sibling folder and renamed at the
// end; an existing out_dir is replaced only when empty or itself an import). progress(done, total)
// after each frame.
ImportSummary ImportVideo(const ImportOptions& options,
                          const std::function<void(size_t, size_t)>& progress = {});

}  // namespace shutterlab
