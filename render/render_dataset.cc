#include "render/render_dataset.h"

#include "io/frames_csv.h"
#include "io/image_io.h"
#include "model/effect_io.h"
#include "model/effects.h"
#include "model/truth_model.h"
#include "render/pictures.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/trace_audit.h"

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

namespace shutterlab {

void RenderOptions::Check() const {
  SHUTTERLAB_CHECK(!scene_path.empty()) << "--scene is required";
  SHUTTERLAB_CHECK(!camera_path.empty()) << "--camera is required";
  SHUTTERLAB_CHECK(!gyro_path.empty()) << "--gyro is required";
  SHUTTERLAB_CHECK(!frames_path.empty()) << "--frames is required";
  SHUTTERLAB_CHECK(!out_dir.empty()) << "--out is required";
  clutter.Check();
  stabiliser.Check();
  SHUTTERLAB_CHECK(video || stabiliser.mode == StabiliserMode::kOff)
      << "--stabiliser needs --video: a stabiliser re-renders a clip";
}

double OutsideSceneFraction(const FrameGeometry& geometry, cv::Size scene_size) {
  const int width = geometry.camera().width, height = geometry.camera().height;
  std::vector<float> xs(width), ys(width);
  size_t outside = 0;
  for (int v = 0; v < height; ++v) {
    geometry.SceneRow(v, xs.data(), ys.data());
    for (int u = 0; u < width; ++u) {
      // Inside when all bilinear taps are: 0 <= x <= W-1, 0 <= y <= H-1 (NaN compares false).
      const bool inside = xs[u] >= 0 && xs[u] <= scene_size.width - 1 && ys[u] >= 0 &&
                          ys[u] <= scene_size.height - 1;
      outside += inside ? 0 : 1;
    }
  }
  return static_cast<double>(outside) / (static_cast<double>(width) * height);
}

namespace {

constexpr int kTileWidth = 720;  // overview tile width, px: two tiles fit a screen

void CreateFolder(const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec) throw IoError(IoMessage(path.string(), 0, "cannot create folder: " + ec.message()));
}

// The declared rig with every `--inject` applied; each injected value into summary->injected.
TrueModel InjectedTruth(const RigModel& declared, const std::vector<std::string>& injections,
                        RenderSummary* summary) {
  TrueModel truth;
  truth.rig = declared;
  for (const std::string& injection : injections) {
    summary->injected.push_back(ApplyInjection(injection, &truth));
  }
  return truth;
}

// truth.json's "injected": {NAME: value}; an effect injected twice keeps its last value.
nlohmann::json InjectedJson(const std::vector<Injection>& injected) {
  nlohmann::json out = nlohmann::json::object();
  for (const Injection& i : injected) out[Spec(i.effect).name] = EffectValueToJson(i.value);
  return out;
}

// A video needs frames, and their times must increase.
void CheckVideoTimes(const RenderOptions& options, const std::vector<FrameEntry>& times) {
  SHUTTERLAB_CHECK(!times.empty()) << options.frames_path << ": no frames";
  for (size_t i = 1; i < times.size(); ++i) {
    if (times[i].t_first_row_ns <= times[i - 1].t_first_row_ns) {
      throw IoError(IoMessage(
          options.frames_path, static_cast<long>(i) + 2,
          "frame " + std::to_string(times[i].frame) + ": a video's frame times must increase"));
    }
  }
}

// Each frame's motion (a video's in the first frame's world); throws std::out_of_range naming the
// frame whose readout lies outside the gyro trace.
std::vector<FrameMotion> FrameMotions(const RenderOptions& options, const GyroTrace& logged,
                                      const TrueModel& truth,
                                      const std::vector<FrameEntry>& times) {
  const CameraMotion camera_motion(logged, truth);
  std::vector<FrameMotion> motions;
  std::optional<int64_t> anchor;
  if (options.video) anchor = times.front().t_first_row_ns;
  for (const FrameEntry& f : times) {
    try {
      motions.push_back(camera_motion.Frame(f.t_first_row_ns, anchor));
    } catch (const std::out_of_range& e) {
      throw std::out_of_range(options.frames_path + ": frame " + std::to_string(f.frame) + ": " +
                              e.what());
    }
  }
  return motions;
}

// Turns each frame by the stabiliser's S_k (none when it is off); returns truth.json's
// "stabiliser" (null when off).
nlohmann::json Stabilise(const RenderOptions& options, const std::vector<FrameEntry>& times,
                         std::vector<FrameMotion>* motions) {
  if (options.stabiliser.mode == StabiliserMode::kOff) return nullptr;
  std::vector<double> t_s;
  for (const FrameEntry& f : times)
    t_s.push_back((f.t_first_row_ns - times.front().t_first_row_ns) * 1e-9);
  const std::vector<Eigen::Matrix3d> turns = StabiliserRotations(options.stabiliser, *motions, t_s);
  nlohmann::json rotations = nlohmann::json::array();
  for (size_t k = 0; k < turns.size(); ++k) {
    TurnFrame(turns[k], &(*motions)[k]);
    const Eigen::Vector3d deg = LogSO3(Eigen::Quaterniond(turns[k]).normalized()) * 180.0 / M_PI;
    rotations.push_back(
        {{"frame", times[k].frame}, {"cam_from_image_deg", {deg.x(), deg.y(), deg.z()}}});
  }
  return {{"mode", StabiliserModeName(options.stabiliser.mode)},
          {"window_s", options.stabiliser.window_s},
          {"frames", rotations}};
}

// What every frame of a render shares.
struct RenderContext {
  const RenderOptions& options;
  const std::filesystem::path& out;
  const cv::Mat& scene;
  const PinholeCamera& camera;
  double altitude_m;
  double f_px;  // the declared camera's
  const std::vector<FrameEntry>& times;
  const std::vector<FrameMotion>& motions;
  const RollingShutter& shutter;  // the true one: the moving patch's row times
  const std::optional<CameraFixedPatch>& camera_fixed;
  const std::optional<MovingPatch>& moving;
};

// What the frames add to as they are written.
struct RenderState {
  std::vector<FrameEntry> entries;
  std::vector<cv::Mat> tiles;
  std::vector<std::string> captions;
  cv::Mat rs, ref, previous_rs;  // reused across frames: first-touch page faults are slow
  nlohmann::json frames_json = nlohmann::json::array();
};

// One frame's truth field and the pictures beside it.
struct FrameTruth {
  cv::Mat field;  // empty when there is none
  std::vector<cv::Mat> panels;
  std::vector<std::string> labels;
};

// Each row's time on the moving patch's clock (render_dataset.h): the rolling-shutter rows of frame
// i, or with `reference` every row at the time of row 0.
std::vector<double> PatchRowTimes(const RenderContext& ctx, size_t i, bool reference) {
  const int height = ctx.camera.height;
  const double row0_s = ctx.shutter.RowTimeOffsetS(0, height);
  const double origin_s =
      ctx.options.video ? (ctx.times[i].t_first_row_ns - ctx.times.front().t_first_row_ns) * 1e-9
                        : -row0_s;
  std::vector<double> t_s(height);
  for (int v = 0; v < height; ++v) {
    t_s[v] = origin_s + (reference ? row0_s : ctx.shutter.RowTimeOffsetS(v, height));
  }
  return t_s;
}

// The clutter over a rendered frame (and its truth field, when given).
void PaintClutter(const RenderContext& ctx, size_t i, const FrameGeometry& geometry, bool reference,
                  cv::Mat* image, cv::Mat* truth) {
  if (ctx.moving) {
    PaintMovingPatch(*ctx.moving, geometry, PatchRowTimes(ctx, i, reference), image, truth);
  }
  if (ctx.camera_fixed) PaintCameraFixed(*ctx.camera_fixed, image, truth);
}

// The truth field and the pictures beside it: against the reference, or (video) against the
// previous frame, which the first frame of a video does not have.
FrameTruth TruthField(const RenderContext& ctx, size_t i, const FrameGeometry& geometry,
                      const cv::Mat& own_field, FrameEntry* entry, nlohmann::json* frame_json,
                      RenderState* state) {
  const std::string name = FrameName(ctx.times[i].frame);
  FrameTruth truth;
  if (!ctx.options.video) {
    const FrameGeometry reference(ctx.camera, ctx.altitude_m, ctx.motions[i].Reference(),
                                  ctx.scene.size());
    RenderFrame(ctx.scene, reference, ctx.options.interpolation, &state->ref);
    PaintClutter(ctx, i, reference, /*reference=*/true, &state->ref, nullptr);
    entry->ref = "images/" + name + "_ref.png";
    WriteImage((ctx.out / entry->ref).string(), state->ref);
    truth.field = ctx.options.clutter.any() ? own_field.clone() : own_field;
    truth.panels = {state->ref, state->rs};
    truth.labels = {"reference", "rolling shutter"};
  } else if (i > 0) {
    const FrameGeometry previous(ctx.camera, ctx.altitude_m, ctx.motions[i - 1], ctx.scene.size());
    truth.field = VideoDisplacementField(geometry, previous);
    (*frame_json)["previous"] = ctx.times[i - 1].frame;
    truth.panels = {state->previous_rs, state->rs};
    truth.labels = {"previous frame " + FrameName(ctx.times[i - 1].frame), "rolling shutter"};
  } else {
    (*frame_json)["previous"] = nullptr;
  }
  return truth;
}

// The heat map, the side-by-side picture and the overview's thumbnail and caption of a frame.
void WritePictures(const RenderContext& ctx, const std::string& name, const RenderedFrame& rendered,
                   FrameTruth* truth, RenderState* state) {
  const cv::Mat heat = DisplacementHeatmap(truth->field);
  WriteImage((ctx.out / "truth" / (name + "_heat.png")).string(), heat);
  truth->panels.push_back(heat);
  truth->labels.push_back(ctx.options.video ? "|q - p|" : "|d|");
  const cv::Mat side = SideBySide(truth->panels, truth->labels);
  WriteImage((ctx.out / "truth" / (name + "_side.png")).string(), side);
  // Keep only a thumbnail for the overview: a flight may have hundreds of frames.
  cv::Mat thumbnail;
  cv::resize(side, thumbnail, cv::Size(kTileWidth, std::max(1, side.rows * kTileWidth / side.cols)),
             0, 0, cv::INTER_AREA);
  state->tiles.push_back(thumbnail);
  char caption[96];
  std::snprintf(caption, sizeof(caption), "frame %s  D = %.2f px = %.3f m", name.c_str(),
                rendered.d_px, rendered.d_m);
  state->captions.emplace_back(caption);
}

// Renders and writes frame i, its truth and pictures.
void WriteFrame(const RenderContext& ctx, size_t i, RenderSummary* summary, RenderState* state) {
  const std::string name = FrameName(ctx.times[i].frame);
  const FrameGeometry geometry(ctx.camera, ctx.altitude_m, ctx.motions[i], ctx.scene.size());
  RenderFrame(ctx.scene, geometry, ctx.options.interpolation, &state->rs);
  // D: the frame against a global shutter at its own row 0 (world_from_ref), in both modes.
  const cv::Mat own_field = DisplacementField(geometry);
  RenderedFrame rendered;
  rendered.frame = ctx.times[i].frame;
  rendered.d_px = FrameDistortionPx(own_field);
  rendered.d_m = rendered.d_px * ctx.altitude_m / ctx.f_px;
  rendered.outside_fraction = OutsideSceneFraction(geometry, ctx.scene.size());
  summary->frames.push_back(rendered);

  FrameEntry entry = ctx.times[i];
  entry.image = "images/" + name + "_rs.png";
  nlohmann::json frame_json = {
      {"frame", rendered.frame}, {"D_px", rendered.d_px}, {"D_m", rendered.d_m}};
  // The truth before the clutter: a video's previous frame is read clean from the scene.
  FrameTruth truth = TruthField(ctx, i, geometry, own_field, &entry, &frame_json, state);
  PaintClutter(ctx, i, geometry, /*reference=*/false, &state->rs, &truth.field);
  WriteImage((ctx.out / entry.image).string(), state->rs);
  state->entries.push_back(entry);
  state->frames_json.push_back(frame_json);
  if (!truth.field.empty()) {
    WriteImage((ctx.out / "truth" / (name + "_disp.exr")).string(), truth.field, {"dx", "dy"});
    if (ctx.options.pictures) WritePictures(ctx, name, rendered, &truth, state);
  }
  if (ctx.options.video) state->rs.copyTo(state->previous_rs);
}

}  // namespace

RenderSummary RenderDataset(const RenderOptions& options,
                            const std::function<void(size_t, size_t)>& progress) {
  options.Check();
  // --- read and check everything first: bad input must leave no output
  RigModel declared = ReadRigModel(options.camera_path);
  RenderSummary summary;
  if (!options.lens_profile_path.empty()) {
    summary.lens_profile = ScaleLensProfile(ReadLensProfile(options.lens_profile_path),
                                            declared.camera.width, declared.camera.height);
    ApplyLensProfile(&*summary.lens_profile, &declared);
  }
  const TrueModel truth = InjectedTruth(declared, options.injections, &summary);
  const GyroTrace logged = ReadGyroCsv(options.gyro_path);
  SHUTTERLAB_CHECK(logged.size() >= 2)
      << options.gyro_path << ": a gyro log needs at least two samples";
  summary.gyro_warnings = AuditTrace(logged);
  const std::vector<FrameEntry> times = ReadFrameTimes(options.frames_path);
  if (options.video) CheckVideoTimes(options, times);
  const cv::Mat scene = ReadImage(options.scene_path);
  std::vector<FrameMotion> motions = FrameMotions(options, logged, truth, times);
  const nlohmann::json stabiliser_json = Stabilise(options, times, &motions);

  // --- write
  const std::filesystem::path out(options.out_dir);
  CreateFolder(out / "images");
  CreateFolder(out / "truth");
  const ClutterOptions& clutter = options.clutter;
  const cv::Size frame_size(truth.rig.camera.width, truth.rig.camera.height);
  std::optional<CameraFixedPatch> camera_fixed;
  if (clutter.camera_fixed_share > 0) {
    camera_fixed = MakeCameraFixedPatch(frame_size, scene.type(), clutter.camera_fixed_share);
  }
  std::optional<MovingPatch> moving;
  if (clutter.moving_patch_mps > 0) {
    const Eigen::Vector2d centre((scene.cols - 1) / 2.0,
                                 (scene.rows - 1) / 2.0 - 0.15 * frame_size.height);
    const double t_mid_s =
        options.video ? 0.5 * (times.back().t_first_row_ns - times.front().t_first_row_ns) * 1e-9
                      : 0.0;
    moving = MakeMovingPatch(truth.rig.camera, truth.rig.altitude_m, clutter.moving_patch_mps,
                             centre, t_mid_s, scene.type());
  }
  const RenderContext ctx{options,
                          out,
                          scene,
                          truth.rig.camera,
                          truth.rig.altitude_m,
                          (declared.camera.fx + declared.camera.fy) / 2,
                          times,
                          motions,
                          truth.rig.shutter,
                          camera_fixed,
                          moving};
  RenderState state;
  for (size_t i = 0; i < times.size(); ++i) {
    WriteFrame(ctx, i, &summary, &state);
    if (progress) progress(i + 1, times.size());
  }
  if (options.pictures && !state.tiles.empty()) {
    WriteImage((out / "overview.png").string(),
               TiledOverview(state.tiles, state.captions, kTileWidth, 2));
  }
  WriteRigModel((out / "camera.json").string(), declared);
  WriteGyroCsv((out / "gyro.csv").string(), logged);
  WriteFramesCsv((out / "frames.csv").string(), state.entries);
  nlohmann::json truth_json = {{"injected", InjectedJson(summary.injected)},
                               {"frames", state.frames_json}};
  if (options.video) truth_json["video"] = true;
  if (!stabiliser_json.is_null()) truth_json["stabiliser"] = stabiliser_json;
  if (camera_fixed) truth_json["camera_fixed_rows_from"] = camera_fixed->rows_from;
  if (moving) {
    truth_json["moving_patch"] = {{"speed_mps", clutter.moving_patch_mps},
                                  {"side_px", moving->side_px},
                                  {"start_px", {moving->start_px.x(), moving->start_px.y()}},
                                  {"velocity_px_s", {moving->velocity_px_s.x(), 0.0}}};
  }
  WriteFileAtomically((out / "truth.json").string(), truth_json.dump(2) + "\n");
  return summary;
}

}  // namespace shutterlab
