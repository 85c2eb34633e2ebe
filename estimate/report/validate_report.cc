#include "estimate/report/validate_report.h"

#include "estimate/paper/analyze.h"
#include "estimate/report/analysis_json.h"
#include "estimate/report/html_report.h"
#include "estimate/report/loop_json.h"
#include "render/effect_io.h"
#include "render/frames_csv.h"
#include "render/image_io.h"
#include "render/pictures.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/text_file.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <utility>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;
constexpr const char* kAxisNames[3] = {"x", "y", "z"};

}  // namespace

nlohmann::json Rounded(const nlohmann::json& value) {
  if (value.is_number_float()) return std::stod(FormatNumber("%.4g", value.get<double>()));
  if (!value.is_structured()) return value;
  nlohmann::json out = value;
  for (auto& item : out.items()) item.value() = Rounded(item.value());
  return out;
}

void WriteLoopSummary(const LoopResult& loop, std::ostream& out) {
  out << "  before: rms " << FormatNumber("%.3f", loop.before.rms_px) << " px, max "
      << FormatNumber("%.3f", loop.before.max_px) << " px\n";
  for (const IdentifiedEffect& e : loop.effects) {
    out << "  + " << Spec(e.effect).name << " = " << Rounded(EffectValueToJson(e.value)).dump()
        << " +- " << Rounded(EffectValueToJson(e.stderr_value)).dump() << " " << Spec(e.effect).unit
        << " -> rms " << FormatNumber("%.3f", e.after.rms_px) << " px, max "
        << FormatNumber("%.3f", e.after.max_px) << " px";
    if (!e.ambiguous_with.empty()) {
      out << " (ambiguous with";
      for (Effect other : e.ambiguous_with) out << " " << Spec(other).name;
      out << ")";
    }
    out << "\n";
  }
  if (loop.effects.empty()) out << "  no effect added\n";
  out << "  after: rms " << FormatNumber("%.3f", loop.after.rms_px) << " px, max "
      << FormatNumber("%.3f", loop.after.max_px)
      << " px ("
      // The noise of the residual's own components (1 of 2 across an epipolar line).
      << FormatNumber("%.2f", loop.noise_px > 0 ? loop.after.rms_px / loop.noise_px /
                                                      std::sqrt(loop.residual_components / 2.0)
                                                : 0.0)
      << "x noise); " << (loop.unexplained ? "UNEXPLAINED residual remains" : "explained") << "\n";
}

namespace {

nlohmann::json StillValidationToJson(const ValidationResult& result) {
  nlohmann::json json = LoopToJson(result.loop, result.frames.size());
  json["dataset"] = result.dataset;
  json["limits_m"] = result.limits_m;
  nlohmann::json frames = nlohmann::json::array();
  for (const FrameValidation& f : result.frames) {
    nlohmann::json flags = nlohmann::json::object();
    for (size_t l = 0; l < result.limits_m.size(); ++l) {
      flags[LimitKey(result.limits_m[l])] = {{"measured", bool(f.flag_meas[l])},
                                             {"full", bool(f.flag_full[l])},
                                             {"paper", bool(f.flag_paper[l])}};
    }
    frames.push_back({{"frame", f.frame},
                      {"image", f.image},
                      {"t_gyro_s", f.t_gyro_s},
                      {"points", f.points},
                      {"measured_fraction", f.measured_fraction},
                      {"noise_px", f.noise_px},
                      {"D_meas_px", f.d_meas_px},
                      {"D_meas_m", f.d_meas_m},
                      {"D_full_px", f.d_full_px},
                      {"D_full_m", f.d_full_m},
                      {"D_paper_m", f.d_paper_m},
                      {"D_vector_m", f.d_vector_m},
                      {"D_centre_px", f.d_centre_px},
                      {"range_arcsec", f.range_arcsec},
                      {"dominant_axis", kAxisNames[f.dominant_axis]},
                      {"flagged", flags},
                      {"before", {{"rms_px", f.before.rms_px}, {"max_px", f.before.max_px}}},
                      {"after", {{"rms_px", f.after.rms_px}, {"max_px", f.after.max_px}}}});
  }
  json["frames_detail"] = frames;
  nlohmann::json confusion = nlohmann::json::array();
  for (size_t l = 0; l < result.confusion_paper.size(); ++l) {
    for (const auto& [model, c] : {std::pair{"paper", result.confusion_paper[l]},
                                   std::pair{"full", result.confusion_full[l]}}) {
      confusion.push_back({{"model", model},
                           {"limit_m", c.limit_m},
                           {"true_positive", c.true_positive},
                           {"false_positive", c.false_positive},
                           {"false_negative", c.false_negative},
                           {"true_negative", c.true_negative}});
    }
  }
  json["confusion"] = confusion;
  nlohmann::json ratios = nlohmann::json::array();
  for (const RatioGroup& g : result.ratios) {
    ratios.push_back({{"dominant_axis", g.axis < 3 ? kAxisNames[g.axis] : "all"},
                      {"frames", g.frames},
                      {"paper_over_measured_min", g.paper_min},
                      {"paper_over_measured_median", g.paper_median},
                      {"paper_over_measured_max", g.paper_max},
                      {"vector_over_measured_median", g.vector_median},
                      {"full_over_measured_median", g.full_median},
                      {"centre_column_over_full_median", g.centre_median}});
  }
  json["ratios"] = ratios;
  json["timing_s"] = {{"read", result.read_s},
                      {"measure", result.measure_s},
                      {"predict", result.predict_s},
                      {"loop", result.loop_s}};
  json["log"] = result.loop.log;
  return json;
}

}  // namespace

nlohmann::json ValidationToJson(const ValidationResult& result) {
  nlohmann::json json =
      result.video ? VideoValidationToJson(result) : StillValidationToJson(result);
  json["warnings"] = WarningsToJson(result.warnings);
  if (result.lens_profile) json["lens_profile"] = LensProfileUseJson(*result.lens_profile);
  return json;
}

std::string LensProfileLines(const ValidationResult& result) {
  std::string out;
  if (result.lens_profile) {
    for (const std::string& note : result.lens_profile->notes) out += "  " + note + "\n";
  }
  return out;
}

std::string ValidationReport(const ValidationResult& result) {
  if (result.video) return VideoValidationReport(result);
  std::ostringstream out;
  const auto& limits = result.limits_m;
  out << "dataset " << result.dataset << ": " << result.frames.size() << " frames, "
      << result.declared.camera.width << "x" << result.declared.camera.height << ", f "
      << FormatNumber("%.1f", 0.5 * (result.declared.camera.fx + result.declared.camera.fy))
      << " px, readout " << FormatNumber("%.2f", result.declared.shutter.readout_s * 1e3) << " ms, "
      << FormatNumber("%g", result.declared.altitude_m) << " m\n"
      << LensProfileLines(result) << "\n";
  out << "frame  points  noise |  D_meas        |  D_full        | D_paper | D_vector | axis |"
         " flags M F P at";
  for (double l : limits) out << " " << FormatNumber("%g", l * 100) << "cm";
  out << "\n";
  out << "                  px |    px      cm  |    px      cm  |    cm   |    cm    |      |\n";
  for (const FrameValidation& f : result.frames) {
    char line[256];
    std::snprintf(line, sizeof(line),
                  "%5lld %7zu %6.3f | %6.2f %7.2f | %6.2f %7.2f | %7.2f | %8.2f |  %s   |",
                  static_cast<long long>(f.frame), f.points, f.noise_px, f.d_meas_px,
                  f.d_meas_m * 100, f.d_full_px, f.d_full_m * 100, f.d_paper_m * 100,
                  f.d_vector_m * 100, kAxisNames[f.dominant_axis]);
    out << line;
    for (size_t l = 0; l < limits.size(); ++l) {
      out << " " << (f.flag_meas[l] ? 'M' : '.') << (f.flag_full[l] ? 'F' : '.')
          << (f.flag_paper[l] ? 'P' : '.');
    }
    out << "\n";
  }
  out << "(M measured, F full model, P paper's model: D over the limit)\n\n";

  out << "paper's flags against the measured D (true pos / false pos / false neg / true neg):\n";
  for (size_t l = 0; l < limits.size(); ++l) {
    const Confusion& p = result.confusion_paper[l];
    const Confusion& f = result.confusion_full[l];
    char line[256];
    std::snprintf(
        line, sizeof(line), "  %5g cm: paper %d / %d / %d / %d   full model %d / %d / %d / %d\n",
        limits[l] * 100, p.true_positive, p.false_positive, p.false_negative, p.true_negative,
        f.true_positive, f.false_positive, f.false_negative, f.true_negative);
    out << line;
  }
  out << "\nD_model / D_meas by dominant axis (frames with D_meas >= " << kMinRatioDPx
      << " px; > 1: conservative):\n";
  for (const RatioGroup& g : result.ratios) {
    if (g.frames == 0) continue;
    const std::string name = g.axis == 0   ? "about x (image rows shift up/down)"
                             : g.axis == 1 ? "about y (image rows shift sideways)"
                             : g.axis == 2 ? "about z (yaw about the optical axis)"
                                           : "all frames";
    char line[320];
    std::snprintf(line, sizeof(line),
                  "  %-36s %2d frames: paper %.2f (%.2f-%.2f)  vector %.2f  full %.2f;"
                  " nadir column holds %.0f%% of D\n",
                  name.c_str(), g.frames, g.paper_median, g.paper_min, g.paper_max, g.vector_median,
                  g.full_median, 100 * g.centre_median);
    out << line;
  }
  const RatioGroup& all = result.ratios.back();
  if (all.frames > 0) {
    out << "  -> the paper's per-axis model is "
        << (all.paper_max < 1.0    ? "NOT conservative on any frame"
            : all.paper_min >= 1.0 ? "conservative on every frame"
                                   : "conservative on some frames only")
        << "; the vector angle gives " << FormatNumber("%.2f", all.vector_median / all.paper_median)
        << "x the per-axis D (median)\n";
  }

  const LoopResult& loop = result.loop;
  out << "\nclosing the loop over " << loop.before.points << " points (noise "
      << FormatNumber("%.3f", loop.noise_px) << " px):\n";
  WriteLoopSummary(loop, out);
  out << "\ntime: read " << FormatNumber("%.2f", result.read_s) << " s, measure "
      << FormatNumber("%.2f", result.measure_s) << " s, predict "
      << FormatNumber("%.2f", result.predict_s) << " s, loop "
      << FormatNumber("%.2f", result.loop_s) << " s\n";
  return out.str();
}

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

// A frame's residual picture: one cell per measure grid step (`cells` of `step_px`), before and
// after (and, for a video, with translation) side by side on one colour scale.
cv::Mat ResidualPanel(const FrameValidation& f, bool video, int step_px, const cv::Size& cells) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat before(cells, CV_32FC2, cv::Scalar(nan, nan)), after = before.clone(),
                                                         translation = before.clone();
  for (const PointResidual& r : f.residuals) {
    const int c = std::clamp(static_cast<int>(std::lround(r.u / step_px)), 0, cells.width - 1);
    const int w = std::clamp(static_cast<int>(std::lround(r.v / step_px)), 0, cells.height - 1);
    before.at<cv::Vec2f>(w, c) = cv::Vec2f(r.before_dx, r.before_dy);
    after.at<cv::Vec2f>(w, c) = cv::Vec2f(r.after_dx, r.after_dy);
    translation.at<cv::Vec2f>(w, c) = cv::Vec2f(r.translation_dx, r.translation_dy);
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
  for (cv::Mat& field : fields) {
    cv::resize(field, field, shown, 0, 0, cv::INTER_NEAREST);
    shown_panels.push_back(DisplacementHeatmap(field, max_px));
  }
  return SideBySide(shown_panels, labels);
}

// Writes every frame's residual picture (DIR/NNNN_residual.png, appended to *written); returns
// (frame index, picture) of those on the page, in frame order.
std::vector<std::pair<size_t, cv::Mat>> WriteResidualPictures(const std::string& dir,
                                                              const ValidationResult& result,
                                                              int step_px,
                                                              std::vector<std::string>* written) {
  const int width = result.declared.camera.width, height = result.declared.camera.height;
  const cv::Size cells((width + step_px - 1) / step_px, (height + step_px - 1) / step_px);
  const std::vector<bool> on_page = FramesOnPage(result);
  std::vector<std::pair<size_t, cv::Mat>> panels;
  for (size_t frame_index = 0; frame_index < result.frames.size(); ++frame_index) {
    const FrameValidation& f = result.frames[frame_index];
    const cv::Mat panel = ResidualPanel(f, result.video, step_px, cells);
    const std::string path = (fs::path(dir) / (FrameName(f.frame) + "_residual.png")).string();
    WriteImage(path, panel);
    written->push_back(path);
    if (on_page[frame_index]) panels.emplace_back(frame_index, panel);
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

// DIR/validate.html: the table, the charts before/after, the residual pictures on the page.
std::string WriteValidationPage(const std::string& dir, const ValidationResult& result,
                                const RowProfile& profile,
                                const std::vector<std::pair<size_t, cv::Mat>>& panels) {
  HtmlPage page("shutterlab validate: " + result.dataset);
  page.Heading("Summary");
  page.Preformatted(ValidationReport(result));
  page.Heading("Residual per image row (all frames)");
  page.AddChart(RowsChart(result.video, profile));
  page.Heading("Per frame");
  AddFrameCharts(result, &page);
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
  written.push_back(WriteValidationPage(dir, result, profile, panels));
  return written;
}

}  // namespace shutterlab
