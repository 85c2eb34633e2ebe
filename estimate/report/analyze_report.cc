#include "estimate/report/analyze_report.h"

#include "estimate/paper/allan.h"
#include "estimate/paper/flight.h"
#include "model/truth_model.h"
#include "render/pictures.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/gyro_trace.h"
#include "sim/units.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <sstream>

namespace shutterlab {
namespace {

constexpr const char* kAxisLabels[3] = {"x (right)", "y (down)", "z (optical axis)"};
// One shade per limit, the strictest (smallest) limit lightest: stricter flags cover looser ones.
constexpr const char* kShades[] = {"rgba(255, 170, 0, 0.22)", "rgba(230, 60, 30, 0.30)",
                                   "rgba(150, 0, 90, 0.35)"};
constexpr const char* kLimitColors[] = {"#e08a00", "#c0301a", "#80005a"};

std::string Fmt(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

std::string Cm(double m) { return Fmt("%.0f cm", m * 100.0); }

std::vector<ChartShading> FlaggedShadings(const AnalyzeResult& result) {
  std::vector<ChartShading> shadings;
  if (!result.flight || !result.flight->summary || result.flight->summary->windows == 0)
    return shadings;
  const FlightWindowSummary& summary = *result.flight->summary;
  // Loosest limit first so the stricter, wider shading lies below it.
  for (size_t r = 0; r < result.flight->rows.size(); ++r) {
    const FlightRow& row = result.flight->rows[r];
    if (row.too_few_samples) continue;
    const size_t l =
        static_cast<size_t>(std::find(result.limits_m.begin(), result.limits_m.end(), row.limit_m) -
                            result.limits_m.begin());
    const IntervalUnion& flagged = summary.flagged.at(l);
    ChartShading shading;
    shading.label = "readout windows (" + Fmt("%g", row.window_s * 1e3) + " ms) over " +
                    Cm(row.limit_m) + " (" + Fmt("%.1f", row.threshold_arcsec) +
                    "\" on any axis): " + Fmt("%.1f", row.flagged_percent) + " % of windows";
    if (flagged.filled_gap() > 0) {
      shading.label += " (gaps up to " + Fmt("%.3g", flagged.filled_gap()) +
                       " s between them shaded too, to keep the chart's intervals few)";
    }
    shading.color = kShades[std::min<size_t>(l, std::size(kShades) - 1)];
    shading.intervals = flagged.intervals();
    shadings.push_back(std::move(shading));
  }
  return shadings;
}

// The rates and angles as the analysis cut them to envelopes (AnalyzePlots).
void AddRateAndAngleCharts(HtmlPage* page, const AnalyzePlots& plots, const AnalyzeResult& result) {
  Chart rate;
  rate.title = "Rotation rate, camera axes (bias removed)";
  rate.x_label = "time on the log clock (s)";
  rate.y_label = "rate (deg/s)";
  rate.x = plots.t_s;
  for (int a = 0; a < 3; ++a) rate.series.emplace_back(kAxisLabels[a], plots.rate_deg_s[a]);
  rate.shadings = FlaggedShadings(result);
  page->AddChart(rate);

  Chart angle = rate;  // the same x; the per-axis angles of the paper's model
  angle.title = "Integrated angle per camera axis (the paper's per-axis sum)";
  angle.y_label = "angle (deg)";
  for (int a = 0; a < 3; ++a) angle.series[a].y = plots.angle_deg[a];
  angle.shadings.clear();  // the rate chart says which windows are flagged; keep this one clear
  page->AddChart(angle);
}

void AddDistortionChart(HtmlPage* page, const AnalyzeResult& result) {
  Chart chart;
  chart.title = "Predicted distortion per image";
  chart.kind = ChartKind::kPoints;
  chart.x_label = "exposure time on the log clock (s)";
  chart.y_label = "D on the ground (cm)";
  ChartSeries paper("D paper model", {}, "#1f77b4");
  ChartSeries full("D full model", {}, "#d62728");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const ImageResult& image : result.images) {
    chart.x.push_back(image.t_ns * 1e-9);
    paper.y.push_back(image.judged() ? image.d_paper_m * 100.0 : nan);
    full.y.push_back(image.judged() ? image.d_full_m * 100.0 : nan);
  }
  chart.series = {paper, full};
  for (size_t l = 0; l < result.limits_m.size(); ++l) {
    ChartSeries limit("limit " + Cm(result.limits_m[l]), {},
                      kLimitColors[std::min<size_t>(l, std::size(kLimitColors) - 1)]);
    limit.y.assign(chart.x.size(), result.limits_m[l] * 100.0);
    limit.dashed = true;
    limit.line = true;
    chart.series.push_back(std::move(limit));
  }
  page->AddChart(chart);
}

void AddWindowHistograms(HtmlPage* page, const FlightResult& flight,
                         const AnalyzeReportOptions& report) {
  const FlightWindowSummary& summary = *flight.summary;
  // Upper edge: past the largest threshold and the bulk (report.histogram_quantile) of the
  // windows; the rest go in the last bin. The summary's histogram places a quantile within 0.1 %.
  LogBinHistogram all;
  for (int a = 0; a < 3; ++a) all.Merge(summary.range_arcsec[a]);
  const uint64_t p = std::min<uint64_t>(
      all.total() - 1, static_cast<uint64_t>(report.histogram_quantile * all.total()));
  double upper = all.Quantile(p);
  for (const FlightRow& row : flight.rows) upper = std::max(upper, 1.15 * row.threshold_arcsec);
  const int bins = report.histogram_bins;
  const double width = upper / bins;
  Chart chart;
  chart.title = "Readout windows (" + Fmt("%g", summary.window_s * 1e3) +
                " ms) by the range of each axis's angle";
  chart.kind = ChartKind::kHistogram;
  const double share_above =
      100.0 * (1.0 - all.CountBelow(upper) / static_cast<double>(all.total()));
  chart.x_label = "range within the window (arcsec); the last bin also holds the " +
                  Fmt("%.1f", share_above) + " % of windows above " + Fmt("%.0f", upper) + "\"";
  chart.y_label = "windows (%)";
  for (int b = 0; b <= bins; ++b) chart.x.push_back(b * width);
  const double n = static_cast<double>(summary.windows);
  for (int a = 0; a < 3; ++a) {
    const LogBinHistogram& ranges = summary.range_arcsec[a];
    ChartSeries s(kAxisLabels[a]);
    double below = 0.0;  // windows below the bin's left edge
    for (int b = 0; b < bins; ++b) {
      const double next =
          b + 1 < bins ? ranges.CountBelow((b + 1) * width) : static_cast<double>(ranges.total());
      s.y.push_back(100.0 * (next - below) / n);
      below = next;
    }
    s.y.push_back(s.y.back());  // the right edge of the last bin
    chart.series.push_back(std::move(s));
  }
  // Shade what lies over each limit's threshold.
  for (size_t r = 0; r < flight.rows.size(); ++r) {
    const FlightRow& row = flight.rows[r];
    chart.shadings.push_back(
        {"over " + Cm(row.limit_m) + " (threshold " + Fmt("%.1f", row.threshold_arcsec) + "\")",
         kShades[std::min<size_t>(r, std::size(kShades) - 1)],
         {{row.threshold_arcsec, upper}}});
  }
  page->AddChart(chart);
}

// A sketch of the camera's axes, which the verdict ("stabilise camera axis y") and every chart
// name: OpenCV's camera frame, the image's rows read top to bottom.
std::string CameraAxesFigure() {
  return R"svg(<figure class="axes"><svg width="320" height="170" viewBox="0 0 320 170" role="img" aria-label="camera axes">
<defs><marker id="arrow" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="#1d2430"/></marker></defs>
<rect x="20" y="20" width="160" height="120" fill="#eef2f7" stroke="#8a94a3"/>
<g stroke="#c5ccd6">
<line x1="26" y1="36" x2="174" y2="36"/><line x1="26" y1="52" x2="174" y2="52"/><line x1="26" y1="68" x2="174" y2="68"/>
<line x1="26" y1="84" x2="174" y2="84"/><line x1="26" y1="100" x2="174" y2="100"/><line x1="26" y1="116" x2="174" y2="116"/></g>
<text x="100" y="15" font-size="11" text-anchor="middle" fill="#4a5462">the image, read row by row, top first</text>
<line x1="20" y1="20" x2="215" y2="20" stroke="#d62728" stroke-width="2.5" marker-end="url(#arrow)"/>
<text x="222" y="24" font-size="13" fill="#d62728">x (right)</text>
<line x1="20" y1="20" x2="20" y2="162" stroke="#2ca02c" stroke-width="2.5" marker-end="url(#arrow)"/>
<text x="27" y="160" font-size="13" fill="#2ca02c">y (down)</text>
<circle cx="100" cy="80" r="9" fill="none" stroke="#1f77b4" stroke-width="2.5"/><circle cx="100" cy="80" r="2.5" fill="#1f77b4"/>
<text x="114" y="84" font-size="13" fill="#1f77b4">z (optical axis, to the ground)</text>
</svg><figcaption>The camera axes: a turn about y moves the ground along the rows (the image skews), about x along the columns (it stretches or squashes), about z turns it (a fan-shaped shear).</figcaption></figure>
)svg";
}

void AddAllan(HtmlPage* page, const AnalyzeResult& result) {
  if (!result.allan) {
    page->Paragraph("Allan deviation: not computed (AnalyzeOptions::allan).");
    return;
  }
  std::string on =
      "the whole log (no still segment found: the flight's motion dominates, so this "
      "bounds the gyro's noise from above)";
  if (!result.bias_estimated) {
    on = "the whole log (bias not estimated, no still segment searched: the flight's motion "
         "dominates, so this bounds the gyro's noise from above)";
  }
  if (result.allan_on_still) {
    on = "the still segment " + Fmt("%.2f", result.still_segment.begin_s) + "-" +
         Fmt("%.2f", result.still_segment.end_s) + " s after the first sample";
  }
  const AllanResult& allan = *result.allan;
  if (allan.empty()) {
    page->Paragraph("Allan deviation: " +
                    (allan.not_computed.empty()
                         ? "too few samples on " + on
                         : "not computed on " + on + ": " + allan.not_computed) +
                    ".");
    return;
  }
  page->Paragraph("Allan deviation of the camera-axis rates on " + on + ".");
  Chart chart;
  chart.title = "Allan deviation";
  chart.log_x = chart.log_y = true;
  chart.x_label = "cluster time tau (s)";
  chart.y_label = "Allan deviation (deg/h)";
  chart.x = allan.tau_s;
  for (int a = 0; a < 3; ++a) {
    ChartSeries s(kAxisLabels[a]);
    for (double v : allan.adev_rad_s[a]) s.y.push_back(v * kDegPerRad * 3600.0);
    chart.series.push_back(std::move(s));
  }
  page->AddChart(chart);
  // Off a still segment the curve is the flight's motion, not the gyro's noise: its coefficients
  // are no property of the sensor, only an upper bound on it, and the table says so in each cell.
  const bool meaningful = result.allan_on_still;
  std::vector<std::vector<std::string>> rows;
  for (int a = 0; a < 3; ++a) {
    const AllanCoefficients& c = allan.axes[a];
    const bool below = c.bias_instability_upper_bound;
    rows.push_back({kAxisLabels[a],
                    (meaningful ? "" : "not meaningful, at most ") + Fmt("%.3g", c.arw_deg_sqrt_h),
                    (meaningful ? (below ? "< " : "")
                                : (below ? "not meaningful, below " : "not meaningful, at most ")) +
                        Fmt("%.3g", c.bias_instability_deg_h),
                    Fmt("%.3g", c.bias_instability_tau_s)});
  }
  page->Table({"axis", "angle random walk (deg/sqrt(h))", "bias instability (deg/h)", "at tau (s)"},
              rows);
  if (!meaningful) {
    page->Paragraph("Not meaningful: computed on " + on +
                    ", it measures the motion, not the gyro. To measure the gyro's noise, record a "
                    "few seconds with the camera still before take-off (and analyze without "
                    "--zero-bias, which searches no still time), or run shutterlab noise on a "
                    "still recording (paper Tables 1-2).");
  }
}

// What neither the user nor the log gave (AnalyzeResult::assumptions), and how to give it.
void AddAssumptions(HtmlPage* page, const AnalyzeResult& result) {
  if (result.assumptions.empty()) return;
  page->Heading("What was assumed");
  page->Paragraph("Neither you nor the log gave these; the results on this page use them:");
  std::vector<std::vector<std::string>> lines;
  for (const Assumption& a : result.assumptions) lines.push_back({a.what, a.taken, a.why, a.give});
  page->Table({"", "taken", "because", "to give your own"}, lines);
}

void AddFlightTable(HtmlPage* page, const AnalyzeResult& result) {
  if (!result.flight) {
    page->Paragraph("Flight table not computed: " + result.flight_problem);
    return;
  }
  const FlightResult& flight = *result.flight;
  std::vector<std::string> header = {"limit", "window", "threshold", "windows",
                                     "x %",   "y %",    "z %",       "per-axis %"};
  if (flight.vector_criterion) header.push_back("vector %");
  std::vector<std::vector<std::string>> rows;
  for (const FlightRow& row : flight.rows) {
    if (row.too_few_samples) {
      rows.push_back({Cm(row.limit_m), Fmt("%g ms", row.window_s * 1e3),
                      Fmt("%.1f\"", row.threshold_arcsec), "too few samples"});
      continue;
    }
    std::vector<std::string> cells = {Cm(row.limit_m),
                                      Fmt("%g ms", row.window_s * 1e3),
                                      Fmt("%.1f\"", row.threshold_arcsec),
                                      std::to_string(row.windows),
                                      Fmt("%.2f", row.flagged_percent_axis[0]),
                                      Fmt("%.2f", row.flagged_percent_axis[1]),
                                      Fmt("%.2f", row.flagged_percent_axis[2]),
                                      Fmt("%.2f", row.flagged_percent)};
    if (flight.vector_criterion) cells.push_back(Fmt("%.2f", row.flagged_percent_vector));
    rows.push_back(std::move(cells));
  }
  page->Table(header, rows);
  // The table's closing lines (rows refused, which criterion flags more) as the text prints them.
  std::istringstream text(FlightTable(flight));
  for (std::string line; std::getline(text, line);) {
    if (line.rfind("criteria:", 0) == 0 || line.rfind("flight:", 0) == 0 ||
        line.rfind("too few samples", 0) == 0)
      page->Paragraph(line);
  }
}

void AddImageTable(HtmlPage* page, const AnalyzeResult& result) {
  std::vector<std::string> header = {"image",        "t (s)",        "D paper (cm)",
                                     "D full (cm)",  "D full (px)",  "range x (\")",
                                     "range y (\")", "range z (\")", "axis"};
  for (double limit : result.limits_m) header.push_back("> " + Cm(limit));
  std::vector<std::vector<std::string>> rows;
  for (const ImageResult& image : result.images) {
    std::vector<std::string> cells = {image.name, Fmt("%.3f", image.t_ns * 1e-9)};
    if (!image.judged()) {
      cells.push_back(image.in_trace ? "too few samples in the readout" : "outside the log");
    } else {
      cells.insert(cells.end(),
                   {Fmt("%.2f", image.d_paper_m * 100), Fmt("%.2f", image.d_full_m * 100),
                    Fmt("%.2f", image.d_full_px), Fmt("%.1f", image.range_arcsec[0]),
                    Fmt("%.1f", image.range_arcsec[1]), Fmt("%.1f", image.range_arcsec[2]),
                    kAxisNames[image.dominant_axis]});
      for (size_t l = 0; l < result.limits_m.size(); ++l) {
        cells.push_back(image.flagged[l] ? "flagged" : "ok");
      }
    }
    rows.push_back(std::move(cells));
  }
  page->Table(header, rows);
}

// |d| heatmap of one frame under the full model, over the rendered scene when there is one.
cv::Mat WorstImagePicture(const FrameMotion& frame, const RigModel& rig,
                          const AnalyzeReportOptions& report) {
  const PinholeCamera& camera = rig.camera;
  const cv::Size scene_size =
      report.scene.empty() ? cv::Size(camera.width, camera.height) : report.scene.size();
  const FrameGeometry geometry(camera, rig.altitude_m, frame, scene_size);
  cv::Mat picture = DisplacementHeatmap(DisplacementField(geometry));
  if (!report.scene.empty()) {
    cv::Mat rendered;
    RenderFrame(report.scene, geometry, Interpolation::kBilinear, &rendered);
    cv::Mat frame = picture(cv::Rect(0, 0, camera.width, camera.height));
    cv::addWeighted(ToRgb8(rendered), 0.5, frame, 0.5, 0.0, frame);
  }
  const double scale = static_cast<double>(report.picture_width_px) / picture.cols;
  if (scale < 1.0) cv::resize(picture, picture, cv::Size(), scale, scale, cv::INTER_AREA);
  return picture;
}

void AddWorstImages(HtmlPage* page, const RigModel& rig, const AnalyzeResult& result,
                    const AnalyzeReportOptions& report) {
  const std::vector<AnalyzePlots::WorstImage>& worst = result.plots->worst;
  if (worst.empty()) {
    page->Paragraph(result.verdict.images_in_trace == 0
                        ? "No image lies inside the log."
                        : "No pictures of the worst images asked for.");
    return;
  }
  page->Paragraph(
      "Expected displacement |d| of every pixel from where a global shutter would have put it "
      "(the full model: the renderer's geometry of the declared camera), colour scale in pixels" +
      std::string(report.scene.empty() ? "."
                                       : ", blended over " +
                                             (report.scene_name.empty() ? std::string("the scene")
                                                                        : report.scene_name) +
                                             " rendered through the same rolling-shutter frame."));
  for (const AnalyzePlots::WorstImage& kept : worst) {
    const ImageResult* image = &result.images.at(kept.image);
    page->Image(WorstImagePicture(kept.frame, rig, report),
                image->name + " at " + Fmt("%.2f", image->t_ns * 1e-9) + " s: D full " +
                    Fmt("%.1f", image->d_full_m * 100) + " cm (" + Fmt("%.1f", image->d_full_px) +
                    " px), D paper " + Fmt("%.1f", image->d_paper_m * 100) + " cm, axis " +
                    kAxisNames[image->dominant_axis]);
  }
}

}  // namespace

void AnalyzeReportOptions::Check() const {
  SHUTTERLAB_CHECK(scene.empty() || (scene.depth() == CV_8U && scene.channels() == 3))
      << "the report's scene must be an 8-bit RGB image";
  SHUTTERLAB_CHECK(histogram_bins >= 2) << "histogram_bins must be >= 2";
  SHUTTERLAB_CHECK(histogram_quantile > 0.0 && histogram_quantile <= 1.0)
      << "histogram_quantile must be in (0, 1] (got " << histogram_quantile << ")";
  SHUTTERLAB_CHECK(picture_width_px >= 64) << "picture_width_px must be >= 64";
}

HtmlPage AnalyzeReportPage(const AnalyzeOptions& options, const AnalyzeResult& result,
                           const AnalyzeReportOptions& report) {
  report.Check();
  SHUTTERLAB_CHECK(result.plots != nullptr)
      << "the report draws what the analysis kept for it: give it a result of Analyze or "
         "AnalyzeStream with AnalyzeOptions::plots";
  RigModel rig = options.rig;
  rig.altitude_m = result.altitude_m;
  HtmlPage page("Rolling-shutter flight report" +
                (report.log_name.empty() ? std::string() : ": " + report.log_name));
  page.Paragraph(result.verdict.line);

  page.Heading("Source and camera");
  const PinholeCamera& cam = rig.camera;
  std::string bias;
  if (result.bias_from_still) {
    bias = (result.bias_segment_given ? "the segment given, " : "still segment ") +
           Fmt("%.2f", result.still_segment.begin_s) + "-" +
           Fmt("%.2f", result.still_segment.end_s) + " s after the first sample";
  } else {
    bias = result.bias_estimated ? "none found: zero bias assumed" : "zero (not estimated)";
  }
  const Eigen::Vector3d b = result.bias_rad_s * kDegPerRad;
  std::vector<std::vector<std::string>> rows = {
      {"log", report.log_name},
      {"format", result.format},
      {"gyro", result.gyro_source},
      {"samples", std::to_string(result.samples)},
      {"duration", Fmt("%.1f s", result.duration_s)},
      {"rate", Fmt("%.1f Hz", result.rate_hz)},
      {"gaps", std::to_string(result.gaps)},
      {"bias", bias},
      {"bias (deg/s, camera x y z)",
       Fmt("%.4f", b.x()) + " " + Fmt("%.4f", b.y()) + " " + Fmt("%.4f", b.z())},
      {"camera", std::to_string(cam.width) + "x" + std::to_string(cam.height) + ", f " +
                     Fmt("%.0f px", 0.5 * (cam.fx + cam.fy)) +
                     (cam.HasDistortion() ? ", lens distortion" : "")},
      {"readout", Fmt("%g ms", result.readout_s * 1e3)},
      {"altitude", Fmt("%g m", result.altitude_m) + " (" + AltitudeText(result) + ")"},
      {"ground sample", Fmt("%.2f cm/px", 100.0 * result.altitude_m / (0.5 * (cam.fx + cam.fy)))},
      {"triggers", result.trigger_source},
      {"images", std::to_string(result.images.size()) + " (" +
                     std::to_string(result.verdict.images_in_trace) + " inside the log" +
                     (result.verdict.images_too_few_samples > 0
                          ? ", " + std::to_string(result.verdict.images_too_few_samples) +
                                " more with too few samples in their readout"
                          : "") +
                     ")"}};
  // Where the camera and its readout came from, beside them, when the caller says it.
  if (!report.camera_source.empty())
    rows.insert(rows.begin() + 11, {"camera from", report.camera_source});
  page.Table({"", ""}, rows);
  page.RawHtml(CameraAxesFigure());

  AddAssumptions(&page, result);

  if (!result.log_warnings.empty()) {
    page.Heading("What the log lost");
    page.Paragraph("The reader could not read or trust everything in the log:");
    std::vector<std::vector<std::string>> lines;
    for (const LogWarning& w : result.log_warnings) {
      lines.push_back({w.kind, w.count ? std::to_string(*w.count) : "",
                       w.t_s ? Fmt("%.3f s", *w.t_s) : "", w.message});
    }
    page.Table({"kind", "count", "first at", "what"}, lines);
  }

  page.Heading("Rotation during the flight");
  if (!result.flight || !result.flight->summary || result.flight->summary->windows == 0) {
    page.Paragraph(
        "Flagged windows are not shaded: the flight table's readout windows were not analysed.");
  }
  AddRateAndAngleCharts(&page, *result.plots, result);

  page.Heading("Distortion per image");
  page.Paragraph(
      "D paper: altitude x tan(largest per-axis angle range within the readout). D full: "
      "docs/FORMATS.md's frame distortion under the declared camera (rotation, lens, velocity) on "
      "a " +
      std::to_string(kGridStepPx) + " px grid. Dashed lines: the limits.");
  AddDistortionChart(&page, result);

  page.Heading("Readout windows (flight table)");
  AddFlightTable(&page, result);
  if (result.flight && result.flight->summary && result.flight->summary->windows > 0) {
    AddWindowHistograms(&page, *result.flight, report);
  }

  page.Heading("Gyro noise");
  AddAllan(&page, result);

  page.Heading("Images");
  AddImageTable(&page, result);

  page.Heading("Worst images");
  AddWorstImages(&page, rig, result, report);
  return page;
}

}  // namespace shutterlab
