// Decoding speed of the blackbox reader on the real Betaflight logs in MB/s, and the logs of any
// length that the memory measurements of docs/speed.md read.
// Run: build/bin/blackbox_bench  (reports bytes_per_second; the log is read once, outside the
// loop). BM_DecodeBlackbox reads a log as every command does (a first pass that decodes every log
// without keeping a sample, then the chosen log decoded again in chunks); BM_ListBlackboxLogs,
// the reference, decodes once and keeps every sample (what reading it whole cost).
//
// Usage: blackbox_bench --generate-only --samples N --file PATH
// writes a blackbox log of N main frames (2 kHz, loopIteration, time and gyroADC[0..2], an I frame
// every 32; about 5 bytes a frame, so 10^8 samples are 0.5 GB) and exits. Other arguments go to
// Google Benchmark.

#include "bench/bench_util.h"
#include "sim/logs/blackbox.h"
#include "sim/text_file.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>
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

void BM_ListBlackboxLogs(benchmark::State& state, const std::string& leaf) {
  const std::string bytes =
      ReadFileToString(bench::RealDataPath("gyro/betaflight_blackbox/" + leaf));
  for (auto _ : state) benchmark::DoNotOptimize(ListBlackboxLogsInBuffer(bytes, leaf));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
                          static_cast<int64_t>(bytes.size()));
}
BENCHMARK_CAPTURE(BM_ListBlackboxLogs, btfl_002, std::string("btfl_002.bbl"))
    ->Unit(benchmark::kMillisecond);

// The firmware's variable-byte integers (betaflight blackbox_encoding.c), into a file.
class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : file_(std::fopen(path.c_str(), "wb")) {
    if (!file_) throw std::runtime_error("cannot write " + path);
  }
  ~LogWriter() {
    if (file_) std::fclose(file_);
  }
  void Text(const char* text) { Write(text, std::strlen(text)); }
  void Byte(uint8_t b) { Write(&b, 1); }
  void UnsignedVb(uint32_t value) {
    while (value > 127) {
      Byte(static_cast<uint8_t>(value | 0x80));
      value >>= 7;
    }
    Byte(static_cast<uint8_t>(value));
  }
  void SignedVb(int32_t value) {
    UnsignedVb((static_cast<uint32_t>(value) << 1) ^ static_cast<uint32_t>(value >> 31));
  }
  void Close() {
    if (std::fclose(file_) != 0) throw std::runtime_error("write failed");
    file_ = nullptr;
  }

 private:
  void Write(const void* data, size_t size) {
    if (std::fwrite(data, 1, size, file_) != size) throw std::runtime_error("write failed");
  }
  FILE* file_;
};

// A 2 kHz flight of n main frames: each axis a slow sine of up to 300 deg/s plus ±2 deg/s of
// noise, the time ±1 us of jitter (so the straight-line time predictor has residuals to encode),
// the 32-bit microsecond clock wrapping every 71.6 minutes.
void GenerateLog(const std::string& path, uint64_t n) {
  constexpr int kIInterval = 32;
  constexpr int64_t kLoopUs = 500;
  LogWriter w(path);
  w.Text(
      "H Product:Blackbox flight data recorder by Nicholas Sherlock\n"
      "H Data version:2\n"
      "H I interval:32\n"
      "H P interval:1\n"
      "H Firmware type:Cleanflight\n"
      "H Firmware revision:shutterlab blackbox_bench\n"
      "H gyro_scale:0x3f800000\n"
      "H Field I name:loopIteration,time,gyroADC[0],gyroADC[1],gyroADC[2]\n"
      "H Field I signed:0,0,1,1,1\n"
      "H Field I predictor:0,0,0,0,0\n"
      "H Field I encoding:1,1,0,0,0\n"
      "H Field P predictor:6,2,1,1,1\n"
      "H Field P encoding:9,0,0,0,0\n");
  uint64_t random = 0x9E3779B97F4A7C15ull;
  const auto next_random = [&random] {
    random ^= random << 13;
    random ^= random >> 7;
    random ^= random << 17;
    return random;
  };
  uint32_t t_prev = 0, t_prev2 = 0;
  int32_t gyro_prev[3] = {0, 0, 0};
  for (uint64_t k = 0; k < n; ++k) {
    const uint32_t t = static_cast<uint32_t>(1000000 + static_cast<int64_t>(k) * kLoopUs +
                                             static_cast<int64_t>(next_random() % 3) - 1);
    int32_t gyro[3];
    for (int axis = 0; axis < 3; ++axis) {
      const double phase = static_cast<double>(k) * 1e-4 * (axis + 1);
      gyro[axis] = static_cast<int32_t>(std::lround(300.0 * std::sin(phase))) +
                   static_cast<int32_t>(next_random() % 5) - 2;
    }
    if (k % kIInterval == 0) {
      w.Byte('I');
      w.UnsignedVb(static_cast<uint32_t>(k));
      w.UnsignedVb(t);
      for (int axis = 0; axis < 3; ++axis) w.SignedVb(gyro[axis]);
    } else {
      w.Byte('P');
      // The straight-line prediction in the firmware's 32-bit arithmetic (the clock wraps).
      w.SignedVb(static_cast<int32_t>(t - (2 * t_prev - t_prev2)));
      for (int axis = 0; axis < 3; ++axis) w.SignedVb(gyro[axis] - gyro_prev[axis]);
    }
    // After an I frame the decoder predicts the next time from it alone (prev2 = prev).
    t_prev2 = k % kIInterval == 0 ? t : t_prev;
    t_prev = t;
    std::memcpy(gyro_prev, gyro, sizeof(gyro));
  }
  w.Byte('E');
  w.Byte(255);
  w.Text("End of log");
  w.Byte(0);
  w.Close();
}

int Main(int argc, char** argv) {
  bool generate_only = false;
  uint64_t samples = 10000000;
  std::string path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--generate-only") {
      generate_only = true;
    } else if (arg == "--samples" && i + 1 < argc) {
      samples = std::stoull(argv[++i]);
    } else if (arg == "--file" && i + 1 < argc) {
      path = argv[++i];
    }
  }
  if (generate_only) {
    if (path.empty()) {
      std::fprintf(stderr, "usage: %s --generate-only --samples N --file PATH\n", argv[0]);
      return 2;
    }
    GenerateLog(path, samples);
    return 0;
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace
}  // namespace shutterlab

int main(int argc, char** argv) { return shutterlab::bench::RunMain(shutterlab::Main, argc, argv); }
