#pragma once
// import.json (docs/FORMATS.md "Import output"): what `shutterlab import` records about where every
// number of an imported dataset came from, as a typed record, and the one place that turns it into
// JSON text.

#include "io/lens_profile.h"
#include "model/lens_distortion.h"
#include "sim/gyro_sync.h"
#include "sim/log_warning.h"
#include "sim/logs/gopro_telemetry.h"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace shutterlab {

// How far a claimed value is to be trusted: the four statuses of docs/FORMATS.md.
enum class ClaimStatus {
  kSourceClaim,          // "source claim": the source says so
  kInferred,             // "inferred": worked out from the data when the importer was written
  kSourceClaimInferred,  // "source claim + inferred"
  kGuess,                // "guess"
};
const char* ClaimStatusName(ClaimStatus status);

// A claimed value: a number (readout_s, time_offset_s), a word or sentence (direction,
// frame_images, stabilizer), a 3x3 matrix (gyro_to_camera, written as its rows), named numbers
// (intrinsics: fx, fy, cx, cy and what else the source states) or a lens (lens_distortion, written
// as camera.json's "distortion").
using ClaimValue = std::variant<double, std::string, Eigen::Matrix3d, std::map<std::string, double>,
                                LensDistortion>;

// What the source states or what the importer had to assume; validate tests some of them.
struct ImportClaim {
  std::string what;  // "intrinsics", "readout_s", "gyro_to_camera", "direction", ...
  ClaimValue value;
  ClaimStatus status = ClaimStatus::kGuess;
  std::string source;  // where it comes from, for a person
};

struct FrameExposure {
  int64_t frame = 0;
  std::optional<double> exposure_s;  // unknown: written as null
};

// How an MP4's frames were decoded (a GoPro's, a video file's): "frames" in import.json.
struct VideoDecoding {
  size_t video_samples = 0;  // in the video track's sample table
  int64_t decoded = 0;       // frames the video reader returned
  int failed_grabs = 0;
  int reader_time_mismatches = 0;
};

// What only a GoPro MP4 records (its "source", "gyro" and "frames" extras).
struct GoproImportDetails {
  std::string device;  // source.device: DVNM
  std::string stream_name, axis_order;
  std::vector<double> scal;
  std::vector<size_t> payload_samples;
  std::string timing;  // how the gyro samples were timed, for a person
  double fit_max_residual_s = 0.0;
  VideoDecoding decoding;
  std::string times;  // where the frame times come from, for a person
  // The GYRO stream's orientation keys as written ("gyro": "orin", "orio", "mtrx" when present).
  std::string gyro_orin, gyro_orio;
  std::vector<double> gyro_mtrx;
  GoproSettings settings;  // "settings" when the clip has global settings
  // image_orientation.csv ("image_orientation" when the clip has IORI): samples read, frames
  // matched, and the largest IORI angle over the imported frames, deg.
  size_t iori_samples = 0, cori_samples = 0, orientation_frames = 0;
  double iori_max_deg = 0.0;
};

// What only a video without a gyro of its own records (an MP4 imported with `--gyro LOG`).
struct VideoFileImportDetails {
  VideoDecoding decoding;
};

// `import --gyro LOG`: the outside log gyro.csv holds, and how it was put on the clip's clock and
// axes (io/clip_alignment.h).
struct GyroLogAlignment {
  std::string path, format, gyro_source;  // the log, its reader's name, the stream read
  size_t log_samples = 0;                 // in the whole log
  double log_duration_s = 0.0;
  std::string method;  // "the clip's own gyro" or "the frames' rotation", for a person
  // The frames' rotation only: consecutive pairs, those with a rotation, their median inlier rays.
  size_t pairs = 0, pairs_used = 0, median_inliers = 0;
  GyroSync sync;               // clip (camera axes, camera clock) against the log
  double time_offset_s = 0.0;  // camera.json's: log clock = clip clock + this, at the clip's middle
  double written_from_s = 0.0, written_to_s = 0.0;  // the span of the log in gyro.csv (log clock)
};

// What only a phone clip folder records.
struct PhoneImportDetails {
  std::string origin;  // source.origin: where the clip comes from
  size_t sof_times = 0;
  size_t images_in_source = 0;
  double dump_sof_max_diff_s = 0.0;
  // exposure_range_s [min, max]; +inf and -inf (written as null) when no exposure is known.
  double exposure_min_s = 0.0, exposure_max_s = 0.0;
};

struct ImportRecord {
  std::string path;  // source.path
  double time_origin_s = 0.0;
  std::string clock;  // what the times are, for a person
  size_t gyro_samples = 0;
  double gyro_rate_hz = 0.0;
  std::string gyro_columns;  // what gyro.csv's columns are, for a person
  size_t frame_count = 0;
  std::string t_first_row;            // what a frame's t_first_row marks, for a person
  std::vector<int64_t> outside_gyro;  // frames whose declared readout the gyro does not cover
  std::vector<FrameExposure> exposures;
  std::vector<ImportClaim> claims;
  // What the clip's gyro lost or doubted (sim/trace_audit.h: gaps, repeated times, rate changes,
  // saturation), also printed on stderr.
  std::vector<LogWarning> warnings;
  std::optional<LensProfileUse> lens_profile;  // `--lens-profile` ("lens_profile" when given)
  // Also gives source.kind.
  std::variant<GoproImportDetails, PhoneImportDetails, VideoFileImportDetails> details;
  std::optional<GyroLogAlignment> gyro_log;  // `--gyro LOG` ("gyro_log")
  // import --mask: the mask file the dataset's camera.json names (docs/FORMATS.md `mask`) and the
  // user's file it was made from; empty when none was given.
  std::string mask_file, mask_source;
};

// A claim's value as import.json holds it, compact ("0.015", "[[0.0,-1.0,0.0],...]").
std::string ClaimValueJson(const ClaimValue& value);

// import.json's whole text: two-space indented JSON, keys sorted, a newline at the end.
std::string ImportJson(const ImportRecord& record);

// Writes import.json whole or not at all; throws IoError.
void WriteImportJson(const std::string& path, const ImportRecord& record);

}  // namespace shutterlab
