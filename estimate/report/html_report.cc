#include "estimate/report/html_report.h"

#include "sim/check.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <png.h>

namespace shutterlab {
namespace {

constexpr const char* kPalette[] = {"#d62728", "#2ca02c", "#1f77b4", "#ff7f0e",
                                    "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};

// Collects script errors before anything else runs, so a failure in uPlot or the drawing code
// is visible to scripts/check_report.sh.
constexpr const char* kErrorScript = R"js(
(function () {
  var errors = [];
  function note(message) {
    errors.push(String(message));
    document.body.dataset.errors = errors.join(" | ");
    document.body.dataset.status = "error";
  }
  window.addEventListener("error", function (e) { note(e.message || e); });
  window.addEventListener("unhandledrejection", function (e) { note(e.reason); });
})();
)js";

// Draws every chart-data block with uPlot: options and hooks only (shading by a drawClear hook).
constexpr const char* kChartScript = R"js(
(function () {
  function shade(intervals, color) {
    return {
      hooks: {
        drawClear: [function (u) {
          var ctx = u.ctx, left = u.bbox.left, right = left + u.bbox.width;
          ctx.save();
          ctx.fillStyle = color;
          intervals.forEach(function (iv) {
            var x0 = Math.max(left, u.valToPos(iv[0], "x", true));
            var x1 = Math.min(right, u.valToPos(iv[1], "x", true));
            if (x1 >= x0) ctx.fillRect(x0, u.bbox.top, Math.max(1, x1 - x0), u.bbox.height);
          });
          ctx.restore();
        }]
      }
    };
  }
  var blocks = document.querySelectorAll("script.chart-data");
  blocks.forEach(function (block) {
    var spec = JSON.parse(block.textContent);
    var holder = document.getElementById(block.dataset.target);
    var series = [{ label: spec.x_label }];
    spec.series.forEach(function (s) {
      var entry = { label: s.label, stroke: s.color, width: 1.5, spanGaps: false };
      if (s.dashed) entry.dash = [8, 5];
      if (spec.kind === "points" && !s.line) {
        entry.paths = function () { return null; };
        entry.points = { show: true, size: 7, fill: s.color };
      } else {
        entry.points = { show: false };
      }
      if (spec.kind === "histogram") {
        entry.paths = uPlot.paths.stepped({ align: 1 });
        entry.fill = s.color + "22";
      }
      series.push(entry);
    });
    var plugins = [];
    spec.shadings.forEach(function (s) { plugins.push(shade(s.intervals, s.color)); });
    var x_axis = { label: spec.x_label };
    // Whole-number steps only: a frame has no frame 2.5.
    if (spec.integer_x) x_axis.incrs = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 1e4, 2e4, 5e4, 1e5];
    var options = {
      title: spec.title,
      width: Math.max(480, holder.clientWidth),
      height: spec.height,
      series: series,
      scales: {
        x: { time: false, distr: spec.log_x ? 3 : 1, log: 10 },
        y: { distr: spec.log_y ? 3 : 1, log: 10 }
      },
      axes: [x_axis, { label: spec.y_label }],
      legend: { live: true },
      cursor: { drag: { x: true, y: false } },
      plugins: plugins
    };
    new uPlot(options, spec.data, holder);
  });
  if (document.body.dataset.status !== "error") document.body.dataset.status = "ok";
})();
)js";

constexpr const char* kPageStyle = R"css(
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 0 auto;
       max-width: 1280px; padding: 16px 28px 40px; color: #1d2430; background: #fff; }
h1 { font-size: 26px; margin: 8px 0 4px; }
h2 { font-size: 20px; margin: 28px 0 8px; padding-top: 8px; border-top: 1px solid #dde2ea; }
h3 { font-size: 16px; margin: 18px 0 6px; }
p { line-height: 1.45; margin: 6px 0 10px; }
table { border-collapse: collapse; font-size: 13px; margin: 6px 0 12px; }
th, td { border: 1px solid #d5dbe3; padding: 3px 9px; text-align: right; white-space: nowrap; }
th { background: #eef2f7; }
td:first-child, th:first-child { text-align: left; }
tr:nth-child(even) td { background: #f8fafc; }
.table-wrap { max-height: 520px; overflow: auto; display: inline-block; max-width: 100%; }
.chart { margin: 6px 0 14px; }
.chart-note { font-size: 12px; color: #4a5462; margin: -8px 0 10px; }
.swatch { display: inline-block; width: 22px; height: 11px; margin-right: 6px;
          vertical-align: -1px; border: 1px solid #c5ccd6; }
figure { display: inline-block; margin: 6px 12px 12px 0; vertical-align: top; }
figure img { max-width: 100%; height: auto; border: 1px solid #d5dbe3; }
figcaption { font-size: 13px; color: #4a5462; margin-top: 3px; }
pre { background: #f5f7fa; padding: 8px; font-size: 12px; overflow: auto; }
table.text td { white-space: normal; text-align: left; max-width: 760px; }
ul { margin: 4px 0 10px; padding-left: 22px; line-height: 1.45; }
.box { border: 1px solid #d5dbe3; border-left: 6px solid #8a94a3; padding: 6px 16px;
       margin: 10px 0 16px; background: #fbfcfd; }
.box.ok { border-left-color: #2e9d4a; } .box.attention { border-left-color: #e0a400; }
.box.problem { border-left-color: #d2372c; }
details summary { cursor: pointer; color: #4a5462; margin: 8px 0; }
)css";

const char* KindName(ChartKind kind) {
  switch (kind) {
    case ChartKind::kPoints:
      return "points";
    case ChartKind::kHistogram:
      return "histogram";
    default:
      return "lines";
  }
}

nlohmann::json Values(const std::vector<double>& values, bool log) {
  nlohmann::json out = nlohmann::json::array();
  for (double v : values) {
    if (!std::isfinite(v) || (log && v <= 0)) {
      out.push_back(nullptr);
    } else {
      out.push_back(v);
    }
  }
  return out;
}

}  // namespace

std::string EscapeHtml(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

namespace {

// An 8-bit grey, RGB or RGBA image as a PNG file's bytes, through libpng's simplified API: a page
// is written without the codecs module (io/codecs.h), whose libraries take 0.35 s to load.
std::string EncodePng(const cv::Mat& image) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.cols);
  png.height = static_cast<png_uint_32>(image.rows);
  png.format = image.channels() == 1   ? PNG_FORMAT_GRAY
               : image.channels() == 3 ? PNG_FORMAT_RGB
                                       : PNG_FORMAT_RGBA;
  png.flags = PNG_IMAGE_FLAG_FAST;  // zlib's fast end: pictures of a page, written once
  const cv::Mat rows = image.isContinuous() ? image : image.clone();
  png_alloc_size_t size = 0;
  SHUTTERLAB_CHECK(png_image_write_get_memory_size(png, size, 0, rows.data, 0, nullptr))
      << "PNG encoding failed: " << png.message;
  std::string bytes(size, '\0');
  SHUTTERLAB_CHECK(png_image_write_to_memory(&png, bytes.data(), &size, 0, rows.data, 0, nullptr))
      << "PNG encoding failed: " << png.message;
  bytes.resize(size);
  return bytes;
}

}  // namespace

std::string Base64(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t n = (static_cast<uint8_t>(bytes[i]) << 16) |
                       (static_cast<uint8_t>(bytes[i + 1]) << 8) |
                       static_cast<uint8_t>(bytes[i + 2]);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += kAlphabet[(n >> 6) & 63];
    out += kAlphabet[n & 63];
  }
  if (i < bytes.size()) {
    uint32_t n = static_cast<uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) n |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

Chart DownsampleMinMax(const Chart& chart, size_t buckets) {
  if (buckets == 0 || chart.x.size() <= 2 * buckets) return chart;
  Chart out = chart;
  out.x.clear();
  for (ChartSeries& s : out.series) s.y.clear();
  const double x0 = chart.x.front(), span = chart.x.back() - chart.x.front();
  size_t begin = 0;
  while (begin < chart.x.size()) {
    // [begin, end): the samples of one bucket.
    const size_t bucket =
        span > 0
            ? std::min(buckets - 1, static_cast<size_t>((chart.x[begin] - x0) / span * buckets))
            : 0;
    size_t end = begin + 1;
    while (end < chart.x.size() &&
           (span <= 0 || std::min(buckets - 1, static_cast<size_t>((chart.x[end] - x0) / span *
                                                                   buckets)) == bucket)) {
      ++end;
    }
    const bool single = end - begin == 1;
    out.x.push_back(chart.x[begin]);
    if (!single) out.x.push_back(chart.x[end - 1]);
    for (size_t k = 0; k < chart.series.size(); ++k) {
      const std::vector<double>& y = chart.series[k].y;
      size_t lo = end, hi = end;
      for (size_t i = begin; i < end; ++i) {
        if (!std::isfinite(y[i])) continue;
        if (lo == end || y[i] < y[lo]) lo = i;
        if (hi == end || y[i] > y[hi]) hi = i;
      }
      std::vector<double>& dst = out.series[k].y;
      const double nan = std::numeric_limits<double>::quiet_NaN();
      if (single) {
        dst.push_back(lo == end ? nan : y[lo]);
      } else if (lo == end) {
        dst.insert(dst.end(), {nan, nan});
      } else {
        dst.push_back(y[std::min(lo, hi)]);
        dst.push_back(y[std::max(lo, hi)]);
      }
    }
    begin = end;
  }
  return out;
}

Chart ClipOutliers(const Chart& chart, std::string* note) {
  note->clear();
  if (chart.kind != ChartKind::kPoints || !chart.clip_outliers) return chart;
  std::vector<double> values;
  for (const ChartSeries& s : chart.series) {
    if (s.line) continue;
    for (double v : s.y) {
      if (std::isfinite(v)) values.push_back(v);
    }
  }
  if (values.size() < 8) return chart;
  const auto quartile = [&](double q) {  // nearest rank: no value the data does not hold
    const size_t k = static_cast<size_t>(q * static_cast<double>(values.size() - 1));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
  };
  const double q1 = quartile(0.25), q3 = quartile(0.75);
  const double top = q3 + 3.0 * (q3 - q1);
  // Only where the far points would squeeze the rest into less than half the height: a large value
  // among a few (one shaken frame of six) is data to show at its place, not an outlier.
  const double largest = *std::max_element(values.begin(), values.end());
  if (!(top > 0.0 && largest > 2.0 * top)) return chart;
  Chart drawn = chart;
  ChartSeries off("off the scale (drawn at " + FormatNumber("%.4g", top) + ")",
                  std::vector<double>(chart.x.size(), std::numeric_limits<double>::quiet_NaN()),
                  "#000000");
  std::vector<std::string> listed;
  size_t clipped = 0;
  for (ChartSeries& s : drawn.series) {
    if (s.line) continue;
    for (size_t i = 0; i < s.y.size(); ++i) {
      if (!(std::isfinite(s.y[i]) && s.y[i] > top)) continue;
      if (++clipped <= 6) {
        listed.push_back(s.label + " " + FormatNumber("%.4g", s.y[i]) + " at " +
                         FormatNumber("%.6g", chart.x[i]));
      }
      s.y[i] = std::numeric_limits<double>::quiet_NaN();
      off.y[i] = top;
    }
  }
  if (clipped == 0) return chart;
  drawn.series.push_back(std::move(off));
  *note = std::to_string(clipped) + " point(s) above " + FormatNumber("%.4g", top) + " " +
          chart.y_label + " (3 interquartile ranges over the upper quartile) drawn in black at " +
          "that height, so they do not flatten the rest: ";
  for (size_t i = 0; i < listed.size(); ++i) *note += (i ? "; " : "") + listed[i];
  if (clipped > listed.size())
    *note += "; and " + std::to_string(clipped - listed.size()) + " more";
  *note += " (" + chart.x_label + ")";
  return drawn;
}

std::string ChartJson(const Chart& chart) {
  nlohmann::json json;
  json["title"] = chart.title;
  json["x_label"] = chart.x_label;
  json["y_label"] = chart.y_label;
  json["kind"] = KindName(chart.kind);
  json["log_x"] = chart.log_x;
  json["log_y"] = chart.log_y;
  json["height"] = chart.height_px;
  json["integer_x"] = chart.integer_x;
  nlohmann::json data = nlohmann::json::array();
  data.push_back(Values(chart.x, chart.log_x));
  nlohmann::json series = nlohmann::json::array();
  for (size_t k = 0; k < chart.series.size(); ++k) {
    const ChartSeries& s = chart.series[k];
    series.push_back({{"label", s.label},
                      {"color", s.color.empty() ? kPalette[k % std::size(kPalette)] : s.color},
                      {"dashed", s.dashed},
                      {"line", s.line}});
    data.push_back(Values(s.y, chart.log_y));
  }
  json["series"] = std::move(series);
  json["data"] = std::move(data);
  nlohmann::json shadings = nlohmann::json::array();
  for (const ChartShading& shading : chart.shadings) {
    nlohmann::json intervals = nlohmann::json::array();
    for (const auto& [a, b] : shading.intervals) intervals.push_back({a, b});
    shadings.push_back(
        {{"label", shading.label}, {"color", shading.color}, {"intervals", std::move(intervals)}});
  }
  json["shadings"] = std::move(shadings);
  // Invalid UTF-8 in a label becomes U+FFFD rather than an exception.
  std::string text = json.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  // "</script" or "<!--" inside the block would change how HTML parses it; "\u003c" is the same
  // JSON string ('<' occurs only inside strings).
  std::string safe;
  safe.reserve(text.size());
  for (char c : text) {
    if (c == '<') {
      safe += "\\u003c";
    } else {
      safe += c;
    }
  }
  return safe;
}

HtmlPage::HtmlPage(std::string title) : title_(std::move(title)) {}

void HtmlPage::Heading(const std::string& text, int level) {
  level = std::clamp(level, 1, 4);
  body_ +=
      "<h" + std::to_string(level) + ">" + EscapeHtml(text) + "</h" + std::to_string(level) + ">\n";
}

void HtmlPage::Paragraph(const std::string& text) { body_ += "<p>" + EscapeHtml(text) + "</p>\n"; }

void HtmlPage::Preformatted(const std::string& text) {
  body_ += "<pre>" + EscapeHtml(text) + "</pre>\n";
}

void HtmlPage::Table(const std::vector<std::string>& header,
                     const std::vector<std::vector<std::string>>& rows, bool text) {
  std::string html = std::string("<div class=\"table-wrap\"><table") +
                     (text ? " class=\"text\"" : "") + ">\n<thead><tr>";
  for (const std::string& cell : header) html += "<th>" + EscapeHtml(cell) + "</th>";
  html += "</tr></thead>\n<tbody>\n";
  for (const auto& row : rows) {
    html += "<tr>";
    for (size_t c = 0; c < std::max(header.size(), row.size()); ++c) {
      html += "<td>" + (c < row.size() ? EscapeHtml(row[c]) : std::string()) + "</td>";
    }
    html += "</tr>\n";
  }
  body_ += html + "</tbody></table></div>\n";
}

void HtmlPage::List(const std::vector<std::string>& items) {
  body_ += "<ul>\n";
  for (const std::string& item : items) body_ += "<li>" + EscapeHtml(item) + "</li>\n";
  body_ += "</ul>\n";
}

void HtmlPage::BeginBox(const std::string& level) {
  body_ += "<div class=\"box " + EscapeHtml(level) + "\">\n";
}

void HtmlPage::EndBox() { body_ += "</div>\n"; }

void HtmlPage::Details(const std::string& summary, const std::string& preformatted) {
  body_ += "<details><summary>" + EscapeHtml(summary) + "</summary><pre>" +
           EscapeHtml(preformatted) + "</pre></details>\n";
}

void HtmlPage::AddChart(const Chart& given) {
  for (const ChartSeries& s : given.series) {
    SHUTTERLAB_CHECK(s.y.size() == given.x.size())
        << "chart '" << given.title << "': series '" << s.label << "' has " << s.y.size()
        << " values for " << given.x.size() << " x values";
  }
  std::string clipped_note;
  const Chart chart = ClipOutliers(given, &clipped_note);
  const std::string id = "chart-" + std::to_string(charts_++);
  body_ += "<div class=\"chart\" id=\"" + id + "\"></div>\n";
  for (const ChartShading& shading : chart.shadings) {
    body_ += "<p class=\"chart-note\"><span class=\"swatch\" style=\"background:" +
             EscapeHtml(shading.color) + "\"></span>" + EscapeHtml(shading.label) + "</p>\n";
  }
  body_ += "<script type=\"application/json\" class=\"chart-data\" data-target=\"" + id + "\">" +
           ChartJson(chart) + "</script>\n";
  if (!clipped_note.empty())
    body_ += "<p class=\"chart-note\">" + EscapeHtml(clipped_note) + "</p>\n";
}

void HtmlPage::Image(const cv::Mat& rgb8, const std::string& caption) {
  SHUTTERLAB_CHECK(!rgb8.empty() && rgb8.depth() == CV_8U &&
                   (rgb8.channels() == 1 || rgb8.channels() == 3 || rgb8.channels() == 4))
      << "image '" << caption << "': expected an 8-bit grey, RGB or RGBA image";
  const std::string png = EncodePng(rgb8);
  // The figure as wide as its image, so a long caption wraps instead of widening it, but no wider
  // than the page: a wide picture (three residual panels side by side) shrinks to fit.
  body_ += "<figure style=\"width:" + std::to_string(rgb8.cols) +
           "px; max-width:100%\"><img alt=\"" + EscapeHtml(caption) + "\" width=\"" +
           std::to_string(rgb8.cols) + "\" src=\"data:image/png;base64," + Base64(png) +
           "\"><figcaption>" + EscapeHtml(caption) + "</figcaption></figure>\n";
}

void HtmlPage::RawHtml(const std::string& html) { body_ += html; }

std::string HtmlPage::Html() const {
  std::string html;
  html.reserve(body_.size() + UplotJs().size() + 8192);
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<title>" + EscapeHtml(title_) + "</title>\n<style>\n";
  html += UplotCss();
  html += "\n";
  html += kPageStyle;
  html += "</style>\n</head>\n<body>\n<script>";
  html += kErrorScript;
  html += "</script>\n<h1>" + EscapeHtml(title_) + "</h1>\n";
  html += body_;
  // uPlot, MIT licence (third_party/uplot/LICENSE).
  html += "<script>\n";
  html += UplotJs();
  html += "\n</script>\n<script>";
  html += kChartScript;
  html += "</script>\n</body>\n</html>\n";
  return html;
}

void HtmlPage::Write(const std::string& path) const { WriteFileAtomically(path, Html()); }

}  // namespace shutterlab
