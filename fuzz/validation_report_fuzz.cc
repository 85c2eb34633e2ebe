// libFuzzer target: a validation report as `correct --report` reads it
// (model/reported_model.h ReadValidationReport).
#include "fuzz/fuzz_util.h"
#include "model/reported_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static shutterlab::fuzz::InputFile file("report.json");
  const std::string& path = file.Write(data, size);
  shutterlab::fuzz::Expect([&] { shutterlab::ReadValidationReport(path); });
  return 0;
}
