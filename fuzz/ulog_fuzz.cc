// libFuzzer target: PX4 ULog bytes (sim/logs/ulog.h ParseULog).
#include "sim/logs/ulog.h"

#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  shutterlab::fuzz::Expect(
      [&] { shutterlab::ParseULog(shutterlab::fuzz::Bytes(data, size), "fuzz.ulg"); });
  return 0;
}
