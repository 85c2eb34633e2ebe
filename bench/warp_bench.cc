// Speed of the rolling-shutter renderer against OpenCV on a 20 MP RGB frame (5472 x 3648), one
// thread (cv::setNumThreads(1)), bilinear, after a warm-up, all buffers preallocated:
//   - RenderRollingShutter: render/rs_warp.h, rotation-only frame, one homography per row;
//   - WarpPerspective:      cv::warpPerspective of the same scene with one homography;
//   - RemapPrecomputed:     cv::remap with a precomputed fixed-point map (convertMaps: CV_16SC2 +
//   CV_16UC1).
// At the end it prints each time relative to warpPerspective, measured in the same run.
// Run: build/bin/warp_bench [--benchmark_repetitions=3]
// The scene is the real asset upscaled to 6000 x 4000 (margin around the frame for the rotation).

#include "bench/bench_util.h"
#include "io/image_io.h"
#include "model/truth_model.h"
#include "render/rs_warp.h"
#include "sim/so3.h"
#include "sim/units.h"

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

constexpr int kWidth = 5472, kHeight = 3648;

// bench::Timed plus the throughput in megapixels per second.
template <typename Body>
void Timed(benchmark::State& state, const std::string& name, Body body) {
  const double mean_s = bench::Timed(state, name, body);
  state.counters["Mpix/s"] = benchmark::Counter(1e-6 * kWidth * kHeight / mean_s);
}

// Everything allocated and touched once, outside the timed loops (first-touch page faults cost
// ~11 us per 4 KiB page on this machine).
struct Fixture {
  cv::Mat scene;
  PinholeCamera camera;
  FrameMotion motion;
  cv::Mat out;
  cv::Mat map1, map2;
  cv::Matx33d homography;
  Fixture() {
    cv::resize(ReadImage(bench::RealDataPath("images/siyi_zr10/IMG_0150.jpg")), scene,
               cv::Size(6000, 4000), 0, 0, cv::INTER_LINEAR);
    camera.width = kWidth;
    camera.height = kHeight;
    camera.fx = camera.fy = 4000.0;
    camera.cx = (kWidth - 1) / 2.0;
    camera.cy = (kHeight - 1) / 2.0;
    // A realistic readout: 30 ms at (0.3, -0.4, 0.6) rad/s, about 20 px of rolling-shutter shear.
    motion.world_from_cam.resize(kHeight);
    motion.cam_center_m.assign(kHeight, Eigen::Vector3d::Zero());
    for (int v = 0; v < kHeight; ++v) {
      motion.world_from_cam[v] =
          ExpSO3(Eigen::Vector3d(0.3, -0.4, 0.6) * (0.030 * v / kHeight)).toRotationMatrix();
    }
    const FrameGeometry geometry(camera, 50.0, motion, scene.size());
    const Eigen::Matrix3d h = geometry.SceneFromImageHomography(kHeight / 2);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) homography(r, c) = h(r, c);
    }
    out.create(kHeight, kWidth, scene.type());
    out.setTo(cv::Scalar::all(0));
    cv::Mat map_xy(kHeight, kWidth, CV_32FC2);
    std::vector<float> xs(kWidth), ys(kWidth);
    for (int v = 0; v < kHeight; ++v) {
      geometry.SceneRow(v, xs.data(), ys.data());
      auto* row = map_xy.ptr<cv::Vec2f>(v);
      for (int u = 0; u < kWidth; ++u) row[u] = cv::Vec2f(xs[u], ys[u]);
    }
    cv::convertMaps(map_xy, cv::noArray(), map1, map2, CV_16SC2);
  }
};

Fixture& Shared() {
  static Fixture fixture;
  return fixture;
}

void BM_RenderRollingShutter(benchmark::State& state) {
  Fixture& f = Shared();
  const FrameGeometry geometry(f.camera, 50.0, f.motion, f.scene.size());
  Timed(state, "render", [&] { RenderFrame(f.scene, geometry, Interpolation::kBilinear, &f.out); });
}

void BM_WarpPerspective(benchmark::State& state) {
  Fixture& f = Shared();
  Timed(state, "warpPerspective", [&] {
    cv::warpPerspective(f.scene, f.out, f.homography, f.out.size(),
                        cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT);
  });
}

void BM_RemapPrecomputed(benchmark::State& state) {
  Fixture& f = Shared();
  Timed(state, "remap",
        [&] { cv::remap(f.scene, f.out, f.map1, f.map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT); });
}

BENCHMARK(BM_WarpPerspective)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_RenderRollingShutter)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_RemapPrecomputed)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace
}  // namespace shutterlab

namespace shutterlab {
namespace {

// The shared build machine's load drifts within seconds: alternate the contenders run by run and
// compare medians, so that both see the same conditions.
void PrintPairedRatios(int runs) {
  Fixture& f = Shared();
  const FrameGeometry geometry(f.camera, 50.0, f.motion, f.scene.size());
  bench::PrintPaired(
      "20 MP RGB, 1 thread, bilinear", runs,
      {{"warpPerspective",
        [&] {
          cv::warpPerspective(f.scene, f.out, f.homography, f.out.size(),
                              cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT);
        }},
       {"render (RS)", [&] { RenderFrame(f.scene, geometry, Interpolation::kBilinear, &f.out); }},
       {"remap (map)", [&] {
          cv::remap(f.scene, f.out, f.map1, f.map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
        }}});
}

}  // namespace
}  // namespace shutterlab

int main(int argc, char** argv) {
  if (!shutterlab::bench::RunBenchmarks(&argc, argv)) return 1;
  shutterlab::bench::PrintAgainstReference(
      "warpPerspective", "20 MP RGB, 1 thread, bilinear, thread CPU time", "warpPerspective");
  shutterlab::PrintPairedRatios(9);
  return 0;
}
