#include "estimate/paper/analyze.h"

#include "render/rs_warp.h"
#include "render/truth_model.h"
#include "sim/bias.h"
#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/integrate.h"
#include "sim/logs/log_clock.h"
#include "sim/still_detect.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace shutterlab {
namespace {

constexpr const char* kAxisNames[3] = {"x", "y", "z"};

GyroTrace RotateTrace(const GyroTrace& trace, const Eigen::Matrix3d& cam_from_gyro,
                      const Eigen::Vector3d& bias_rad_s) {
  std::vector<GyroSample> samples = trace.samples();
  for (GyroSample& s : samples) s.omega_rad_s = cam_from_gyro * s.omega_rad_s - bias_rad_s;
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

ImageResult AnalyzeImage(const ImageContext& context, const ImageTrigger& trigger,
                         int64_t latency_ns) {
  ImageResult image;
  image.name = trigger.name;
  image.trigger_t_ns = trigger.t_ns;
  image.t_ns = trigger.t_ns + latency_ns;
  image.flagged.assign(context.limits_m.size(), false);
  const PerAxisAngles& angles = *context.angles;
  const int64_t readout_ns = SecondsToNs(context.rig.shutter.readout_s);
  const int64_t end_ns = image.t_ns + readout_ns;
  if (angles.size() < 2 || image.t_ns < angles.t_ns.front() || end_ns > angles.t_ns.back()) {
    return image;
  }
  image.in_trace = true;
  if (readout_ns <= kMinWindowSampleIntervals * context.sample_interval_ns) {
    image.too_few_samples = true;
    return image;
  }
  const auto first = std::upper_bound(angles.t_ns.begin(), angles.t_ns.end(), image.t_ns);
  const auto last = std::lower_bound(angles.t_ns.begin(), angles.t_ns.end(), end_ns);
  const size_t i0 = static_cast<size_t>(first - angles.t_ns.begin());
  const size_t i1 = static_cast<size_t>(last - angles.t_ns.begin());
  double max_range_rad = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const double a_begin = AngleAt(angles, axis, image.t_ns);
    const double a_end = AngleAt(angles, axis, end_ns);
    double lo = std::min(a_begin, a_end), hi = std::max(a_begin, a_end);
    for (size_t i = i0; i < i1; ++i) {
      lo = std::min(lo, angles.angle_rad[axis][i]);
      hi = std::max(hi, angles.angle_rad[axis][i]);
    }
    image.range_arcsec[axis] = (hi - lo) * kArcsecPerRad;
    if (hi - lo > max_range_rad) {
      max_range_rad = hi - lo;
      image.dominant_axis = axis;
    }
  }
  image.d_paper_m = context.rig.altitude_m * std::tan(max_range_rad);
  for (size_t l = 0; l < context.limits_m.size(); ++l) {
    image.flagged[l] = image.d_paper_m > context.limits_m[l];
  }
  if (context.motion != nullptr) {
    const FrameGeometry geometry(context.rig.camera, context.rig.altitude_m,
                                 context.motion->Frame(image.t_ns),
                                 cv::Size(context.rig.camera.width, context.rig.camera.height));
    image.d_full_px = GridDistortionPx(geometry);
    const double f_px = 0.5 * (context.rig.camera.fx + context.rig.camera.fy);
    image.d_full_m = image.d_full_px * context.rig.altitude_m / f_px;
  }
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
void DescribeSource(const FlightLog& log, const AnalyzeOptions& options,
                    const std::string& altitude_source, AnalyzeResult* result) {
  const GyroTrace& gyro = log.gyro;
  result->format = log.format;
  result->gyro_source = log.gyro_source;
  result->samples = gyro.samples().size();
  result->duration_s = (gyro.samples().back().t_ns - gyro.samples().front().t_ns) * 1e-9;
  result->rate_hz = gyro.sampling().RateHz();
  result->gaps = gyro.sampling().gap_indices.size();
  result->log_warnings = log.warnings;
  result->altitude_method = log.altitude_source;
  result->limits_m = options.limits_m;
  result->altitude_m = options.rig.altitude_m;
  result->altitude_source = altitude_source;
  result->readout_s = options.rig.shutter.readout_s;
}

// The bias (camera axes) from the log's still stretch when asked; zero, and said so in the output,
// when there is none.
void EstimateStillBias(const GyroTrace& camera_rates, bool estimate_bias, AnalyzeResult* result) {
  result->bias_estimated = estimate_bias;
  if (!estimate_bias) return;
  try {
    const StillSegment still = DetectStillSegment(camera_rates);
    result->still_segment = still.segment;
    result->bias_rad_s = EstimateBias(camera_rates, still.segment).bias_rad_s;
    result->bias_from_still = true;
  } catch (const std::invalid_argument&) {
    result->bias_from_still = false;  // no still stretch: zero bias, said so in the output
  }
}

// The Allan deviation of the camera-axis rates, on the still segment when it holds enough samples
// (AnalyzeResult::allan, allan_on_still).
void AllanOfRates(const GyroTrace& rates, AnalyzeResult* result) {
  result->allan_on_still = false;
  if (result->bias_from_still) {
    // [begin_s, end_s): the samples the bias was averaged over, not one more.
    const auto [begin, end] = SamplesInSegment(rates, result->still_segment);
    std::vector<GyroSample> still(rates.samples().begin() + begin, rates.samples().begin() + end);
    if (still.size() >= 20) {
      result->allan = AllanAnalysis(GyroTrace(std::move(still)));
      result->allan_on_still = true;
      return;
    }
  }
  result->allan = AllanAnalysis(rates);
}

// The flight table for this camera's readout (result->flight), or why there is none
// (result->flight_problem). Progress 0 to 0.7.
void FlightTableForReadout(const GyroTrace& camera_rates, const AnalyzeOptions& options,
                           AnalyzeResult* result) {
  FlightOptions flight_options;
  flight_options.altitude_m = options.rig.altitude_m;
  flight_options.limits_m = options.limits_m;
  flight_options.windows_s = {options.rig.shutter.readout_s};
  flight_options.noise_allowance_arcsec = options.noise_allowance_arcsec;
  flight_options.progress = [&options](double f) { ReportProgress(options, 0.7 * f); };
  flight_options.series = options.flight_series;
  flight_options.series_vector = false;  // the report plots the per-axis ranges only
  try {
    // The still segment may lie anywhere (often after landing), so its bias is applied to every
    // sample rather than starting the statistics after the segment as `flight --bias` does.
    flight_options.known_bias_rad_s = result->bias_rad_s;
    result->flight = Flight(camera_rates, flight_options);
    result->log_warnings.insert(result->log_warnings.end(), result->flight->warnings.begin(),
                                result->flight->warnings.end());
  } catch (const std::invalid_argument& e) {
    result->flight_problem = e.what();
  }
}

// The images to analyse: the options' triggers, else one every options.every_s over the log, else
// the log's camera events; *trigger_source says which.
std::vector<ImageTrigger> ChooseTriggers(const FlightLog& log, const AnalyzeOptions& options,
                                         std::string* trigger_source) {
  const GyroTrace& gyro = log.gyro;
  std::vector<ImageTrigger> triggers = options.triggers;
  *trigger_source = options.triggers_source;
  if (triggers.empty() && options.every_s > 0) {
    *trigger_source = FormatNumber("every %g s", options.every_s);
    const int64_t every_ns = SecondsToNs(options.every_s);
    const int64_t t0_ns = gyro.samples().front().t_ns;
    const int64_t span_ns = gyro.samples().back().t_ns - t0_ns;
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

// The what-if shares, recomputed (not scaled) with a fast readout and at half the altitude
// (without D_full).
void WhatIfShares(const ImageContext& context, const std::vector<ImageTrigger>& triggers,
                  int64_t latency_ns, AnalyzeVerdict* verdict) {
  ImageContext fast = context;
  fast.motion = nullptr;
  fast.rig.shutter.readout_s = verdict->fast_readout_s;
  ImageContext low = context;
  low.motion = nullptr;
  low.rig.altitude_m = 0.5 * context.rig.altitude_m;
  std::vector<ImageResult> fast_images, low_images;
  for (const ImageTrigger& trigger : triggers) {
    fast_images.push_back(AnalyzeImage(fast, trigger, latency_ns));
    low_images.push_back(AnalyzeImage(low, trigger, latency_ns));
  }
  // A fast readout may hold too few samples to judge any image: then no share, not 0 %.
  const bool fast_judged = std::any_of(fast_images.begin(), fast_images.end(),
                                       [](const ImageResult& image) { return image.judged(); });
  verdict->share_fast_readout_percent.clear();
  if (fast_judged)
    verdict->share_fast_readout_percent = SharesPercent(fast_images, context.limits_m.size());
  verdict->share_half_altitude_percent = SharesPercent(low_images, context.limits_m.size());
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

void AnalyzeOptions::Check() const {
  rig.Check();
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

AnalyzeResult Analyze(const FlightLog& log, const AnalyzeOptions& given_options) {
  given_options.Check();
  AnalyzeOptions options = given_options;
  std::string altitude_source = "camera";
  if (options.use_log_altitude && log.altitude_above_ground_m && *log.altitude_above_ground_m > 0) {
    options.rig.altitude_m = *log.altitude_above_ground_m;
    altitude_source = "log";
  }
  const GyroTrace& gyro = log.gyro;
  SHUTTERLAB_CHECK(gyro.samples().size() >= 2) << "the log's gyro trace has fewer than 2 samples";

  AnalyzeResult result;
  DescribeSource(log, options, altitude_source, &result);
  {
    // The bias is not known yet: the still search and the flight table take the rates as logged.
    const GyroTrace camera_rates =
        RotateTrace(gyro, options.rig.cam_from_gyro, Eigen::Vector3d::Zero());
    EstimateStillBias(camera_rates, options.estimate_bias, &result);
    FlightTableForReadout(camera_rates, options, &result);
  }

  // Per-image distortion, from the traces the result keeps for the report. The angles are the
  // same numbers as IntegratePerAxis(rates as logged, bias): each step is (w - b) * dt either way.
  GyroTrace rates = RotateTrace(gyro, options.rig.cam_from_gyro, result.bias_rad_s);
  PerAxisAngles angles = IntegratePerAxis(rates, Eigen::Vector3d::Zero());
  result.traces = std::make_shared<const AnalyzeTraces>(
      AnalyzeTraces{std::move(rates), std::move(angles),
                    CameraMotion(gyro, AnalyzeTrueModel(options.rig, result.bias_rad_s))});
  if (options.allan) AllanOfRates(result.traces->camera_rates, &result);
  const std::vector<ImageTrigger> triggers = ChooseTriggers(log, options, &result.trigger_source);
  ImageContext context{&result.traces->angles, &result.traces->motion, options.rig,
                       options.limits_m, gyro.sampling().median_interval_ns};
  const int64_t latency_ns = SecondsToNs(options.trigger_latency_s);
  result.images.reserve(triggers.size());
  for (size_t i = 0; i < triggers.size(); ++i) {
    result.images.push_back(AnalyzeImage(context, triggers[i], latency_ns));
    ReportProgress(options, 0.7 + 0.25 * (i + 1) / triggers.size());
  }

  // The verdict, with the what-if shares recomputed (not scaled) under the changed camera.
  AnalyzeVerdict& verdict = result.verdict;
  for (const ImageResult& image : result.images) {
    verdict.images_in_trace += image.judged();
    verdict.images_too_few_samples += image.in_trace && image.too_few_samples;
  }
  verdict.share_percent = SharesPercent(result.images, options.limits_m.size());
  verdict.axis_to_stabilise = AxisToStabilise(result.images, verdict.images_in_trace);
  if (options.what_if && verdict.images_in_trace > 0) {
    WhatIfShares(context, triggers, latency_ns, &verdict);
  }
  verdict.line = VerdictLine(verdict, result.images.empty(), result.rate_hz, options);
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

std::string AnalyzeReport(const AnalyzeResult& result) {
  std::ostringstream out;
  out << "source: " << result.format << ", gyro " << result.gyro_source << ", " << result.samples
      << " samples, " << FormatNumber("%.1f", result.duration_s) << " s at "
      << FormatNumber("%.1f", result.rate_hz) << " Hz, " << result.gaps << " gaps\n";
  for (const LogWarning& w : result.log_warnings) out << "log warning: " << WarningLine(w) << "\n";
  if (result.bias_from_still) {
    out << "bias: still segment " << FormatNumber("%.2f", result.still_segment.begin_s) << ":"
        << FormatNumber("%.2f", result.still_segment.end_s) << " s\n";
  } else if (!result.bias_estimated) {
    out << "bias: zero (not estimated)\n";
  } else {
    out << "bias: none (no still segment found; zero bias assumed)\n";
  }
  out << "camera: readout " << FormatNumber("%g", result.readout_s * 1e3) << " ms, altitude "
      << FormatNumber("%g", result.altitude_m) << " m (" << AltitudeText(result)
      << "); triggers: " << result.trigger_source << "\n\n";
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
