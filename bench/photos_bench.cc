// Speed of `correct --photos` on 12 MP drone photos against the job's floor, side by side:
//   - floor:   each photo decoded and re-encoded at its own JPEG quality with its EXIF and XMP,
//              through the same calls `correct` makes (ReadWholeImage into one buffer reused
//              photo to photo, as correct's workers do, and WriteImageLike). A fresh buffer a
//              photo (ReadImage) costs its page faults: a floor 8 % slower (12.0 s against 13.0 s
//              for 100 photos), which would flatter the command;
//   - correct: CorrectDataset on the folder with its ULog and camera.json, one job: the log
//              read, the photos placed, every photo's map, warp, mask and writes, and the
//              overview.png that the command writes unless told --no-pictures.
// The photos: a `shutterlab survey` of 4 photos of 4000 x 3000 (f 3500 px, 30 ms, gusty), rendered
// once into $TMPDIR/shutterlab_photos_bench_noisy/ (about 3 min) and reused by later runs; with
// PHOTOS, a survey of that many, into shutterlab_photos_bench_noisy_PHOTOS/: from 20 photos on,
// on 5 lines at 82 % front overlap over a texture of the camera's own GSD, so that the ground fits
// the renderer's largest texture (100 photos: about 80 min). Both
// contenders write into a fresh folder each run; the runs alternate, and the medians of process
// CPU time and wall time are printed with their ratio, then each run's ratio and the best run's.
// The photos are placed on the log by a trigger file made from the truth (a photo alone cannot be
// placed by its capture time). The command's fixed cost (the log read, the photos placed) weighs
// more on 4 photos than on a survey's 100: the command is also timed on the first photo alone, and
// its cost a photo, (T4 - T1) / 3, gives the ratio 100 photos would have, said as that projection
// (its overview draws one frame where a folder's draws four: about 0.1 s less than the folder's).
// Last, a 12 MP mask (0/255, bands without source at three edges) written ten times as correct
// writes it (WriteMask, one bit a pixel) and as an 8-bit PNG (WriteImage), the mean of each.
// The sampler takes the widest path this CPU runs, or with PATH (avx512, avx2, sse4.1, one-pixel)
// at most that one: the command timed with each.
// Run: build/bin/photos_bench [RUNS [PHOTOS [PATH]]] (default 3 runs, 4 photos)

#include "bench/bench_util.h"
#include "estimate/correct/correct_dataset.h"
#include "io/image_io.h"
#include "model/camera.h"
#include "render/survey.h"
#include "render/warp_kernel.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// The survey's folder of `photos` photos, rendered on first use.
fs::path SurveyFolder(int photos) {
  const char* tmp = std::getenv("TMPDIR");
  const std::string name = "shutterlab_photos_bench_noisy" +
                           (photos == 4 ? std::string() : "_" + std::to_string(photos));
  const fs::path dir = fs::path(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") / name;
  if (fs::is_regular_file(dir / "survey.json")) return dir;
  std::fprintf(stderr, "rendering %d photos of 4000 x 3000 into %s (once, about %d min)\n", photos,
               dir.c_str(), 1 + photos * 3 / 4);
  SurveyOptions survey;
  survey.camera.width = 4000;
  survey.camera.height = 3000;
  survey.camera.fx = survey.camera.fy = 3500.0;
  survey.camera.cx = (survey.camera.width - 1) / 2.0;
  survey.camera.cy = (survey.camera.height - 1) / 2.0;
  survey.lines = photos < 20 ? 2 : 5;
  survey.photos_per_line = photos / survey.lines;
  if (photos >= 20) {
    survey.front_overlap = 0.82;
    survey.texture_gsd_m = survey.altitude_m / survey.camera.fx;
  }
  SynthOptions synth;  // a gusty multirotor, as `survey` flies by default
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 1000.0;
  synth.duration_s = SurveyEndS(survey) + 2.0;
  synth.t0_s = 0.001;
  // A MEMS gyro's white noise and nothing else (its density as ImuErrorModel's default): a real
  // log's noise makes correct draw its prediction 32 times, as it does for a real flight.
  synth.imu = ImuErrorModel::Ideal();
  synth.imu.noise_density_rad_s_sqrt_hz = ImuErrorModel().noise_density_rad_s_sqrt_hz;
  fs::remove_all(dir);
  WriteSurvey(survey, SynthesizeTrace(synth), dir.string(), {});
  return dir;
}

// "image,t" of every photo, its first row's time on the log's clock from truth/photos.csv
// (columns photo, line, index, t_first_row_s, ...).
std::string TriggersFromTruth(const fs::path& survey) {
  const std::string truth = ReadFileToString((survey / "truth/photos.csv").string());
  std::string triggers = "image,t\n";
  LineCursor lines(truth);
  lines.Next();  // the header
  std::vector<std::string_view> fields;
  while (const std::optional<std::string_view> line = lines.Next()) {
    SplitFields(*line, ',', &fields);
    if (fields.size() > 3) triggers += std::string(fields[0]) + "," + std::string(fields[3]) + "\n";
  }
  return triggers;
}

double ProcessCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

struct Seconds {
  double cpu_s = 0.0, wall_s = 0.0;
};

template <typename Body>
Seconds Time(Body&& body) {
  const double cpu_start_s = ProcessCpuSeconds();
  const auto wall_start = std::chrono::steady_clock::now();
  body();
  return {ProcessCpuSeconds() - cpu_start_s,
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count()};
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// A 12 MP mask written ten times each way into `out`: as correct writes it (WriteMask, one bit a
// pixel) and as an 8-bit PNG (WriteImage); the mean times and sizes.
void PrintMaskWriteTimes(const fs::path& out) {
  cv::Mat mask(3000, 4000, CV_8UC1, cv::Scalar(255));
  mask(cv::Rect(0, 0, 4000, 40)).setTo(0);
  mask(cv::Rect(0, 0, 25, 3000)).setTo(0);
  mask(cv::Rect(1000, 2950, 3000, 50)).setTo(0);
  fs::create_directories(out);
  const fs::path mask_path = out / "mask.png";
  const auto mean_ms = [&](const auto& write) {
    write();  // warm-up
    return 100.0 * Time([&] {
                     for (int i = 0; i < 10; ++i) write();
                   }).wall_s;
  };
  const PackedMask packed = PackMask(mask);
  const double one_bit_ms = mean_ms([&] { WriteMask(mask_path.string(), packed); });
  const double one_bit_bytes = static_cast<double>(fs::file_size(mask_path));
  const double eight_bit_ms = mean_ms([&] { WriteImage(mask_path.string(), mask); });
  std::printf(
      "  a 12 MP mask: %.1f ms one bit a pixel (%.0f kB), %.1f ms as an 8-bit PNG (%.0f kB)\n",
      one_bit_ms, one_bit_bytes / 1e3, eight_bit_ms, fs::file_size(mask_path) / 1e3);
}

// Each run's CPU ratio, and the ratio of the best run of each side. On a shared machine a
// neighbour's load comes and goes on the scale of a run: the runs show the spread, and the best
// runs, the least disturbed, give a second estimate.
void PrintRunSpread(const std::vector<double>& floor_cpu, const std::vector<double>& correct_cpu) {
  std::printf("  run by run (CPU):");
  for (size_t i = 0; i < floor_cpu.size(); ++i)
    std::printf(" %.2fx", correct_cpu[i] / floor_cpu[i]);
  const double best_floor_s = *std::min_element(floor_cpu.begin(), floor_cpu.end());
  const double best_correct_s = *std::min_element(correct_cpu.begin(), correct_cpu.end());
  std::printf("; best of each: %.2f s against %.2f s, %.2fx\n", best_correct_s, best_floor_s,
              best_correct_s / best_floor_s);
}

// The sampler's paths (render/warp_kernel.h) by the names PATH takes.
constexpr std::pair<const char*, SamplerPath> kSamplerPaths[] = {
    {"avx512", SamplerPath::kAvx512},
    {"avx2", SamplerPath::kAvx2},
    {"sse4.1", SamplerPath::kSse41},
    {"one-pixel", SamplerPath::kOnePixel}};

const char* SamplerPathName(SamplerPath path) {
  for (const auto& [name, named] : kSamplerPaths) {
    if (named == path) return name;
  }
  return "?";
}

// Caps the sampler at the path of that name; false for a name of none.
bool CapSamplerPathNamed(const std::string& name) {
  for (const auto& [path_name, path] : kSamplerPaths) {
    if (name != path_name) continue;
    CapSamplerPath(path);
    return true;
  }
  return false;
}

int Main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const int photo_count = argc > 2 ? std::atoi(argv[2]) : 4;
  if (photo_count < 2 || photo_count % (photo_count < 20 ? 2 : 5) != 0) {
    std::fprintf(stderr, "PHOTOS: an even count, a multiple of 5 from 20 on (got %s)\n", argv[2]);
    return 2;
  }
  if (argc > 3 && !CapSamplerPathNamed(argv[3])) {
    std::fprintf(stderr, "PATH: avx512, avx2, sse4.1 or one-pixel (got %s)\n", argv[3]);
    return 2;
  }
  const fs::path survey = SurveyFolder(photo_count);
  const fs::path out = survey / "bench_out";
  std::vector<std::string> photos;
  for (const auto& entry : fs::directory_iterator(survey / "images")) {
    photos.push_back(entry.path().string());
  }
  std::sort(photos.begin(), photos.end());
  cv::setNumThreads(1);

  cv::Mat decoded;  // reused photo to photo, as each of correct's workers reuses its own
  const auto floor = [&] {
    fs::remove_all(out);
    fs::create_directories(out);
    for (const std::string& photo : photos) {
      const cv::Mat image = ReadWholeImage(photo, &decoded);
      WriteImageLike((out / fs::path(photo).filename()).string(), image,
                     ImageLike{photo, ReadImageFileInfo(photo)});
    }
  };
  CorrectOptions options;
  options.dataset_dir = (survey / "images").string();
  options.out_dir = out.string();
  options.photos.emplace();
  options.photos->log_path = (survey / "flight.ulg").string();
  options.photos->camera = ReadRigModel((survey / "truth/camera.json").string());
  options.photos->camera_path = (survey / "truth/camera.json").string();
  options.photos->triggers_path = (survey / "triggers.csv").string();
  WriteFileAtomically(options.photos->triggers_path, TriggersFromTruth(survey));
  options.reference = CorrectionReference::kMidReadout;
  options.jobs = 1;
  const auto correct = [&] {
    fs::remove_all(out);
    CorrectDataset(options);
  };
  // The first photo alone, in a folder of its own beside the survey's.
  const fs::path one_photo = survey / "one_photo";
  fs::remove_all(one_photo);
  fs::create_directories(one_photo);
  fs::copy_file(photos.front(), one_photo / fs::path(photos.front()).filename());
  CorrectOptions one_options = options;
  one_options.dataset_dir = one_photo.string();
  const auto correct_one = [&] {
    fs::remove_all(out);
    CorrectDataset(one_options);
  };

  floor();  // warm-up: page cache, codecs loaded, exiv2 initialised
  correct();
  correct_one();
  std::vector<double> floor_cpu, floor_wall, correct_cpu, correct_wall, one_cpu;
  for (int i = 0; i < runs; ++i) {
    const Seconds f = Time(floor), c = Time(correct), o = Time(correct_one);
    floor_cpu.push_back(f.cpu_s);
    floor_wall.push_back(f.wall_s);
    correct_cpu.push_back(c.cpu_s);
    correct_wall.push_back(c.wall_s);
    one_cpu.push_back(o.cpu_s);
  }
  fs::remove_all(out);
  fs::remove_all(one_photo);
  const double n = static_cast<double>(photos.size());
  std::printf(
      "%zu photos of 4000 x 3000 (JPEG, EXIF and XMP), 1 job, 1 OpenCV thread, the sampler's "
      "%s path; %d alternating runs, medians:\n",
      photos.size(), SamplerPathName(WidestSamplerPath()), runs);
  std::printf("  decode + re-encode (the floor)  %6.2f s CPU (%.2f s a photo)  %6.2f s wall\n",
              Median(floor_cpu), Median(floor_cpu) / n, Median(floor_wall));
  std::printf("  correct --photos                %6.2f s CPU (%.2f s a photo)  %6.2f s wall\n",
              Median(correct_cpu), Median(correct_cpu) / n, Median(correct_wall));
  std::printf("  correct / floor: %.2fx CPU, %.2fx wall\n", Median(correct_cpu) / Median(floor_cpu),
              Median(correct_wall) / Median(floor_wall));
  PrintRunSpread(floor_cpu, correct_cpu);
  // Cost a photo and fixed cost from the two folder sizes, then the 100-photo projection.
  const double per_photo_s = (Median(correct_cpu) - Median(one_cpu)) / (n - 1.0);
  const double fixed_s = Median(one_cpu) - per_photo_s;
  const double floor_per_photo_s = Median(floor_cpu) / n;
  std::printf(
      "  correct --photos on the first photo alone %.2f s CPU: %.2f s a photo and %.2f s once "
      "(log, placement)\n",
      Median(one_cpu), per_photo_s, fixed_s);
  std::printf("  projected for 100 photos: %.2fx CPU the floor (%.2fx a photo)\n",
              (fixed_s + 100.0 * per_photo_s) / (100.0 * floor_per_photo_s),
              per_photo_s / floor_per_photo_s);
  PrintMaskWriteTimes(out);
  fs::remove_all(out);
  return 0;
}

}  // namespace
}  // namespace shutterlab

int main(int argc, char** argv) { return shutterlab::bench::RunMain(shutterlab::Main, argc, argv); }
