// libFuzzer target: camera.json (model/camera.h ReadRigModel).
#include "fuzz/fuzz_util.h"
#include "model/camera.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static shutterlab::fuzz::InputFile file("camera.json");
  const std::string& path = file.Write(data, size);
  shutterlab::fuzz::Expect([&] { shutterlab::ReadRigModel(path); });
  return 0;
}
