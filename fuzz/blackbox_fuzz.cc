// libFuzzer target: Betaflight blackbox bytes, native or CSV (sim/logs/blackbox.h DecodeBlackbox).
#include "sim/logs/blackbox.h"

#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  shutterlab::fuzz::Expect(
      [&] { shutterlab::DecodeBlackbox(shutterlab::fuzz::Bytes(data, size), "fuzz.bbl"); });
  return 0;
}
