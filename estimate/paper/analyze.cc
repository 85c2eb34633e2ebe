#include "estimate/paper/analyze.h"

#include "model/truth_model.h"
#include "render/rs_warp.h"
#include "sim/bias.h"
#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/gyro_trace.h"
#include "sim/integrate.h"
#include "sim/interval_histogram.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/log_clock.h"
#include "sim/still_detect.h"
#include "sim/text_file.h"
#include "sim/trace_audit.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace shutterlab {
namespace {

// A sample's rate in camera axes less a bias (camera axes).
GyroSample InCameraAxes(const GyroSample& s, const Eigen::Matrix3d& cam_from_gyro,
                        const Eigen::Vector3d& bias_rad_s) {
  return {s.t_ns, cam_from_gyro * s.omega_rad_s - bias_rad_s};
}

GyroTrace RotateTrace(const GyroTrace& trace, const Eigen::Matrix3d& cam_from_gyro,
                      const Eigen::Vector3d& bias_rad_s) {
  std::vector<GyroSample> samples = trace.samples();
  for (GyroSample& s : samples) s = InCameraAxes(s, cam_from_gyro, bias_rad_s);
  return GyroTrace(std::move(samples));
}

// Per-axis angle at t_ns, linear between samples (the rectangle rule holds w_i over
// (t_{i-1}, t_i]). Requires t_ns within the trace.
double AngleAt(const PerAxisAngles& angles, int axis, int64_t t_ns) {
  const auto& t = angles.t_ns;
  const size_t k = static_cast<size_t>(std::lower_bound(t.begin(), t.end(), t_ns) - t.begin());
  const auto& a = angles.angle_rad[axis];
  if (k == 0) return a[0];
  if (k >= t.size()) return a.back();
  if (t[k] == t_ns) return a[k];
  const double w = static_cast<double>(t_ns - t[k - 1]) / static_cast<double>(t[k] - t[k - 1]);
  return a[k - 1] + (a[k] - a[k - 1]) * w;
}

// docs/FORMATS.md frame distortion D on the coarse grid (kGridStepPx), pixels: per grid column, the
// largest distance between two rows' displacements RefPixel - p.
double GridDistortionPx(const FrameGeometry& geometry) {
  const PinholeCamera& cam = geometry.camera();
  std::vector<int> rows, cols;
  for (int v = 0; v < cam.height; v += kGridStepPx) rows.push_back(v);
  if (rows.back() != cam.height - 1) rows.push_back(cam.height - 1);
  for (int u = 0; u < cam.width; u += kGridStepPx) cols.push_back(u);
  if (cols.back() != cam.width - 1) cols.push_back(cam.width - 1);
  double d_px = 0.0;
  std::vector<Eigen::Vector2d> displacement;
  for (int u : cols) {
    displacement.clear();
    for (int v : rows) {
      const std::optional<Eigen::Vector2d> ref = geometry.RefPixel(u, v);
      if (ref) displacement.push_back(*ref - Eigen::Vector2d(u, v));
    }
    for (size_t a = 0; a < displacement.size(); ++a) {
      for (size_t b = a + 1; b < displacement.size(); ++b) {
        d_px = std::max(d_px, (displacement[a] - displacement[b]).norm());
      }
    }
  }
  return d_px;
}

struct ImageContext {
  const PerAxisAngles* angles;
  const CameraMotion* motion;  // null: skip D_full
  RigModel rig;
  std::vector<double> limits_m;
  int64_t sample_interval_ns = 0;  // the log's median: a readout must be longer than two
};

// The first and last sample times of a trace.
struct TraceSpan {
  int64_t first_ns = 0, last_ns = 0;
};

// AnalyzePlots built as the samples and the images come, in the same order from the whole trace as
// from a stream, so that both give the same plots.
class PlotBuilder {
 public:
  PlotBuilder(const AnalyzePlotOptions& options, size_t samples, const TraceSpan& span)
      : worst_images_(options.worst_images),
        envelope_(6, options.chart_buckets, samples, span.first_ns * 1e-9, span.last_ns * 1e-9) {}

  // The next sample: its rate in camera axes less the bias, and its per-axis angles.
  void AddSample(int64_t t_ns, const Eigen::Vector3d& rate_rad_s, const double* angle_rad) {
    const double y[6] = {rate_rad_s[0] * kDegPerRad, rate_rad_s[1] * kDegPerRad,
                         rate_rad_s[2] * kDegPerRad, angle_rad[0] * kDegPerRad,
                         angle_rad[1] * kDegPerRad,  angle_rad[2] * kDegPerRad};
    envelope_.Add(t_ns * 1e-9, y);
  }

  // A judged image (its index in the result's images): its frame, asked of frame() only when it
  // ranks among the worst so far.
  void OfferImage(size_t image, double d_full_m, const std::function<FrameMotion()>& frame) {
    const auto worse = [](const Ranked& a, const Ranked& b) {
      return a.d_full_m > b.d_full_m || (a.d_full_m == b.d_full_m && a.worst.image < b.worst.image);
    };
    Ranked candidate{d_full_m, {image, {}}};
    if (worst_.size() == worst_images_ && (worst_.empty() || !worse(candidate, worst_.back())))
      return;
    candidate.worst.frame = frame();
    worst_.insert(std::upper_bound(worst_.begin(), worst_.end(), candidate, worse),
                  std::move(candidate));
    if (worst_.size() > worst_images_) worst_.pop_back();
  }

  std::shared_ptr<const AnalyzePlots> Finish() {
    envelope_.Finish();
    auto plots = std::make_shared<AnalyzePlots>();
    plots->t_s = envelope_.x();
    for (int a = 0; a < 3; ++a) {
      plots->rate_deg_s[a] = envelope_.y()[a];
      plots->angle_deg[a] = envelope_.y()[3 + a];
    }
    for (Ranked& ranked : worst_) plots->worst.push_back(std::move(ranked.worst));
    return plots;
  }

 private:
  struct Ranked {
    double d_full_m = 0.0;
    AnalyzePlots::WorstImage worst;
  };
  size_t worst_images_;
  MinMaxEnvelope envelope_;
  std::vector<Ranked> worst_;  // worst first
};

// The image's exposure and whether the trace can judge it (in_trace, too_few_samples), from the
// trace's ends and sampling alone: nothing of it is measured yet.
ImageResult ImageTiming(const ImageContext& context, const ImageTrigger& trigger,
                        int64_t latency_ns, const TraceSpan& span) {
  ImageResult image;
  image.name = trigger.name;
  image.trigger_t_ns = trigger.t_ns;
  image.t_ns = trigger.t_ns + latency_ns;
  image.flagged.assign(context.limits_m.size(), false);
  const int64_t readout_ns = SecondsToNs(context.rig.shutter.readout_s);
  if (image.t_ns < span.first_ns || image.t_ns + readout_ns > span.last_ns) return image;
  image.in_trace = true;
  image.too_few_samples = readout_ns <= kMinWindowSampleIntervals * context.sample_interval_ns;
  return image;
}

// The ranges, D and flags of a judged image, from context's angles (and motion) covering its
// readout: the whole trace, or a stretch of it that holds the samples either side of the readout.
void MeasureImage(const ImageContext& context, ImageResult* image) {
  const PerAxisAngles& angles = *context.angles;
  const int64_t end_ns = image->t_ns + SecondsToNs(context.rig.shutter.readout_s);
  const auto first = std::upper_bound(angles.t_ns.begin(), angles.t_ns.end(), image->t_ns);
  const auto last = std::lower_bound(angles.t_ns.begin(), angles.t_ns.end(), end_ns);
  const size_t i0 = static_cast<size_t>(first - angles.t_ns.begin());
  const size_t i1 = static_cast<size_t>(last - angles.t_ns.begin());
  double max_range_rad = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double a_begin = AngleAt(angles, axis, image->t_ns);
    const double a_end = AngleAt(angles, axis, end_ns);
    double lo = std::min(a_begin, a_end), hi = std::max(a_begin, a_end);
    for (size_t i = i0; i < i1; ++i) {
      lo = std::min(lo, angles.angle_rad[axis][i]);
      hi = std::max(hi, angles.angle_rad[axis][i]);
    }
    image->range_arcsec[axis] = (hi - lo) * kArcsecPerRad;
    if (hi - lo > max_range_rad) {
      max_range_rad = hi - lo;
      image->dominant_axis = axis;
    }
  }
  image->d_paper_m = context.rig.altitude_m * std::tan(max_range_rad);
  for (size_t l = 0; l < context.limits_m.size(); ++l) {
    image->flagged[l] = image->d_paper_m > context.limits_m[l];
  }
  if (context.motion != nullptr) {
    const FrameGeometry geometry(context.rig.camera, context.rig.altitude_m,
                                 context.motion->Frame(image->t_ns),
                                 cv::Size(context.rig.camera.width, context.rig.camera.height));
    image->d_full_px = GridDistortionPx(geometry);
    const double f_px = 0.5 * (context.rig.camera.fx + context.rig.camera.fy);
    image->d_full_m = image->d_full_px * context.rig.altitude_m / f_px;
  }
}

// One image on the whole trace (context.angles holds every sample, at least two).
ImageResult AnalyzeImage(const ImageContext& context, const ImageTrigger& trigger,
                         int64_t latency_ns) {
  const PerAxisAngles& angles = *context.angles;
  ImageResult image =
      ImageTiming(context, trigger, latency_ns, {angles.t_ns.front(), angles.t_ns.back()});
  if (image.judged()) MeasureImage(context, &image);
  return image;
}

std::vector<double> SharesPercent(const std::vector<ImageResult>& images, size_t limits) {
  std::vector<double> shares(limits, 0.0);
  size_t in_trace = 0;
  for (const ImageResult& image : images) {
    if (!image.judged()) continue;
    ++in_trace;
    for (size_t l = 0; l < limits; ++l) shares[l] += image.flagged[l] ? 1.0 : 0.0;
  }
  for (double& s : shares) s = in_trace > 0 ? 100.0 * s / in_trace : 0.0;
  return shares;
}

std::string SharesText(const std::vector<double>& shares, const std::vector<double>& limits_m) {
  std::string text;
  for (size_t l = 0; l < shares.size(); ++l) {
    if (l > 0) text += ", ";
    text += FormatNumber("%.1f%%", shares[l]) + " over " + LengthText(limits_m[l]);
  }
  return text;
}

std::string ImageName(size_t index) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "IMG_%04zu", index + 1);
  return buffer;
}

// Reports a fraction done (0..1) when the options ask for progress.
void ReportProgress(const AnalyzeOptions& options, double fraction) {
  if (options.progress) options.progress(fraction);
}

// The log's size, rate and gaps and the camera the analysis uses.
// log: its metadata (its gyro may be empty: a streamed log); sampling: its samples'.
void DescribeSource(const FlightLog& log, const TraceSampling& sampling,
                    const AnalyzeOptions& options, const std::string& altitude_source,
                    AnalyzeResult* result) {
  result->format = log.format;
  result->gyro_source = log.gyro_source;
  result->samples = sampling.samples;
  result->duration_s = (sampling.t_end_ns - sampling.t_begin_ns) * 1e-9;
  result->rate_hz = sampling.RateHz();
  result->gaps = sampling.gaps;
  result->log_warnings = log.warnings;
  result->altitude_method = log.altitude_source;
  result->limits_m = options.limits_m;
  result->altitude_m = options.rig.altitude_m;
  result->altitude_source = altitude_source;
  result->readout_s = options.rig.shutter.readout_s;
}

// The bias (camera axes) from the log's still stretch when asked; zero, and said so in the output,
// when there is none.
void EstimateStillBias(const GyroTrace& camera_rates, bool estimate_bias,
                       const std::optional<BiasSegment>& given, AnalyzeResult* result) {
  result->bias_estimated = estimate_bias;
  if (!estimate_bias) return;
  if (given) {  // the caller's segment: too few samples in it is an error, not a zero bias
    result->still_segment = *given;
    result->bias_rad_s = EstimateBias(camera_rates, *given).bias_rad_s;
    result->bias_from_still = result->bias_segment_given = true;
    return;
  }
  try {
    const StillSegment still = DetectStillSegment(camera_rates);
    result->still_segment = still.segment;
    result->bias_rad_s = EstimateBias(camera_rates, still.segment).bias_rad_s;
    result->bias_from_still = true;
  } catch (const std::invalid_argument&) {
    result->bias_from_still = false;  // no still stretch: zero bias, said so in the output
  }
}

// What the Allan deviation needs to know of its segment before it reads it (AllanStream): the
// segment's samples, their intervals, and the sum of their rates after the first, in camera axes
// as logged (the bias is not known yet when a stream reads them).
struct AllanSegment {
  size_t samples = 0;
  IntervalHistogram intervals;
  Eigen::Vector3d rate_sum_rad_s = Eigen::Vector3d::Zero();
  int64_t previous_t_ns = 0;

  void Add(const GyroSample& camera_as_logged) {
    if (samples > 0) {
      intervals.Add(camera_as_logged.t_ns - previous_t_ns);
      rate_sum_rad_s += camera_as_logged.omega_rad_s;
    }
    previous_t_ns = camera_as_logged.t_ns;
    ++samples;
  }
  // The stream to give the segment's rates less the bias: AllanAnalysis removes their mean.
  AllanStream Open(const Eigen::Vector3d& bias_rad_s) const {
    const Eigen::Vector3d mean =
        samples > 1
            ? Eigen::Vector3d(rate_sum_rad_s / static_cast<double>(samples - 1) - bias_rad_s)
            : Eigen::Vector3d::Zero();
    return AllanStream(samples, intervals.Median(), mean);
  }
};

// Whether the Allan deviation is taken on the still segment (one was found, with 20 samples or
// more in it), else on the whole log (AnalyzeResult::allan_on_still).
bool AllanOnStill(const AnalyzeResult& result, const AllanSegment& still) {
  return result.bias_from_still && still.samples >= 20;
}

// The flight table's options for this camera's readout, with the bias found (result->bias_rad_s).
FlightOptions FlightOptionsForReadout(const AnalyzeOptions& options, const AnalyzeResult& result) {
  FlightOptions flight_options;
  flight_options.altitude_m = options.rig.altitude_m;
  flight_options.limits_m = options.limits_m;
  flight_options.windows_s = {options.rig.shutter.readout_s};
  flight_options.noise_allowance_arcsec = options.noise_allowance_arcsec;
  if (options.plots) {
    flight_options.summary = true;
    flight_options.summary_max_intervals = options.plots->chart_buckets;
  }
  // The still segment may lie anywhere (often after landing), so its bias is applied to every
  // sample rather than starting the statistics after the segment as `flight --bias` does.
  flight_options.known_bias_rad_s = result.bias_rad_s;
  return flight_options;
}

// The flight table for this camera's readout (result->flight), or why there is none
// (result->flight_problem): finish() gives the table or throws std::invalid_argument.
void KeepFlightTable(const std::function<FlightResult()>& finish, AnalyzeResult* result) {
  try {
    result->flight = finish();
    result->log_warnings.insert(result->log_warnings.end(), result->flight->warnings.begin(),
                                result->flight->warnings.end());
  } catch (const std::invalid_argument& e) {
    result->flight_problem = e.what();
  }
}

// The images to analyse: the options' triggers, else one every options.every_s over the log, else
// the log's camera events; *trigger_source says which.
std::vector<ImageTrigger> ChooseTriggers(const FlightLog& log, const TraceSpan& span,
                                         const AnalyzeOptions& options,
                                         std::string* trigger_source) {
  std::vector<ImageTrigger> triggers = options.triggers;
  *trigger_source = options.triggers_source;
  if (triggers.empty() && options.every_s > 0) {
    *trigger_source = FormatNumber("every %g s", options.every_s);
    const int64_t every_ns = SecondsToNs(options.every_s);
    const int64_t t0_ns = span.first_ns;
    const int64_t span_ns = span.last_ns - t0_ns;
    const int64_t count = span_ns / every_ns;
    for (int64_t k = 0; k < count; ++k) {
      triggers.push_back({ImageName(static_cast<size_t>(k)), t0_ns + k * every_ns});
    }
  } else if (triggers.empty() && options.log_events && !log.camera_events.empty()) {
    // The readers keep one kind already; a log built elsewhere gets the same choice.
    FlightLog events_only;
    events_only.camera_events = log.camera_events;
    KeepOneCameraEventKind(&events_only);
    const std::vector<CameraEvent>& events = events_only.camera_events;
    *trigger_source = "camera events (" + events.front().kind + ")";
    for (size_t i = 0; i < events.size(); ++i) {
      const CameraEvent& event = events[i];
      triggers.push_back(
          {event.sequence >= 0 ? "IMG_" + std::to_string(event.sequence) : ImageName(i),
           event.t_ns});
    }
  } else if (triggers.empty()) {
    *trigger_source = "none";
  }
  if (!options.triggers.empty() || options.every_s > 0) {
    if (!log.camera_events.empty()) {
      *trigger_source +=
          " (the log's " + std::to_string(log.camera_events.size()) + " camera events not used)";
    }
  }
  return triggers;
}

// The most frequent dominant axis of the images flagged at the strictest (first) limit; with none
// flagged there, the most frequent dominant axis overall is still the best advice. -1 with no
// image in the trace.
int AxisToStabilise(const std::vector<ImageResult>& images, size_t images_in_trace) {
  int axis_to_stabilise = -1;
  std::array<size_t, 3> dominant{};
  for (const ImageResult& image : images) {
    if (image.judged() && image.flagged[0]) ++dominant[image.dominant_axis];
  }
  for (int axis = 0; axis < 3; ++axis) {
    if (dominant[axis] > 0 &&
        (axis_to_stabilise < 0 || dominant[axis] > dominant[axis_to_stabilise])) {
      axis_to_stabilise = axis;
    }
  }
  if (axis_to_stabilise < 0) {
    std::array<size_t, 3> all{};
    for (const ImageResult& image : images) {
      if (image.judged()) ++all[image.dominant_axis];
    }
    if (images_in_trace > 0) {
      axis_to_stabilise = static_cast<int>(std::max_element(all.begin(), all.end()) - all.begin());
    }
  }
  return axis_to_stabilise;
}

// The what-if cameras, whose shares are recomputed (not scaled) with a fast readout and at half
// the altitude (without D_full).
ImageContext FastReadoutContext(const ImageContext& context, double fast_readout_s) {
  ImageContext fast = context;
  fast.motion = nullptr;
  fast.rig.shutter.readout_s = fast_readout_s;
  return fast;
}
ImageContext HalfAltitudeContext(const ImageContext& context) {
  ImageContext low = context;
  low.motion = nullptr;
  low.rig.altitude_m = 0.5 * context.rig.altitude_m;
  return low;
}

// The what-if shares from the images under the what-if cameras.
void WhatIfShares(const std::vector<ImageResult>& fast_images,
                  const std::vector<ImageResult>& low_images, size_t limits,
                  AnalyzeVerdict* verdict) {
  // A fast readout may hold too few samples to judge any image: then no share, not 0 %.
  const bool fast_judged = std::any_of(fast_images.begin(), fast_images.end(),
                                       [](const ImageResult& image) { return image.judged(); });
  verdict->share_fast_readout_percent.clear();
  if (fast_judged) verdict->share_fast_readout_percent = SharesPercent(fast_images, limits);
  verdict->share_half_altitude_percent = SharesPercent(low_images, limits);
}

// The images judged under the context's camera, on the whole trace.
std::vector<ImageResult> AnalyzeImages(const ImageContext& context,
                                       const std::vector<ImageTrigger>& triggers,
                                       int64_t latency_ns) {
  std::vector<ImageResult> images;
  images.reserve(triggers.size());
  for (const ImageTrigger& trigger : triggers)
    images.push_back(AnalyzeImage(context, trigger, latency_ns));
  return images;
}

// What was taken as a default: the caller's (AnalyzeOptions::assumptions), the altitude when the
// log had none to give, a zero bias when no still stretch was found to measure it on.
void NoteAssumptions(const AnalyzeOptions& options, AnalyzeResult* result) {
  result->assumptions = options.assumptions;
  if (options.use_log_altitude && options.altitude_is_default && result->altitude_source != "log") {
    result->assumptions.push_back({"altitude", FormatNumber("%g m", result->altitude_m),
                                   "the log has no height above ground", "--altitude"});
  }
  if (result->bias_estimated && !result->bias_from_still) {
    result->assumptions.push_back(
        {"bias", "zero", "the log has no still stretch to measure it on",
         "a log that starts with the camera still for a few seconds, or --zero-bias for rates "
         "calibrated at arming"});
  }
}

// The verdict on result->images (with the what-if shares from the images under the what-if
// cameras, when asked for and an image is judged: what_if() gives {fast, low}).
using WhatIfImages = std::pair<std::vector<ImageResult>, std::vector<ImageResult>>;
void JudgeImages(const AnalyzeOptions& options, const std::function<WhatIfImages()>& what_if,
                 AnalyzeResult* result) {
  AnalyzeVerdict& verdict = result->verdict;
  for (const ImageResult& image : result->images) {
    verdict.images_in_trace += image.judged();
    verdict.images_too_few_samples += image.in_trace && image.too_few_samples;
  }
  verdict.share_percent = SharesPercent(result->images, options.limits_m.size());
  verdict.axis_to_stabilise = AxisToStabilise(result->images, verdict.images_in_trace);
  if (options.what_if && verdict.images_in_trace > 0) {
    const WhatIfImages images = what_if();
    WhatIfShares(images.first, images.second, options.limits_m.size(), &verdict);
  }
}

// The one-line verdict for a person.
std::string VerdictLine(const AnalyzeVerdict& verdict, bool no_images, double rate_hz,
                        const AnalyzeOptions& options) {
  if (verdict.images_in_trace == 0) {
    if (verdict.images_too_few_samples > 0) {
      return "verdict: no image can be judged: at " + FormatNumber("%.4g", rate_hz) + " Hz the " +
             FormatNumber("%g", options.rig.shutter.readout_s * 1e3) +
             " ms readout holds at most two samples; it must be longer than " +
             FormatNumber("%.4g", kMinWindowSampleIntervals * 1e3 / rate_hz) +
             " ms (2 sample intervals), or the log sampled faster";
    }
    return no_images ? "verdict: no images to judge (the log has no camera events; give "
                       "--triggers or --every)"
                     : "verdict: no image lies inside the gyro trace";
  }
  std::ostringstream line;
  line << "verdict: " << verdict.images_in_trace
       << (verdict.images_in_trace == 1 ? " image, " : " images, ")
       << SharesText(verdict.share_percent, options.limits_m);
  if (verdict.images_too_few_samples > 0) {
    line << " (" << verdict.images_too_few_samples
         << " more not judged: too few samples in their readout)";
  }
  const bool any_flagged = std::any_of(verdict.share_percent.begin(), verdict.share_percent.end(),
                                       [](double s) { return s > 0; });
  line << (any_flagged ? "; stabilise camera axis " : "; largest rotation about camera axis ")
       << kAxisNames[verdict.axis_to_stabilise];
  if (options.what_if) {
    line << "; with a " << FormatNumber("%g", verdict.fast_readout_s * 1e3) << " ms readout: "
         << (verdict.share_fast_readout_percent.empty()
                 ? "too few samples at " + FormatNumber("%.4g", rate_hz) + " Hz to judge"
                 : SharesText(verdict.share_fast_readout_percent, options.limits_m))
         << "; at " << FormatNumber("%g", 0.5 * options.rig.altitude_m)
         << " m altitude: " << SharesText(verdict.share_half_altitude_percent, options.limits_m);
  }
  return line.str();
}

}  // namespace

TrueModel AnalyzeTrueModel(const RigModel& rig, const Eigen::Vector3d& bias_cam_rad_s) {
  TrueModel model;
  model.rig = rig;
  model.rig.time_offset_s = 0.0;
  model.gyro_bias_rad_s = rig.cam_from_gyro.transpose() * bias_cam_rad_s;
  return model;
}

void AnalyzePlotOptions::Check() const {
  SHUTTERLAB_CHECK(chart_buckets >= 10) << "chart_buckets must be >= 10";
}

void AnalyzeOptions::Check() const {
  rig.Check();
  if (plots) plots->Check();
  SHUTTERLAB_CHECK(!bias_segment ||
                   (bias_segment->begin_s >= 0.0 && bias_segment->end_s > bias_segment->begin_s))
      << "bias segment " << bias_segment->begin_s << ":" << bias_segment->end_s
      << " must satisfy 0 <= A < B";
  SHUTTERLAB_CHECK(rig.shutter.readout_s > 0 && rig.shutter.readout_s < 10.0)
      << "readout must be in (0, 10) s (got " << rig.shutter.readout_s << " s)";
  SHUTTERLAB_CHECK(std::isfinite(rig.altitude_m) && rig.altitude_m > 0)
      << "altitude must be positive (got " << rig.altitude_m << " m)";
  SHUTTERLAB_CHECK(!limits_m.empty()) << "give at least one ground limit";
  for (double limit : limits_m) {
    SHUTTERLAB_CHECK(std::isfinite(limit) && limit > 0)
        << "ground limit must be positive (got " << limit << " m)";
  }
  SHUTTERLAB_CHECK(std::isfinite(noise_allowance_arcsec) && noise_allowance_arcsec >= 0)
      << "noise allowance must be >= 0 (got " << noise_allowance_arcsec << " arcsec)";
  SHUTTERLAB_CHECK(std::isfinite(every_s) && every_s >= 0 && every_s < 1e6)
      << "trigger interval must be >= 0 (got " << every_s << " s)";
  SHUTTERLAB_CHECK(every_s == 0 || SecondsToNs(every_s) > 0)
      << "trigger interval " << every_s << " s is below 1 ns";
  SHUTTERLAB_CHECK(std::isfinite(trigger_latency_s) && std::abs(trigger_latency_s) < 1e3)
      << "trigger latency must be finite and below 1000 s (got " << trigger_latency_s << " s)";
}

namespace {

// The options with the log's altitude above ground when they ask for it and the log has one;
// *altitude_source says which was used.
AnalyzeOptions WithLogAltitude(const FlightLog& log, const AnalyzeOptions& given_options,
                               std::string* altitude_source) {
  given_options.Check();
  AnalyzeOptions options = given_options;
  *altitude_source = "camera";
  if (options.use_log_altitude && log.altitude_above_ground_m && *log.altitude_above_ground_m > 0) {
    options.rig.altitude_m = *log.altitude_above_ground_m;
    *altitude_source = "log";
  }
  return options;
}

// The Allan deviation of the camera-axis rates (result->traces) as AnalyzeStream computes it.
void AllanOfWholeTrace(const GyroTrace& gyro, const Eigen::Matrix3d& cam_from_gyro,
                       AnalyzeResult* result) {
  const GyroTrace& rates = result->traces->camera_rates;
  AllanSegment whole, still;
  const auto [begin, end] =
      result->bias_from_still ? SamplesInSegment(rates, result->still_segment) : SampleRange{0, 0};
  for (size_t k = 0; k < gyro.size(); ++k) {
    const GyroSample as_logged = InCameraAxes(gyro[k], cam_from_gyro, Eigen::Vector3d::Zero());
    whole.Add(as_logged);
    if (k >= begin && k < end) still.Add(as_logged);
  }
  result->allan_on_still = AllanOnStill(*result, still);
  AllanStream allan = (result->allan_on_still ? still : whole).Open(result->bias_rad_s);
  const size_t first = result->allan_on_still ? begin : 0;
  const size_t last = result->allan_on_still ? end : rates.size();
  for (size_t k = first; k < last; ++k) allan.Add(rates[k]);
  result->allan = allan.Finish();
}

// The plots of the traces held whole.
std::shared_ptr<const AnalyzePlots> WholeTracePlots(const AnalyzePlotOptions& options,
                                                    const AnalyzeTraces& traces,
                                                    const std::vector<ImageResult>& images) {
  const auto& samples = traces.camera_rates.samples();
  PlotBuilder plots(options, samples.size(), {samples.front().t_ns, samples.back().t_ns});
  for (size_t k = 0; k < samples.size(); ++k) {
    const double angle_rad[3] = {traces.angles.angle_rad[0][k], traces.angles.angle_rad[1][k],
                                 traces.angles.angle_rad[2][k]};
    plots.AddSample(samples[k].t_ns, samples[k].omega_rad_s, angle_rad);
  }
  for (size_t i = 0; i < images.size(); ++i) {
    if (!images[i].judged()) continue;
    plots.OfferImage(i, images[i].d_full_m, [&] { return traces.motion.Frame(images[i].t_ns); });
  }
  return plots.Finish();
}

}  // namespace

AnalyzeResult Analyze(const FlightLog& log, const AnalyzeOptions& given_options) {
  std::string altitude_source;
  const AnalyzeOptions options = WithLogAltitude(log, given_options, &altitude_source);
  const GyroTrace& gyro = log.gyro;
  SHUTTERLAB_CHECK(gyro.samples().size() >= 2) << "the log's gyro trace has fewer than 2 samples";

  AnalyzeResult result;
  const TraceSpan span{gyro.t_begin_ns(), gyro.samples().back().t_ns};
  DescribeSource(log, TraceSampling::Of(gyro), options, altitude_source, &result);
  {
    // The bias is not known yet: the still search and the flight table take the rates as logged.
    const GyroTrace camera_rates =
        RotateTrace(gyro, options.rig.cam_from_gyro, Eigen::Vector3d::Zero());
    EstimateStillBias(camera_rates, options.estimate_bias, options.bias_segment, &result);
    FlightOptions flight_options = FlightOptionsForReadout(options, result);
    flight_options.progress = [&options](double f) { ReportProgress(options, 0.7 * f); };
    KeepFlightTable([&] { return Flight(camera_rates, flight_options); }, &result);
  }

  // Per-image distortion, from the traces the result keeps for the report. The angles are the
  // same numbers as IntegratePerAxis(rates as logged, bias): each step is (w - b) * dt either way.
  GyroTrace rates = RotateTrace(gyro, options.rig.cam_from_gyro, result.bias_rad_s);
  PerAxisAngles angles = IntegratePerAxis(rates, Eigen::Vector3d::Zero());
  result.traces = std::make_shared<const AnalyzeTraces>(
      AnalyzeTraces{std::move(rates), std::move(angles),
                    CameraMotion(gyro, AnalyzeTrueModel(options.rig, result.bias_rad_s))});
  if (options.allan) AllanOfWholeTrace(gyro, options.rig.cam_from_gyro, &result);
  const std::vector<ImageTrigger> triggers =
      ChooseTriggers(log, span, options, &result.trigger_source);
  const ImageContext context{&result.traces->angles, &result.traces->motion, options.rig,
                             options.limits_m, gyro.sampling().median_interval_ns};
  const int64_t latency_ns = SecondsToNs(options.trigger_latency_s);
  result.images.reserve(triggers.size());
  for (size_t i = 0; i < triggers.size(); ++i) {
    result.images.push_back(AnalyzeImage(context, triggers[i], latency_ns));
    ReportProgress(options, 0.7 + 0.25 * (i + 1) / triggers.size());
  }
  if (options.plots) result.plots = WholeTracePlots(*options.plots, *result.traces, result.images);
  // The verdict, with the what-if shares recomputed (not scaled) under the changed camera.
  NoteAssumptions(options, &result);
  JudgeImages(
      options,
      [&] {
        return WhatIfImages{
            AnalyzeImages(FastReadoutContext(context, result.verdict.fast_readout_s), triggers,
                          latency_ns),
            AnalyzeImages(HalfAltitudeContext(context), triggers, latency_ns)};
      },
      &result);
  result.verdict.line = VerdictLine(result.verdict, result.images.empty(), result.rate_hz, options);
  ReportProgress(options, 1.0);
  return result;
}

namespace {

// A source whose rates are turned into camera axes (InCameraAxes, no bias): the still search sees
// what Analyze's search sees on the whole trace. report gets the share read after each chunk.
class CameraAxesSource : public GyroSource {
 public:
  CameraAxesSource(std::unique_ptr<GyroSource> source, const Eigen::Matrix3d& cam_from_gyro,
                   std::function<void(double)> report)
      : source_(std::move(source)), cam_from_gyro_(cam_from_gyro), report_(std::move(report)) {}
  GyroChunk Next() override {
    const GyroChunk chunk = source_->Next();
    rotated_.resize(chunk.size);
    for (size_t i = 0; i < chunk.size; ++i)
      rotated_[i] = InCameraAxes(chunk.data[i], cam_from_gyro_, Eigen::Vector3d::Zero());
    report_(source_->Fraction());
    return {rotated_.data(), rotated_.size()};
  }
  double Fraction() const override { return source_->Fraction(); }
  std::vector<LogWarning> Warnings() const override { return source_->Warnings(); }

 private:
  std::unique_ptr<GyroSource> source_;
  Eigen::Matrix3d cam_from_gyro_;
  std::function<void(double)> report_;
  std::vector<GyroSample> rotated_;
};

// One readout to measure: image `image` under the camera of context `variant`, [begin, end].
struct ReadoutJob {
  size_t image = 0;
  size_t variant = 0;
  int64_t begin_ns = 0, end_ns = 0;
  bool done = false;
};

// The images' readouts measured as the trace streams past. The rates in camera axes less the bias,
// their per-axis angles and the camera's orientation are integrated from the first sample exactly
// as Analyze integrates them over the whole trace (IntegratePerAxis, CameraMotion), and kept only
// from the sample before the earliest readout still open: memory O(chunk + longest readout).
class StreamedReadouts {
 public:
  // contexts: one per camera variant (their angles and motion are set here; the first, the camera
  // analysed, gets D_full, the what-if ones none); images[v]: the images under variant v, timed
  // (ImageTiming); every judged one is measured.
  // plots, when not null, is given every sample and every judged image of the camera analysed.
  StreamedReadouts(std::vector<ImageContext> contexts, std::vector<std::vector<ImageResult>> images,
                   const TrueModel& model, const Eigen::Vector3d& bias_rad_s, PlotBuilder* plots)
      : contexts_(std::move(contexts)),
        images_(std::move(images)),
        model_(model),
        bias_rad_s_(bias_rad_s),
        plots_(plots) {
    for (size_t v = 0; v < images_.size(); ++v) {
      const int64_t readout_ns = SecondsToNs(contexts_[v].rig.shutter.readout_s);
      for (size_t i = 0; i < images_[v].size(); ++i) {
        const ImageResult& image = images_[v][i];
        if (image.judged()) jobs_.push_back({i, v, image.t_ns, image.t_ns + readout_ns});
      }
    }
    std::stable_sort(jobs_.begin(), jobs_.end(), [](const ReadoutJob& a, const ReadoutJob& b) {
      return a.begin_ns < b.begin_ns;
    });
  }

  void Add(const GyroChunk& chunk) {
    if (chunk.empty()) return;
    for (const GyroSample& s : chunk) Integrate(s);
    // A readout is measured once a sample past its end is kept: the lookups then see the samples
    // either side of it, as on the whole trace.
    const int64_t last_ns = kept_.back().t_ns;
    for (size_t j = first_open_; j < jobs_.size() && jobs_[j].begin_ns <= last_ns; ++j) {
      if (!jobs_[j].done && jobs_[j].end_ns < last_ns) Measure(&jobs_[j]);
    }
    while (first_open_ < jobs_.size() && jobs_[first_open_].done) ++first_open_;
    Trim();
  }

  // After the last chunk: the readouts that end at the trace's last sample.
  std::vector<std::vector<ImageResult>> Finish() {
    for (size_t j = first_open_; j < jobs_.size(); ++j) {
      if (!jobs_[j].done) Measure(&jobs_[j]);
    }
    return std::move(images_);
  }

 private:
  struct Kept {
    int64_t t_ns = 0;
    double angle_rad[3] = {0.0, 0.0, 0.0};
    Eigen::Vector3d cam_rate_rad_s;     // the full model's camera rate (TrueModel::CamRate)
    Eigen::Quaterniond world_from_cam;  // its orientation
  };

  // The next sample: IntegratePerAxis's step (the bias already removed, as Analyze's rates) and
  // OrientationTrace's.
  void Integrate(const GyroSample& logged) {
    const GyroSample rate = InCameraAxes(logged, model_.rig.cam_from_gyro, bias_rad_s_);
    Kept next;
    next.t_ns = logged.t_ns;
    next.cam_rate_rad_s = model_.CamRate(logged.omega_rad_s);
    if (kept_.empty()) {
      next.world_from_cam = Eigen::Quaterniond::Identity().normalized();
    } else {
      const Kept& before = kept_.back();
      const double dt_s = (next.t_ns - before.t_ns) * 1e-9;
      for (int a = 0; a < 3; ++a)
        next.angle_rad[a] = before.angle_rad[a] + rate.omega_rad_s[a] * dt_s;
      next.world_from_cam =
          OrientationStep(before.world_from_cam, before.cam_rate_rad_s, next.cam_rate_rad_s, dt_s);
    }
    if (plots_ != nullptr) plots_->AddSample(next.t_ns, rate.omega_rad_s, next.angle_rad);
    kept_.push_back(next);
  }

  // Drops the samples before the one before the earliest open readout (all but the last when none
  // is open yet).
  void Trim() {
    size_t keep_from = kept_.size() - 1;
    if (first_open_ < jobs_.size())
      keep_from = std::min(keep_from, LowerBound(jobs_[first_open_].begin_ns));
    if (keep_from > 0) --keep_from;  // the sample before the readout's start
    kept_.erase(kept_.begin(), kept_.begin() + static_cast<std::ptrdiff_t>(keep_from));
  }

  size_t LowerBound(int64_t t_ns) const {
    return static_cast<size_t>(
        std::lower_bound(kept_.begin(), kept_.end(), t_ns,
                         [](const Kept& k, int64_t t) { return k.t_ns < t; }) -
        kept_.begin());
  }

  // Measures a readout on the stretch of kept samples from the one before its start to the one
  // after its end (where there is one).
  void Measure(ReadoutJob* job) {
    const size_t begin = LowerBound(job->begin_ns);
    const size_t first = begin > 0 ? begin - 1 : 0;
    size_t last =
        static_cast<size_t>(std::upper_bound(kept_.begin(), kept_.end(), job->end_ns,
                                             [](int64_t t, const Kept& k) { return t < k.t_ns; }) -
                            kept_.begin());
    last = std::min(last + 1, kept_.size());
    PerAxisAngles angles;
    std::vector<Eigen::Vector3d> rates;
    std::vector<Eigen::Quaterniond> orientations;
    for (size_t k = first; k < last; ++k) {
      angles.t_ns.push_back(kept_[k].t_ns);
      for (int a = 0; a < 3; ++a) angles.angle_rad[a].push_back(kept_[k].angle_rad[a]);
      rates.push_back(kept_[k].cam_rate_rad_s);
      orientations.push_back(kept_[k].world_from_cam);
    }
    ImageContext context = contexts_[job->variant];
    context.angles = &angles;
    std::optional<CameraMotion> motion;
    if (job->variant == 0) {
      motion.emplace(model_,
                     OrientationTrace(angles.t_ns, std::move(rates), std::move(orientations)));
      context.motion = &*motion;
    }
    ImageResult& image = images_[job->variant][job->image];
    MeasureImage(context, &image);
    if (motion && plots_ != nullptr)
      plots_->OfferImage(job->image, image.d_full_m, [&] { return motion->Frame(image.t_ns); });
    job->done = true;
  }

  std::vector<ImageContext> contexts_;
  std::vector<std::vector<ImageResult>> images_;
  TrueModel model_;
  Eigen::Vector3d bias_rad_s_;
  PlotBuilder* plots_;
  std::vector<ReadoutJob> jobs_;  // by start time
  size_t first_open_ = 0;         // jobs before it are done
  std::deque<Kept> kept_;
};

// The log's streams, one per pass: the one opened first (for the log's metadata), then fresh ones,
// each read a chunk ahead on a second thread.
class LogPasses {
 public:
  LogPasses(const AnalyzeLogSource& source, const AnalyzeOptions& options, size_t passes)
      : source_(source),
        options_(options),
        passes_(passes),
        first_(source.open()),
        metadata_(first_->log) {}
  // The log but its samples: its format, camera events, altitude and the reader's warnings.
  const FlightLog& log() const { return metadata_; }
  FlightLogStream Next() {
    FlightLogStream stream = first_ ? std::move(*first_) : source_.open();
    first_.reset();
    stream.gyro = ReadAhead(std::move(stream.gyro));
    ++pass_;
    return stream;
  }
  // The share of the whole analysis done when the current pass has read `fraction` of the log.
  void Report(double fraction) const {
    ReportProgress(options_, (std::min(pass_, passes_) - 1 + fraction) / passes_);
  }

 private:
  const AnalyzeLogSource& source_;
  const AnalyzeOptions& options_;
  size_t passes_;
  size_t pass_ = 0;
  std::optional<FlightLogStream> first_;
  FlightLog metadata_;
};

}  // namespace

namespace {

// AnalyzeStream's second pass: the sampling, the warnings and the bias (the mean over the still
// segment's samples, [begin_s, end_s) after the first sample as sim/bias.h SamplesInSegment takes
// them, summed in order), and with options.allan what the Allan deviation needs of the whole log
// and of the segment.
struct BiasPass {
  std::optional<StillSegment> still;
  Eigen::Vector3d bias_sum = Eigen::Vector3d::Zero();
  size_t bias_samples = 0;
  std::optional<int64_t> t0_ns;
  int64_t still_begin_ns = 0, still_end_ns = 0;
  AllanSegment allan_whole, allan_still;

  bool InStill(int64_t t_ns) const { return t_ns >= still_begin_ns && t_ns < still_end_ns; }
  void Add(const GyroChunk& chunk, const Eigen::Matrix3d& cam_from_gyro, bool allan) {
    if (!t0_ns) {
      t0_ns = chunk.data[0].t_ns;
      if (still) {
        still_begin_ns = *t0_ns + SecondsToNs(still->segment.begin_s);
        still_end_ns = *t0_ns + SecondsToNs(still->segment.end_s);
      }
    }
    if (allan) {
      for (const GyroSample& s : chunk)
        allan_whole.Add(InCameraAxes(s, cam_from_gyro, Eigen::Vector3d::Zero()));
    }
    if (!still) return;
    for (const GyroSample& s : chunk) {
      if (!InStill(s.t_ns)) continue;
      const GyroSample as_logged = InCameraAxes(s, cam_from_gyro, Eigen::Vector3d::Zero());
      bias_sum += as_logged.omega_rad_s;
      ++bias_samples;
      if (allan) allan_still.Add(as_logged);
    }
  }
};

// The images, timed once the trace's span is known, under the camera analysed (contexts[0]) and,
// with options.what_if and an image to judge, the what-if ones (a fast readout, half the altitude).
struct TimedImages {
  std::vector<ImageContext> contexts;
  std::vector<std::vector<ImageResult>> images;  // one list per context
};
TimedImages TimeImages(const std::vector<ImageTrigger>& triggers, const AnalyzeOptions& options,
                       const TraceSpan& span, int64_t median_interval_ns,
                       const AnalyzeResult& result) {
  TimedImages timed{{{nullptr, nullptr, options.rig, options.limits_m, median_interval_ns}}, {}};
  const int64_t latency_ns = SecondsToNs(options.trigger_latency_s);
  const auto time_all = [&](const ImageContext& context) {
    std::vector<ImageResult> images;
    for (const ImageTrigger& trigger : triggers)
      images.push_back(ImageTiming(context, trigger, latency_ns, span));
    return images;
  };
  timed.images.push_back(time_all(timed.contexts[0]));
  const bool any_judged = std::any_of(timed.images[0].begin(), timed.images[0].end(),
                                      [](const ImageResult& image) { return image.judged(); });
  if (options.what_if && any_judged) {
    timed.contexts.push_back(FastReadoutContext(timed.contexts[0], result.verdict.fast_readout_s));
    timed.contexts.push_back(HalfAltitudeContext(timed.contexts[0]));
    timed.images.push_back(time_all(timed.contexts[1]));
    timed.images.push_back(time_all(timed.contexts[2]));
  }
  return timed;
}

// The still segment, searched on the rates in camera axes as logged (the bias is not known yet);
// nullopt when the log has no still stretch (zero bias, said so in the output).
std::optional<StillSegment> StillSegmentOfLog(LogPasses* passes,
                                              const Eigen::Matrix3d& cam_from_gyro) {
  try {
    return DetectStillSegment([&]() -> std::unique_ptr<GyroSource> {
      FlightLogStream stream = passes->Next();
      return std::make_unique<CameraAxesSource>(std::move(stream.gyro), cam_from_gyro,
                                                [passes](double f) { passes->Report(f); });
    });
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
}

}  // namespace

AnalyzeResult AnalyzeStream(const AnalyzeLogSource& source, const AnalyzeOptions& given_options) {
  constexpr size_t kStillPasses = 5;  // DetectStillSegment on a source reads it at most five times
  const bool search_still = given_options.estimate_bias && !given_options.bias_segment;
  LogPasses passes(source, given_options, (search_still ? kStillPasses : 0) + 2);
  std::string altitude_source;
  const AnalyzeOptions options = WithLogAltitude(passes.log(), given_options, &altitude_source);
  const Eigen::Matrix3d& cam_from_gyro = options.rig.cam_from_gyro;
  const auto consume = [&](const std::function<void(const GyroChunk&)>& take) {
    FlightLogStream stream = passes.Next();
    return ConsumeFlightLog(&stream, take, [&](double f) { passes.Report(f); });
  };
  BiasPass bias;
  if (search_still) bias.still = StillSegmentOfLog(&passes, cam_from_gyro);
  if (options.estimate_bias && options.bias_segment)
    bias.still = StillSegment{*options.bias_segment};
  const StreamedLog read =
      consume([&](const GyroChunk& chunk) { bias.Add(chunk, cam_from_gyro, options.allan); });
  FlightLog log = passes.log();
  log.warnings = read.warnings;
  log.warnings.insert(log.warnings.end(), source.more_warnings.begin(), source.more_warnings.end());
  if (source.on_read) source.on_read(read.warnings);
  SHUTTERLAB_CHECK(read.sampling.samples >= 2) << "the log's gyro trace has fewer than 2 samples";

  AnalyzeResult result;
  DescribeSource(log, read.sampling, options, altitude_source, &result);
  result.bias_estimated = options.estimate_bias;
  if (bias.still) {
    result.still_segment = bias.still->segment;
    result.bias_from_still = bias.bias_samples >= kMinBiasSamples;  // EstimateBias's refusal
    result.bias_segment_given = !search_still;
    // The caller's segment must hold the samples a bias needs, as EstimateBias says of a trace.
    SHUTTERLAB_CHECK(!result.bias_segment_given || result.bias_from_still)
        << "bias segment " << FormatNumber("%g", result.still_segment.begin_s) << ":"
        << FormatNumber("%g", result.still_segment.end_s) << " s holds " << bias.bias_samples
        << " samples (need at least " << kMinBiasSamples
        << "): give a --bias A:B over a still part of the log, --auto-bias, or --zero-bias";
    if (result.bias_from_still)
      result.bias_rad_s = bias.bias_sum / static_cast<double>(bias.bias_samples);
  }
  // The Allan deviation, on the still segment or the whole log, in the last pass.
  std::optional<AllanStream> allan;
  if (options.allan) {
    result.allan_on_still = AllanOnStill(result, bias.allan_still);
    allan = (result.allan_on_still ? bias.allan_still : bias.allan_whole).Open(result.bias_rad_s);
  }
  const TraceSpan span{read.sampling.t_begin_ns, read.sampling.t_end_ns};
  TimedImages timed = TimeImages(ChooseTriggers(log, span, options, &result.trigger_source),
                                 options, span, read.sampling.median_interval_ns, result);

  // The flight table and the images' readouts, in one pass.
  std::unique_ptr<FlightStream> flight;
  std::exception_ptr flight_refused;
  try {
    flight = std::make_unique<FlightStream>(FlightOptionsForReadout(options, result));
  } catch (const std::invalid_argument&) {
    flight_refused = std::current_exception();
  }
  std::optional<PlotBuilder> plots;
  if (options.plots) plots.emplace(*options.plots, read.sampling.samples, span);
  StreamedReadouts readouts(timed.contexts, std::move(timed.images),
                            AnalyzeTrueModel(options.rig, result.bias_rad_s), result.bias_rad_s,
                            plots ? &*plots : nullptr);
  std::vector<GyroSample> rotated;
  consume([&](const GyroChunk& chunk) {
    if (allan) {
      for (const GyroSample& s : chunk) {
        if (result.allan_on_still && !bias.InStill(s.t_ns)) continue;
        allan->Add(InCameraAxes(s, cam_from_gyro, result.bias_rad_s));
      }
    }
    if (flight) {
      rotated.resize(chunk.size);
      for (size_t i = 0; i < chunk.size; ++i)
        rotated[i] = InCameraAxes(chunk.data[i], cam_from_gyro, Eigen::Vector3d::Zero());
      flight->Add(rotated.data(), rotated.size());
    }
    readouts.Add(chunk);
  });
  KeepFlightTable(
      [&] {
        if (flight_refused) std::rethrow_exception(flight_refused);
        return flight->Finish();
      },
      &result);
  std::vector<std::vector<ImageResult>> measured = readouts.Finish();
  result.images = std::move(measured[0]);
  if (plots) result.plots = plots->Finish();
  if (allan) result.allan = allan->Finish();
  NoteAssumptions(options, &result);
  JudgeImages(
      options,
      [&] {
        return WhatIfImages{std::move(measured[1]), std::move(measured[2])};
      },
      &result);
  result.verdict.line = VerdictLine(result.verdict, result.images.empty(), result.rate_hz, options);
  ReportProgress(options, 1.0);
  return result;
}

std::vector<ImageTrigger> TriggersOnLogClock(const TriggerFile& file, const FlightLog& log,
                                             const std::string& path) {
  std::optional<LogUtcClock> clock;
  if (file.clock != TriggerClock::kLog) {
    clock = FitLogUtcClock(log.utc_fixes);
    if (!clock) {
      throw IoError(IoMessage(path, 0,
                              std::string("the trigger times are ") + TriggerClockName(file.clock) +
                                  " and the log has no GPS time to place them on its clock"));
    }
  }
  std::vector<ImageTrigger> triggers;
  triggers.reserve(file.events.size());
  for (size_t i = 0; i < file.events.size(); ++i) {
    const TriggerEvent& e = file.events[i];
    ImageTrigger trigger;
    trigger.name = !e.name.empty()   ? e.name
                   : e.sequence >= 0 ? "IMG_" + std::to_string(e.sequence)
                                     : ImageName(i);
    trigger.t_ns = e.t_ns;
    if (file.clock == TriggerClock::kGps) trigger.t_ns = clock->LogNsFromUtc(UtcFromGpsNs(e.t_ns));
    if (file.clock == TriggerClock::kUtc) trigger.t_ns = clock->LogNsFromUtc(e.t_ns);
    triggers.push_back(std::move(trigger));
  }
  return triggers;
}

std::string LengthText(double m) {
  return m < 1.0 ? FormatNumber("%.3g cm", m * 100.0) : FormatNumber("%.3g m", m);
}

std::string LimitKey(double limit_m) { return FormatNumber("%.12g", limit_m); }

std::string AltitudeText(const AnalyzeResult& result) {
  if (result.altitude_source != "log" || result.altitude_method.empty())
    return result.altitude_source;
  return "log: " + result.altitude_method;
}

std::string AssumptionLine(const Assumption& a) {
  return "assumed: " + a.what + " " + a.taken + (a.why.empty() ? "" : " (" + a.why + ")") +
         "; give " + a.give;
}

std::string AnalyzeReport(const AnalyzeResult& result) {
  std::ostringstream out;
  out << "source: " << result.format << ", gyro " << result.gyro_source << ", " << result.samples
      << " samples, " << FormatNumber("%.1f", result.duration_s) << " s at "
      << FormatNumber("%.1f", result.rate_hz) << " Hz, " << result.gaps << " gaps\n";
  for (const LogWarning& w : result.log_warnings) out << "log warning: " << WarningLine(w) << "\n";
  if (result.bias_from_still) {
    out << "bias: " << (result.bias_segment_given ? "the segment given, " : "still segment ")
        << FormatNumber("%.2f", result.still_segment.begin_s) << ":"
        << FormatNumber("%.2f", result.still_segment.end_s) << " s\n";
  } else if (!result.bias_estimated) {
    out << "bias: zero (not estimated)\n";
  } else {
    out << "bias: none (no still segment found; zero bias assumed)\n";
  }
  out << "camera: readout " << FormatNumber("%g", result.readout_s * 1e3) << " ms, altitude "
      << FormatNumber("%g", result.altitude_m) << " m (" << AltitudeText(result)
      << "); triggers: " << result.trigger_source << "\n";
  for (const Assumption& a : result.assumptions) out << AssumptionLine(a) << "\n";
  out << "\n";
  if (result.flight) {
    out << FlightTable(*result.flight) << "\n";
  } else {
    out << "flight table: not computed (" << result.flight_problem << ")\n\n";
  }
  if (!result.images.empty()) {
    out << "image          t (s)   D_paper (cm)  D_full (cm)  axis  flagged\n";
    for (const ImageResult& image : result.images) {
      char line[256];
      if (!image.judged()) {
        std::snprintf(line, sizeof(line), "%-12s %9.3f  %s\n", image.name.c_str(),
                      image.t_ns * 1e-9,
                      image.in_trace ? "too few samples in the readout" : "outside the log");
      } else {
        std::string flags;
        for (size_t l = 0; l < result.limits_m.size(); ++l) {
          if (image.flagged[l])
            flags += (flags.empty() ? ">" : ", >") + LengthText(result.limits_m[l]);
        }
        std::snprintf(line, sizeof(line), "%-12s %9.3f  %12.2f %12.2f  %4s  %s\n",
                      image.name.c_str(), image.t_ns * 1e-9, image.d_paper_m * 100.0,
                      image.d_full_m * 100.0, kAxisNames[image.dominant_axis], flags.c_str());
      }
      out << line;
    }
    out << "\n";
  }
  out << result.verdict.line << "\n";
  return out.str();
}

void WriteAnalyzeOutputs(const std::string& dir, const AnalyzeResult& result) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(IoMessage(dir, 0, "cannot create folder: " + ec.message()));
  std::string csv = "name,t,D_paper_m,D_full_m";
  for (double limit : result.limits_m) csv += ",flag_" + LimitKey(limit);
  csv += ",dominant_axis\n";
  std::string exclude;
  for (const ImageResult& image : result.images) {
    csv += image.name + ",";
    AppendDouble(image.t_ns * 1e-9, &csv);
    if (!image.judged()) {
      csv += ",,";
      for (size_t l = 0; l < result.limits_m.size(); ++l) csv += ",";
      csv += image.in_trace ? ",too_few_samples\n" : ",outside\n";
      continue;
    }
    csv += ",";
    AppendDouble(image.d_paper_m, &csv);
    csv += ",";
    AppendDouble(image.d_full_m, &csv);
    bool any = false;
    for (size_t l = 0; l < result.limits_m.size(); ++l) {
      csv += image.flagged[l] ? ",1" : ",0";
      any = any || image.flagged[l];
    }
    csv += std::string(",") + kAxisNames[image.dominant_axis] + "\n";
    if (any) exclude += image.name + "\n";
  }
  WriteFileAtomically(dir + "/images.csv", csv);
  WriteFileAtomically(dir + "/exclude.txt", exclude);
}

}  // namespace shutterlab
