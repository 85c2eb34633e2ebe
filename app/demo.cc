// shutterlab demo: the main job, in seconds, on data it makes itself (nothing is read from
// outside):
//  0. the inputs: a synthetic multirotor survey flight written as a PX4 ULog with a camera trigger
//     every 2 s and its altitude (the file any user's own log would be), and a procedural nadir
//     ground texture (fields, roads, roofs, trees) as the scene;
//  1. the source paper's static noise and accuracy analyses (Tables 1-3) on synthetic MPU-9250
//  traces;
//  2. its flight analysis (Table 4) on that flight log, read back through the ULog reader;
//  3. `analyze` of that log for a typical mapping camera at its own camera triggers: the
//     per-image table, the flagged images and shutterlab-demo/report.html;
//  4. that log's gyro driving the rolling-shutter renderer over the ground texture, frames every
//     few seconds as a mapping camera would take them: images, exact displacement truth, pictures;
//  5. closing the loop: a small dataset rendered with a 4 ms clock offset that camera.json does
//     not declare; validate measures it, finds the residual, names and fits the effect, and writes
//     the before/after residual report.
// Orchestration only: every step is one library call that the other subcommands also make. Each
// step is a function of the shared DemoContext, run in order by RunDemo (add a step there).

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/demo_dataset.h"
#include "estimate/loop/validate.h"
#include "estimate/paper/accuracy.h"
#include "estimate/paper/analyze.h"
#include "estimate/paper/flight.h"
#include "estimate/paper/noise.h"
#include "estimate/report/analyze_report.h"
#include "estimate/report/validate_report.h"
#include "io/frames_csv.h"
#include "io/image_io.h"
#include "model/camera.h"
#include "render/pictures.h"
#include "render/render_dataset.h"
#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab::app {
namespace {

struct DemoOptions {
  std::string out_dir = "shutterlab-demo";
  double frame_every_s = 4.0;  // a mapping camera's trigger cadence
  void Check() const { SHUTTERLAB_CHECK(frame_every_s > 0) << "--every must be positive"; }
};

void Section(const std::string& title) { std::cout << "\n== " << title << " ==\n"; }

std::string SizeText(uintmax_t bytes) {
  return bytes < 1000000 ? FormatNumber("%.1f kB", bytes / 1e3)
                         : FormatNumber("%.1f MB", bytes / 1e6);
}

// Where the demo wrote what, and how much: each folder of `out` with its size and file count.
void PrintWritten(const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, std::pair<uintmax_t, size_t>>> folders;
  uintmax_t total_bytes = 0;
  size_t total_files = 0;
  for (const fs::directory_entry& top : fs::directory_iterator(out)) {
    uintmax_t bytes = 0;
    size_t files = 0;
    const auto add = [&](const fs::directory_entry& entry) {
      if (!entry.is_regular_file()) return;
      bytes += entry.file_size();
      ++files;
    };
    add(top);
    if (top.is_directory()) {
      for (const fs::directory_entry& entry : fs::recursive_directory_iterator(top)) add(entry);
    }
    folders.push_back(
        {top.path().filename().string() + (top.is_directory() ? "/" : ""), {bytes, files}});
    total_bytes += bytes;
    total_files += files;
  }
  std::sort(folders.begin(), folders.end());
  Section("Written to " + out.string() + ": " + SizeText(total_bytes) + " in " +
          std::to_string(total_files) + " files");
  for (const auto& [name, size] : folders) {
    std::printf("%-24s %10s %6zu files\n", name.c_str(), SizeText(size.first).c_str(), size.second);
  }
  std::fflush(stdout);
}

struct DemoContext {
  DemoOptions options;
  std::filesystem::path out;
  std::string log_path;    // the synthetic flight, written as a PX4 ULog
  std::string scene_path;  // the procedural ground texture
  FlightLog log;
};

void StepInputs(DemoContext& context) {
  const DemoInputs inputs = WriteDemoInputs(context.log_path, context.scene_path);
  context.log = inputs.log;
  PrintLogWarnings(context.log_path, context.log.warnings);
  std::cout << "flight log " << context.log_path << ": " << context.log.gyro.size()
            << " gyro samples over " << FormatNumber("%.1f", context.log.gyro.DurationS()) << " s, "
            << context.log.camera_events.size() << " camera triggers, altitude "
            << FormatNumber("%.0f", context.log.altitude_above_ground_m.value_or(0.0)) << " m\n";
  std::cout << "scene " << context.scene_path << ": " << inputs.scene_width_px << "x"
            << inputs.scene_height_px << " px at "
            << FormatNumber("%.1f", 100 * inputs.scene_m_per_px) << " cm/px\n";
}

void StepStaticNoise(DemoContext&) {
  SynthOptions still;
  still.profile = MotionProfile::kStill;
  still.duration_s = 20.0;
  std::cout << NoiseTable(AnalyzeNoise(SynthesizeTrace(still), NoiseOptions{}));
}

void StepAccuracy(DemoContext&) {
  SynthOptions steps;
  steps.profile = MotionProfile::kSteps;
  std::cout << AccuracyTable(AnalyzeAccuracy(SynthesizeTrace(steps), AccuracyOptions{}));
}

void StepFlightTable(DemoContext& context) {
  const FlightLog& log = context.log;
  std::cout << log.gyro.size() << " gyro samples over " << log.gyro.DurationS() << " s at "
            << log.gyro.sampling().RateHz() << " Hz (" << log.gyro_source << ")\n";
  FlightOptions flight;
  flight.windows_s = {0.010, 0.020, 0.030};  // the bias: the paper's mean over the still 0..5 s
  Progress progress("flight windows", 100);
  flight.progress = [&progress](double fraction) {
    progress.Update(static_cast<size_t>(fraction * 100));
  };
  std::cout << FlightTable(Flight(log.gyro, flight));
}

void StepAnalyze(DemoContext& context) {
  AnalyzeOptions options;
  options.rig = DemoAnalyzeCamera();
  options.plots = AnalyzePlotOptions{};  // the report's charts; triggers: the log's own
  options.allan = true;                  // the report's noise plot
  AnalyzeResult result;
  {
    Progress progress("analyze", 1000);
    options.progress = [&progress](double f) { progress.Update(static_cast<size_t>(f * 1000)); };
    result = Analyze(context.log, options);
  }
  std::cout << AnalyzeReport(result);
  std::string flagged;
  for (const ImageResult& image : result.images) {
    if (image.judged() && image.flagged.back())
      flagged += (flagged.empty() ? "" : " ") + image.name;
  }
  std::cout << "flagged over " << LimitKey(options.limits_m.back() * 100)
            << " cm: " << (flagged.empty() ? "none" : flagged) << "\n";
  AnalyzeReportOptions report;
  report.log_name = std::filesystem::path(context.log_path).filename().string();
  report.scene = ToRgb8(ReadImage(context.scene_path));
  report.scene_name = std::filesystem::path(context.scene_path).filename().string();
  WriteAnalyzeOutputs(context.out.string(), result);
  {
    Progress progress("report", 1);
    AnalyzeReportPage(options, result, report).Write((context.out / "report.html").string());
  }
  std::cout << "Report: " << (context.out / "report.html").string() << "; "
            << (context.out / "images.csv").string() << ", "
            << (context.out / "exclude.txt").string() << "\n";
}

void StepRender(DemoContext& context) {
  const FlightLog& log = context.log;
  const std::filesystem::path& out = context.out;
  const RigModel rig = DemoRenderCamera();
  WriteRigModel((out / "inputs/camera.json").string(), rig);
  WriteGyroCsv((out / "inputs/gyro.csv").string(), log.gyro);
  const std::vector<int64_t> frame_times_ns =
      DemoFrameTimesNs(log.gyro, rig.shutter.readout_s, context.options.frame_every_s);
  WriteFrameTimes((out / "inputs/frames.csv").string(), frame_times_ns);
  const size_t frame_count = frame_times_ns.size();
  RenderOptions render;
  render.scene_path = context.scene_path;
  render.camera_path = (out / "inputs/camera.json").string();
  render.gyro_path = (out / "inputs/gyro.csv").string();
  render.frames_path = (out / "inputs/frames.csv").string();
  render.out_dir = (out / "render").string();
  render.Check();
  RenderSummary summary;
  {
    Progress progress("rendering frames", frame_count);
    summary = RenderDataset(render, [&progress](size_t done, size_t) { progress.Update(done); });
  }
  std::printf("%6s %10s %10s %8s\n", "frame", "D [px]", "D [cm]", "> 5 cm");
  for (const RenderedFrame& f : summary.frames) {
    std::printf("%6lld %10.2f %10.2f %8s\n", static_cast<long long>(f.frame), f.d_px, 100 * f.d_m,
                f.d_m > 0.05 ? "yes" : "no");
  }
  std::cout << "\nPictures: " << (out / "render").string()
            << "/ (side-by-side reference | rolling shutter | displacement heatmap per frame, and "
               "an overview)\n"
            << "Dataset with exact truth: " << (out / "render").string()
            << "/ (camera.json, gyro.csv, frames.csv, truth/)\n";
}

void StepCloseTheLoop(DemoContext& context) {
  InjectedDemoOptions options;
  options.scene_path = context.scene_path;
  options.out_dir = (context.out / "validate").string();
  options.injection = "time_offset=4ms";
  ValidationResult result;
  {
    StagedProgress progress;
    result = RenderAndValidate(options, std::ref(progress));
  }
  std::cout << ValidationReport(result);
  std::cout << "\nResiduals before/after: " << options.out_dir
            << "/plots/validate.html; report: " << options.out_dir << "/report.json\n";
}

void RunDemo(const DemoOptions& options) {
  DemoContext context;
  context.options = options;
  context.out = options.out_dir;
  std::filesystem::create_directories(context.out / "inputs");
  context.log_path = (context.out / "inputs/flight.ulg").string();
  context.scene_path = (context.out / "inputs/ground.png").string();
  struct Step {
    const char* title;
    void (*run)(DemoContext&);
  };
  const Step steps[] = {
      {"The inputs, made here: a survey flight as a PX4 ULog and a nadir ground texture",
       StepInputs},
      {"Static noise of a synthetic MPU-9250 at 3 kHz (paper Tables 1-2)", StepStaticNoise},
      {"Accuracy against a synthetic total station turning 1 deg steps (paper Table 3)",
       StepAccuracy},
      {"The flight log: 60 s of a multirotor survey at 1 kHz (paper Table 4)", StepFlightTable},
      {"Which photos of that flight are distorted: analyze for a 1280x960, f 1100 px, 30 ms "
       "camera at 50 m, at the log's camera triggers",
       StepAnalyze},
      {"The same flight's gyro through a 30 ms rolling shutter over the ground texture",
       StepRender},
      {"Closing the loop: a dataset rendered with a 4 ms clock offset camera.json does not "
       "declare",
       StepCloseTheLoop},
  };
  int number = 0;
  for (const Step& step : steps) {
    Section(std::to_string(number++) + ". " + step.title);
    step.run(context);
  }
  PrintWritten(context.out);
}

const CommandRegistration kDemoRegistration(5, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "demo",
      "run the main job on data it makes itself (a synthetic ULog flight, a procedural "
      "nadir ground texture)");
  auto options = std::make_shared<DemoOptions>();
  cmd->add_option("--out", options->out_dir, "output folder")->capture_default_str();
  AddQuantityOption(cmd, "--every", &options->frame_every_s, "s", "s",
                    "time between rendered frames");
  return std::function<void()>([options] {
    options->Check();
    RunDemo(*options);
  });
});

}  // namespace
}  // namespace shutterlab::app
