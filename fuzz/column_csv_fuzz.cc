// libFuzzer target: a delimited gyro log read by its columns (sim/logs/column_csv.h), a block at a
// time. The first input byte picks the column choice, delimiter and units, the second the block
// size (1 to 256 bytes) and the samples per chunk (fuzz::ChunkSamples); the rest is the file's
// text. Every chunk goes through the trace audit.
#include "fuzz/fuzz_util.h"
#include "sim/logs/column_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  if (size < 2) return 0;
  const uint8_t pick = data[0];
  ColumnCsvOptions options;
  options.columns = (pick & 1) ? std::vector<std::string>{"4", "1", "2", "3"}
                               : std::vector<std::string>{"t", "gx", "gy", "gz"};
  constexpr char kDelimiters[] = {'\0', ',', ';', '\t', ' '};
  options.delimiter = kDelimiters[(pick >> 1) % 5];
  options.time_unit = (pick & 0x10) ? TimeUnit::kMicroseconds : TimeUnit::kSeconds;
  options.rate_unit = (pick & 0x20) ? RateUnit::kDegPerSecond : RateUnit::kRadPerSecond;
  fuzz::Expect([&] {
    ColumnCsvStream stream =
        OpenColumnCsv(TextBlocks::InMemory(fuzz::Bytes(data + 2, size - 2), 1 + data[1]),
                      "fuzz.csv", options, fuzz::ChunkSamples(data[1]));
    fuzz::AuditEveryChunk(stream.samples.get());
  });
  return 0;
}
