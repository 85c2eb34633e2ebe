#pragma once
// A phone clip folder in the lhaippp/gyro-video-stabilization layout: gyro.txt (gx,gy,gz,t in
// rad/s and s), framestamp.txt (start-of-frame time of frame N on line N), gyro_dump.txt (optional:
// "SOF <us>, frameNum :N exp time <s>", the exposure per frame), frames/RE_frame-N.jpg (frame N;
// also .jpeg, .png). The text files are read here; the images are only listed.

#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace shutterlab {

// The phone clip's text files.
struct PhoneClip {
  GyroTrace gyro;               // device clock minus time_origin_ns, rad/s, sensor axes
  int64_t time_origin_ns = 0;   // subtracted from every time (whole seconds of the first sample)
  std::vector<int64_t> sof_ns;  // framestamp.txt: sof_ns[N-1] = start of frame N, minus origin
  std::map<int64_t, double> exposure_s;         // gyro_dump.txt: frame N -> exposure time
  double dump_sof_max_diff_s = 0.0;             // largest |SOF in gyro_dump.txt - framestamp.txt|
  std::map<int64_t, std::string> frame_images;  // frame N -> image path (frames/RE_frame-N.*)
  std::vector<LogWarning> warnings;  // gyro.txt cut inside its last line: that line left out
};

// The first of gyro.txt, framestamp.txt and frames/ that the folder lacks; "" when it has all
// three (what tells a phone clip folder; gyro_dump.txt is optional).
std::string MissingPhoneClipPart(const std::string& folder);

// Reads the folder's text files and lists its frame images. Throws IoError("PATH:LINE: problem") on
// a malformed line, a blank line in framestamp.txt, times going backwards, an image with no
// start-of-frame time, or no image at all. A gyro.txt cut inside its last line is read up to the
// last whole line, with a `truncated` warning in warnings.
PhoneClip ReadPhoneClip(const std::string& folder);

}  // namespace shutterlab
