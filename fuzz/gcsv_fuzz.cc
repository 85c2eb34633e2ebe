// libFuzzer target: Gyroflow .gcsv (sim/logs/gcsv.h OpenGcsv): its header block, then the samples a
// block at a time. The first input byte picks the block size (1 to 256 bytes) and the samples per
// chunk (fuzz::ChunkSamples); the rest is the file's text. Every chunk goes through the trace
// audit.
#include "fuzz/fuzz_util.h"
#include "sim/logs/gcsv.h"
#include "sim/trace_audit.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  if (size == 0) return 0;
  const std::string_view text = fuzz::Bytes(data + 1, size - 1);
  fuzz::Expect([&] {
    GcsvStream stream =
        OpenGcsv(TextBlocks::InMemory(text, 1 + data[0]), "fuzz.gcsv", fuzz::ChunkSamples(data[0]));
    fuzz::AuditEveryChunk(stream.samples.get());
  });
  return 0;
}
