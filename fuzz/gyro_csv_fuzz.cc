// libFuzzer target: gyro.csv (sim/logs/gyro_io.h OpenGyroCsv) read as flight reads it, a block at
// a time: the first input byte picks the block size (1 to 256 bytes, so that every line end falls
// on a block edge somewhere) and the samples per chunk (fuzz::ChunkSamples), the rest is the file's
// text. Every chunk goes through the trace audit. Then the text read in one block, by row shapes
// (sim/logs/gyro_row_shapes.h) and byte by byte: the two must give the same samples bit for bit,
// or the same error.
#include "fuzz/fuzz_util.h"
#include "sim/logs/gyro_io.h"
#include "sim/trace_audit.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  if (size == 0) return 0;
  const std::string_view text = fuzz::Bytes(data + 1, size - 1);
  fuzz::Expect([&] {
    auto source = OpenGyroCsv(TextBlocks::InMemory(text, 1 + data[0]), "fuzz.csv",
                              fuzz::ChunkSamples(data[0]));
    fuzz::AuditEveryChunk(source.get());
  });
  const auto read_whole = [&](GyroCsvRows rows) {
    return fuzz::ReadOutcome([&] {
      FlightLog log;
      auto source =
          OpenGyroCsv(TextBlocks::InMemory(text), "fuzz.csv", fuzz::ChunkSamples(data[0]), rows);
      return fuzz::TakeAll(&log, source.get());
    });
  };
  if (read_whole(GyroCsvRows::kByShape) != read_whole(GyroCsvRows::kByteLoop)) __builtin_trap();
  return 0;
}
