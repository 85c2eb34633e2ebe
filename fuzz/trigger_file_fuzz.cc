// libFuzzer target: the trigger-file parsers (sim/logs/trigger_file.h): a DJI/Autel .MRK and a
// trigger CSV (plain, named, or with a header naming its time column), on the same bytes.
#include "fuzz/fuzz_util.h"
#include "sim/logs/trigger_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  const std::string_view text = fuzz::Bytes(data, size);
  fuzz::Expect([&] { ParseMrk(text, "fuzz.MRK"); });
  fuzz::Expect([&] { ParseTriggerCsv(text, "fuzz.csv"); });
  return 0;
}
