// libFuzzer target: gyro.csv (sim/logs/gyro_io.h OpenGyroCsv) read as flight reads it, a block at
// a time: the first input byte picks the block size (1 to 256 bytes, so that every line end falls
// on a block edge somewhere) and the samples per chunk (fuzz::ChunkSamples), the rest is the file's
// text. Every chunk goes through the trace audit.
#include "sim/logs/gyro_io.h"
#include "sim/trace_audit.h"

#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  if (size == 0) return 0;
  const std::string_view text = fuzz::Bytes(data + 1, size - 1);
  fuzz::Expect([&] {
    auto source = OpenGyroCsv(TextBlocks::InMemory(text, 1 + data[0]), "fuzz.csv",
                              fuzz::ChunkSamples(data[0]));
    fuzz::AuditEveryChunk(source.get());
  });
  return 0;
}
