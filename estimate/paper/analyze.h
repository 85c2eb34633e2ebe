#pragma once
// `analyze`: per-image rolling-shutter distortion from a flight log.
//
// For each image, exposed at t = trigger + trigger_latency_s (the capture time of row 0, on the
// log's gyro clock; camera.json's time_offset_s is not applied because the triggers are already on
// the log clock):
//  - D_paper_m = altitude_m * tan(max over camera axes of the range of the per-axis integrated
//    angle within [t, t + readout_s]) — the source paper's threshold model (docs/FORMATS.md). The
//    angle is the paper's rectangle-rule sum (sim/integrate.h IntegratePerAxis), linear between
//    samples, so the window's end points are interpolated: a constant rate w gives exactly w *
//    readout_s.
//  - D_full_m = docs/FORMATS.md's frame distortion D under the renderer's model of the declared rig
//    (model/truth_model.h CameraMotion, render/rs_warp.h FrameGeometry::RefPixel): lens distortion
//    and camera.json's velocity count; the bias-corrected rates are the truth (TrueModel with
//    gyro_bias = the bias, time_offset_s 0 since the triggers are on the log clock). D is evaluated
//    on a coarse grid, every kGridStepPx-th column and row plus the last ones, and converted to the
//    ground as D_px * altitude_m / f, f = (fx + fy) / 2.
//  - flagged[i] = D_paper_m > limits_m[i] (no noise allowance: the allowance belongs to the
//    flight table's windows, whose flags it reproduces).
// The gyro rates are rotated into camera axes with rig.cam_from_gyro before anything else, so
// "axis" means camera x (right), y (down), z (optical axis). Bias: the still segment that
// DetectStillSegment finds, else zero (AnalyzeResult::bias_from_still says which; with
// AnalyzeOptions::estimate_bias false, zero without a search); it applies to
// every sample, the flight table's included (FlightOptions::known_bias_rad_s).
// Analyze's result keeps the traces the images came from (AnalyzeTraces: the camera-axis rates,
// their per-axis angles, the full model's motion), each built once; with AnalyzeOptions::plots
// both Analyze and AnalyzeStream keep what a report draws in bounded memory (AnalyzePlots).

#include "estimate/paper/allan.h"
#include "estimate/paper/flight.h"
#include "model/camera.h"
#include "model/truth_model.h"
#include "sim/gyro_trace.h"
#include "sim/integrate.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/trigger_file.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// Grid step of the D_full evaluation, pixels (columns and rows). The first and last rows and
// columns are always on the grid, so the frame's extremes, where a smooth rotation's D peaks, are
// included; interior peaks (rare) can be missed by a fraction of the displacement over 16 px.
inline constexpr int kGridStepPx = 16;

struct ImageTrigger {
  std::string name;  // image name (e.g. "IMG_0001")
  int64_t t_ns = 0;  // trigger time on the log's gyro clock
};

// What a report draws (AnalyzeOptions::plots, AnalyzeResult::plots).
struct AnalyzePlotOptions {
  // The time charts' buckets: the rates and angles are cut to min/max envelopes over this many
  // equal time spans, as DownsampleMinMax cuts them (estimate/report/html_report.h); the flagged
  // readout windows are kept as up to this many intervals per limit.
  size_t chart_buckets = 4000;
  size_t worst_images = 3;  // the full model's frames kept for the images with the largest D_full
  void Check() const;       // throws std::invalid_argument naming the first bad field
};

// An input that neither the user nor the file gave, taken as a default: what was taken and how to
// give it, said in the terminal, the JSON and the page.
struct Assumption {
  std::string what;   // "camera", "readout", "lens", "altitude", "bias"
  std::string taken;  // "1280 x 960 px, f 1100 px", "30 ms", ...
  std::string why;    // why it was not read from the file, "" when there is no file to read
  std::string give;   // how to give it: "--readout, --camera or --lens-profile"
};

struct AnalyzeOptions {
  RigModel rig;                              // camera, readout, altitude_m, cam_from_gyro
  std::vector<double> limits_m{0.05, 0.10};  // acceptable smear on the ground
  double noise_allowance_arcsec = 20.0;      // for the flight table (docs/FORMATS.md `flight`)
  // Image triggers, first match wins: these; else, when every_s > 0, simulated triggers every
  // every_s seconds from the first gyro sample (a mapping cadence); else the log's camera events.
  std::vector<ImageTrigger> triggers;
  std::string triggers_source = "triggers";  // what `triggers` are, for trigger_source
  double every_s = 0.0;
  bool log_events = true;  // false: never the log's camera events (`triggers` are all there is)
  double trigger_latency_s = 0.0;  // trigger to exposure of row 0, s (may be negative)
  // Use the log's altitude above ground (FlightLog::altitude_above_ground_m) instead of
  // rig.altitude_m when the log has one.
  bool use_log_altitude = false;
  // rig.altitude_m is a default, not a height anything gave (the photos' median is not): when
  // the log has none either, it is said as assumed.
  bool altitude_is_default = true;
  bool what_if = true;  // compute the verdict's faster-readout / half-altitude shares
  // false: zero bias and no still-segment search (calibrated flight-controller rates, or a
  // caller that removed the bias itself, e.g. `validate` on synthetic truth).
  bool estimate_bias = true;
  // The still segment to take the bias from (seconds after the first sample, `--bias A:B`),
  // instead of searching for one; ignored when estimate_bias is false.
  std::optional<BiasSegment> bias_segment;
  // Keep what a report draws (AnalyzeResult::plots and the flight table's window summary,
  // FlightResult::summary), in memory that does not grow with the log.
  std::optional<AnalyzePlotOptions> plots;
  // Compute the Allan deviation of the camera-axis rates (AnalyzeResult::allan) for the report.
  bool allan = false;
  std::function<void(double)> progress;  // fraction done (0..1); may be empty
  // The caller's defaults (the camera, its readout, its lens); the analysis adds its own (the
  // altitude when the log has none, a zero bias when no still segment is found).
  std::vector<Assumption> assumptions;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct ImageResult {
  std::string name;
  int64_t trigger_t_ns = 0;
  int64_t t_ns = 0;       // exposure of row 0 = trigger + latency
  bool in_trace = false;  // false: [t, t + readout] is not covered by the gyro trace
  // The readout is not longer than kMinWindowSampleIntervals sample intervals (the log's median):
  // it holds one or two samples, too few for a range, and the image is not judged (as flight's
  // rows; "too few samples" in the table, null values in the JSON).
  bool too_few_samples = false;
  bool judged() const { return in_trace && !too_few_samples; }
  double d_paper_m = 0.0;  // meaningful only when judged()
  double d_full_m = 0.0;
  double d_full_px = 0.0;
  std::array<double, 3> range_arcsec{};  // per camera axis within the readout
  int dominant_axis = 0;                 // 0 x, 1 y, 2 z: largest range
  std::vector<bool> flagged;             // one per limit
};

struct AnalyzeVerdict {
  size_t images_in_trace = 0;  // judged: inside the trace, with samples enough in the readout
  size_t images_too_few_samples = 0;  // inside the trace, but not judged (ImageResult)
  std::vector<double> share_percent;  // per limit: images over the limit / images in the trace
  int axis_to_stabilise = -1;         // most frequent dominant axis of flagged images; -1 none
  double fast_readout_s = 0.010;
  // Recomputed with readout fast_readout_s; empty when that readout holds too few samples to
  // judge any image.
  std::vector<double> share_fast_readout_percent;
  std::vector<double> share_half_altitude_percent;  // recomputed with half the altitude
  std::string line;                                 // the one-line verdict for a person
};

// What the per-image analysis was computed from, when the log is held whole (Analyze), for callers
// that look at the traces themselves (a report draws AnalyzePlots instead).
struct AnalyzeTraces {
  // The log's rates in camera axes with the bias removed (rig.cam_from_gyro * w - bias), rad/s, on
  // the log's gyro clock.
  GyroTrace camera_rates;
  // Their per-axis angles, the paper's sum (IntegratePerAxis with zero bias), rad, one per sample:
  // the images' ranges and D_paper come from these.
  PerAxisAngles angles;
  // The full model's motion (AnalyzeTrueModel of the rig analysed, the log's altitude when used):
  // D_full comes from its frames.
  CameraMotion motion;
};

// What a report draws of the analysis (AnalyzeOptions::plots), the same whether the log was read
// whole (Analyze) or streamed (AnalyzeStream), and bounded whatever the log's length.
struct AnalyzePlots {
  // The camera-axis rates (deg/s, bias removed) and their per-axis angles (deg, the paper's sum)
  // against time on the log clock (s): DownsampleMinMax(chart, chart_buckets) of the whole traces
  // (AnalyzeTraces::camera_rates and angles times kDegPerRad), the same numbers.
  std::vector<double> t_s;
  std::array<std::vector<double>, 3> rate_deg_s, angle_deg;
  // The full model's frame (model/truth_model.h CameraMotion::Frame at the image's t_ns) of the
  // judged images with the largest D_full, largest first (ties: the earlier image), at most
  // worst_images of them.
  struct WorstImage {
    size_t image = 0;  // index in AnalyzeResult::images
    FrameMotion frame;
  };
  std::vector<WorstImage> worst;
};

struct AnalyzeResult {
  // source
  std::string format, gyro_source;
  size_t samples = 0;
  double duration_s = 0.0, rate_hz = 0.0;
  size_t gaps = 0;
  std::vector<LogWarning> log_warnings;  // FlightLog::warnings: what the log lost
  // analysis
  std::optional<FlightResult> flight;  // empty when the trace is too short for one window
  std::string flight_problem;          // why flight is empty
  bool bias_estimated = true;          // AnalyzeOptions::estimate_bias
  bool bias_from_still = false;
  bool bias_segment_given = false;  // still_segment is AnalyzeOptions::bias_segment, not found
  BiasSegment still_segment;
  Eigen::Vector3d bias_rad_s = Eigen::Vector3d::Zero();  // camera axes
  // "none", "camera events (KIND)", AnalyzeOptions::triggers_source ("triggers"), "every N s"
  std::string trigger_source;
  std::vector<double> limits_m;
  double altitude_m = 0.0, readout_s = 0.0;
  std::string altitude_source;  // "camera" (the options) or "log"
  std::string altitude_method;  // how the log's altitude was formed (FlightLog::altitude_source)
  std::vector<Assumption> assumptions;  // AnalyzeOptions::assumptions and the analysis's own
  std::vector<ImageResult> images;
  AnalyzeVerdict verdict;
  // With AnalyzeOptions::allan, the Allan deviation of the camera-axis rates (bias removed): on the
  // still segment when one was found with 20 samples or more (allan_on_still), else on the whole
  // log, where the flight's motion dominates and it bounds the gyro's noise from above. Computed
  // as the log streams past (AllanStream: AllanAnalysis's taus, its exact values up to
  // kAllanExactClusterMax samples a cluster, within a small part of its scatter beyond), with the
  // mean it removes formed from the rates as logged less the bias. Empty (AllanResult::empty) when
  // too few samples; nullopt when not asked for.
  std::optional<AllanResult> allan;
  bool allan_on_still = false;
  // Set by Analyze, never null there; shared, so that copying a result does not copy the traces.
  std::shared_ptr<const AnalyzeTraces> traces;
  // With AnalyzeOptions::plots; shared as the traces are.
  std::shared_ptr<const AnalyzePlots> plots;
};

AnalyzeResult Analyze(const FlightLog& log, const AnalyzeOptions& options);

// How AnalyzeStream reads a log too long to hold.
struct AnalyzeLogSource {
  // A fresh stream of the log from its start, each call (sim/logs/flight_log_io.h OpenFlightLog);
  // the first one's FlightLogStream::log gives the metadata (format, camera events, altitude).
  std::function<FlightLogStream()> open;
  // Warnings that go after the log's own, as Analyze takes them in FlightLog::warnings (e.g. what
  // reading a trigger file lost).
  std::vector<LogWarning> more_warnings;
  // Called once with the log's own warnings when it has been read through (may be empty).
  std::function<void(const std::vector<LogWarning>&)> on_read;
};

// Analyze on a log read as a stream, in memory bounded by a chunk and the longest readout whatever
// the log's length. The log is read seven times (two with estimate_bias false): the still search's
// five passes (sim/still_detect.h), one for the sampling, warnings and bias, one for the flight
// table and the images' readouts. The result is Analyze's on the log read whole, to the bit: the
// same sums in the same order; the readouts are measured on a stretch of the same integration
// kept while they are open. (Where the sample intervals take over 65,536 distinct values, the
// median interval and the gap count come from bucketed intervals: sim/interval_histogram.h.)
// With options.plots, AnalyzeResult::plots and the flight's window summary are the same as
// Analyze's (the same values fed to the same accumulators in the same order). What it does not
// give: traces is null. With options.allan the Allan deviation is Analyze's too.
AnalyzeResult AnalyzeStream(const AnalyzeLogSource& source, const AnalyzeOptions& options);

// The renderer's true model that D_full uses: the declared rig with no time offset (triggers are
// on the log clock) and the bias (camera axes) removed as the gyro bias (gyro axes).
TrueModel AnalyzeTrueModel(const RigModel& rig, const Eigen::Vector3d& bias_cam_rad_s);

// A trigger file's events (sim/logs/trigger_file.h) as image triggers on the log's clock: log-clock
// times as they are, GPS or UTC times through the log's GPS fixes (sim/logs/log_clock.h). Named
// by the file's image names, else IMG_<photo number>, else IMG_0001, ... in file order. Throws
// IoError(path: problem) when the times are GPS or UTC and the log has no GPS time.
std::vector<ImageTrigger> TriggersOnLogClock(const TriggerFile& file, const FlightLog& log,
                                             const std::string& path);

// Where the altitude came from, for a person: "camera", or "log: median CAM.RelAlt ...".
std::string AltitudeText(const AnalyzeResult& result);

// "assumed: readout 30 ms; give --readout, --camera or --lens-profile", with the reason when
// there is one.
std::string AssumptionLine(const Assumption& a);

// Report for a person: source, bias, camera and what was assumed, flight table, per-image table,
// verdict.
std::string AnalyzeReport(const AnalyzeResult& result);
// DIR/images.csv (name,t,D_paper_m,D_full_m,flag_<limit>...,dominant_axis; images outside the
// trace have empty values and dominant_axis "outside") and DIR/exclude.txt (flagged names at any
// limit, one a line), each written whole. Creates DIR when missing.
void WriteAnalyzeOutputs(const std::string& dir, const AnalyzeResult& result);

// The key used for a limit in JSON and CSV: shortest round-trip decimal ("0.05", "0.1").
std::string LimitKey(double limit_m);
// A length for a person, three digits: "5 cm", "12.5 cm", "1.5 m".
std::string LengthText(double length_m);

}  // namespace shutterlab
