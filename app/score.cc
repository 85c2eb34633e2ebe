// `shutterlab score SURVEY MODEL`: a COLMAP reconstruction of a survey's photos measured against
// the survey's truth (render/survey_score.h).

#include "app/command.h"
#include "render/survey_score.h"
#include "sim/text_file.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

namespace shutterlab::app {
namespace {

struct ScoreCliOptions {
  std::string survey_dir, model_dir;
  bool json = false;
};

nlohmann::json ScoreJson(const ReconstructionScore& s) {
  nlohmann::json photos = nlohmann::json::array();
  for (const PhotoScore& p : s.per_photo) {
    nlohmann::json j = {{"name", p.name}, {"registered", p.registered}};
    if (p.registered && s.alignment_scale > 0) {
      j["horizontal_error_m"] = p.horizontal_error_m;
      j["vertical_error_m"] = p.vertical_error_m;
      j["orientation_error_deg"] = p.orientation_error_deg;
    }
    photos.push_back(j);
  }
  return {{"format", "score/1"},
          {"photos", s.photos},
          {"registered", s.registered},
          {"mean_reprojection_error_px", s.mean_reprojection_error_px},
          {"alignment_scale", s.alignment_scale},
          {"horizontal_rms_m", s.horizontal_rms_m},
          {"vertical_rms_m", s.vertical_rms_m},
          {"orientation_rms_deg", s.orientation_rms_deg},
          {"points", s.points},
          {"points_on_terrain", s.points_on_terrain},
          {"point_median_m", s.point_median_m},
          {"point_rms_m", s.point_rms_m},
          {"per_photo", photos},
          {"notes", s.notes}};
}

void PrintScore(const ReconstructionScore& s) {
  std::printf("registered %zu of %zu photos; mean reprojection error %.3f px\n", s.registered,
              s.photos, s.mean_reprojection_error_px);
  if (s.alignment_scale > 0) {
    std::printf(
        "camera centres (similarity-aligned to the truth's middle-row centres, %.4g m a "
        "model unit): horizontal %.2f cm, vertical %.2f cm RMS\n",
        s.alignment_scale, 100 * s.horizontal_rms_m, 100 * s.vertical_rms_m);
    if (std::isnan(s.orientation_rms_deg)) {  // cameras on one line: said in the notes
      std::printf("orientation and points: left out (see the note)\n");
    } else {
      std::printf("orientation: %.4f deg RMS\n", s.orientation_rms_deg);
      std::printf(
          "sparse points: %zu, %zu over the terrain: |z - terrain| median %.2f cm, RMS "
          "%.2f cm\n",
          s.points, s.points_on_terrain, 100 * s.point_median_m, 100 * s.point_rms_m);
    }
    std::printf("%-16s %14s %12s %16s\n", "photo", "horizontal cm", "vertical cm",
                "orientation deg");
    for (const PhotoScore& p : s.per_photo) {
      if (!p.registered) {
        std::printf("%-16s not registered\n", p.name.c_str());
        continue;
      }
      std::printf("%-16s %14.2f %12.2f %16.4f\n", p.name.c_str(), 100 * p.horizontal_error_m,
                  100 * p.vertical_error_m, p.orientation_error_deg);
    }
  }
  for (const std::string& note : s.notes) std::fprintf(stderr, "note: %s\n", note.c_str());
}

const CommandRegistration kScoreRegistration(48, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "score",
      "measure a COLMAP reconstruction of a survey's photos against the survey's truth: "
      "registered photos, reprojection error, camera centre and orientation errors, points "
      "against the terrain");
  auto o = std::make_shared<ScoreCliOptions>();
  cmd->add_option("SURVEY", o->survey_dir, "the survey folder (`shutterlab survey --out`)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("MODEL", o->model_dir,
                  "a COLMAP text model of its photos (cameras.txt, images.txt, points3D.txt)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_flag("--json", o->json, "print JSON");
  return std::function<void()>([o] {
    const ReconstructionScore score =
        ScoreReconstruction(ReadSurveyTruth(o->survey_dir), o->model_dir);
    if (o->json) {
      std::cout << JsonText(ScoreJson(score)) << "\n";
    } else {
      PrintScore(score);
    }
  });
});

}  // namespace
}  // namespace shutterlab::app
