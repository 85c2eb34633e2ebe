#include "render/render_dataset.h"

#include "render/effects.h"
#include "render/frames_csv.h"
#include "render/image_io.h"
#include "render/pictures.h"
#include "render/truth_model.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"

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

}  // namespace

RenderSummary RenderDataset(const RenderOptions& options,
                            const std::function<void(size_t, size_t)>& progress) {
  options.Check();
  // --- read and check everything first: bad input must leave no output
  const RigModel declared = ReadRigModel(options.camera_path);
  TrueModel truth;
  truth.rig = declared;
  RenderSummary summary;
  for (const std::string& injection : options.injections) {
    const size_t eq = injection.find('=');
    const nlohmann::json value = ApplyInjection(injection, &truth);
    summary.injected[injection.substr(0, eq)] = value;
  }
  const GyroTrace logged = ReadGyroCsv(options.gyro_path);
  SHUTTERLAB_CHECK(logged.size() >= 2)
      << options.gyro_path << ": a gyro log needs at least two samples";
  const std::vector<FrameEntry> times = ReadFrameTimes(options.frames_path);
  if (options.video) {
    SHUTTERLAB_CHECK(!times.empty()) << options.frames_path << ": no frames";
    for (size_t i = 1; i < times.size(); ++i) {
      if (times[i].t_first_row_ns <= times[i - 1].t_first_row_ns) {
        throw IoError(IoMessage(
            options.frames_path, static_cast<long>(i) + 2,
            "frame " + std::to_string(times[i].frame) + ": a video's frame times must increase"));
      }
    }
  }
  const cv::Mat scene = ReadImage(options.scene_path);
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

  // --- write
  const std::filesystem::path out(options.out_dir);
  CreateFolder(out / "images");
  CreateFolder(out / "truth");
  const PinholeCamera& camera = truth.rig.camera;
  const double altitude_m = truth.rig.altitude_m;
  const double f_px = (declared.camera.fx + declared.camera.fy) / 2;
  std::vector<FrameEntry> entries;
  std::vector<cv::Mat> tiles;
  std::vector<std::string> captions;
  cv::Mat rs, ref, previous_rs;  // reused across frames: first-touch page faults are slow
  nlohmann::json frames_json = nlohmann::json::array();
  for (size_t i = 0; i < times.size(); ++i) {
    const std::string name = FrameName(times[i].frame);
    const FrameGeometry geometry(camera, altitude_m, motions[i], scene.size());
    RenderFrame(scene, geometry, options.interpolation, &rs);
    // D: the frame against a global shutter at its own row 0 (world_from_ref), in both modes.
    const cv::Mat own_field = DisplacementField(geometry);
    RenderedFrame rendered;
    rendered.frame = times[i].frame;
    rendered.d_px = FrameDistortionPx(own_field);
    rendered.d_m = rendered.d_px * altitude_m / f_px;
    rendered.outside_fraction = OutsideSceneFraction(geometry, scene.size());
    summary.frames.push_back(rendered);

    FrameEntry entry = times[i];
    entry.image = "images/" + name + "_rs.png";
    WriteImage((out / entry.image).string(), rs);
    nlohmann::json frame_json = {
        {"frame", rendered.frame}, {"D_px", rendered.d_px}, {"D_m", rendered.d_m}};
    // The truth field and the pictures beside it: against the reference, or (video) against the
    // previous frame, which the first frame of a video does not have.
    cv::Mat field;
    std::vector<cv::Mat> panels;
    std::vector<std::string> labels;
    if (!options.video) {
      const FrameGeometry reference(camera, altitude_m, motions[i].Reference(), scene.size());
      RenderFrame(scene, reference, options.interpolation, &ref);
      entry.ref = "images/" + name + "_ref.png";
      WriteImage((out / entry.ref).string(), ref);
      field = own_field;
      panels = {ref, rs};
      labels = {"reference", "rolling shutter"};
    } else if (i > 0) {
      const FrameGeometry previous(camera, altitude_m, motions[i - 1], scene.size());
      field = VideoDisplacementField(geometry, previous);
      frame_json["previous"] = times[i - 1].frame;
      panels = {previous_rs, rs};
      labels = {"previous frame " + FrameName(times[i - 1].frame), "rolling shutter"};
    } else {
      frame_json["previous"] = nullptr;
    }
    entries.push_back(entry);
    frames_json.push_back(frame_json);
    if (!field.empty()) {
      WriteImage((out / "truth" / (name + "_disp.exr")).string(), field, {"dx", "dy"});
      if (options.pictures) {
        const cv::Mat heat = DisplacementHeatmap(field);
        WriteImage((out / "truth" / (name + "_heat.png")).string(), heat);
        panels.push_back(heat);
        labels.push_back(options.video ? "|q - p|" : "|d|");
        const cv::Mat side = SideBySide(panels, labels);
        WriteImage((out / "truth" / (name + "_side.png")).string(), side);
        // Keep only a thumbnail for the overview: a flight may have hundreds of frames.
        cv::Mat thumbnail;
        cv::resize(side, thumbnail,
                   cv::Size(kTileWidth, std::max(1, side.rows * kTileWidth / side.cols)), 0, 0,
                   cv::INTER_AREA);
        tiles.push_back(thumbnail);
        char caption[96];
        std::snprintf(caption, sizeof(caption), "frame %s  D = %.2f px = %.3f m", name.c_str(),
                      rendered.d_px, rendered.d_m);
        captions.emplace_back(caption);
      }
    }
    if (options.video) rs.copyTo(previous_rs);
    if (progress) progress(i + 1, times.size());
  }
  if (options.pictures && !tiles.empty())
    WriteImage((out / "overview.png").string(), TiledOverview(tiles, captions, kTileWidth, 2));
  WriteRigModel((out / "camera.json").string(), declared);
  WriteGyroCsv((out / "gyro.csv").string(), logged);
  WriteFramesCsv((out / "frames.csv").string(), entries);
  nlohmann::json truth_json = {{"injected", summary.injected}, {"frames", frames_json}};
  if (options.video) truth_json["video"] = true;
  WriteFileAtomically((out / "truth.json").string(), truth_json.dump(2) + "\n");
  return summary;
}

}  // namespace shutterlab
