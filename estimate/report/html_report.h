#pragma once
// A small builder for self-contained HTML reports: headings, paragraphs, tables, images and uPlot
// charts, in one file that opens offline (uPlot's script and style are inlined from the copy that
// CMake compiles into the binary; images are base64 PNG data URIs).
//
// Every text argument is plain text: the builder escapes it. A chart's data goes into the page as
// JSON in <script type="application/json" class="chart-data"> (NaN -> null, '<' written "\u003c"),
// and a fixed script draws each one with uPlot. When every chart is drawn the page sets
// document.body.dataset.status = "ok"; script errors and unhandled rejections are collected in
// document.body.dataset.errors (scripts/check_report.sh reads both in headless Chromium).
//
// Usage:
//   HtmlPage page("Flight report");
//   page.Heading("Rates");
//   Chart chart;  chart.title = "rate"; chart.x = t_s; chart.series = {{"x", rate_x}};
//   page.AddChart(chart);
//   page.Write("out/report.html");  // whole or not at all

#include <opencv2/core.hpp>

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace shutterlab {

// The vendored uPlot (third_party/uplot), embedded at build time.
std::string_view UplotJs();
std::string_view UplotCss();
std::string_view UplotLicense();

// &, <, >, ", ' as character references.
std::string EscapeHtml(std::string_view text);
// RFC 4648 base64 with padding.
std::string Base64(std::string_view bytes);

enum class ChartKind {
  kLines,      // series drawn as lines (NaN breaks the line)
  kPoints,     // markers only
  kHistogram,  // steps: x holds each bin's left edge, the last x the right edge of the last bin
};

struct ChartSeries {
  explicit ChartSeries(std::string label_ = "", std::vector<double> y_ = {},
                       std::string color_ = "")
      : label(std::move(label_)), y(std::move(y_)), color(std::move(color_)) {}
  std::string label;
  std::vector<double> y;  // one per Chart::x; NaN = no value
  std::string color;      // "#rrggbb"; empty: the builder's palette
  bool dashed = false;    // e.g. limit lines
  // Drawn as a line even in a kPoints chart (e.g. a limit line beside points).
  bool line = false;
};

struct ChartShading {
  std::string label;  // said in a note under the chart
  std::string color;  // CSS colour, e.g. "rgba(255, 140, 0, 0.25)"
  std::vector<std::pair<double, double>> intervals;
};

struct Chart {
  std::string title;
  std::string x_label, y_label;
  ChartKind kind = ChartKind::kLines;
  bool log_x = false, log_y = false;  // base 10; values <= 0 are not drawn
  std::vector<double> x;              // ascending
  std::vector<ChartSeries> series;
  // Sets of [x0, x1] intervals shaded behind the data (e.g. flagged time windows), drawn in order.
  std::vector<ChartShading> shadings;
  int height_px = 260;
  // Ticks on whole numbers only (frame numbers, counts).
  bool integer_x = false;
  // A points chart's outliers (above Q3 + 3 IQR of its points, where the largest is over twice
  // that) would flatten the rest: they are drawn at that height in a series of their own and
  // listed, with their values, under the chart (ClipOutliers).
  bool clip_outliers = true;
};

class HtmlPage {
 public:
  explicit HtmlPage(std::string title);

  void Heading(const std::string& text, int level = 2);  // level 1..4
  void Paragraph(const std::string& text);
  void Preformatted(const std::string& text);
  // rows may be shorter than header (missing cells are empty). Cells are plain text; `text`: cells
  // are sentences (left-aligned, wrapped) rather than numbers.
  void Table(const std::vector<std::string>& header,
             const std::vector<std::vector<std::string>>& rows, bool text = false);
  // Throws std::invalid_argument when a series' length differs from x's.
  void AddChart(const Chart& chart);
  // An 8-bit grey, RGB (channel order R, G, B as render/pictures.h gives) or RGBA image as PNG.
  void Image(const cv::Mat& rgb8, const std::string& caption);
  // A bulleted list of plain-text items.
  void List(const std::vector<std::string>& items);
  // A framed box around what follows until EndBox: "ok" (green), "attention" (amber) or "problem"
  // (red) edge, e.g. a verdict.
  void BeginBox(const std::string& level);
  void EndBox();
  // Text a reader may open: a summary line over preformatted text, closed at first.
  void Details(const std::string& summary, const std::string& preformatted);
  // Raw HTML, for callers that need a construct the builder lacks (not escaped).
  void RawHtml(const std::string& html);

  size_t charts() const { return charts_; }
  std::string Html() const;
  // Writes the page whole or not at all (sim/text_file.h WriteFileAtomically).
  void Write(const std::string& path) const;

 private:
  std::string title_;
  std::string body_;
  size_t charts_ = 0;
};

// A long trace made short enough for a page: x is split into `buckets` equal spans, and each
// series keeps its smallest and largest value of each span, in their order, at the span's first
// and last x (a line through them draws the trace's exact envelope). Charts with at most
// 2 * buckets points are returned unchanged. NaNs are skipped; a span with none left gives NaN.
Chart DownsampleMinMax(const Chart& chart, size_t buckets = 4000);

// The chart as AddChart draws it: with clip_outliers, when the largest of a kPoints chart's points
// (at least 8 of them, its line series aside) lies over twice the fence Q3 + 3 IQR of them all,
// each point above the fence is taken out of its series and drawn at the fence in a series of its
// own ("off the scale"); `note` says which and their values (empty when nothing was clipped).
Chart ClipOutliers(const Chart& chart, std::string* note);

// The JSON of one chart as the page embeds it (exposed for tests).
std::string ChartJson(const Chart& chart);

}  // namespace shutterlab
