// validate --out DIR: the residual pictures, the row profile and the page (validate_report.h).

#include "estimate/paper/analyze.h"
#include "estimate/report/html_report.h"
#include "estimate/report/loop_json.h"
#include "estimate/report/validate_report.h"
#include "estimate/report/validate_verdict.h"
#include "io/frames_csv.h"
#include "io/image_io.h"
#include "model/effect_io.h"
#include "render/pictures.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/text_file.h"

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <sstream>
#include <utility>

namespace shutterlab {

namespace fs = std::filesystem;
namespace {

// A small line chart (8-bit RGB): each series over x, a legend, axes with min/max labels.
cv::Mat LineChart(const std::vector<double>& x, const std::vector<std::vector<double>>& series,
                  const std::vector<std::string>& labels, const std::vector<cv::Scalar>& colours,
                  const std::string& title, const std::string& x_label) {
  const int width = 900, height = 420, left = 70, right = 20, top = 40, bottom = 50;
  cv::Mat chart(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  double lo = 0.0, hi = 0.0;
  for (const auto& s : series) {
    for (double y : s) {
      if (!std::isfinite(y)) continue;
      lo = std::min(lo, y);
      hi = std::max(hi, y);
    }
  }
  if (hi - lo < 1e-9) hi = lo + 1.0;
  const double x0 = x.empty() ? 0.0 : x.front(), x1 = x.empty() ? 1.0 : std::max(x.back(), x0 + 1);
  auto to_px = [&](double xv, double yv) {
    return cv::Point(left + static_cast<int>((xv - x0) / (x1 - x0) * (width - left - right)),
                     top + static_cast<int>((hi - yv) / (hi - lo) * (height - top - bottom)));
  };
  const cv::Scalar grey(120, 120, 120);
  cv::rectangle(chart, to_px(x0, hi), to_px(x1, lo), grey, 1);
  cv::line(chart, to_px(x0, 0.0), to_px(x1, 0.0), cv::Scalar(200, 200, 200), 1);
  const auto text = [&](const std::string& s, cv::Point at, double scale = 0.45) {
    cv::putText(chart, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  };
  text(title, cv::Point(left, 25), 0.6);
  text(FormatNumber("%.3g", hi), cv::Point(5, top + 5));
  text(FormatNumber("%.3g", lo), cv::Point(5, height - bottom));
  text("0", cv::Point(left - 15, to_px(x0, 0.0).y + 5));
  text(FormatNumber("%g", x0), cv::Point(left, height - bottom + 20));
  text(FormatNumber("%g", x1), cv::Point(width - right - 40, height - bottom + 20));
  text(x_label, cv::Point(width / 2 - 40, height - bottom + 20));
  for (size_t s = 0; s < series.size(); ++s) {
    for (size_t i = 1; i < x.size(); ++i) {
      if (!std::isfinite(series[s][i - 1]) || !std::isfinite(series[s][i])) continue;
      cv::line(chart, to_px(x[i - 1], series[s][i - 1]), to_px(x[i], series[s][i]), colours[s], 2,
               cv::LINE_AA);
    }
    const cv::Point at(left + 10 + static_cast<int>(s) * 200, height - bottom + 38);
    cv::line(chart, at + cv::Point(0, -4), at + cv::Point(20, -4), colours[s], 2);
    text(labels[s], at + cv::Point(25, 0));
  }
  return chart;
}

// Residual pictures inlined in validate.html; the rest stay files beside it.
constexpr size_t kMaxPagePictures = 24;

// The measure grid step, px: the spacing of the first frame's first residual points (kGridStepPx
// when they do not tell).
int ResidualGridStepPx(const ValidationResult& result) {
  int step = kGridStepPx;
  for (const FrameValidation& f : result.frames) {
    for (size_t k = 1; k < f.residuals.size() && k < 4; ++k) {
      const float du = std::abs(f.residuals[k].u - f.residuals[k - 1].u);
      if (du >= 1) step = std::max(1, static_cast<int>(std::lround(du)));
    }
    break;
  }
  return step;
}

// Every frame's picture goes to a file; the page inlines only the kMaxPagePictures frames with the
// largest residual before (a 360-pair clip would make a page of 85 MB). Per frame: whether it is
// on the page.
std::vector<bool> FramesOnPage(const ValidationResult& result) {
  std::vector<size_t> by_residual(result.frames.size());
  for (size_t i = 0; i < by_residual.size(); ++i) by_residual[i] = i;
  std::stable_sort(by_residual.begin(), by_residual.end(), [&](size_t a, size_t b) {
    return result.frames[a].before.rms_px > result.frames[b].before.rms_px;
  });
  by_residual.resize(std::min(by_residual.size(), kMaxPagePictures));
  std::vector<bool> on_page(result.frames.size(), false);
  for (size_t i : by_residual) on_page[i] = true;
  return on_page;
}

// One colour scale for all panels of a frame: the largest residual before (robust: the 99th
// percentile, so one bad match does not wash the picture out), px.
double PanelScalePx(const FrameValidation& f) {
  std::vector<float> lengths;
  for (const PointResidual& r : f.residuals)
    lengths.push_back(std::hypot(r.before_dx, r.before_dy));
  double max_px = f.before.max_px;
  if (!lengths.empty()) {
    const size_t at = std::min(lengths.size() - 1, static_cast<size_t>(0.99 * lengths.size()));
    std::nth_element(lengths.begin(), lengths.begin() + at, lengths.end());
    max_px = lengths[at];
  }
  return std::max(max_px, 1e-3);
}

// The colours of the points a loop left out (R, G, B), and their legend for the page.
const cv::Vec3b kCameraFixedColour(150, 150, 150), kMovingColour(230, 40, 200);
const char* kLeftOutLegend =
    "Grey cells: points in a region that moves with the camera; magenta: points that no single "
    "camera motion of their frame explains (with translation: off their epipolar line). Those "
    "points were left out of the fit; the colour scale shows the others.";

// Paints the left-out cells (marks: a PointStatus per pixel of the shown panel) over a heat map.
void PaintLeftOut(const cv::Mat& marks, cv::Mat* heat) {
  for (int y = 0; y < marks.rows && y < heat->rows; ++y) {
    const uchar* m = marks.ptr<uchar>(y);
    cv::Vec3b* h = heat->ptr<cv::Vec3b>(y);
    for (int x = 0; x < marks.cols && x < heat->cols; ++x) {
      const PointStatus s = static_cast<PointStatus>(m[x]);
      if (s == PointStatus::kCameraFixed) h[x] = kCameraFixedColour;
      if (s == PointStatus::kMoving || s == PointStatus::kOffEpipolar) h[x] = kMovingColour;
    }
  }
}

// A frame's residual picture: one cell per measure grid step (`cells` of `step_px`), before and
// after (and, for a video, with translation) side by side on one colour scale.
cv::Mat ResidualPanel(const FrameValidation& f, bool video, int step_px, const cv::Size& cells) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat before(cells, CV_32FC2, cv::Scalar(nan, nan)), after = before.clone(),
                                                         translation = before.clone();
  // Points a loop left out (PointStatus): drawn in their own colour over the heat map.
  cv::Mat status(cells, CV_8U, cv::Scalar(0)), translation_status = status.clone();
  for (const PointResidual& r : f.residuals) {
    // Point (k, j) lies in [k step, (k + 1) step) (measure.cc moves it off the cell's centre).
    const int c = std::clamp(static_cast<int>(r.u / step_px), 0, cells.width - 1);
    const int w = std::clamp(static_cast<int>(r.v / step_px), 0, cells.height - 1);
    before.at<cv::Vec2f>(w, c) = cv::Vec2f(r.before_dx, r.before_dy);
    after.at<cv::Vec2f>(w, c) = cv::Vec2f(r.after_dx, r.after_dy);
    translation.at<cv::Vec2f>(w, c) = cv::Vec2f(r.translation_dx, r.translation_dy);
    status.at<uchar>(w, c) = static_cast<uchar>(r.status);
    translation_status.at<uchar>(w, c) = static_cast<uchar>(r.translation_status);
  }
  // Display at about 640 px wide, nearest neighbour so each cell stays one measured point.
  const double scale = 640.0 / cells.width;
  const cv::Size shown(640, std::max(1, static_cast<int>(std::lround(cells.height * scale))));
  const double max_px = PanelScalePx(f);
  std::vector<cv::Mat> shown_panels;
  std::vector<std::string> labels = {
      "residual before: rms " + FormatNumber("%.3f", f.before.rms_px) + " px",
      (video ? "rotation only, after: rms " : "after: rms ") +
          FormatNumber("%.3f", f.after.rms_px) + " px"};
  std::vector<cv::Mat> fields = {before, after};
  if (video) {
    fields.push_back(translation);
    labels.push_back("with translation (across): rms " +
                     FormatNumber("%.3f", f.translation_after.rms_px) + " px");
  }
  for (size_t k = 0; k < fields.size(); ++k) {
    cv::resize(fields[k], fields[k], shown, 0, 0, cv::INTER_NEAREST);
    cv::Mat heat = DisplacementHeatmap(fields[k], max_px);
    cv::Mat marks;
    cv::resize(k == 2 ? translation_status : status, marks, shown, 0, 0, cv::INTER_NEAREST);
    PaintLeftOut(marks, &heat);
    shown_panels.push_back(heat);
  }
  return SideBySide(shown_panels, labels);
}

// Writes every frame's residual picture (DIR/NNNN_residual.png, appended to *written); returns
// (frame index, picture) of those on the page, in frame order. The pictures are drawn and written
// in parallel (each frame's file is its own; a karma clip's 360 take 9 s of CPU), collected in
// frame order; the first error is thrown after all have finished.
std::vector<std::pair<size_t, cv::Mat>> WriteResidualPictures(const std::string& dir,
                                                              const ValidationResult& result,
                                                              int step_px,
                                                              std::vector<std::string>* written) {
  const int width = result.declared.camera.width, height = result.declared.camera.height;
  const cv::Size cells((width + step_px - 1) / step_px, (height + step_px - 1) / step_px);
  const std::vector<bool> on_page = FramesOnPage(result);
  const size_t count = result.frames.size();
  std::vector<std::string> paths(count);
  std::vector<cv::Mat> shown(count);
  std::vector<std::exception_ptr> errors(count);
  cv::parallel_for_(cv::Range(0, static_cast<int>(count)), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      try {
        const FrameValidation& f = result.frames[i];
        const cv::Mat panel = ResidualPanel(f, result.video, step_px, cells);
        paths[i] = (fs::path(dir) / (FrameName(f.frame) + "_residual.png")).string();
        WriteImage(paths[i], panel);
        if (on_page[i]) shown[i] = panel;
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  });
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  std::vector<std::pair<size_t, cv::Mat>> panels;
  for (size_t frame_index = 0; frame_index < count; ++frame_index) {
    written->push_back(paths[frame_index]);
    if (on_page[frame_index]) panels.emplace_back(frame_index, shown[frame_index]);
  }
  return panels;
}

// Per-row profile over all frames, per band of `step` rows: its centre row, px, the points in it,
// and 7 series: mean residual dx, dy and RMS before (0-2), after (3-5), RMS with translation (6).
struct RowProfile {
  std::vector<double> row, count;
  std::vector<std::vector<double>> mean;
};

RowProfile ProfileRows(const ValidationResult& result, int step_px) {
  const int height = result.declared.camera.height;
  const int bands = (height + step_px - 1) / step_px;
  std::vector<double> sum[7], count(bands, 0.0), translation_count(bands, 0.0);
  for (auto& s : sum) s.assign(bands, 0.0);
  for (const FrameValidation& f : result.frames) {
    for (const PointResidual& r : f.residuals) {
      const int b = std::clamp(static_cast<int>(r.v) / step_px, 0, bands - 1);
      count[b] += 1;
      sum[0][b] += r.before_dx;
      sum[1][b] += r.before_dy;
      sum[2][b] += r.before_dx * r.before_dx + r.before_dy * r.before_dy;
      sum[3][b] += r.after_dx;
      sum[4][b] += r.after_dy;
      sum[5][b] += r.after_dx * r.after_dx + r.after_dy * r.after_dy;
      if (std::isfinite(r.translation_dx) && std::isfinite(r.translation_dy)) {
        sum[6][b] += r.translation_dx * r.translation_dx + r.translation_dy * r.translation_dy;
        translation_count[b] += 1;
      }
    }
  }
  RowProfile profile;
  profile.row.resize(bands);
  profile.count = count;
  profile.mean.assign(7, std::vector<double>(bands));
  for (int b = 0; b < bands; ++b) {
    profile.row[b] = std::min(height - 1.0, (b + 0.5) * step_px);
    for (int s = 0; s < 7; ++s) {
      const double n = s == 6 ? translation_count[b] : count[b];
      const double m = n > 0 ? sum[s][b] / n : std::numeric_limits<double>::quiet_NaN();
      profile.mean[s][b] = (s == 2 || s == 5 || s == 6) ? std::sqrt(m) : m;
    }
  }
  return profile;
}

// DIR/residual_rows.csv and DIR/residual_rows.png (the before and after charts), appended to
// *written.
void WriteRowProfile(const std::string& dir, bool video, const RowProfile& profile,
                     std::vector<std::string>* written) {
  const std::vector<std::vector<double>>& mean = profile.mean;
  std::string csv =
      "row_px,points,before_dx_px,before_dy_px,before_rms_px,after_dx_px,"
      "after_dy_px,after_rms_px";
  csv += video ? ",translation_rms_px\n" : "\n";
  const int columns = video ? 7 : 6;
  for (size_t b = 0; b < profile.row.size(); ++b) {
    csv += FormatNumber("%.1f", profile.row[b]) + "," +
           std::to_string(static_cast<long long>(profile.count[b]));
    for (int s = 0; s < columns; ++s) {
      csv += "," + (std::isfinite(mean[s][b]) ? FormatNumber("%.5f", mean[s][b]) : "");
    }
    csv += "\n";
  }
  const std::string csv_path = (fs::path(dir) / "residual_rows.csv").string();
  WriteFileAtomically(csv_path, csv);
  written->push_back(csv_path);
  // Colours in R, G, B order (image_io writes the file's channel order).
  const cv::Mat chart_before =
      LineChart(profile.row, {mean[0], mean[1], mean[2]}, {"mean dx", "mean dy", "rms"},
                {cv::Scalar(31, 119, 180), cv::Scalar(255, 127, 14), cv::Scalar(60, 60, 60)},
                "residual per row, before (declared model), px", "image row");
  const cv::Mat chart_after =
      LineChart(profile.row, {mean[3], mean[4], mean[5]}, {"mean dx", "mean dy", "rms"},
                {cv::Scalar(31, 119, 180), cv::Scalar(255, 127, 14), cv::Scalar(60, 60, 60)},
                "residual per row, after (declared + identified effects), px", "image row");
  cv::Mat charts;
  cv::vconcat(chart_before, chart_after, charts);
  const std::string chart_path = (fs::path(dir) / "residual_rows.png").string();
  WriteImage(chart_path, charts);
  written->push_back(chart_path);
}

// The page's chart of the row profile: RMS and mean residual per row band, before and after.
Chart RowsChart(bool video, const RowProfile& profile) {
  const std::vector<std::vector<double>>& mean = profile.mean;
  Chart rows_chart;
  rows_chart.title = "RMS residual per row band, before and after the loop";
  rows_chart.x_label = "image row";
  rows_chart.y_label = "px";
  rows_chart.x = profile.row;
  rows_chart.series = {
      ChartSeries("before rms", mean[2]),     ChartSeries("after rms", mean[5]),
      ChartSeries("before mean dx", mean[0]), ChartSeries("before mean dy", mean[1]),
      ChartSeries("after mean dx", mean[3]),  ChartSeries("after mean dy", mean[4])};
  if (video) {
    rows_chart.series.push_back(ChartSeries("with translation rms (across the line)", mean[6]));
  }
  return rows_chart;
}

// The page's per-frame charts: RMS residual per frame (per pair for a video) and, for a still
// dataset, the distortion D on the ground (a video has no global-shutter reference for it).
void AddFrameCharts(const ValidationResult& result, HtmlPage* page) {
  Chart frames_chart, d_chart;
  frames_chart.title = "RMS residual per frame";
  frames_chart.kind = d_chart.kind = ChartKind::kPoints;
  frames_chart.x_label = d_chart.x_label = "frame";
  frames_chart.integer_x = d_chart.integer_x = true;
  frames_chart.y_label = "px";
  d_chart.title = "frame distortion D on the ground";
  d_chart.y_label = "cm";
  std::vector<double> ids, before_rms, after_rms, translation_rms, noise, d_meas, d_full, d_paper;
  for (const FrameValidation& f : result.frames) {
    ids.push_back(static_cast<double>(f.frame));
    before_rms.push_back(f.before.rms_px);
    after_rms.push_back(f.after.rms_px);
    translation_rms.push_back(f.translation_after.rms_px);
    noise.push_back(f.noise_px);
    d_meas.push_back(100 * f.d_meas_m);
    d_full.push_back(100 * f.d_full_m);
    d_paper.push_back(100 * f.d_paper_m);
  }
  // uPlot wants x ascending: frames.csv lists frames in any order.
  std::vector<size_t> order(ids.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return ids[a] < ids[b]; });
  const auto sorted = [&](const std::vector<double>& v) {
    std::vector<double> out;
    for (size_t i : order) out.push_back(v[i]);
    return out;
  };
  frames_chart.x = d_chart.x = sorted(ids);
  frames_chart.series = {ChartSeries("before", sorted(before_rms)),
                         ChartSeries("after", sorted(after_rms)),
                         ChartSeries("measurement noise", sorted(noise))};
  d_chart.series = {ChartSeries("measured", sorted(d_meas)),
                    ChartSeries("full model", sorted(d_full)),
                    ChartSeries("paper's model", sorted(d_paper))};
  if (result.video) {
    frames_chart.title = "RMS residual per pair (x: the later frame)";
    frames_chart.series.insert(
        frames_chart.series.begin() + 2,
        ChartSeries("with translation (across the line)", sorted(translation_rms)));
    // The distance across the line is one component: its noise is noise_px / sqrt(2).
    std::vector<double> component_noise = sorted(noise);
    for (double& v : component_noise) v /= std::sqrt(2.0);
    frames_chart.series.push_back(ChartSeries("noise of one component", component_noise));
  }
  page->AddChart(frames_chart);
  // D needs a global-shutter reference: video datasets have none.
  if (!result.video) page->AddChart(d_chart);
}

// The screening drawn over the first frame's image (the later frame of the first pair): masked
// pixels tinted blue, the camera-fixed region red, that frame's left-out points magenta. Empty when
// the image cannot be read (the dataset moved since).
cv::Mat ScreeningPicture(const ValidationResult& result) {
  if (result.frames.empty()) return cv::Mat();
  const FrameValidation& f = result.frames.front();
  cv::Mat rgb;
  try {
    rgb = ToRgb8(ReadImage((fs::path(result.dataset) / f.image).string()));
  } catch (const std::exception&) {
    return cv::Mat();
  }
  if (rgb.cols != result.declared.camera.width || rgb.rows != result.declared.camera.height) {
    return cv::Mat();
  }
  const CameraFixedRegion& region = result.screen.region;
  for (int v = 0; v < rgb.rows; ++v) {
    cv::Vec3b* row = rgb.ptr<cv::Vec3b>(v);
    const uchar* mask = result.mask.empty() ? nullptr : result.mask.ptr<uchar>(v);
    for (int u = 0; u < rgb.cols; ++u) {
      const cv::Vec3b tint = mask != nullptr && mask[u] == 0                ? cv::Vec3b(40, 90, 230)
                             : !region.whole_image && region.Contains(u, v) ? cv::Vec3b(230, 40, 30)
                                                                            : row[u];
      row[u] = 0.45 * cv::Vec3f(tint) + 0.55 * cv::Vec3f(row[u]);
    }
  }
  const int radius = std::max(2, rgb.cols / 300);
  for (const PointResidual& r : f.residuals) {
    if (r.status == PointStatus::kMoving || r.translation_status == PointStatus::kOffEpipolar) {
      cv::circle(rgb, cv::Point(static_cast<int>(r.u), static_cast<int>(r.v)), radius,
                 cv::Scalar(230, 40, 200), cv::FILLED, cv::LINE_AA);
    }
  }
  return rgb;
}

// The camera-fixed region as a mask of the camera's size (white = use, black = the region), as
// --mask and camera.json's `mask` take it; all white when there is no region.
cv::Mat CameraFixedMask(const ValidationResult& result) {
  const CameraFixedRegion& region = result.screen.region;
  cv::Mat mask(result.declared.camera.height, result.declared.camera.width, CV_8U, cv::Scalar(255));
  if (region.whole_image) return mask;
  for (int v = 0; v < mask.rows; ++v) {
    uchar* row = mask.ptr<uchar>(v);
    for (int u = 0; u < mask.cols; ++u) row[u] = region.Contains(u, v) ? 0 : 255;
  }
  return mask;
}

// The camera-fixed check's evidence over the first frame's image: each cell with a testable
// measurement tinted from green (it moved with the scene in every testable pair or frame) to red
// (it stayed in every one), cells with none left untinted (unmeasured), the region's cells
// crossed. Empty when the image cannot be read.
cv::Mat CameraFixedEvidence(const ValidationResult& result) {
  if (result.frames.empty()) return cv::Mat();
  cv::Mat rgb;
  try {
    rgb = ToRgb8(ReadImage((fs::path(result.dataset) / result.frames.front().image).string()));
  } catch (const std::exception&) {
    return cv::Mat();
  }
  const CameraFixedRegion& region = result.screen.region;
  if (rgb.cols != result.declared.camera.width || rgb.rows != result.declared.camera.height ||
      region.fixed.empty()) {
    return cv::Mat();
  }
  const int step = region.step_px;
  for (int r = 0; r < region.rows; ++r) {
    for (int c = 0; c < region.cols; ++c) {
      const size_t k = static_cast<size_t>(r) * region.cols + c;
      const cv::Rect cell =
          cv::Rect(c * step, r * step, step, step) & cv::Rect(0, 0, rgb.cols, rgb.rows);
      cv::Mat view = rgb(cell);
      if (region.testable[k] > 0) {
        const double stayed = static_cast<double>(region.still[k]) / region.testable[k];
        const cv::Vec3f tint(static_cast<float>(255 * stayed),
                             static_cast<float>(200 * (1 - stayed)), 40.0f);
        view.forEach<cv::Vec3b>(
            [&](cv::Vec3b& p, const int*) { p = cv::Vec3b(0.55 * tint + 0.45 * cv::Vec3f(p)); });
      }
      if (region.fixed[k] && !region.whole_image) {
        cv::line(rgb, cell.tl(), cell.br() - cv::Point(1, 1), cv::Scalar(255, 255, 255));
        cv::line(rgb, {cell.x, cell.br().y - 1}, {cell.br().x - 1, cell.y},
                 cv::Scalar(255, 255, 255));
      }
    }
  }
  return rgb;
}

// The verdict in a box (validate_verdict.h): what the data show, how sure, what to do.
void AddVerdict(const ValidationResult& result, HtmlPage* page) {
  const ValidationVerdict verdict = MakeVerdict(result);
  page->BeginBox(VerdictLevelName(verdict.level));
  page->Heading("Verdict", 2);
  page->Paragraph(verdict.headline);
  if (!verdict.findings.empty()) {
    page->Heading("What the data show", 4);
    page->List(verdict.findings);
  }
  page->Heading("How sure", 4);
  page->Paragraph(verdict.certainty);
  if (!verdict.actions.empty()) {
    page->Heading("What to do", 4);
    page->List(verdict.actions);
  }
  page->EndBox();
}

// What the screening left out: the picture and its numbers.
void AddScreening(const ValidationResult& result, HtmlPage* page) {
  const PointScreen& s = result.screen;
  page->Heading("What was left out before the fit");
  const auto percent = [](double share) { return FormatNumber("%.1f", 100 * share) + " %"; };
  std::vector<std::vector<std::string>> rows = {
      {"mask (camera.json, --mask)", result.mask.empty() ? "none" : result.mask_description},
      {"region that moves with the camera",
       s.region.whole_image ? "none: the whole image stays (see the image against the gyro)"
                            : percent(s.camera_fixed_share) + " of the points, " +
                                  std::to_string(s.region.cells_fixed) + " of " +
                                  std::to_string(s.region.cells_testable) + " cells of " +
                                  std::to_string(s.region.step_px) + " px"},
      {"moving on their own (no single camera motion explains them)", percent(s.moving_share)}};
  if (result.video) {
    rows.push_back(
        {"off their pair's epipolar geometry (translation model)", percent(s.off_epipolar_share)});
    if (result.axes_not_following) {
      rows.push_back(
          {"the image against the gyro, per camera axis (before the image's own "
           "rotation was taken for the axes that do not follow)",
           result.axes_not_following->verdict});
    }
    rows.push_back({"the image against the gyro", s.gyro_follow.verdict});
  }
  page->Table({"what", "left out"}, rows, /*text=*/true);
  // The overlay of what was left out only where something was: an empty one says nothing. The
  // camera-fixed check's evidence is shown either way (it says why nothing was left out).
  const bool left_out_any = !result.mask.empty() ||
                            (!s.region.whole_image && s.region.cells_fixed > 0) ||
                            s.moving_share > 0 || s.off_epipolar_share > 0;
  const cv::Mat picture = left_out_any ? ScreeningPicture(result) : cv::Mat();
  if (!picture.empty()) {
    page->Image(picture, "frame " + FrameName(result.frames.front().frame) +
                             ": red, a region that moves with the camera; blue, masked; magenta, "
                             "points moving on their own");
  }
  const cv::Mat evidence = CameraFixedEvidence(result);
  if (!evidence.empty()) {
    page->Image(evidence,
                "the camera-fixed check's evidence (corner tracks, cells of " +
                    std::to_string(s.region.step_px) +
                    " px): green, measured moving with the scene in every testable pair; red, "
                    "staying with the camera in every one; untinted, nothing trustworthy measured "
                    "there; crossed, the region left out (camera_fixed_evidence.png; "
                    "camera_fixed_mask.png beside this page, white = use, is the region as a "
                    "--mask)");
  }
}

// The effects of each loop, their standard errors and where those came from.
void AddEffectsTable(const ValidationResult& result, HtmlPage* page) {
  std::vector<std::pair<std::string, const LoopResult*>> loops = {
      {result.video ? "rotation only" : "loop", &result.loop}};
  if (result.video) loops.push_back({"with each pair's translation", &result.translation_loop});
  std::vector<std::vector<std::string>> rows;
  for (const auto& [name, loop] : loops) {
    for (const IdentifiedEffect& e : loop->effects) {
      const EffectSpec& spec = Spec(e.effect);
      rows.push_back(
          {name, spec.name, Rounded(EffectValueToJson(e.value)).dump(),
           e.stderr_withheld.empty() ? Rounded(EffectValueToJson(e.stderr_value)).dump()
                                     : "withheld: " + e.stderr_withheld,
           spec.unit,
           std::string(CovarianceKindName(e.stderr_from)) + " over " + std::to_string(e.clusters),
           FormatNumber("%.3f", e.after.rms_px)});
    }
    rows.push_back({name, loop->effects.empty() ? "(no effect)" : "after", "", "", "", "",
                    FormatNumber("%.3f", loop->after.rms_px) +
                        (loop->unexplained ? " (unexplained)" : " (explained)")});
  }
  page->Heading("Effects found");
  page->Table({"model", "effect", "value", "standard error", "unit", "standard error from",
               "rms after, px"},
              rows);
  if (!result.claims.empty()) {
    std::vector<std::vector<std::string>> claims;
    for (const ClaimCheck& c : result.claims) claims.push_back({c.claim, c.status, c.verdict});
    page->Heading("The source's claims", 3);
    page->Table({"claim", "status", "the data"}, claims, /*text=*/true);
  }
  std::vector<std::vector<std::string>> halves;
  for (const HalfCheck& h : result.halves) {
    for (const HalfAgreement& a : h.effects) {
      halves.push_back({Spec(a.effect).name,
                        Rounded(EffectValueToJson(a.first)).dump() + " ± " +
                            Rounded(EffectValueToJson(a.first_stderr)).dump(),
                        Rounded(EffectValueToJson(a.second)).dump() + " ± " +
                            Rounded(EffectValueToJson(a.second_stderr)).dump(),
                        a.determined ? FormatNumber("%.2f", a.distance) : "not determined",
                        a.agree ? "agree" : "DISAGREE"});
    }
  }
  if (!halves.empty()) {
    page->Heading("The two halves of the clip", 3);
    page->Table({"effect", "first half", "second half", "Mahalanobis distance", ""}, halves);
  }
}

// One row per frame or pair: points, what was left out, noise and residuals.
void AddFramesTable(const ValidationResult& result, HtmlPage* page) {
  std::vector<std::vector<std::string>> rows;
  for (const FrameValidation& f : result.frames) {
    std::vector<std::string> row = {
        f.previous ? FrameName(*f.previous) + " -> " + FrameName(f.frame) : FrameName(f.frame),
        std::to_string(f.points),
        std::to_string(f.camera_fixed),
        std::to_string(f.moving),
        FormatNumber("%.3f", f.noise_px),
        FormatNumber("%.3f", f.before.rms_px),
        FormatNumber("%.3f", f.after.rms_px)};
    if (result.video) {
      row.push_back(std::to_string(f.off_epipolar));
      row.push_back(FormatNumber("%.3f", f.translation_after.rms_px));
    } else {
      row.push_back(FormatNumber("%.2f", 100 * f.d_meas_m));
      row.push_back(FormatNumber("%.2f", 100 * f.d_paper_m));
    }
    rows.push_back(std::move(row));
  }
  std::vector<std::string> header = {result.video ? "pair" : "frame",
                                     "points",
                                     "camera-fixed",
                                     "moving",
                                     "noise, px",
                                     "rms before, px",
                                     result.video ? "rotation only after, px" : "rms after, px"};
  if (result.video) {
    header.push_back("off epipolar");
    header.push_back("with translation after, px");
  } else {
    header.push_back("D measured, cm");
    header.push_back("D paper's model, cm");
  }
  page->Heading(result.video ? "Every pair's numbers" : "Every frame's numbers", 3);
  page->Table(header, rows);
}

// DIR/validate.html: the verdict first, then what was left out, the effects, the charts and the
// residual pictures; the terminal's table last, closed.
std::string WriteValidationPage(const std::string& dir, const ValidationResult& result,
                                const RowProfile& profile,
                                const std::vector<std::pair<size_t, cv::Mat>>& panels) {
  HtmlPage page("shutterlab validate: " + result.dataset);
  AddVerdict(result, &page);
  AddScreening(result, &page);
  AddEffectsTable(result, &page);
  page.Heading("Residual per image row (all frames)");
  page.AddChart(RowsChart(result.video, profile));
  page.Heading(result.video ? "Per pair" : "Per frame");
  AddFrameCharts(result, &page);
  AddFramesTable(result, &page);
  page.Heading("Residual pictures");
  page.Paragraph(kLeftOutLegend);
  if (panels.size() < result.frames.size()) {
    page.Paragraph("The " + std::to_string(panels.size()) + " of " +
                   std::to_string(result.frames.size()) + (result.video ? " pairs" : " frames") +
                   " with the largest residual before; every one's picture is NNNN_residual.png "
                   "beside this page.");
  }
  for (const auto& [frame_index, panel] : panels) {
    const FrameValidation& f = result.frames[frame_index];
    page.Image(panel, f.previous
                          ? "pair " + FrameName(*f.previous) + " -> " + FrameName(f.frame) +
                                ": |residual| at the measured points: declared model, rotation "
                                "only after the loop, with each pair's translation"
                          : "frame " + FrameName(f.frame) +
                                ": |residual| at the measured points, before and after");
  }
  page.Details("The full table (as the terminal prints it)", ValidationReport(result));
  const std::string html_path = (fs::path(dir) / "validate.html").string();
  page.Write(html_path);
  return html_path;
}

}  // namespace

std::vector<std::string> WriteValidationPlots(const std::string& dir,
                                              const ValidationResult& result) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError(IoMessage(dir, 0, "cannot create folder: " + ec.message()));
  std::vector<std::string> written;
  const int step_px = ResidualGridStepPx(result);
  const std::vector<std::pair<size_t, cv::Mat>> panels =
      WriteResidualPictures(dir, result, step_px, &written);
  const RowProfile profile = ProfileRows(result, step_px);
  WriteRowProfile(dir, result.video, profile, &written);
  const std::string mask_path = (fs::path(dir) / "camera_fixed_mask.png").string();
  WriteImage(mask_path, CameraFixedMask(result));
  written.push_back(mask_path);
  const cv::Mat evidence = CameraFixedEvidence(result);
  if (!evidence.empty()) {
    written.push_back((fs::path(dir) / "camera_fixed_evidence.png").string());
    WriteImage(written.back(), evidence);
  }
  written.push_back(WriteValidationPage(dir, result, profile, panels));
  return written;
}

}  // namespace shutterlab
