// libFuzzer target: camera.json (render/camera.h ReadRigModel).
#include "render/camera.h"

#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static shutterlab::fuzz::InputFile file("camera.json");
  const std::string& path = file.Write(data, size);
  shutterlab::fuzz::Expect([&] { shutterlab::ReadRigModel(path); });
  return 0;
}
