// libFuzzer target: a Gyroflow lens profile (io/lens_profile.h ReadLensProfile), scaled to an
// image of another aspect as the commands do.
#include "fuzz/fuzz_util.h"
#include "io/lens_profile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static shutterlab::fuzz::InputFile file("profile.json");
  const std::string& path = file.Write(data, size);
  shutterlab::fuzz::Expect([&] {
    const shutterlab::LensProfile profile = shutterlab::ReadLensProfile(path);
    shutterlab::ScaleLensProfile(profile, 848, 480, 29.97);
  });
  return 0;
}
