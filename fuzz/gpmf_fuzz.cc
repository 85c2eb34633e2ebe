// libFuzzer target: one GoPro GPMF payload (sim/logs/gpmf.h): the KLV tree, its values and the
// GYRO streams with their axis order, as the GoPro reader walks them.
#include "fuzz/fuzz_util.h"
#include "sim/logs/gpmf.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  fuzz::Expect([&] {
    const std::vector<GpmfKlv> payload = ParseGpmf(fuzz::Bytes(data, size), 0, "fuzz.gpmf");
    for (const GpmfStreamData& stream : FindGpmfStreams(payload, "GYRO", "fuzz.gpmf")) {
      GpmfAxisOrder(stream, "fuzz.gpmf");
    }
  });
  return 0;
}
