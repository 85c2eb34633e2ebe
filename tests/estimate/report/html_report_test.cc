#include "estimate/report/html_report.h"

#include "estimate/paper/plot_summary.h"
#include "io/image_io.h"
#include "sim/text_file.h"
#include "tests/estimate/report/report_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <regex>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::ChartBlocks;

TEST(EscapeHtml, EscapesTheFiveSpecialCharacters) {
  EXPECT_EQ(EscapeHtml("a<b>&\"c\"'d'"), "a&lt;b&gt;&amp;&quot;c&quot;&#39;d&#39;");
  EXPECT_EQ(EscapeHtml("plain text"), "plain text");
}

TEST(Base64, KnownAnswers) {
  // RFC 4648 section 10.
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(Base64(std::string("\xff\x00\x10", 3)), "/wAQ");
}

TEST(Uplot, EmbeddedCopyIsTheVendoredFile) {
  EXPECT_EQ(std::string(UplotJs()),
            ReadFileToString(test::SourcePath("third_party/uplot/uPlot.iife.min.js")));
  EXPECT_EQ(std::string(UplotCss()),
            ReadFileToString(test::SourcePath("third_party/uplot/uPlot.min.css")));
  EXPECT_NE(std::string(UplotLicense()).find("MIT"), std::string::npos);
}

TEST(HtmlPage, SelfContainedWithEscapedTextAndParsableChartData) {
  HtmlPage page("Report <1> & \"two\"");
  page.Heading("Section </h2><script>alert(1)</script>");
  page.Paragraph("x < y && y > z");
  page.Table({"name", "value"}, {{"<b>bold</b>", "1"}, {"short"}});
  Chart chart;
  chart.title = "rates </script><script>alert(2)</script>";
  chart.x = {0.0, 1.0, 2.0};
  ChartSeries dashed("y", {-1, 0, 1}, "#123456");
  dashed.dashed = true;
  chart.series = {ChartSeries("x </script>", {1.5, std::nan(""), 3.0}), dashed};
  chart.shadings = {{"flagged <5 cm>", "rgba(255, 140, 0, 0.25)", {{0.5, 1.5}}}};
  page.AddChart(chart);
  Chart histogram;
  histogram.kind = ChartKind::kHistogram;
  histogram.log_y = true;
  histogram.x = {0, 10, 20};
  histogram.series = {ChartSeries("count", {5, 0, 2})};
  page.AddChart(histogram);
  page.Image(cv::Mat(4, 6, CV_8UC3, cv::Scalar(10, 200, 30)), "heat <map>");
  const std::string html = page.Html();

  // No raw markup from the text, and no external loads.
  EXPECT_EQ(html.find("<script>alert"), std::string::npos);
  EXPECT_EQ(html.find("<b>bold"), std::string::npos);
  EXPECT_NE(html.find("&lt;b&gt;bold&lt;/b&gt;"), std::string::npos);
  EXPECT_NE(html.find("<title>Report &lt;1&gt; &amp; &quot;two&quot;</title>"), std::string::npos);
  EXPECT_NE(html.find("x &lt; y &amp;&amp; y &gt; z"), std::string::npos);
  EXPECT_TRUE(test::SelfContained(html));
  EXPECT_FALSE(std::regex_search(html, std::regex(R"((src|href)\s*=\s*["']?(https?:)?//)")));
  // uPlot inlined, once, and the chart driver after it.
  EXPECT_NE(html.find(std::string(UplotJs()).substr(0, 200)), std::string::npos);
  EXPECT_LT(html.find("var uPlot="), html.find("new uPlot("));
  EXPECT_NE(html.find("data:image/png;base64,iVBORw0KGgo"), std::string::npos);  // PNG magic
  EXPECT_NE(html.find("<figcaption>heat &lt;map&gt;</figcaption>"), std::string::npos);

  const std::vector<nlohmann::json> blocks = ChartBlocks(html);
  ASSERT_EQ(blocks.size(), 2u);
  EXPECT_EQ(page.charts(), 2u);
  const nlohmann::json& a = blocks[0];
  EXPECT_EQ(a["title"], chart.title);  // "</script>" survived as JSON, not as markup
  ASSERT_EQ(a["data"].size(), 3u);
  EXPECT_EQ(a["data"][0], nlohmann::json({0.0, 1.0, 2.0}));
  EXPECT_EQ(a["data"][1][0], 1.5);
  EXPECT_TRUE(a["data"][1][1].is_null());  // NaN -> null
  EXPECT_EQ(a["series"][0]["label"], "x </script>");
  EXPECT_EQ(a["series"][1]["color"], "#123456");
  EXPECT_TRUE(a["series"][1]["dashed"].get<bool>());
  EXPECT_EQ(a["shadings"][0]["intervals"], nlohmann::json::parse("[[0.5, 1.5]]"));
  EXPECT_NE(html.find("flagged &lt;5 cm&gt;"), std::string::npos);
  const nlohmann::json& h = blocks[1];
  EXPECT_EQ(h["kind"], "histogram");
  EXPECT_TRUE(h["data"][1][1].is_null());  // 0 on a log axis is not drawn
  EXPECT_EQ(h["data"][1][0], 5);
}

TEST(HtmlPage, ChartRejectsMismatchedSeries) {
  HtmlPage page("t");
  Chart chart;
  chart.x = {1, 2, 3};
  chart.series = {ChartSeries("short", {1, 2})};
  EXPECT_THROW(page.AddChart(chart), std::invalid_argument);
}

// One outlier among 20 points (a 406 cm image among 5-25 cm ones) is drawn at the fence
// Q3 + 3 IQR in its own black series and listed with its value; the limit line is left alone; a
// chart with nothing far out is drawn as given.
TEST(ClipOutliers, DrawsFarPointsAtTheFenceAndSaysTheirValues) {
  Chart chart;
  chart.kind = ChartKind::kPoints;
  chart.x_label = "t (s)";
  chart.y_label = "cm";
  ChartSeries d("D");
  for (int i = 0; i < 20; ++i) {
    chart.x.push_back(i);
    d.y.push_back(5.0 + i);  // 5..24 cm
  }
  d.y[7] = 406.0;
  ChartSeries limit("limit 5 cm", std::vector<double>(20, 5.0));
  limit.line = true;
  chart.series = {d, limit};
  std::string note;
  const Chart drawn = ClipOutliers(chart, &note);
  // Nearest-rank quartiles (ranks 4 and 14 of 0..19) of the 20 values sorted (5..11, 13..24, 406):
  // Q1 = 9, Q3 = 20.
  const double fence = 20.0 + 3.0 * (20.0 - 9.0);
  ASSERT_EQ(drawn.series.size(), 3u);
  EXPECT_TRUE(std::isnan(drawn.series[0].y[7]));
  EXPECT_EQ(drawn.series[0].y[6], 11.0);
  EXPECT_EQ(drawn.series[1].y, limit.y);
  EXPECT_EQ(drawn.series[2].y[7], fence);
  EXPECT_TRUE(std::isnan(drawn.series[2].y[6]));
  EXPECT_EQ(drawn.series[2].color, "#000000");
  EXPECT_NE(note.find("1 point(s) above 53 cm"), std::string::npos) << note;
  EXPECT_NE(note.find("D 406 at 7"), std::string::npos) << note;
  // On the page: the note under the chart, the clipped series in the data.
  HtmlPage page("t");
  page.AddChart(chart);
  const std::string html = page.Html();
  EXPECT_NE(html.find("<p class=\"chart-note\">1 point(s) above 53 cm"), std::string::npos);
  EXPECT_EQ(ChartBlocks(html).at(0)["series"].size(), 3u);
  // Nothing far out, a point above the fence but under twice it (a value to show in place), a lines
  // chart, or clipping turned off: unchanged, no note.
  chart.series[0].y[7] = 12.0;
  EXPECT_EQ(ClipOutliers(chart, &note).series.size(), 2u);
  EXPECT_TRUE(note.empty());
  chart.series[0].y[7] = 2.0 * fence - 1.0;
  EXPECT_EQ(ClipOutliers(chart, &note).series.size(), 2u);
  EXPECT_TRUE(note.empty());
  chart.series[0].y[7] = 406.0;
  chart.clip_outliers = false;
  EXPECT_EQ(ClipOutliers(chart, &note).series.size(), 2u);
  chart.clip_outliers = true;
  chart.kind = ChartKind::kLines;
  EXPECT_EQ(ClipOutliers(chart, &note).series.size(), 2u);
}

// Frame numbers: the chart says so, and the page's script gives uPlot whole-number steps only.
TEST(HtmlPage, IntegerAxisHasWholeNumberSteps) {
  Chart chart;
  chart.x = {0, 1, 2};
  chart.series = {ChartSeries("a", {1, 2, 3})};
  chart.integer_x = true;
  HtmlPage page("t");
  page.AddChart(chart);
  const std::string html = page.Html();
  EXPECT_TRUE(ChartBlocks(html).at(0)["integer_x"].get<bool>());
  EXPECT_NE(html.find("if (spec.integer_x) x_axis.incrs = [1, 2, 5"), std::string::npos);
}

TEST(HtmlPage, WriteIsAtomicAndWhole) {
  test::TempDir dir;
  HtmlPage page("t");
  page.Paragraph("hello");
  page.Write(dir / "report.html");
  EXPECT_EQ(ReadFileToString(dir / "report.html"), page.Html());
  // A path whose folder does not exist: an error, and nothing left behind.
  EXPECT_ANY_THROW(page.Write(dir / "missing/report.html"));
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
  size_t files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path()))
    ++files;
  EXPECT_EQ(files, 1u);  // no temporary left beside the report
}

// The bytes of a base64 text (RFC 4648, with padding), decoded here rather than by the code under
// test.
std::string FromBase64(const std::string& text) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string bytes;
  uint32_t bits = 0;
  int count = 0;
  for (const char c : text) {
    if (c == '=') break;
    bits = bits << 6 | static_cast<uint32_t>(alphabet.find(c));
    if ((count += 6) >= 8) bytes += static_cast<char>(bits >> (count -= 8) & 0xFF);
  }
  return bytes;
}

// A page's pictures are lossless PNGs of what it was given: each read back through OpenImageIO
// equals its image, grey and RGB, and a view into a larger image (rows not contiguous) too.
TEST(HtmlPage, PicturesAreTheImagesGivenAsLosslessPngs) {
  std::mt19937 random(3);
  cv::Mat grey(37, 53, CV_8UC1), rgb(41, 29, CV_8UC3), wide(60, 90, CV_8UC3);
  for (cv::Mat* image : {&grey, &rgb, &wide}) cv::randu(*image, 0, 256);
  const cv::Mat view = wide(cv::Rect(7, 5, 31, 23));
  ASSERT_FALSE(view.isContinuous());
  HtmlPage page("pictures");
  page.Image(grey, "grey");
  page.Image(rgb, "rgb");
  page.Image(view, "view");
  const std::string html = page.Html();
  test::TempDir dir;
  size_t at = 0;
  for (const cv::Mat& given : {grey, rgb, view}) {
    const std::string key = "data:image/png;base64,";
    at = html.find(key, at);
    ASSERT_NE(at, std::string::npos);
    at += key.size();
    const std::string png = FromBase64(html.substr(at, html.find('"', at) - at));
    ASSERT_EQ(png.substr(1, 3), "PNG");
    WriteFileAtomically(dir / "picture.png", png);
    const cv::Mat read = ReadImage(dir / "picture.png");
    ASSERT_EQ(read.size(), given.size());
    ASSERT_EQ(read.type(), given.type());
    EXPECT_EQ(cv::norm(read, given, cv::NORM_INF), 0) << "a picture changed in its PNG";
  }
}

TEST(DownsampleMinMax, KeepsEachBucketsExtremesInOrder) {
  Chart chart;
  const size_t n = 10000;
  ChartSeries s("s");
  for (size_t i = 0; i < n; ++i) {
    chart.x.push_back(static_cast<double>(i));
    s.y.push_back(std::sin(i * 0.01) + (i == 5003 ? 7.0 : 0.0) - (i == 777 ? 9.0 : 0.0));
  }
  chart.series = {s};
  const Chart small = DownsampleMinMax(chart, 100);
  ASSERT_EQ(small.x.size(), 200u);
  ASSERT_EQ(small.series[0].y.size(), 200u);
  double lo = 1e9, hi = -1e9;
  for (double v : small.series[0].y) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_DOUBLE_EQ(hi, std::sin(5003 * 0.01) + 7.0);  // a one-sample spike survives
  EXPECT_DOUBLE_EQ(lo, std::sin(777 * 0.01) - 9.0);
  // Bucket 0 holds samples 0..99: its first x, its last x; sin rises there, so min then max.
  EXPECT_EQ(small.x[0], 0.0);
  EXPECT_EQ(small.x[1], 99.0);
  EXPECT_DOUBLE_EQ(small.series[0].y[0], 0.0);
  EXPECT_DOUBLE_EQ(small.series[0].y[1], std::sin(0.99));
  // Short charts are left alone.
  EXPECT_EQ(DownsampleMinMax(chart, 5000).x.size(), n);
}

// The streamed envelope against its whole-chart twin: the same x and values, to the bit, on
// charts shorter than the buckets, at the 2 * buckets edge, and long ones; with jittered x, ties,
// NaNs and infinities, a flat series, and a chart whose x does not move.
TEST(MinMaxEnvelope, EqualsDownsampleMinMaxOfTheWholeChart) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> jitter(0.0, 0.9);
  std::uniform_int_distribution<int> level(-3, 3);
  const size_t buckets = 50;
  for (const size_t n : {size_t{1}, size_t{2}, size_t{37}, size_t{100}, size_t{101}, size_t{173},
                         size_t{1000}, size_t{20011}}) {
    for (const bool flat_x : {false, true}) {
      SCOPED_TRACE("n " + std::to_string(n) + (flat_x ? ", flat x" : ""));
      Chart chart;
      chart.series = {ChartSeries("a"), ChartSeries("b"), ChartSeries("c")};
      for (size_t i = 0; i < n; ++i) {
        // Uneven steps (a gap every 97 points), x in seconds of a nanosecond clock as the report.
        const double t_ns = i * 1e6 + jitter(rng) * 1e6 + (i / 97) * 3e7;
        chart.x.push_back(flat_x ? 5.0 : std::round(t_ns) * 1e-9);
        chart.series[0].y.push_back(std::sin(i * 0.013) * 100.0);
        chart.series[1].y.push_back(level(rng));  // many ties: the first extreme wins
        double c = i % 11 == 3 ? std::numeric_limits<double>::quiet_NaN() : level(rng) * 0.5;
        if (i % 13 == 5) c = std::numeric_limits<double>::infinity();
        if (i >= 200 && i < 400) c = std::numeric_limits<double>::quiet_NaN();  // empty buckets
        chart.series[2].y.push_back(c);
      }
      const Chart whole = DownsampleMinMax(chart, buckets);
      MinMaxEnvelope envelope(3, buckets, n, chart.x.front(), chart.x.back());
      for (size_t i = 0; i < n; ++i) {
        const double y[3] = {chart.series[0].y[i], chart.series[1].y[i], chart.series[2].y[i]};
        envelope.Add(chart.x[i], y);
      }
      envelope.Finish();
      ASSERT_EQ(envelope.x(), whole.x);
      for (size_t k = 0; k < 3; ++k) {
        const std::vector<double>& a = envelope.y()[k];
        const std::vector<double>& b = whole.series[k].y;
        ASSERT_EQ(a.size(), b.size()) << k;
        for (size_t i = 0; i < b.size(); ++i) {
          if (std::isnan(b[i])) {
            ASSERT_TRUE(std::isnan(a[i])) << k << " " << i;
          } else {
            ASSERT_EQ(a[i], b[i]) << k << " " << i;
          }
        }
      }
      if (n > 2 * buckets && !flat_x) {
        EXPECT_LE(whole.x.size(), 2 * buckets);
      }
    }
  }
}

}  // namespace
}  // namespace shutterlab
