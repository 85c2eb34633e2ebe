// libFuzzer target: frames.csv (io/frames_csv.h ReadFramesCsv, ReadFrameTimes).
#include "fuzz/fuzz_util.h"
#include "io/frames_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static shutterlab::fuzz::InputFile file("frames.csv");
  const std::string& path = file.Write(data, size);
  shutterlab::fuzz::Expect([&] { shutterlab::ReadFramesCsv(path); });
  shutterlab::fuzz::Expect([&] { shutterlab::ReadFrameTimes(path); });
  return 0;
}
