// libFuzzer target: ArduPilot DataFlash bytes (sim/logs/dataflash.h ParseDataFlash).
#include "sim/logs/dataflash.h"

#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  shutterlab::fuzz::Expect(
      [&] { shutterlab::ParseDataFlash(shutterlab::fuzz::Bytes(data, size), "fuzz.bin"); });
  return 0;
}
