#pragma once
// Image files through OpenImageIO, their metadata through exiv2. This unit is the only one that
// includes either (both link PRIVATE to shutterlab_render), so the rest of the project sees plain
// cv::Mat.
//
// Channel order is the file's (R, G, B), not OpenCV's BGR: images are read and written here only,
// so the order never matters to the geometry, and a grey image stays one channel.
// Rows are never reoriented (oiio:reorient = 0): an image row must stay a sensor row.

#include "sim/check.h"

#include <opencv2/core.hpp>

#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

// Reads PNG, TIFF, JPEG, EXR, ... as CV_8U or CV_16U (other pixel types are converted to CV_16U,
// float to CV_32F), with 1 or 3 channels (an alpha channel is dropped, two channels are refused).
// Throws IoError("PATH: problem") with OpenImageIO's own message when the file cannot be read.
cv::Mat ReadImage(const std::string& path);

// A file whose pixels do not decode, in whole or in part: what() is "PATH: REASON", the reason
// "its image data does not decode (PROBLEM): a cut or damaged file; ...".
class UndecodableImage : public IoError {
 public:
  UndecodableImage(const std::string& path, const std::string& reason)
      : IoError(IoMessage(path, 0, reason)), reason(reason) {}
  std::string reason;  // without the path, for a list that names the file its own way
};

// ReadImage for pixels that must all be there: a JPEG cut short or damaged inside its coded data
// still decodes, with grey or smeared rows, and OpenImageIO says so only in a warning. Throws
// UndecodableImage then and when the pixels do not decode (ImageDataProblem's verdict, asked only
// when the decode failed or warned), IoError for a file that cannot be opened or read otherwise
// (memory included). One decode for a whole file, where ImageDataProblem's check and then
// ReadImage would be two. With `buffer` the pixels are decoded into it, its memory
// reused when the size and type match: the result shares it and holds until the next call with
// the same buffer. A job that decodes many photos of one camera so skips each one's first-touch
// page faults (a 12 MP RGB photo is 36 MB).
cv::Mat ReadWholeImage(const std::string& path, cv::Mat* buffer = nullptr);

// A picture of the image for an overview, at least min_width pixels wide where the image is: a
// JPEG at its smallest DCT scale that keeps min_width (ReadJpegScaled: 1/8 of a 4000-pixel photo
// for a 480-pixel tile), any other file, or a JPEG libjpeg cannot decode, whole (ReadImage).
cv::Mat ReadImagePreview(const std::string& path, int min_width);

// Writes a CV_8U / CV_16U / CV_32F image with 1, 2, 3 or 4 channels, format chosen by the
// extension. Whole or not at all: written to a temporary file in the same folder, then renamed.
// channel_names (optional) name the channels, e.g. {"dx", "dy"} for an EXR displacement field.
void WriteImage(const std::string& path, const cv::Mat& image,
                const std::vector<std::string>& channel_names = {});

// A mask of one bit a pixel, packed as a one-bit PNG stores its rows: `bits` is CV_8UC1, one row
// per image row of (width + 7) / 8 bytes, pixel u in bit 7 - u % 8 of byte u / 8, 1 where the
// pixel may be used; the bits past the width are 0. A 12 MP mask is 1.5 MB instead of 12 MB, so a
// job that makes one per photo writes, counts and stores an eighth of the bytes.
struct PackedMask {
  int width = 0;
  cv::Mat bits;
  int height() const { return bits.rows; }
};
// Sets pixel k of a packed row.
inline void SetMaskBit(int k, uint8_t* bits) {
  bits[k / 8] |= static_cast<uint8_t>(0x80 >> (k % 8));
}
// Sets pixels 0 to n - 1 of a packed row, the rest of its last byte clear.
inline void SetFirstMaskBits(int n, uint8_t* bits) {
  std::memset(bits, 0xFF, n / 8);
  if (n % 8 != 0) bits[n / 8] = static_cast<uint8_t>(0xFF00 >> (n % 8));
}
// Packs a CV_8UC1 mask: nonzero pixels set.
PackedMask PackMask(const cv::Mat& mask);
// The mask as CV_8UC1, 255 where set and 0 elsewhere.
cv::Mat UnpackMask(const PackedMask& mask);
// How many pixels are set.
size_t CountSetPixels(const PackedMask& mask);

// Writes a mask as a PNG of one bit a pixel (the packed rows as they are, unfiltered), whole or
// not at all. OpenImageIO reads it back as 0 and 255, and COLMAP's feature extractor honours it
// as it does an 8-bit mask (tests/io/image_io_test.cc). A 12 MP mask in 3 ms against 21 ms as an
// 8-bit PNG (bench/photos_bench.cc).
void WriteMask(const std::string& path, const PackedMask& mask);

// Reads a float image (e.g. an EXR displacement field) as CV_32FC(n) and returns its channel names.
cv::Mat ReadFloatImage(const std::string& path, std::vector<std::string>* channel_names = nullptr);

// How an image file stores its pixels, so that another image can be written alike.
struct ImageFileInfo {
  std::string format;  // OpenImageIO's format name: "jpeg", "png", "tiff", "openexr", ...
  int width = 0, height = 0, channels = 0;
  int bits_per_channel = 8;  // as stored: 8, 16 (integer or half float), 32 (float)
  bool floating = false;     // float or half samples
  std::string compression;   // OpenImageIO's "Compression" ("lzw", "zip", "piz", ...), "" if none
  // JPEG: the quality of the IJG scale that gives the file's luminance quantisation table (the
  // estimate ImageMagick makes; exact for files written by libjpeg at that quality), and the chroma
  // subsampling ("4:2:0", ...).
  std::optional<int> jpeg_quality;
  std::string jpeg_subsampling;
};
// Throws IoError("PATH: problem") when the file cannot be opened as an image.
ImageFileInfo ReadImageFileInfo(const std::string& path);

// Writes `image` (its depth as ReadImage gives it for `like`) into `path` as `like` is stored: the
// same bits per channel (half floats again as half), JPEG quality and subsampling, compression; the
// format follows path's extension. Then copies the EXIF, IPTC and XMP metadata of the file at
// like.path (exiv2; an EXIF thumbnail is carried as it is) and sets the XMP properties in `xmp`
// (keys "Xmp.shutterlab.Name", namespace https://shutterlab.invalid/ns/1.0/). Whole or not at all.
// Returns what could not be carried, one line each (a format without a metadata container: EXR).
struct ImageLike {
  std::string path;  // the file whose metadata is copied
  ImageFileInfo info;
};
std::vector<std::string> WriteImageLike(
    const std::string& path, const cv::Mat& image, const ImageLike& like,
    const std::vector<std::pair<std::string, std::string>>& xmp = {});

// Writes `image` (JPEG at `jpeg_quality`, other formats as WriteImage) with the EXIF and XMP
// properties given as (exiv2 key, value text), each value as exiv2 reads its type's text
// ("Exif.Photo.FocalLength" "4500/1000", "Exif.GPSInfo.GPSLatitude" "47/1 0/1 0/1",
// "Xmp.drone-dji.FlightXSpeed" "+5.00"; the drone-dji prefix is bound to DJI's namespace
// http://www.dji.com/drone-dji/1.0/). Whole or not at all; IoError naming a value exiv2 refuses.
using MetadataFields = std::vector<std::pair<std::string, std::string>>;
void WriteImageWithMetadata(const std::string& path, const cv::Mat& image, int jpeg_quality,
                            const MetadataFields& exif, const MetadataFields& xmp);

// The EXIF, IPTC and XMP metadata of an image file as (exiv2 key, value text) pairs, e.g.
// ("Exif.Image.Make", "DJI"), ("Xmp.drone-dji.RelativeAltitude", "+117.90"); empty for a format
// exiv2 does not read. Throws IoError for a file that is not there.
std::vector<std::pair<std::string, std::string>> ReadImageMetadata(const std::string& path);

}  // namespace shutterlab
