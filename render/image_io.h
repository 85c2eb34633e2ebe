#pragma once
// Image files through OpenImageIO. This unit is the only one that includes OpenImageIO (it links
// PRIVATE to shutterlab_render), so the rest of the project sees plain cv::Mat.
//
// Channel order is the file's (R, G, B), not OpenCV's BGR: images are read and written here only,
// so the order never matters to the geometry, and a grey image stays one channel.
// Rows are never reoriented (oiio:reorient = 0): an image row must stay a sensor row.

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace shutterlab {

// Reads PNG, TIFF, JPEG, EXR, ... as CV_8U or CV_16U (other pixel types are converted to CV_16U,
// float to CV_32F), with 1 or 3 channels (an alpha channel is dropped, two channels are refused).
// Throws IoError("PATH: problem") with OpenImageIO's own message when the file cannot be read.
cv::Mat ReadImage(const std::string& path);

// Writes a CV_8U / CV_16U / CV_32F image with 1, 2, 3 or 4 channels, format chosen by the
// extension. Whole or not at all: written to a temporary file in the same folder, then renamed.
// channel_names (optional) name the channels, e.g. {"dx", "dy"} for an EXR displacement field.
void WriteImage(const std::string& path, const cv::Mat& image,
                const std::vector<std::string>& channel_names = {});

// Reads a float image (e.g. an EXR displacement field) as CV_32FC(n) and returns its channel names.
cv::Mat ReadFloatImage(const std::string& path, std::vector<std::string>* channel_names = nullptr);

}  // namespace shutterlab
