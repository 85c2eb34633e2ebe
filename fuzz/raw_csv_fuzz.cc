// libFuzzer target: the source paper's raw-count logs (sim/logs/raw_csv.h OpenRawCsv), a block at
// a time. The first input byte picks the block size (1 to 64 bytes), the range, the time unit and
// the samples per chunk (fuzz::ChunkSamples); the rest is the file's text. Every chunk goes through
// the trace audit at the stated full scale.
#include "fuzz/fuzz_util.h"
#include "sim/logs/raw_csv.h"
#include "sim/trace_audit.h"
#include "sim/units.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  if (size == 0) return 0;
  constexpr int kRanges[] = {250, 500, 1000, 2000};
  constexpr TimeUnit kUnits[] = {TimeUnit::kSeconds, TimeUnit::kMilliseconds,
                                 TimeUnit::kMicroseconds, TimeUnit::kNanoseconds};
  const int range_dps = kRanges[data[0] & 3];
  const TimeUnit unit = kUnits[(data[0] >> 2) & 3];
  const std::string_view text = fuzz::Bytes(data + 1, size - 1);
  fuzz::Expect([&] {
    auto source = OpenRawCsv(TextBlocks::InMemory(text, 1 + (data[0] >> 4) * 4), "fuzz.csv",
                             range_dps, unit, fuzz::ChunkSamples(data[0]));
    TraceAuditOptions audit;
    audit.full_scale_rad_s = range_dps * kRadPerDeg;
    fuzz::AuditEveryChunk(source.get(), audit);
  });
  return 0;
}
