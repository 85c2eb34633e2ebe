#pragma once
// Shared by the benchmarks: where the repository and the real data are, and a per-thread CPU
// clock with a warm-up, so that ratios against a reference measured in the same run are stable
// on a shared machine.

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <time.h>
#include <utility>
#include <vector>

namespace shutterlab::bench {

// A benchmark's main: runs main_body, and an exception ends it with a one-line error (exit 1).
inline int RunMain(int (*main_body)(int, char**), int argc, char** argv) {
  try {
    return main_body(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

// A path inside the repository (this file's folder's parent).
inline std::string RepoPath(const std::string& relative) {
  const std::string here = __FILE__;
  const size_t cut = here.rfind("bench/");
  return (cut == std::string::npos ? std::string() : here.substr(0, cut)) + relative;
}

// A real recorded file: the shared data folder beside the checkout (../shared/data) or
// SHUTTERLAB_DATA_DIR. Exits with a one-line message when it is not there.
inline std::string RealDataPath(const std::string& relative) {
  const char* dir = std::getenv("SHUTTERLAB_DATA_DIR");
  const std::string root = dir != nullptr && *dir != '\0' ? dir : RepoPath("../shared/data");
  const std::string path = root + "/" + relative;
  if (!std::filesystem::exists(path)) {
    std::fprintf(stderr, "real data %s not found (set SHUTTERLAB_DATA_DIR)\n", path.c_str());
    std::exit(2);
  }
  return path;
}

// This thread's CPU time: the machine is shared, and wall time there measures the queue, not the
// code. With cv::setNumThreads(1) OpenCV runs everything in the calling thread.
inline double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// Mean seconds per iteration of each timed benchmark, for the ratios printed at the end.
inline std::map<std::string, double>& MeanSeconds() {
  static std::map<std::string, double> seconds;
  return seconds;
}

// Runs body once as warm-up (caches, lazy initialisation, page faults of the output), then times
// the benchmark loop with this thread's CPU clock on one OpenCV thread. Keeps the best mean of the
// repetitions under `name` (MeanSeconds) and returns this run's mean, s.
template <typename Body>
double Timed(benchmark::State& state, const std::string& name, Body body) {
  cv::setNumThreads(1);
  body();
  double total_s = 0.0;
  for (auto _ : state) {
    const double start_s = ThreadCpuSeconds();
    body();
    total_s += ThreadCpuSeconds() - start_s;
    benchmark::ClobberMemory();
  }
  const double mean_s = total_s / static_cast<double>(state.iterations());
  double& best = MeanSeconds()[name];
  if (best == 0.0 || mean_s < best) best = mean_s;
  return mean_s;
}

// Thread CPU seconds of one call of body: the paired runs, which alternate the contenders call by
// call so that each sees the same load on the shared machine.
template <typename Body>
double CpuSecondsOf(Body&& body) {
  const double start_s = ThreadCpuSeconds();
  body();
  return ThreadCpuSeconds() - start_s;
}

// Google Benchmark's usual main up to the end of the timed runs; false when an argument was not
// understood (said on stderr), and nothing ran.
inline bool RunBenchmarks(int* argc, char** argv) {
  benchmark::Initialize(argc, argv);
  if (benchmark::ReportUnrecognizedArguments(*argc, argv)) return false;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return true;
}

// Prints every MeanSeconds entry against the one named `reference`, under `heading`, each ratio
// followed by `against` (what the reference is, for a person); nothing when the reference did not
// run (filtered out by --benchmark_filter).
inline void PrintAgainstReference(const std::string& reference, const std::string& heading,
                                  const std::string& against) {
  const auto& seconds = MeanSeconds();
  const auto found = seconds.find(reference);
  if (found == seconds.end() || found->second <= 0) return;
  int width = 0;
  for (const auto& entry : seconds) width = std::max(width, static_cast<int>(entry.first.size()));
  std::printf("\n%s (best mean per repetition):\n", heading.c_str());
  for (const auto& [name, s] : seconds) {
    std::printf("  %-*s %9.2f ms   %7.2fx %s\n", width, name.c_str(), s * 1e3, s / found->second,
                against.c_str());
  }
}

// The paired runs: each contender called once per run, in turn (so that each sees the same load on
// the shared machine), on one OpenCV thread; prints the median thread CPU time of each and its
// ratio to the first, under "Paired, RUNS alternating runs, median thread CPU time (WHAT), against
// FIRST:".
inline void PrintPaired(
    const std::string& what, int runs,
    const std::vector<std::pair<std::string, std::function<void()>>>& contenders) {
  cv::setNumThreads(1);
  std::vector<std::vector<double>> seconds(contenders.size());
  for (int i = 0; i < runs; ++i) {
    for (size_t k = 0; k < contenders.size(); ++k) {
      seconds[k].push_back(CpuSecondsOf(contenders[k].second));
    }
  }
  size_t width = 0;
  for (const auto& contender : contenders) width = std::max(width, contender.first.size());
  std::printf("\nPaired, %d alternating runs, median thread CPU time (%s), against %s:\n", runs,
              what.c_str(), contenders[0].first.c_str());
  std::vector<double> medians;
  for (std::vector<double>& s : seconds) {
    std::sort(s.begin(), s.end());
    medians.push_back(s[s.size() / 2]);  // the upper median
  }
  for (size_t k = 0; k < contenders.size(); ++k) {
    std::printf("  %-*s %8.1f ms   %.2fx\n", static_cast<int>(width), contenders[k].first.c_str(),
                medians[k] * 1e3, medians[k] / medians[0]);
  }
}

}  // namespace shutterlab::bench
