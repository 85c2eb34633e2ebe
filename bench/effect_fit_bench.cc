// Speed of the effect fit (estimate/loop/effect_fit.h) on a mapping camera's case: 12 frames of
// 1280x960 (f = 1100 px, 30 ms readout, 50 m), ~1500 measured points a frame (grid step 28 px), a
// multirotor-like 1 kHz trace, 0.1 px noise per component. One thread, thread CPU time.
//   - Prediction:        one PredictDisplacements pass over all 12 frames' points (what the solver
//                        evaluates ~2p+1 times per iteration);
//   - DisplacementField: the renderer's exact truth field of ONE frame (1.2 M pixels), the
//                        reference in the same run;
//   - LoopClean:         CloseTheLoop, all candidates, clean data (one evaluation: the level test
//                        passes);
//   - LoopTimeOffset:    CloseTheLoop, all candidates, a 4 ms time offset hidden in the data (the
//                        full search: every candidate fitted, then the loop stops);
//   - LoopUnexplained:   CloseTheLoop, all candidates, per-frame trigger jitter (the search runs
//                        and explains nothing).
// At the end it prints the times against DisplacementField, and the false-alarm rate of the
// level test on clean data (white and spatially correlated noise, 200 data sets each).
// Run: build/bin/effect_fit_bench

#include "bench/bench_util.h"
#include "estimate/loop/effect_fit.h"
#include "model/truth_model.h"
#include "render/rs_warp.h"
#include "tests/estimate/loop/effect_fixtures.h"

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using bench::Timed;

constexpr int kStepPx = 28;  // 46 x 34 = 1564 points a frame
constexpr double kSigmaPx = 0.1;

struct Fixture {
  RigModel declared = test::MappingRig();
  GyroTrace gyro = test::FlightTrace(24.0, 3);
  std::vector<FramePoints> clean, offset, jitter;
  Fixture() {
    TrueModel truth;
    truth.rig = declared;
    clean = test::GridFrames(declared, test::EverySecond(12), kStepPx);
    test::MeasureExactly(truth, gyro, &clean, 1, kSigmaPx);
    offset = clean;
    TrueModel shifted = truth;
    shifted.rig.time_offset_s = 0.004;
    test::MeasureExactly(shifted, gyro, &offset, 2, kSigmaPx);
    std::mt19937_64 rng(3);
    std::normal_distribution<double> jitter_s(0.0, 0.008);
    jitter = clean;
    for (FramePoints& f : jitter) {
      TrueModel late = truth;
      late.rig.time_offset_s = jitter_s(rng);
      std::vector<FramePoints> one = {f};
      test::MeasureExactly(late, gyro, &one, 4 + f.frame, kSigmaPx);
      f = one[0];
    }
  }
  double NoisePx() const { return kSigmaPx * std::sqrt(2.0); }
};

Fixture& Shared() {
  static Fixture fixture;
  return fixture;
}

void BM_Prediction(benchmark::State& state) {
  Fixture& f = Shared();
  TrueModel model;
  model.rig = f.declared;
  size_t points = 0;
  Timed(state, "prediction (12 frames' points)", [&] {
    points = 0;
    for (const FramePoints& frame : f.clean) {
      benchmark::DoNotOptimize(PredictDisplacements(model, f.gyro, frame));
      points += frame.points.size();
    }
  });
  state.counters["points"] = static_cast<double>(points);
}

void BM_DisplacementField(benchmark::State& state) {
  Fixture& f = Shared();
  TrueModel model;
  model.rig = f.declared;
  const CameraMotion motion(f.gyro, model);
  Timed(state, "DisplacementField (1 frame)", [&] {
    const FrameGeometry geometry(model.rig.camera, model.rig.altitude_m,
                                 motion.Frame(f.clean[0].t_first_row_ns), cv::Size(4000, 3000));
    benchmark::DoNotOptimize(DisplacementField(geometry));
  });
}

void BM_LoopClean(benchmark::State& state) {
  Fixture& f = Shared();
  Timed(state, "loop, clean",
        [&] { benchmark::DoNotOptimize(CloseTheLoop(f.declared, f.gyro, f.clean, f.NoisePx())); });
}

void BM_LoopTimeOffset(benchmark::State& state) {
  Fixture& f = Shared();
  Timed(state, "loop, time offset",
        [&] { benchmark::DoNotOptimize(CloseTheLoop(f.declared, f.gyro, f.offset, f.NoisePx())); });
}

void BM_LoopUnexplained(benchmark::State& state) {
  Fixture& f = Shared();
  Timed(state, "loop, jitter (unexplained)",
        [&] { benchmark::DoNotOptimize(CloseTheLoop(f.declared, f.gyro, f.jitter, f.NoisePx())); });
}

BENCHMARK(BM_DisplacementField)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_Prediction)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_LoopClean)->Unit(benchmark::kMillisecond)->MinTime(0.5);
BENCHMARK(BM_LoopTimeOffset)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(BM_LoopUnexplained)->Unit(benchmark::kMillisecond)->Iterations(2);

// Share of clean data sets (12 frames, 1564 points each) on which the level test fires, for white
// noise and for noise correlated over 3x3 neighbouring grid points (correlation factor ~9).
void PrintFalseAlarmRate(int sets) {
  Fixture& f = Shared();
  TrueModel truth;
  truth.rig = f.declared;
  const std::vector<FramePoints> exact = [&] {
    std::vector<FramePoints> frames = test::GridFrames(f.declared, test::EverySecond(12), kStepPx);
    test::MeasureExactly(truth, f.gyro, &frames, 0, 0.0);
    return frames;
  }();
  const int cols = (f.declared.camera.width - kStepPx / 2 + kStepPx - 1) / kStepPx;
  for (const bool correlated : {false, true}) {
    int alarms = 0, added = 0, unexplained = 0;
    for (int set = 0; set < sets; ++set) {
      std::mt19937_64 rng(100 + set);
      std::normal_distribution<double> white(0.0, 1.0);
      std::vector<FramePoints> frames = exact;
      for (FramePoints& frame : frames) {
        const int n = static_cast<int>(frame.points.size()), rows = n / cols;
        std::vector<double> wx(n), wy(n);
        for (int i = 0; i < n; ++i) {
          wx[i] = white(rng);
          wy[i] = white(rng);
        }
        for (int i = 0; i < n; ++i) {
          double sx = wx[i], sy = wy[i];
          int count = 1;
          if (correlated) {
            sx = sy = 0.0;
            count = 0;
            const int r = i / cols, c = i % cols;
            for (int dr = -1; dr <= 1; ++dr) {
              for (int dc = -1; dc <= 1; ++dc) {
                if (r + dr < 0 || r + dr >= rows || c + dc < 0 || c + dc >= cols) continue;
                sx += wx[(r + dr) * cols + c + dc];
                sy += wy[(r + dr) * cols + c + dc];
                ++count;
              }
            }
          }
          frame.points[i].dx += kSigmaPx * sx / std::sqrt(count);
          frame.points[i].dy += kSigmaPx * sy / std::sqrt(count);
        }
      }
      const LoopResult r = CloseTheLoop(f.declared, f.gyro, frames, f.NoisePx());
      alarms += r.above_noise_before;
      added += !r.effects.empty();
      unexplained += r.unexplained;
    }
    std::printf(
        "clean data, %s noise, %d sets: level test fired %d times (%.1f %%), an effect added "
        "%d times, unexplained %d times\n",
        correlated ? "3x3-correlated" : "white", sets, alarms, 100.0 * alarms / sets, added,
        unexplained);
  }
}

}  // namespace
}  // namespace shutterlab

int main(int argc, char** argv) {
  if (!shutterlab::bench::RunBenchmarks(&argc, argv)) return 1;
  shutterlab::bench::PrintAgainstReference("DisplacementField (1 frame)",
                                           "12 frames x 1564 points, 1 thread, thread CPU time",
                                           "DisplacementField of one frame");
  shutterlab::PrintFalseAlarmRate(200);
  return 0;
}
