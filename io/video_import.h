#pragma once
// `shutterlab import SOURCE --out DATASET`: real rolling-shutter footage with its own gyro, turned
// into a video rig dataset (docs/FORMATS.md: camera.json, gyro.csv, frames.csv with `ref` empty,
// images/) plus import.json, which records where every number came from.
//
// Sources, their bytes read in sim/logs:
//  - a GoPro MP4 with a GPMF 'gpmd' track (HERO5 and later; sim/logs/gopro_telemetry.h): GYRO
//    (SCAL, and ORIN/ORIO/MTRX: the camera's own axes), SHUT, CORI/IORI (passed on in
//    image_orientation.csv), the global settings (SROT: the readout; ZFOV: the field of view;
//    EISE/EISA: the stabiliser, stated as a claim to test); frames through OpenCV's video reader,
//    times from the MP4 video track's sample table;
//  - a phone clip folder (lhaippp/gyro-video-stabilization layout; sim/logs/phone_clip.h):
//    gyro.txt, framestamp.txt, gyro_dump.txt (exposure per frame), frames/RE_frame-N.jpg (frame
//    N), the images copied as they are.
//  - any other MP4 or MOV (an FPV camera's, a GoPro's without GPMF), with `--gyro LOG` only: frames
//    and times as for the GoPro, the camera from `--camera` or `--lens-profile`.
// With `--gyro LOG` the dataset's gyro is an outside log's (a flight controller's, a recorder's),
// put on the clip's clock and axes from the motion (io/clip_alignment.h): camera.json's
// time_offset_s and gyro_to_camera are what the alignment found, import.json's gyro_log says how.
// What the sources do not state (GoPro intrinsics, readout, axis mapping) is declared as a claim or
// a guess and listed in import.json: validate tests it, this importer does not.

#include "io/import_io.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace shutterlab {

enum class ImportSource { kGoproMp4, kPhoneFolder, kVideoFile };

struct ImportOptions {
  std::string source;   // an .mp4 with a gpmd track, or a phone clip folder
  std::string out_dir;  // written whole or not at all
  // A Gyroflow lens profile (io/lens_profile.h): the declared lens, scaled to the frames, and
  // its readout where the source states none (a GoPro's SROT wins); import.json names it as the
  // claims' source.
  std::string lens_profile_path;
  int64_t max_frames = -1;   // at most this many frames (-1: all)
  int64_t start_frame = -1;  // first frame id to import (-1: the first one); ids as in frames.csv
                             // (GoPro: video frame index from 0; phone: frame number N)
  // A mask image of the frames' size (non-zero = may be measured: a dashboard, landing gear or
  // burned-in text painted black); written as the dataset's mask.png, named by camera.json's
  // `mask` and recorded in import.json. Empty: none.
  std::string mask_path;
  // An outside gyro log (any format sim/logs/flight_log_io.h reads) that becomes the dataset's
  // gyro, aligned to the clip (io/clip_alignment.h). Empty: the clip's own gyro.
  std::string gyro_log;
  // camera.json (rig/1) of a video without a gyro of its own: its camera (the frames' size),
  // lens, readout and direction. Empty: from lens_profile_path.
  std::string camera_path;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Recognises SOURCE (an MP4 without GPMF only when an outside gyro log is given); throws
// IoError("SOURCE: problem") saying what was expected otherwise.
ImportSource DetectImportSource(const std::string& source, bool with_gyro_log = false);

struct ImportSummary {
  ImportSource kind = ImportSource::kGoproMp4;
  size_t gyro_samples = 0;
  double gyro_rate_hz = 0.0;
  size_t frames = 0;
  double t_first_s = 0.0, t_last_s = 0.0;  // first and last frame's t_first_row
  ImportRecord record;                     // what import.json holds
};

// Imports SOURCE into options.out_dir (written under a temporary sibling folder and renamed at the
// end; an existing out_dir is replaced only when empty or itself an import). progress(done, total)
// after each frame.
ImportSummary ImportVideo(const ImportOptions& options,
                          const std::function<void(size_t, size_t)>& progress = {});

}  // namespace shutterlab
