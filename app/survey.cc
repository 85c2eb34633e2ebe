// `shutterlab survey --out DIR`: a mapping flight with exact truth (render/survey.h):
// rolling-shutter photos as a drone writes them, their global-shutter references, the flight's ULog
// and the truth.

#include "render/survey.h"

#include "app/command.h"
#include "sim/logs/flight_log_io.h"
#include "sim/synth/synth.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab::app {
namespace {

struct SurveyCliOptions {
  SurveyOptions survey;
  std::string out_dir;
  std::string gyro_path;       // "": a synthetic multirotor's
  std::string wind = "gusty";  // the synthetic multirotor's: calm, gusty or none
  int width = 640, height = 480;
  double focal_px = 560.0;
};

// The gyro: the given log's (its axes taken as the camera's), or a synthetic multirotor's, ideal,
// 1 kHz, long enough for the flight.
GyroTrace SurveyGyro(const SurveyCliOptions& o, std::string* source) {
  if (!o.gyro_path.empty()) {
    *source = o.gyro_path + " (its axes taken as the camera's)";
    return ReadFlightLog(o.gyro_path).gyro;
  }
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 1000.0;
  synth.duration_s = SurveyEndS(o.survey) + 2.0;
  synth.t0_s = 0.001;  // PX4 times start above 0
  synth.seed = o.survey.seed;
  synth.imu = ImuErrorModel::Ideal();
  if (o.wind == "none") {  // a perfect gimbal's hold: the translation alone
    synth.profile = MotionProfile::kStill;
    *source = "no rotation (sim/synth still profile, ideal sensor, 1 kHz)";
    return SynthesizeTrace(synth);
  }
  if (o.wind == "calm") {  // a still day: a slow wobble, few and weak gusts
    synth.flight.wobble_rms_dps = 1.0;
    synth.flight.gusts_per_s = 0.1;
    synth.flight.gust_max_dps = 10.0;
  }
  *source = "a synthetic multirotor's motion (sim/synth flight profile, " + o.wind + ", seed " +
            std::to_string(o.survey.seed) + ", ideal sensor, 1 kHz)";
  return SynthesizeTrace(synth);
}

const CommandRegistration kSurveyRegistration(47, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "survey",
      "render a mapping flight with exact truth: rolling-shutter photos with a drone's metadata, "
      "their global-shutter references, the flight's ULog, terrain and poses");
  auto o = std::make_shared<SurveyCliOptions>();
  cmd->add_option("--out", o->out_dir, "output folder")->required();
  cmd->add_option("--gyro", o->gyro_path,
                  "a gyro log (any format `analyze` reads) for the rotation during each readout, "
                  "its axes the camera's (default: a synthetic multirotor's)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--wind", o->wind,
                  "without --gyro: gusty (gusts of 4-50 deg/s, 0.7 a second), calm (1 deg/s "
                  "wobble, gusts to 10 deg/s) or none (no rotation: the flight's translation "
                  "alone, as behind a perfect gimbal)")
      ->check(CLI::IsMember({"calm", "gusty", "none"}))
      ->capture_default_str();
  cmd->add_option("--width", o->width, "image width, px")->capture_default_str();
  cmd->add_option("--height", o->height, "image height, px")->capture_default_str();
  cmd->add_option("--focal-px", o->focal_px, "focal length, px")->capture_default_str();
  AddQuantityOption(cmd, "--readout", &o->survey.readout_s, "s", "ms",
                    "readout, first row to last");
  AddQuantityOption(
      cmd, "--start", &o->survey.start_s, "s", "s",
      "the first photo's first row on the gyro's clock (with --gyro: inside its log)");
  AddQuantityOption(cmd, "--altitude", &o->survey.altitude_m, "m", "m", "height above the datum");
  AddQuantityOption(cmd, "--speed", &o->survey.speed_mps, "m/s", "m/s",
                    "ground speed along a line");
  cmd->add_option("--front-overlap", o->survey.front_overlap,
                  "share of a photo the next one sees again (0.7 = 70 %)")
      ->capture_default_str();
  cmd->add_option("--side-overlap", o->survey.side_overlap,
                  "share of a line's strip the next line sees again")
      ->capture_default_str();
  cmd->add_option("--lines", o->survey.lines, "lines flown north, south, ...")
      ->capture_default_str();
  cmd->add_option("--photos-per-line", o->survey.photos_per_line, "photos on each line")
      ->capture_default_str();
  AddQuantityOption(cmd, "--hills", &o->survey.terrain.hill_height_m, "m", "m",
                    "the hills' height, peak to trough (0: flat ground)");
  cmd->add_option("--buildings", o->survey.terrain.buildings, "box buildings, 6-12 m tall")
      ->capture_default_str();
  cmd->add_option("--seed", o->survey.seed, "the terrain's, texture's and motion's random seed")
      ->capture_default_str();
  return std::function<void()>([o] {
    o->survey.camera.width = o->width;
    o->survey.camera.height = o->height;
    o->survey.camera.fx = o->survey.camera.fy = o->focal_px;
    o->survey.camera.cx = 0.5 * (o->width - 1);
    o->survey.camera.cy = 0.5 * (o->height - 1);
    o->survey.Check();
    std::string gyro_source;
    const GyroTrace gyro = SurveyGyro(*o, &gyro_source);
    auto progress = std::make_unique<Progress>(
        "photos", static_cast<size_t>(o->survey.lines * o->survey.photos_per_line));
    const SurveySummary summary = WriteSurvey(
        o->survey, gyro, o->out_dir, [&progress](size_t done, size_t) { progress->Update(done); });
    progress.reset();
    std::vector<double> d_px;
    for (const SurveyPhoto& p : summary.photos) d_px.push_back(p.d_px);
    std::printf(
        "survey: %zu photos on %d lines at %g m, %g m/s, readout %g ms, ground sample %.1f "
        "cm/px; terrain %.1f to %.1f m\n",
        summary.photos.size(), o->survey.lines, o->survey.altitude_m, o->survey.speed_mps,
        o->survey.readout_s * 1e3, summary.gsd_m * 100, summary.terrain.min_m,
        summary.terrain.max_m);
    std::printf(
        "rolling shutter against the global-shutter references: D median %.2f px, largest "
        "%.2f px\n",
        Median(d_px), *std::max_element(d_px.begin(), d_px.end()));
    std::printf("motion: %s\n", gyro_source.c_str());
    SayWritten(o->out_dir, summary.files);
    std::printf(
        "next: shutterlab correct --photos %s/images %s/flight.ulg --camera "
        "%s/truth/camera.json --out CORRECTED; scripts/photogrammetry.sh reconstructs it "
        "with COLMAP (docs/photogrammetry.md)\n",
        o->out_dir.c_str(), o->out_dir.c_str(), o->out_dir.c_str());
  });
});

}  // namespace
}  // namespace shutterlab::app
