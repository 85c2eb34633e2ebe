#include "estimate/correct/correct_dataset.h"

#include "estimate/correct/correct_io.h"
#include "io/frames_csv.h"
#include "io/image_io.h"
#include "io/rig_dataset.h"
#include "model/effect_io.h"
#include "model/reported_model.h"
#include "render/pictures.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/gyro_trace.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// Gyro samples either side of a frame's readout that a residual draw may need (a clock-rate draw
// moves a frame at 1000 s by 1 ms per ppm).
constexpr int64_t kGyroMarginNs = 1'000'000'000;
// Frames drawn in overview.png.
constexpr size_t kOverviewFrames = 4;
constexpr int kOverviewTileWidthPx = 480;
// DIR's copy of camera.json's mask (docs/FORMATS.md v1.1 `mask`).
constexpr const char* kCameraMaskName = "camera_mask.png";

struct Context {
  const CorrectOptions& options;
  const RigDataset& dataset;
  const CorrectionModel& model;
  const CorrectionSetting& setting;
  const CameraMotion& motion;
  // Photos: each one's own velocity (its metadata), unless the model's was set for all of them.
  const std::map<int64_t, PhotoVelocity>* photo_velocity;
  std::string image_root;   // DIR's folder of the corrected images ("": DIR itself)
  std::string translation;  // the summary's words, for frames without their own velocity
  std::vector<std::pair<std::string, std::string>> xmp;  // the same for every frame
  bool photos = false;  // correct --photos: a frame is named by its photo in what is said
};

// A corrected image's mask, named by the image's path under the image root (COLMAP's
// --ImageReader.mask_path convention, with --image_path the root).
fs::path MaskPath(const std::string& out_dir, const std::string& image_under_root) {
  return fs::path(out_dir) / "masks" / (image_under_root + ".png");
}

void CreateParent(const fs::path& path) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec)
    throw IoError(IoMessage(path.parent_path().string(), 0, "cannot create: " + ec.message()));
}

// The instant the corrected frame shows, camera clock: the reference row's capture time.
int64_t ReferenceTimeNs(const TrueModel& model, int64_t t_first_row_ns, double reference_row) {
  return t_first_row_ns +
         SecondsToNs(model.rig.shutter.RowTimeOffsetS(reference_row, model.rig.camera.height));
}

// A worker's decoded source, corrected image and mask, reused frame to frame: a 12 MP photo's
// output touched afresh cost about as much in page faults as its warp (bench/photos_bench.cc).
struct FrameBuffers {
  cv::Mat source, corrected;
  PackedMask mask;
};

// An overview frame's pictures, made from the pixels in memory while the frame is corrected: from
// the files afterwards they took a decode of each photo twice over.
struct OverviewPictures {
  cv::Mat recorded, corrected;
};

// Which of n frames overview.png shows: a few, evenly spread, the first and the last among them.
std::vector<size_t> OverviewIndices(size_t n) {
  const size_t count = std::min(kOverviewFrames, n);
  std::vector<size_t> indices;
  for (size_t k = 0; k < count; ++k)
    indices.push_back(k * (n - 1) / std::max<size_t>(1, count - 1));
  return indices;
}

// Writes the corrected image and its mask (unless DIR holds both and force is off), and with
// `pictures` the overview's pictures of the frame when it was corrected here; the share of pixels
// with no source.
double WriteCorrected(const Context& c, const FrameEntry& e, const CorrectionMap& map,
                      const ResidualPrediction& residual, CorrectedFrame* out,
                      FrameBuffers* buffers, std::optional<OverviewPictures>* pictures) {
  const fs::path image_path = fs::path(c.options.out_dir) / out->image;
  const fs::path mask_path = MaskPath(c.options.out_dir, e.image);
  PackedMask& mask = buffers->mask;
  if (!c.options.force && fs::is_regular_file(image_path) && fs::is_regular_file(mask_path)) {
    out->kept = true;
    mask = PackMask(ReadImage(mask_path.string()));
  } else {
    const std::string input = (c.dataset.dir / e.image).string();
    const cv::Mat rs = ReadWholeImage(input, &buffers->source);
    if (rs.cols != map.geometry().camera().width || rs.rows != map.geometry().camera().height) {
      throw IoError(IoMessage(input, 0,
                              "is " + std::to_string(rs.cols) + "x" + std::to_string(rs.rows) +
                                  ", camera.json declares " +
                                  std::to_string(map.geometry().camera().width) + "x" +
                                  std::to_string(map.geometry().camera().height)));
    }
    cv::Mat& corrected = buffers->corrected;
    CorrectFrame(rs, map, c.options.interpolation, &corrected, &mask);
    if (pictures) {  // ToRgb8 copies: nothing of the worker's reused buffers is kept
      *pictures = OverviewPictures{ToRgb8(ShrinkByWholeFactor(rs, kOverviewTileWidthPx)),
                                   ToRgb8(ShrinkByWholeFactor(corrected, kOverviewTileWidthPx))};
    }
    if (!c.dataset.mask.empty()) {
      // camera.json's mask moves with the pixels: a corrected pixel may be used where every tap
      // of its source may (the bilinear sample of 0/255 is 255 exactly there).
      cv::Mat moved;
      CorrectFrame(c.dataset.mask, map, Interpolation::kBilinear, &moved);
      mask.bits &= PackMask(moved == 255).bits;
    }
    std::vector<std::pair<std::string, std::string>> xmp = c.xmp;
    xmp.emplace_back("Xmp.shutterlab.Translation", out->translation);
    xmp.emplace_back("Xmp.shutterlab.ReferenceTime",
                     FormatNumber("%.9f", out->t_reference_ns * 1e-9));
    xmp.emplace_back("Xmp.shutterlab.ReferenceRow", FormatNumber("%g", out->reference_row));
    xmp.emplace_back("Xmp.shutterlab.DistortionBeforePx",
                     FormatNumber("%.3f", residual.d_before_px));
    xmp.emplace_back("Xmp.shutterlab.PredictedDistortionAfterPx",
                     FormatNumber("%.3f", out->predicted_d_after_px));
    CreateParent(image_path);
    CreateParent(mask_path);
    out->notes = WriteImageLike(image_path.string(), corrected,
                                ImageLike{input, ReadImageFileInfo(input)}, xmp);
    WriteMask(mask_path.string(), mask);
  }
  return 1.0 - static_cast<double>(CountSetPixels(mask)) /
                   (static_cast<double>(mask.width) * mask.height());
}

// The frame's own velocity (a photo's metadata) when it has one, and the words for what of the
// motion is corrected.
std::optional<Eigen::Vector3d> FrameVelocity(const Context& c, int64_t frame, CorrectedFrame* out) {
  out->velocity_mps = c.model.model.rig.velocity_mps;
  out->translation = c.translation;
  if (!c.photo_velocity || !c.setting.plane_depth_m) return std::nullopt;
  const auto it = c.photo_velocity->find(frame);
  if (it == c.photo_velocity->end()) return std::nullopt;
  const PhotoVelocity& own = it->second;
  const std::string plane = FormatNumber("ground plane at %g m", *c.setting.plane_depth_m);
  if (!own.velocity_mps) {
    out->translation = c.model.model.rig.velocity_mps.isZero()
                           ? "rotation only: " + own.source
                           : plane + ", camera.json's velocity (" + own.source + ")";
    return std::nullopt;
  }
  out->velocity_mps = *own.velocity_mps;
  out->translation = plane + ", velocity " + own.source;
  return own.velocity_mps;
}

CorrectedFrame CorrectOne(const Context& c, const FrameEntry& e, FrameBuffers* buffers,
                          std::optional<OverviewPictures>* pictures) {
  CorrectedFrame out;
  out.frame = e.frame;
  out.source_image = e.image;
  out.image = c.image_root.empty() ? e.image : (fs::path(c.image_root) / e.image).string();
  const std::optional<Eigen::Vector3d> own_velocity = FrameVelocity(c, e.frame, &out);
  std::optional<CorrectionModel> own_model;
  if (own_velocity) {
    own_model = c.model;
    own_model->model.rig.velocity_mps = *own_velocity;
  }
  const CorrectionModel& frame_model = own_model ? *own_model : c.model;
  const TrueModel& model = frame_model.model;
  out.t_first_row_ns = e.t_first_row_ns;
  out.reference_row = ReferenceRow(c.setting.reference, model.rig.shutter, model.rig.camera.height);
  out.t_reference_ns = ReferenceTimeNs(model, e.t_first_row_ns, out.reference_row);
  // std::out_of_range: skipped
  FrameMotion motion = c.motion.Frame(e.t_first_row_ns, std::nullopt, own_velocity);
  const int64_t readout_ns = SecondsToNs(model.rig.shutter.readout_s);
  // The prediction first, on the frame's poses, which the geometry then takes without a copy.
  out.residual = PredictResidual(frame_model,
                                 GyroAround(c.dataset.gyro, e.t_first_row_ns - kGyroMarginNs,
                                            e.t_first_row_ns + readout_ns + kGyroMarginNs),
                                 e.t_first_row_ns, c.setting, c.options.prediction, &motion);
  const CorrectionGeometry geometry(model.rig.camera, std::move(motion), out.reference_row,
                                    c.setting.plane_depth_m);
  const CorrectionMap map(geometry, c.options.map);
  out.cell_px = map.cell_px();
  out.map_error_px = map.estimated_error_px();
  out.predicted_d_after_px = out.residual.d_after_px + 2 * out.map_error_px;
  out.predicted_d_after_p90_px = out.residual.d_after_p90_px + 2 * out.map_error_px;
  out.no_source_fraction = WriteCorrected(c, e, map, out.residual, &out, buffers, pictures);
  if (c.options.check_truth) {
    const fs::path truth_dir =
        c.options.truth_dir.empty() ? c.dataset.dir / "truth" : fs::path(c.options.truth_dir);
    const fs::path truth = truth_dir / (FrameName(e.frame) + "_disp.exr");
    if (!fs::is_regular_file(truth)) throw IoError(IoMessage(truth.string(), 0, "missing"));
    out.truth = MeasureAgainstTruth(map, ReadFloatImage(truth.string()));
  }
  return out;
}

// Every frame on `jobs` threads, frames.csv order kept; frames whose readout the gyro does not
// cover, and photos whose image does not decode whole (a cut photo: found here, in the one decode,
// rather than by decoding every photo first), go to skipped. The first other error stops the
// others and is thrown. With pictures, the overview's pictures of its frames, by frame number.
void RunFrames(const Context& c, const CorrectProgress& progress, CorrectSummary* summary,
               std::map<int64_t, OverviewPictures>* pictures) {
  const std::vector<FrameEntry>& entries = c.dataset.frames;
  std::vector<std::optional<CorrectedFrame>> done(entries.size());
  std::vector<std::optional<OverviewPictures>> drawn(entries.size());
  // The frames overview.png shows if none is skipped.
  std::vector<bool> draw(entries.size(), false);
  if (pictures) {
    for (const size_t i : OverviewIndices(entries.size())) draw[i] = true;
  }
  std::vector<std::string> skipped(entries.size());
  std::atomic<size_t> next{0}, finished{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex lock;
  const auto work = [&] {
    FrameBuffers buffers;
    for (size_t i = next++; i < entries.size() && !failed; i = next++) {
      try {
        done[i] = CorrectOne(c, entries[i], &buffers, draw[i] ? &drawn[i] : nullptr);
      } catch (const std::out_of_range&) {
        skipped[i] = "its readout is outside " + fs::path(c.dataset.gyro_path).filename().string();
      } catch (const UndecodableImage& e) {
        // A cut photo is skipped (named by its name below); a dataset's damaged frame stops the
        // run like any other unreadable input.
        if (c.photos) {
          skipped[i] = e.reason;
        } else {
          const std::lock_guard<std::mutex> guard(lock);
          if (!failed.exchange(true)) error = std::current_exception();
        }
      } catch (...) {
        const std::lock_guard<std::mutex> guard(lock);
        if (!failed.exchange(true)) error = std::current_exception();
      }
      const std::lock_guard<std::mutex> guard(lock);
      if (progress) progress(++finished, entries.size());
    }
  };
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int jobs = c.options.jobs > 0 ? c.options.jobs : std::min(hardware, 4);
  std::vector<std::thread> workers;
  for (int k = 1; k < std::min<int>(jobs, static_cast<int>(entries.size())); ++k) {
    workers.emplace_back(work);
  }
  work();
  for (std::thread& t : workers) t.join();
  if (error) std::rethrow_exception(error);
  for (size_t i = 0; i < entries.size(); ++i) {
    if (done[i]) summary->frames.push_back(std::move(*done[i]));
    if (done[i] && drawn[i]) pictures->emplace(entries[i].frame, std::move(*drawn[i]));
    if (skipped[i].empty()) continue;
    summary->skipped.emplace_back(entries[i].frame,
                                  c.photos ? entries[i].image + ": " + skipped[i] : skipped[i]);
  }
}

// The logged trace with the model's gyro scale, bias and clock rate applied (rates in gyro axes;
// times moved so that gyro time = camera time + time_offset_s), so that camera.json with identity
// scale, zero bias and no clock rate declares the whole model.
GyroTrace CorrectedGyro(const GyroTrace& logged, const TrueModel& model) {
  std::vector<GyroSample> samples = logged.samples();
  const int64_t offset_ns = SecondsToNs(model.rig.time_offset_s);
  const double rate = 1.0 + model.clock_rate_ppm * 1e-6;
  for (GyroSample& s : samples) {
    s.omega_rad_s = model.gyro_scale.cwiseProduct(s.omega_rad_s - model.gyro_bias_rad_s);
    if (model.clock_rate_ppm != 0.0) {
      s.t_ns = offset_ns + static_cast<int64_t>(std::llround((s.t_ns - offset_ns) / rate));
    }
  }
  return GyroTrace(std::move(samples));
}

// camera.json, gyro.csv, frames.csv and the copied references of DIR.
void WriteDatasetFiles(const Context& c, const CorrectSummary& summary) {
  const fs::path out(c.options.out_dir);
  RigModel rig = c.model.model.rig;
  rig.shutter.readout_s = 0.0;
  // camera.json's mask as it was (each frame's masks/ image has it moved with the frame).
  rig.mask = c.dataset.mask.empty() ? "" : kCameraMaskName;
  if (!rig.mask.empty()) WriteImage((out / rig.mask).string(), c.dataset.mask);
  WriteRigModel((out / "camera.json").string(), rig);
  WriteGyroCsv((out / "gyro.csv").string(), CorrectedGyro(c.dataset.gyro, c.model.model));
  const bool keep_refs = !c.dataset.video && c.setting.reference == CorrectionReference::kFirstRow;
  std::vector<FrameEntry> frames;
  for (const CorrectedFrame& f : summary.frames) {
    FrameEntry e;
    e.frame = f.frame;
    e.t_first_row_ns = f.t_reference_ns;
    e.image = f.image;
    for (const FrameEntry& in : c.dataset.frames) {
      if (keep_refs && in.frame == f.frame) e.ref = in.ref;
    }
    if (!e.ref.empty()) {
      const fs::path ref = out / e.ref;
      CreateParent(ref);
      std::error_code ec;
      fs::copy_file(c.dataset.dir / e.ref, ref, fs::copy_options::overwrite_existing, ec);
      if (ec)
        throw IoError(IoMessage(ref.string(), 0, "cannot copy the reference: " + ec.message()));
    }
    frames.push_back(e);
  }
  WriteFramesCsv((out / "frames.csv").string(), frames);
}

// A hard link to target at link (a copy where links are refused), replacing what is there.
void LinkOrCopy(const fs::path& target, const fs::path& link) {
  std::error_code ec;
  fs::remove(link, ec);
  fs::create_hard_link(target, link, ec);
  if (!ec) return;
  fs::copy_file(target, link, fs::copy_options::overwrite_existing, ec);
  if (ec) throw IoError(IoMessage(link.string(), 0, "cannot link or copy: " + ec.message()));
}

// colmap/image_list.txt and odm/images/ (one folder: names flattened where folders would clash).
void WritePipelineLists(const CorrectSummary& summary) {
  const fs::path out(summary.out_dir);
  std::string list;  // under the image root (COLMAP's --image_path)
  for (const CorrectedFrame& f : summary.frames) list += f.source_image + "\n";
  CreateParent(out / "colmap" / "image_list.txt");
  WriteFileAtomically((out / "colmap" / "image_list.txt").string(), list);
  std::vector<std::string> names;
  for (const CorrectedFrame& f : summary.frames)
    names.push_back(fs::path(f.image).filename().string());
  std::vector<std::string> sorted = names;
  std::sort(sorted.begin(), sorted.end());
  const bool clash = std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
  const fs::path odm = out / "odm" / "images";
  std::error_code ec;
  fs::create_directories(odm, ec);
  if (ec) throw IoError(IoMessage(odm.string(), 0, "cannot create: " + ec.message()));
  for (size_t i = 0; i < summary.frames.size(); ++i) {
    std::string name = names[i];
    if (clash) {
      name = summary.frames[i].image;
      std::replace(name.begin(), name.end(), '/', '_');
    }
    const fs::path image = odm / name;
    LinkOrCopy(out / summary.frames[i].image, image);
    LinkOrCopy(MaskPath(summary.out_dir, summary.frames[i].source_image),
               odm / (image.stem().string() + "_mask.png"));
  }
}

// overview.png: a few frames, evenly spread, rolling shutter beside corrected; each frame's
// pictures from `drawn`, or from the files when the frame was not drawn while corrected (kept from
// an earlier run, or another frame's place taken by a skipped one).
void WriteOverview(const CorrectSummary& summary,
                   const std::map<int64_t, OverviewPictures>& drawn) {
  if (summary.frames.empty()) return;
  std::vector<cv::Mat> tiles;
  std::vector<std::string> captions;
  for (const size_t i : OverviewIndices(summary.frames.size())) {
    const CorrectedFrame& f = summary.frames[i];
    const auto it = drawn.find(f.frame);
    if (it != drawn.end()) {
      tiles.push_back(it->second.recorded);
      tiles.push_back(it->second.corrected);
    } else {  // pictures, not whole photos: eight 12 MP decodes and resizes took 1.2 s of a run
      tiles.push_back(ToRgb8(ReadImagePreview((fs::path(summary.dataset) / f.source_image).string(),
                                              kOverviewTileWidthPx)));
      tiles.push_back(ToRgb8(
          ReadImagePreview((fs::path(summary.out_dir) / f.image).string(), kOverviewTileWidthPx)));
    }
    captions.push_back("frame " + std::to_string(f.frame) + ": rolling shutter, D " +
                       FormatNumber("%.2f px", f.residual.d_before_px));
    captions.push_back("corrected (" +
                       std::string(CorrectionReferenceName(summary.setting.reference)) +
                       "), predicted D " + FormatNumber("%.2f px", f.predicted_d_after_px));
  }
  WriteImage((fs::path(summary.out_dir) / "overview.png").string(),
             TiledOverview(tiles, captions, kOverviewTileWidthPx, 2));
}

// The setting and its words: the ground plane for stills, rotation only for video unless a depth.
void ChooseSetting(const CorrectOptions& options, const RigDataset& dataset, const TrueModel& model,
                   CorrectSummary* summary) {
  summary->setting.reference = options.reference;
  const Eigen::Vector3d& v = model.rig.velocity_mps;
  // With a zero velocity nothing translates: said, so that the plane is not taken for a
  // translation corrected.
  const std::string velocity =
      v.isZero() ? std::string(", velocity zero (camera.json velocity_mps): rotation only")
                 : FormatNumber(", velocity (%g", v.x()) + FormatNumber(", %g", v.y()) +
                       FormatNumber(", %g) m/s", v.z());
  if (!dataset.video) {
    summary->setting.plane_depth_m = model.rig.altitude_m;
    summary->translation = FormatNumber("ground plane at %g m", model.rig.altitude_m) + velocity;
  } else if (options.depth_m) {
    summary->setting.plane_depth_m = *options.depth_m;
    summary->translation =
        FormatNumber("scene plane at %g m (--depth)", *options.depth_m) + velocity;
  } else {
    summary->translation = "rotation only (video: no depth known; give --depth for translation)";
  }
  if (options.reference == CorrectionReference::kMidReadout && !dataset.video && !options.photos) {
    summary->notes.push_back(
        "--reference mid: the references show row 0's instant, not the corrected frames': "
        "frames.csv leaves ref empty");
  }
}

// The field (CV_32FC2) at (x, y) inside it, bilinear (NaN where a tap is NaN).
cv::Vec2f BilinearAt(const cv::Mat& field, double x, double y) {
  const int x0 = std::min(static_cast<int>(x), field.cols - 2);
  const int y0 = std::min(static_cast<int>(y), field.rows - 2);
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const cv::Vec2f* top = field.ptr<cv::Vec2f>(y0) + x0;
  const cv::Vec2f* bottom = field.ptr<cv::Vec2f>(y0 + 1) + x0;
  return (1 - fy) * ((1 - fx) * top[0] + fx * top[1]) +
         fy * ((1 - fx) * bottom[0] + fx * bottom[1]);
}

}  // namespace

void CorrectOptions::Check() const {
  SHUTTERLAB_CHECK(!dataset_dir.empty()) << "the dataset folder is required";
  SHUTTERLAB_CHECK(!out_dir.empty()) << "--out is required";
  SHUTTERLAB_CHECK(!depth_m || (*depth_m > 0 && std::isfinite(*depth_m)))
      << "--depth must be positive (got " << *depth_m << " m)";
  SHUTTERLAB_CHECK(!gyro_noise_rad_s_sqrt_hz ||
                   (*gyro_noise_rad_s_sqrt_hz >= 0 && std::isfinite(*gyro_noise_rad_s_sqrt_hz)))
      << "--gyro-noise must be 0 or positive";
  SHUTTERLAB_CHECK(jobs >= 0 && jobs <= 256) << "--jobs must be 0 to 256 (got " << jobs << ")";
  SHUTTERLAB_CHECK(!check_truth || reference == CorrectionReference::kFirstRow)
      << "--truth compares with the renderer's references, which show row 0: use --reference row0";
  map.Check();
  prediction.Check();
}

TruthResidual MeasureAgainstTruth(const CorrectionMap& map, const cv::Mat& truth_field) {
  const PinholeCamera& camera = map.geometry().camera();
  SHUTTERLAB_CHECK(truth_field.type() == CV_32FC2 && truth_field.cols == camera.width &&
                   truth_field.rows == camera.height)
      << "the truth field must be the camera's size with two float channels";
  TruthResidual out;
  out.d_before_px = FrameDistortionPx(truth_field);
  cv::Mat residual(truth_field.size(), CV_32FC2, cv::Scalar::all(NAN));
  std::vector<float> xs(camera.width), ys(camera.width);
  double sum_sq = 0.0;
  for (int v = 0; v < camera.height; ++v) {
    map.SourceRow(v, 0, camera.width, xs.data(), ys.data());
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector2d q(xs[u], ys[u]);
      if (!map.geometry().HasSource(q)) continue;
      const cv::Vec2f dq = BilinearAt(truth_field, q.x(), q.y());
      if (!std::isfinite(dq[0]) || !std::isfinite(dq[1])) continue;
      const cv::Vec2f r(static_cast<float>(q.x() + dq[0] - u),
                        static_cast<float>(q.y() + dq[1] - v));
      residual.at<cv::Vec2f>(v, u) = r;
      const double r2 = double{r[0]} * r[0] + double{r[1]} * r[1];
      sum_sq += r2;
      out.max_px = std::max(out.max_px, std::sqrt(r2));
      ++out.pixels;
    }
  }
  out.rms_px = out.pixels > 0 ? std::sqrt(sum_sq / out.pixels) : 0.0;
  out.d_px = FrameDistortionPx(residual);
  return out;
}

namespace {

// Whether the report identified `effect` or --effect sets it: then it holds for every frame.
bool EffectSet(const CorrectionModel& model, const CorrectOptions& options, Effect effect) {
  const std::string prefix = Spec(effect).name + "=";
  return std::count(model.effects.begin(), model.effects.end(), effect) > 0 ||
         std::any_of(options.effects.begin(), options.effects.end(),
                     [&](const std::string& e) { return e.rfind(prefix, 0) == 0; });
}

// A folder of photos: its triggers are on the log's clock (the model's time offset is not
// applied), and the log's still segment gives the bias unless the report or --effect sets one.
void AdaptModelToPhotos(const PhotoInput& input, bool bias_given, CorrectionModel* model) {
  TrueModel& m = model->model;
  if (m.rig.time_offset_s != 0.0) {
    model->notes.push_back(
        FormatNumber("time_offset_s %g s not applied: the photos' triggers are "
                     "on the log's clock (give --latency)",
                     m.rig.time_offset_s));
    m.rig.time_offset_s = 0.0;
  }
  if (bias_given) return;
  if (input.still_bias_rad_s) {
    m.gyro_bias_rad_s = *input.still_bias_rad_s;
    const Eigen::Vector3d deg_s = kDegPerRad * m.gyro_bias_rad_s;
    model->notes.push_back(
        "gyro bias " + FormatNumber("%.4f", deg_s.x()) + ", " + FormatNumber("%.4f", deg_s.y()) +
        ", " + FormatNumber("%.4f", deg_s.z()) + " deg/s from " + input.still_bias_source);
  } else {
    model->notes.push_back("gyro bias 0: no still segment (" + input.still_bias_source + ")");
  }
}

// The photos' translation in words: each one's own velocity, or the model's for every one.
void DescribePhotoVelocities(const PhotoInput& input, bool velocity_given,
                             CorrectSummary* summary) {
  if (velocity_given) {
    summary->notes.push_back(
        "velocity: the one given (--effect or the report) for every photo, over each photo's own");
    return;
  }
  size_t own = 0;
  for (const auto& [frame, v] : input.velocity) own += v.velocity_mps ? 1 : 0;
  summary->translation = FormatNumber("ground plane at %g m", *summary->setting.plane_depth_m) +
                         ", each photo's own velocity (" + std::to_string(own) + " of " +
                         std::to_string(input.velocity.size()) +
                         " photos have one: recorded, the log's, or from the photos' positions)";
  if (own < input.velocity.size()) {
    summary->notes.push_back(std::to_string(input.velocity.size() - own) +
                             " photo(s) without a speed (recorded, logged or from positions) or "
                             "an attitude to turn it: " +
                             (summary->model.model.rig.velocity_mps.isZero()
                                  ? "rotation only (camera.json velocity_mps would serve them)"
                                  : "camera.json's velocity"));
  }
}

// A model less certain than the rolling shutter is large (a gimbal clip with little to correct, a
// fit from few frames) moves the image by more than it removes: said, so the originals are kept.
void NoteWhenPredictedWorse(CorrectSummary* summary) {
  std::vector<double> before, after;
  for (const CorrectedFrame& f : summary->frames) {
    before.push_back(f.residual.d_before_px);
    after.push_back(f.predicted_d_after_px);
  }
  const double median_before = UpperMedian(before), median_after = UpperMedian(after);
  if (!(median_after > median_before)) return;
  summary->notes.push_back(
      "the correction is predicted to leave more distortion than it removes: median D " +
      FormatNumber("%.3f", median_after) + " px after against " +
      FormatNumber("%.3f", median_before) +
      " px before (the model's uncertainty outweighs the rolling shutter here): keep the "
      "originals, or narrow the model first (more frames or pairs for validate)");
}

CorrectSummary CorrectInput(const CorrectOptions& options, const RigDataset& dataset,
                            const PhotoInput* photos, const CorrectProgress& progress) {
  SHUTTERLAB_CHECK(!options.check_truth || !dataset.video)
      << "--truth: a video dataset's truth is each frame's match in the one before, not a "
         "global-shutter reference";
  std::error_code ec;
  if (fs::weakly_canonical(options.out_dir, ec) == fs::weakly_canonical(options.dataset_dir, ec)) {
    throw IoError(
        IoMessage(options.out_dir, 0, "--out is the dataset itself: the input is never modified"));
  }
  CorrectSummary summary;
  summary.dataset = options.dataset_dir;
  summary.out_dir = options.out_dir;
  summary.report_path = options.report_path;
  summary.video = dataset.video;
  summary.photos = photos != nullptr;
  summary.warnings = dataset.gyro_warnings;
  if (photos) {
    summary.notes = photos->notes;
    summary.skipped = photos->skipped;
  }
  std::optional<ReportedModel> report;
  if (!options.report_path.empty()) report = ReadValidationReport(options.report_path);
  summary.model = BuildCorrectionModel(dataset.declared, report, options.report_path);
  for (const std::string& effect : options.effects) {
    const Injection set = ApplyInjection(effect, &summary.model.model);
    summary.model.notes.push_back("--effect " + Spec(set.effect).name + " = " +
                                  EffectValueText(set.value) + " (no uncertainty)");
  }
  if (photos) {
    AdaptModelToPhotos(*photos, EffectSet(summary.model, options, Effect::kGyroBias),
                       &summary.model);
  }
  if (options.gyro_noise_rad_s_sqrt_hz) {
    summary.model.gyro_noise_rad_s_sqrt_hz = *options.gyro_noise_rad_s_sqrt_hz;
    summary.model.gyro_noise_source = "--gyro-noise";
  } else {
    const GyroNoiseEstimate noise = EstimateGyroNoise(dataset.gyro);
    summary.model.gyro_noise_rad_s_sqrt_hz = noise.rad_s_sqrt_hz;
    summary.model.gyro_noise_source = "estimated from " + noise.source;
  }
  const TrueModel& model = summary.model.model;
  ChooseSetting(options, dataset, model, &summary);
  if (summary.setting.plane_depth_m) {
    summary.m_per_px =
        *summary.setting.plane_depth_m / (0.5 * (model.rig.camera.fx + model.rig.camera.fy));
  }
  const CameraMotion motion(dataset.gyro, model);
  const bool velocity_given = EffectSet(summary.model, options, Effect::kVelocity);
  if (photos) DescribePhotoVelocities(*photos, velocity_given, &summary);
  Context context{options,
                  dataset,
                  summary.model,
                  summary.setting,
                  motion,
                  photos && !velocity_given ? &photos->velocity : nullptr,
                  photos ? "images" : "",
                  summary.translation,
                  {},
                  photos != nullptr};
  summary.image_root = context.image_root;
  context.xmp = {{"Xmp.shutterlab.RollingShutterCorrected", "True"},
                 {"Xmp.shutterlab.Reference", CorrectionReferenceName(options.reference)}};
  fs::create_directories(options.out_dir, ec);
  if (ec) throw IoError(IoMessage(options.out_dir, 0, "cannot create: " + ec.message()));
  std::map<int64_t, OverviewPictures> pictures;
  RunFrames(context, progress, &summary, options.pictures ? &pictures : nullptr);
  if (summary.frames.empty()) {
    // Every frame was skipped here (its readout outside the log, or its image cut): say why.
    const size_t first_here = photos ? photos->skipped.size() : 0;
    throw IoError(IoMessage(
        dataset.frames_path, 0,
        first_here < summary.skipped.size()
            ? "no frame could be corrected (the first: " + summary.skipped[first_here].second + ")"
            : "no frames"));
  }
  NoteWhenPredictedWorse(&summary);
  WriteDatasetFiles(context, summary);
  WritePipelineLists(summary);
  if (options.pictures) WriteOverview(summary, pictures);
  WriteFileAtomically((fs::path(options.out_dir) / "correct.json").string(),
                      CorrectionToJson(summary).dump(2) + "\n");
  return summary;
}

}  // namespace

CorrectSummary CorrectDataset(const CorrectOptions& options, const CorrectProgress& progress) {
  options.Check();
  if (!options.photos)
    return CorrectInput(options, ReadRigDataset(options.dataset_dir), nullptr, progress);
  const PhotoInput input = ReadPhotoInput(options.dataset_dir, *options.photos);
  return CorrectInput(options, input.dataset, &input, progress);
}

}  // namespace shutterlab
