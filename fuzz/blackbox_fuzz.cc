// libFuzzer target: Betaflight blackbox bytes, native or CSV export (sim/logs/blackbox.h
// OpenBlackboxBuffer), read twice: in one chunk, and streamed in chunks of 1 to 17 samples, so that
// the decoder pauses and resumes everywhere. Both must give the same samples bit for bit, the same
// warnings and the same error; a difference traps.
#include "fuzz/fuzz_util.h"
#include "sim/logs/blackbox.h"

#include <limits>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes = shutterlab::fuzz::Bytes(data, size);
  // The last bytes choose the chunk and the log (-1: the longest, or 0..2).
  const size_t chunk = size > 0 ? shutterlab::fuzz::ChunkSamples(data[size - 1]) : 1;
  const int log_index = size > 1 ? data[size - 2] % 4 - 1 : -1;
  const auto read = [&](size_t chunk_samples) {
    return shutterlab::fuzz::ReadOutcome([&] {
      shutterlab::BlackboxStream stream =
          shutterlab::OpenBlackboxBuffer(bytes, "fuzz.bbl", log_index, chunk_samples);
      return shutterlab::fuzz::TakeAll(&stream.log, stream.samples.get());
    });
  };
  if (read(std::numeric_limits<size_t>::max()) != read(chunk)) __builtin_trap();
  return 0;
}
