#pragma once
// A folder of photos as input: each photo's metadata (io/photo_metadata.h) turned into what the
// analyses need (the camera's focal length in pixels, the readout, the height above ground, the
// ground speed, the capture time), each with where it came from, and what is missing. A photo that
// cannot be read is a record with an error, never an exception: one bad file does not stop a
// survey. Shared by `analyze --photos` and any command that takes the same folder.

#include "io/lens_profile.h"
#include "io/photo_metadata.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// Diagonal of the 36 x 24 mm frame, mm: the 35 mm-equivalent focal length is defined on it
// (the equivalent lens gives the same diagonal field of view).
inline constexpr double kFullFrameDiagonalMm = 43.266615305567875;  // sqrt(36^2 + 24^2)

// The focal length in pixels of a width x height image from a 35 mm-equivalent focal length,
// defined on the diagonal: f_px = f35_mm / 43.27 mm * sqrt(width^2 + height^2). A camera whose
// equivalent describes the whole sensor but whose photo is a crop of it (a 16:9 photo from a 4:3
// sensor, when the camera keeps writing the 4:3 equivalent) gets a focal length too short by the
// ratio of the diagonals (0.92 for 16:9 from 4:3).
double FocalPxFrom35mm(double focal_35mm, int width, int height);

// Where a photo's readout came from, best first.
enum class ReadoutOrigin {
  kUser,         // --readout
  kCameraFile,   // camera.json
  kLensProfile,  // a lens profile's frame readout
  kPhoto,        // the photo's own metadata (no drone camera we know writes it)
  kTable,        // model/readout_table.h
  kNone,         // unknown: nothing is predicted that needs it
};
// "user", "camera.json", "lens profile", "photo", "table", "none".
const char* ReadoutOriginName(ReadoutOrigin origin);

struct PhotoSetOptions {
  // Given by the user or a camera file, they win over the photos' own values.
  std::optional<double> readout_s;
  ReadoutOrigin readout_origin = ReadoutOrigin::kUser;  // kUser, kCameraFile or kLensProfile
  std::string readout_text;                             // e.g. "--readout 20ms", "camera.json"
  std::optional<double> focal_px;
  std::string focal_text;  // e.g. "--focal-px", "camera.json"
  // camera.json's camera: a photo of its size takes its principal point and lens too (exports).
  std::optional<PinholeCamera> camera;
  // A Gyroflow lens profile (--lens-profile), scaled to each photo: its focal length after the
  // given one, its readout (ReadoutOrigin::kLensProfile) after the given one.
  std::optional<LensProfile> lens_profile;
  std::optional<double> altitude_m;
  // --ground-elevation: the ground's elevation (the take-off point's, flat ground) in the datum of
  // the photos' absolute altitude (XMP drone-dji:AbsoluteAltitude, else EXIF GPSAltitude: above
  // sea level). A photo without a height above take-off gets absolute minus this, said as derived.
  std::optional<double> ground_elevation_m;
  // --speed: the ground speed of every photo, over their metadata's (the direction, when the
  // metadata has one, is kept).
  std::optional<double> speed_m_s;
  // Read the folder's subfolders too (a card's DCIM/100MEDIA, 101MEDIA, ...); a photo's name is
  // then its path under the folder ("101MEDIA/DJI_0001.JPG").
  bool recursive = false;
  // Decode each photo's pixels to find a cut or damaged file (io/image_check.h). A job that
  // decodes every photo in full anyway (correct --photos, through ReadWholeImage) finds it then.
  bool check_image_data = true;
  std::function<void(double)> progress;  // fraction read (0..1); may be empty
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct PhotoRecord {
  std::string path;
  std::string
      name;  // the file name, e.g. "DJI_0123.JPG" (read recursively: its path under the folder)
  std::optional<int64_t> number;  // the stem's last digits (DJI_0123 -> 123), for trigger indexes
  // The file could not be read (nothing below is set), or its image data does not decode
  // (io/image_check.h: the metadata below is kept, the photo is not used).
  std::string error;
  PhotoMetadata metadata;
  // What the analyses use, each with its source for a person ("EXIF FocalLengthIn35mmFilm 24 mm
  // on the diagonal", "XMP drone-dji:RelativeAltitude", ...).
  std::optional<double> focal_px;
  std::string focal_source;
  // The whole camera where camera.json (at the photo's size) or the lens profile gives one: its
  // principal point and lens beside the focal length, for the exports; unset: the metadata give
  // a focal length only.
  std::optional<PinholeCamera> camera;
  std::optional<double> readout_s;
  ReadoutOrigin readout_origin = ReadoutOrigin::kNone;
  std::string readout_source;
  std::optional<double> altitude_m;  // above the ground under the camera (flat ground assumed)
  std::string altitude_source;
  std::optional<double> ground_speed_m_s;  // horizontal, |(north, east)|
  std::optional<double> course_deg;        // direction of that motion, degrees from north
  std::string speed_source;
  // The speed and course above are the photos' GPS positions differentiated (SpeedsFromPositions),
  // not recorded: a log's velocity, where one is given, is better and replaces them.
  bool speed_from_positions = false;
  // What could not be found, in words ("focal length", "readout", "altitude", "flight speed",
  // "capture time", "image size"), in that order.
  std::vector<std::string> missing;
  bool ok() const { return error.empty(); }
  // width * height / 1e6 of the camera's own image (EXIF PixelX/YDimension when written).
  double CaptureMegapixels() const;
};

struct PhotoSet {
  std::string source;               // the folder (or the one file) read
  std::vector<PhotoRecord> photos;  // by file name
  size_t in_subfolders = 0;         // photo files in subfolders, not read (not recursive)
};

// Photo files are .jpg, .jpeg, .tif, .tiff and .dng, any case.
bool IsPhotoFileName(const std::string& name);

// Reads every photo file in dir (its subfolders too with options.recursive, else only counted),
// sorted by name; a path to one photo file reads that one. Throws IoError("DIR: problem") when dir
// does not exist or holds no photo file (saying so when its subfolders hold some).
PhotoSet ReadPhotoSet(const std::string& dir, const PhotoSetOptions& options = {});

// The record of one photo's metadata, as ReadPhotoSet makes it (for callers that have the
// metadata already, and for tests).
PhotoRecord MakePhotoRecord(const std::string& path, const PhotoMetadata& metadata,
                            const PhotoSetOptions& options);

// Photos that record no flight speed (and were given none) take it from the GPS positions of the
// photos around them on their camera clock: the distance between two photos (north and east on
// the sphere) over their capture times' difference. The two end a window of at least three photos
// in time order: the photo's neighbours, else the two before it, else the two after it (a line's
// last and first photos), widened on its open sides until its ends' times are at least
// kSpeedSpanResolutions times their resolution apart (a capture time without sub-seconds is good
// to a second), within kMaxSpeedSpanS. A window whose steps of a metre or more leave its chord's
// course by more than kMaxSpeedBendDeg (a turn) is not used. None for a photo without a position
// or capture time, or without such a window. Each says which photos and how far apart.
// ReadPhotoSet calls it.
inline constexpr double kSpeedSpanResolutions = 10.0;
inline constexpr double kMaxSpeedSpanS = 30.0;
inline constexpr double kMaxSpeedBendDeg = 15.0;
void SpeedsFromPositions(PhotoSet* set);

// What a lens profile gives the photos of a folder: its notes (io/lens_profile.h
// ScaleLensProfile) at the size of the first readable photo that has one; empty when none has.
std::vector<std::string> LensProfileNotes(const PhotoSet& set, const LensProfile& profile);

}  // namespace shutterlab
