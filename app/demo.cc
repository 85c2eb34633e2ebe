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
#include "render/camera.h"
#include "render/ground_texture.h"
#include "render/image_io.h"
#include "render/pictures.h"
#include "render/render_dataset.h"
#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"

#include <cstdio>
#include <filesystem>
#include <iostream>

namespace shutterlab::app {
namespace {

struct DemoOptions {
  std::string out_dir = "shutterlab-demo";
  double frame_every_s = 4.0;  // a mapping camera's trigger cadence
  void Check() const { SHUTTERLAB_CHECK(frame_every_s > 0) << "--every must be positive"; }
};

void Section(const std::string& title) { std::cout << "\n== " << title << " ==\n"; }

// The demo camera: a 1280x720 mapping camera, 30 ms readout, 50 m above ground, looking down with
// the image top towards the nose. The flight log's gyro is about the body's roll, pitch, yaw axes
// (x forward, y right, z down, as PX4 logs it), so camera x (right) = body y, camera y (down the
// image) = -body x.
RigModel DemoCamera() {
  RigModel rig;
  rig.camera.width = 1280;
  rig.camera.height = 720;
  rig.camera.fx = rig.camera.fy = 1400.0;
  rig.camera.cx = (rig.camera.width - 1) / 2.0;
  rig.camera.cy = (rig.camera.height - 1) / 2.0;
  rig.shutter.readout_s = 0.030;
  rig.cam_from_gyro << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  rig.altitude_m = 50.0;
  return rig;
}

struct DemoContext {
  DemoOptions options;
  std::filesystem::path out;
  std::string log_path;    // the synthetic flight, written as a PX4 ULog
  std::string scene_path;  // the procedural ground texture
  FlightLog log;
};

// The demo's altitude above ground, m, and its survey flight: a multirotor with an MPU-9250-like
// gyro at 1 kHz, a still lead for the bias, a camera trigger every 2 s.
constexpr double kDemoAltitudeM = 50.0;
constexpr double kTriggerEveryS = 2.0;

void StepInputs(DemoContext& context) {
  SynthOptions flight;
  flight.profile = MotionProfile::kFlight;
  flight.rate_hz = 1000.0;
  flight.duration_s = 60.0;
  flight.t0_s = 1.0;  // ULog times start after 0
  flight.seed = 7;
  SynthOutputOptions output;
  output.out_path = context.log_path;
  output.ulog = true;
  output.trigger_every_s = kTriggerEveryS;
  output.altitude_m = kDemoAltitudeM;
  WriteSynthetic(flight, output);
  context.log = ReadFlightLog(context.log_path);
  PrintLogWarnings(context.log_path, context.log.warnings);
  std::cout << "flight log " << context.log_path << ": " << context.log.gyro.size()
            << " gyro samples over " << FormatNumber("%.1f", context.log.gyro.DurationS()) << " s, "
            << context.log.camera_events.size() << " camera triggers, altitude "
            << FormatNumber("%.0f", context.log.altitude_above_ground_m.value_or(0.0)) << " m\n";
  // The scene at the render camera's ground sample distance (docs/FORMATS.md "The scene image":
  // seen by a pinhole with the rig's focal length from the world origin), twice the frame's size.
  const RigModel rig = DemoCamera();
  GroundTextureOptions scene;
  scene.width_px = 2 * rig.camera.width;
  scene.height_px = 2 * rig.camera.height;
  scene.ground_sample_distance_m = kDemoAltitudeM / rig.camera.fx;
  WriteImage(context.scene_path, MakeGroundTexture(scene));
  std::cout << "scene " << context.scene_path << ": " << scene.width_px << "x" << scene.height_px
            << " px at " << FormatNumber("%.1f", 100 * scene.ground_sample_distance_m)
            << " cm/px\n";
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

// The analyze camera: a typical mapping camera (1280x960, f = 1100 px, 30 ms readout, 50 m),
// mounted as DemoCamera.
RigModel AnalyzeCamera() {
  RigModel rig = DemoCamera();
  rig.camera.height = 960;
  rig.camera.fx = rig.camera.fy = 1100.0;
  rig.camera.cy = (rig.camera.height - 1) / 2.0;
  return rig;
}

void StepAnalyze(DemoContext& context) {
  AnalyzeOptions options;
  options.rig = AnalyzeCamera();
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
  const RigModel rig = DemoCamera();
  WriteRigModel((out / "inputs/camera.json").string(), rig);
  WriteGyroCsv((out / "inputs/gyro.csv").string(), log.gyro);
  std::string frames = "frame,t_first_row\n";
  int frame_count = 0;
  const int64_t first_ns = log.gyro.t_begin_ns() + SecondsToNs(2.0);
  for (int64_t t = first_ns; t + SecondsToNs(rig.shutter.readout_s + 0.1) < log.gyro.t_end_ns();
       t += SecondsToNs(context.options.frame_every_s)) {
    frames += std::to_string(frame_count++) + ",";
    AppendSecondsFromNs(t, &frames);
    frames += "\n";
  }
  WriteFileAtomically((out / "inputs/frames.csv").string(), frames);
  RenderOptions render;
  render.scene_path = context.scene_path;
  render.camera_path = (out / "inputs/camera.json").string();
  render.gyro_path = (out / "inputs/gyro.csv").string();
  render.frames_path = (out / "inputs/frames.csv").string();
  render.out_dir = (out / "render").string();
  render.Check();
  RenderSummary summary;
  {
    Progress progress("rendering frames", static_cast<size_t>(frame_count));
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
  options.injection = "time_offset=0.004";
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
}

const CommandRegistration kDemoRegistration(5, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "demo",
      "run the main job on data it makes itself (a synthetic ULog flight, a procedural "
      "nadir ground texture)");
  auto options = std::make_shared<DemoOptions>();
  cmd->add_option("--out", options->out_dir, "output folder")->capture_default_str();
  cmd->add_option("--every", options->frame_every_s, "seconds between rendered frames")
      ->capture_default_str();
  return std::function<void()>([options] {
    options->Check();
    RunDemo(*options);
  });
});

}  // namespace
}  // namespace shutterlab::app
