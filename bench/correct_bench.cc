// Speed of the rolling-shutter correction on a 20 MP RGB frame (5472 x 3648), one thread
// (cv::setNumThreads(1)), bilinear, after a warm-up, all buffers preallocated, against
// cv::warpPerspective of the same image with one homography, measured in the same run:
//   - Correct:            render/rs_correct.h, a rotation-only frame (30 ms readout at
//                         (0.3, -0.4, 0.6) rad/s, about 20 px of shear): the map (exact solution on
//                         a grid, refined to 0.01 px) and the warp, everything a frame costs;
//   - CorrectTranslation: the same with the ground plane at 50 m, 8 m/s and a lens (k1 = -0.05);
//   - CorrectWarpOnly:    the warp of an already built map;
//   - WarpPerspective:    cv::warpPerspective, one homography, INTER_LINEAR.
// At the end it prints each time relative to warpPerspective, paired run by run, and the warp of
// the built map by each of the sampler's block paths this CPU runs (render/warp_kernel.h), paired.
// Run: build/bin/correct_bench [--benchmark_repetitions=3]
// The frame is the real asset upscaled to 20 MP.

#include "bench/bench_util.h"
#include "io/image_io.h"
#include "model/truth_model.h"
#include "render/rs_correct.h"
#include "sim/so3.h"
#include "sim/units.h"

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

constexpr int kWidth = 5472, kHeight = 3648;

struct Fixture {
  cv::Mat image, out;
  PackedMask mask;
  PinholeCamera camera, lens_camera;
  FrameMotion motion, moving;
  cv::Matx33d homography;
  Fixture() {
    cv::resize(ReadImage(bench::RealDataPath("images/siyi_zr10/IMG_0150.jpg")), image,
               cv::Size(kWidth, kHeight), 0, 0, cv::INTER_LINEAR);
    camera.width = kWidth;
    camera.height = kHeight;
    camera.fx = camera.fy = 4000.0;
    camera.cx = (kWidth - 1) / 2.0;
    camera.cy = (kHeight - 1) / 2.0;
    lens_camera = camera;
    lens_camera.distortion = BrownConrady{{-0.05, 0, 0, 0, 0}};
    motion.world_from_cam.resize(kHeight);
    motion.cam_center_m.assign(kHeight, Eigen::Vector3d::Zero());
    moving = motion;
    for (int v = 0; v < kHeight; ++v) {
      const double t_s = 0.030 * v / kHeight;
      motion.world_from_cam[v] = ExpSO3(Eigen::Vector3d(0.3, -0.4, 0.6) * t_s).toRotationMatrix();
      moving.world_from_cam[v] = motion.world_from_cam[v];
      moving.cam_center_m[v] = Eigen::Vector3d(8.0, 0.0, 0.0) * t_s;
    }
    const Eigen::Matrix3d k = camera.K();
    const Eigen::Matrix3d h = k * motion.world_from_cam[kHeight / 2].transpose() * k.inverse();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) homography(r, c) = h(r, c);
    }
    out.create(kHeight, kWidth, image.type());
    out.setTo(cv::Scalar::all(0));
    mask.width = kWidth;
    mask.bits = cv::Mat::zeros(kHeight, (kWidth + 7) / 8, CV_8UC1);
  }
  void Correct(const PinholeCamera& cam, const FrameMotion& m, std::optional<double> depth) {
    const CorrectionGeometry geometry(cam, m, 0.0, depth);
    const CorrectionMap map(geometry, {});
    CorrectFrame(image, map, Interpolation::kBilinear, &out, &mask);
  }
  void Warp() {
    cv::warpPerspective(image, out, homography, out.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                        cv::BORDER_CONSTANT);
  }
};

Fixture& Shared() {
  static Fixture fixture;
  return fixture;
}

void BM_WarpPerspective(benchmark::State& state) {
  Fixture& f = Shared();
  bench::Timed(state, "warpPerspective", [&] { f.Warp(); });
}

void BM_Correct(benchmark::State& state) {
  Fixture& f = Shared();
  bench::Timed(state, "correct", [&] { f.Correct(f.camera, f.motion, std::nullopt); });
}

void BM_CorrectTranslation(benchmark::State& state) {
  Fixture& f = Shared();
  bench::Timed(state, "correct (plane, lens)", [&] { f.Correct(f.lens_camera, f.moving, 50.0); });
}

void BM_CorrectWarpOnly(benchmark::State& state) {
  Fixture& f = Shared();
  const CorrectionGeometry geometry(f.camera, f.motion, 0.0, std::nullopt);
  const CorrectionMap map(geometry, {});
  bench::Timed(state, "correct (warp of a built map)",
               [&] { CorrectFrame(f.image, map, Interpolation::kBilinear, &f.out, &f.mask); });
}

BENCHMARK(BM_WarpPerspective)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_Correct)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_CorrectTranslation)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_CorrectWarpOnly)->Unit(benchmark::kMillisecond)->MinTime(1.0);

// The shared machine's load drifts within seconds: alternate the contenders run by run and compare
// medians, so that both see the same conditions.
void PrintPairedRatios(int runs) {
  Fixture& f = Shared();
  bench::PrintPaired(
      "20 MP RGB, 1 thread, bilinear", runs,
      {{"warpPerspective", [&] { f.Warp(); }},
       {"correct (rotation)", [&] { f.Correct(f.camera, f.motion, std::nullopt); }},
       {"correct (plane, lens)", [&] { f.Correct(f.lens_camera, f.moving, 50.0); }}});
  // The warp of one built map with the kernel capped at each of its block paths this CPU runs,
  // widest last (under AVX2 the coordinates along a line and the mask bits are plain C++ too).
  const CorrectionGeometry geometry(f.camera, f.motion, 0.0, std::nullopt);
  const CorrectionMap map(geometry, {});
  const SamplerPath widest = WidestSamplerPath();
  std::vector<std::pair<std::string, std::function<void()>>> paths;
  for (const auto& [path, name] :
       {std::pair{SamplerPath::kSse41, "SSE4.1 blocks of 4, C++ coordinates"},
        std::pair{SamplerPath::kAvx2, "AVX2 blocks of 8"},
        std::pair{SamplerPath::kAvx512, "AVX-512 blocks of 16"}}) {
    if (path > widest) break;
    paths.push_back({name, [&f, &map, path = path] {
                       const SamplerPath cap = CapSamplerPath(path);
                       CorrectFrame(f.image, map, Interpolation::kBilinear, &f.out, &f.mask);
                       CapSamplerPath(cap);
                     }});
  }
  if (!paths.empty())
    bench::PrintPaired("the warp of a built map, by the kernel's path", runs, paths);
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
