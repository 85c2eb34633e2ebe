// Speed of `measure` (estimate/loop/measure.h) on a rendered 1280 x 960 RGB pair of a real scene
// (fx 1100, 30 ms readout, a multirotor-like trace, D about 10 px), one thread
// (cv::setNumThreads(1)), thread CPU time, after a warm-up, against references measured in the same
// run:
//   - Measure:            MeasureDisplacement, everything (both flow directions, masks, row model,
//                         points);
//   - DisUltrafastFull:   cv::DISOpticalFlow ULTRAFAST at finest scale 0, one direction, on the
//   grey
//                         pair: the flow that Measure runs twice;
//   - DisMediumDefault:   cv::DISOpticalFlow MEDIUM as shipped (finest scale 1), one direction.
// The budget is about 1.5 s per frame on one core (validate: 12 frames and the fit in 60 s on 2).
// Run: build/bin/measure_bench [--benchmark_repetitions=3]

#include "bench/bench_util.h"
#include "estimate/loop/measure.h"
#include "io/image_io.h"
#include "model/truth_model.h"
#include "render/rs_warp.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/estimate/loop/effect_fixtures.h"

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

struct Fixture {
  cv::Mat ref, rs, ref_grey, rs_grey, flow;
  double d_px = 0.0;
  Fixture() {
    const cv::Mat scene = ReadImage(bench::RealDataPath("images/siyi_zr10/IMG_0100.jpg"));
    TrueModel truth;
    truth.rig = test::MappingRig();
    const CameraMotion motion(test::FlightTrace(20.0, 11), truth);
    const FrameMotion fm = motion.Frame(SecondsToNs(10.1));
    const FrameGeometry geometry(truth.rig.camera, 50.0, fm, scene.size());
    RenderFrame(scene, geometry, Interpolation::kBilinear, &rs);
    RenderFrame(scene, FrameGeometry(truth.rig.camera, 50.0, fm.Reference(), scene.size()),
                Interpolation::kBilinear, &ref);
    d_px = FrameDistortionPx(DisplacementField(geometry));
    cv::cvtColor(ref, ref_grey, cv::COLOR_RGB2GRAY);
    cv::cvtColor(rs, rs_grey, cv::COLOR_RGB2GRAY);
  }
};

Fixture& Shared() {
  static Fixture fixture;
  return fixture;
}

void RunMeasure(Fixture& f) { benchmark::DoNotOptimize(MeasureDisplacement(f.ref, f.rs)); }
void RunDisUltrafast(Fixture& f) {
  auto dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_ULTRAFAST);
  dis->setFinestScale(0);
  dis->calc(f.rs_grey, f.ref_grey, f.flow);
}
void RunDisMedium(Fixture& f) {
  cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM)
      ->calc(f.rs_grey, f.ref_grey, f.flow);
}

// bench::Timed on the shared fixture, with the mean in ms as a counter.
void Timed(benchmark::State& state, const std::string& name, void (*body)(Fixture&)) {
  Fixture& f = Shared();
  state.counters["cpu_ms"] = 1e3 * bench::Timed(state, name, [&f, body] { body(f); });
}

void BM_Measure(benchmark::State& state) { Timed(state, "measure", RunMeasure); }
void BM_DisUltrafastFull(benchmark::State& state) {
  Timed(state, "DIS ULTRAFAST finest 0", RunDisUltrafast);
}
void BM_DisMediumDefault(benchmark::State& state) {
  Timed(state, "DIS MEDIUM default", RunDisMedium);
}

BENCHMARK(BM_Measure)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_DisUltrafastFull)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_DisMediumDefault)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The shared machine's load drifts: alternate the contenders run by run, compare medians.
void PrintPairedRatios(int runs) {
  Fixture& f = Shared();
  bench::PrintPaired(FormatNumber("1280x960 RGB, D %.1f px, 1 thread", f.d_px), runs,
                     {{"DIS ULTRAFAST finest 0, one way", [&f] { RunDisUltrafast(f); }},
                      {"measure (all)", [&f] { RunMeasure(f); }},
                      {"DIS MEDIUM default, one way", [&f] { RunDisMedium(f); }}});
}

}  // namespace
}  // namespace shutterlab

int main(int argc, char** argv) {
  if (!shutterlab::bench::RunBenchmarks(&argc, argv)) return 1;
  shutterlab::PrintPairedRatios(7);
  return 0;
}
