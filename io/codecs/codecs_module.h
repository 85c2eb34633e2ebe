#pragma once
// The codecs module: the one place OpenImageIO and OpenCV's video reader and image encoders are
// called. It is a shared object of its own that io/codecs.h loads on first use, not a linked
// library: linked into a process, those libraries (271 shared objects with their dependencies:
// gdal, ffmpeg, dcmtk, openvdb, ...) cost 0.37 s before main, 0.34 s of it OpenImageIO's alone
// (docs/development.md, "Start-up"), paid by every command and every test case, most of which
// read no image. Its functions take and give cv::Mat and std::string: the module and its loader
// are built together, from this header, and the loader refuses a module of another version.
// Nothing here throws: each failure is returned as the library's own message.

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace shutterlab::codecs {

// Bumped whenever anything below changes.
constexpr int kCodecsVersion = 5;

// A sample type as OpenImageIO names it.
enum class SampleType { kUint8, kUint16, kHalf, kFloat, kDouble, kOther };

// An image file's header, as OpenImageIO reads it (EXIF orientation ignored: rows stay sensor
// rows).
struct ImageHeader {
  std::string format;                                  // "jpeg", "png", "tiff", "openexr", ...
  int width = 0, height = 0, depth = 0, channels = 0;  // depth: 1 for a 2-D image
  SampleType sample_type = SampleType::kOther;
  int bytes_per_sample = 0;
  std::string compression;       // "Compression" ("lzw", "zip", "jpeg", ...), "" if none
  std::string jpeg_subsampling;  // "4:2:0", ...
  std::vector<std::string> channel_names;
};

// How WriteImage stores an image.
struct ImageWriteSettings {
  SampleType file_type = SampleType::kUint8;
  std::vector<std::string> channel_names;  // empty: the format's own
  int alpha_channel = -1;                  // -1: none
  std::string compression;                 // "" : the format's default
  std::string jpeg_subsampling;            // "" : the format's default
  int png_compression_level = -1;          // zlib level, -1: the format's default
  int png_filter = 0;                      // libpng's PNG_FILTER_* bits; 0: its own (adaptive)
};

struct Functions {
  int version = kCodecsVersion;
  // "" on success; otherwise the library's message, on one line.
  std::string (*read_header)(const std::string& path, ImageHeader* header);
  // Reads every channel of the first subimage as `as` (kUint8, kUint16 or kFloat) into *image
  // (CV_8U, CV_16U or CV_32F with the file's channel count), and its header. A decoder may read
  // the image and still complain (a JPEG cut short decodes with grey rows): *complaint, "" if not.
  std::string (*read_image)(const std::string& path, SampleType as, cv::Mat* image,
                            ImageHeader* header, std::string* complaint);
  // Writes a continuous CV_8U, CV_16U or CV_32F image; the format follows the extension.
  std::string (*write_image)(const std::string& path, const cv::Mat& image,
                             const ImageWriteSettings& settings);
  // OpenCV's encoder (cv::imencode): an image in OpenCV's channel order (BGR) as a file's bytes
  // of the format `extension` names (".png", ".jpg", ".tif"); false when it cannot.
  bool (*encode)(const std::string& extension, const cv::Mat& bgr, std::vector<uchar>* bytes);
  // OpenCV's video reader: open returns nullptr when it cannot open the file; read gives the next
  // frame (BGR) and the reader's time of it (ms), false at the end or on a failed grab.
  void* (*open_video)(const std::string& path);
  bool (*read_video_frame)(void* video, cv::Mat* bgr, double* position_ms);
  void (*close_video)(void* video);
};

}  // namespace shutterlab::codecs

// The module's one exported symbol.
extern "C" const shutterlab::codecs::Functions* shutterlab_codecs();
