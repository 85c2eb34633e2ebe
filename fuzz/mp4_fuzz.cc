// libFuzzer target: an MP4 file (sim/logs/mp4.h Mp4File, sim/logs/gopro_telemetry.h): boxes,
// sample tables, and the GoPro telemetry and frame times when a gpmd track is there.
#include "fuzz/fuzz_util.h"
#include "sim/logs/gopro_telemetry.h"
#include "sim/logs/mp4.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  static fuzz::InputFile file("clip.mp4");
  const std::string& path = file.Write(data, size);
  fuzz::Expect([&] {
    Mp4File mp4(path);
    if (!HasGoproTelemetry(path)) return;
    ReadGoproTelemetry(path);
    ReadVideoFrameTimesS(path);
  });
  return 0;
}
