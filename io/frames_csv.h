#pragma once
// Frame lists: the capture-times file that `render` reads (frame,t_first_row) and a rig dataset's
// frames.csv (docs/FORMATS.md: frame,t_first_row,ref,image).

#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab {

struct FrameEntry {
  int64_t frame = 0;           // frame id
  int64_t t_first_row_ns = 0;  // camera clock: capture time of the first row READ (docs/FORMATS.md)
  std::string ref;    // reference image path relative to the dataset folder ("" in video datasets)
  std::string image;  // rolling-shutter image path relative to the dataset folder
};

// Reads `frame,t_first_row[,...]` (header required, extra columns ignored). Frame ids must be
// non-negative and unique. Throws IoError("PATH:LINE: problem").
std::vector<FrameEntry> ReadFrameTimes(const std::string& path);

// Writes the capture-times file ReadFrameTimes reads: frames 0, 1, ... at times_ns, whole or not
// at all; times with nine decimals, exact to the nanosecond.
void WriteFrameTimes(const std::string& path, const std::vector<int64_t>& times_ns);

// Reads a dataset's frames.csv (header frame,t_first_row,ref,image). Throws IoError("PATH:LINE:
// problem").
std::vector<FrameEntry> ReadFramesCsv(const std::string& path);

// A frame id zero-padded to 4 digits, as in truth/NNNN_disp.exr (docs/FORMATS.md) and
// images/NNNN_*.
std::string FrameName(int64_t frame);

// Writes frames.csv whole or not at all; times with nine decimals, exact to the nanosecond.
void WriteFramesCsv(const std::string& path, const std::vector<FrameEntry>& frames);

}  // namespace shutterlab
