#pragma once
// The codecs module (io/codecs/codecs_module.h: OpenImageIO, OpenCV's video reader and
// encoders), loaded the first time a process needs it, so that the commands and tests that read
// no image never load those libraries.
//
// The module is looked for beside the running executable, then in ../lib/shutterlab/ from it (an
// installed layout). Failing that, the first call throws std::runtime_error naming where it looked
// and what the loader said: a broken build or installation, not bad input.

#include "io/codecs/codecs_module.h"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace shutterlab {

// The module's functions; loads it on the first call (thread-safe).
const codecs::Functions& Codecs();

// OpenCV's encoder: `bgr` as the bytes of an image file of the format `extension` names (".png",
// ".jpg", ".tif"). Throws std::invalid_argument when OpenCV cannot encode it.
std::vector<uchar> EncodeImage(const std::string& extension, const cv::Mat& bgr);

// A video's frames in order, through OpenCV's reader.
class VideoFrames {
 public:
  // Throws IoError("PATH: OpenCV cannot open the video").
  explicit VideoFrames(const std::string& path);
  ~VideoFrames();
  VideoFrames(const VideoFrames&) = delete;
  VideoFrames& operator=(const VideoFrames&) = delete;

  // The next frame (BGR or BGRA) and the reader's time of it in ms (after a read OpenCV reports
  // the time of the frame it returned; not for the first or last). false at the end or on a
  // failed grab, after which the reader may go on.
  bool Read(cv::Mat* bgr, double* position_ms);

 private:
  void* video_;
};

}  // namespace shutterlab
