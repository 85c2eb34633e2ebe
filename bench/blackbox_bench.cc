// Decoding speed of the blackbox reader on the real 1.9 MB Betaflight log (issue 5 asks for MB/s).
// Run: build/bin/blackbox_bench  (reports bytes_per_second; the log is read once, outside the
// loop).

#include "sim/logs/blackbox.h"
#include "sim/text_file.h"

#include <benchmark/benchmark.h>

#include <string>

namespace shutterlab {
namespace {

// The repository root, from this file's own path (CMake compiles it by absolute path).
std::string RepoPath(const std::string& relative) {
  std::string here = __FILE__;
  const size_t cut = here.rfind("bench/");
  return (cut == std::string::npos ? std::string() : here.substr(0, cut)) + relative;
}

void BM_DecodeBlackbox(benchmark::State& state, const std::string& leaf) {
  const std::string bytes = ReadFileToString(RepoPath("tests/data/betaflight/" + leaf));
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
