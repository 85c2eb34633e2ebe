// Decoding speed of the blackbox reader on the real 1.9 MB Betaflight log in MB/s.
// Run: build/bin/blackbox_bench  (reports bytes_per_second; the log is read once, outside the
// loop).

#include "sim/logs/blackbox.h"
#include "sim/text_file.h"

#include <benchmark/benchmark.h>

#include "bench/bench_util.h"
#include <string>

namespace shutterlab {
namespace {

void BM_DecodeBlackbox(benchmark::State& state, const std::string& leaf) {
  const std::string bytes =
      ReadFileToString(bench::RealDataPath("gyro/betaflight_blackbox/" + leaf));
  size_t samples = 0;
  for (auto _ : state) {
    const FlightLog log = DecodeBlackbox(bytes, leaf);
    samples = log.gyro.size();
    benchmark::DoNotOptimize(samples);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
                          static_cast<int64_t>(bytes.size()));
  state.counters["samples"] = static_cast<double>(samples);
}
BENCHMARK_CAPTURE(BM_DecodeBlackbox, btfl_002, std::string("btfl_002.bbl"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DecodeBlackbox, LOG00037, std::string("LOG00037.BFL"))
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace shutterlab

BENCHMARK_MAIN();
