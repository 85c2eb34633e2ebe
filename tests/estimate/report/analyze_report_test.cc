#include "estimate/report/analyze_report.h"

#include "estimate/paper/flight.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/estimate/paper/paper_fixtures.h"
#include "tests/estimate/report/report_test_util.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

// Still for 4 s, then about camera x a rate that is `fast` during [6, 7) s and slow elsewhere.
FlightLog StepLog(double total_s, double slow_rad_s, double fast_rad_s) {
  return test::StillThenRateLog(
      total_s,
      [=](double t_s) {
        return Eigen::Vector3d(t_s >= 6.0 && t_s < 7.0 ? fast_rad_s : slow_rad_s, 0, 0);
      },
      "step");
}

AnalyzeOptions SmallCamera() {
  AnalyzeOptions options;
  // A small frame keeps the heatmaps cheap (under sanitizers too): 160x120, f 140 px, 30 ms, 50 m.
  options.rig = test::NadirRig(160, 120, 140.0);
  options.plots = AnalyzePlotOptions{};
  options.allan = true;
  return options;
}

// The rate whose 30 ms readout smears d_m on the ground at 50 m (paper model).
using test::RateForGroundSmear;

TEST(AnalyzeReport, ChartsHoldTheAnalysedValues) {
  const FlightLog log = StepLog(10.0, RateForGroundSmear(0.02), RateForGroundSmear(0.07));
  AnalyzeOptions options = SmallCamera();
  options.triggers = {{"quiet", SecondsToNs(5.0)},
                      {"shaken", SecondsToNs(6.5)},
                      {"late", SecondsToNs(9.99)}};  // readout past the log's end
  options.plots->worst_images = 1;
  const AnalyzeResult result = Analyze(log, options);
  AnalyzeReportOptions report;
  report.log_name = "flight<1>.bbl";
  const std::string html = AnalyzeReportPage(options, result, report).Html();
  EXPECT_TRUE(test::SelfContained(html));
  EXPECT_NE(html.find("var uPlot="), std::string::npos);
  EXPECT_NE(html.find("flight&lt;1&gt;.bbl"), std::string::npos);
  EXPECT_EQ(html.find("flight<1>"), std::string::npos);
  EXPECT_NE(html.find("outside the log"), std::string::npos);

  const std::vector<nlohmann::json> charts = test::ChartBlocks(html);
  ASSERT_EQ(charts.size(), 5u);  // rate, angle, D per image, window histogram, Allan
  // Rate: 10001 samples > 2 * 4000 buckets, so enveloped; the peak rate survives exactly.
  const nlohmann::json& rate = charts[0];
  ASSERT_EQ(rate["data"].size(), 4u);
  EXPECT_LE(rate["data"][0].size(), 8000u);
  double peak = 0;
  for (const auto& v : rate["data"][1]) peak = std::max(peak, v.get<double>());
  EXPECT_NEAR(peak, RateForGroundSmear(0.07) * kDegPerRad, 1e-9);
  // Shading per limit: at 5 cm, the windows that overlap the fast second by a share f whose range
  // f * fast + (1 - f) * slow passes the threshold (20" noise allowance included); none at 10 cm.
  ASSERT_EQ(rate["shadings"].size(), 2u);
  const auto& at5 = rate["shadings"][0]["intervals"];
  ASSERT_EQ(at5.size(), 1u);
  const double arcsec = 180.0 * 3600.0 / M_PI;
  const double threshold = std::atan(0.05 / 50.0) * arcsec + 20.0;
  const double slow = RateForGroundSmear(0.02) * 0.030 * arcsec,
               fast = RateForGroundSmear(0.07) * 0.030 * arcsec;
  const double overlap_s = 0.030 * (threshold - slow) / (fast - slow);
  // Within 3 samples: the rectangle rule and the sample-bounded windows shift the edges by 1-2 ms.
  EXPECT_NEAR(at5[0][0].get<double>(), 6.0 - (0.030 - overlap_s), 0.003);
  EXPECT_NEAR(at5[0][1].get<double>(), 7.0 + (0.030 - overlap_s), 0.003);
  EXPECT_EQ(rate["shadings"][1]["intervals"].size(), 0u);

  // D per image: one x per image, the paper model's values in cm, null outside the log.
  const nlohmann::json& d = charts[2];
  ASSERT_EQ(d["data"][0].size(), 3u);
  EXPECT_NEAR(d["data"][1][0].get<double>(), 2.0, 1e-6);
  EXPECT_NEAR(d["data"][1][1].get<double>(), 7.0, 1e-6);
  EXPECT_TRUE(d["data"][1][2].is_null());
  EXPECT_NEAR(d["data"][2][1].get<double>(), result.images[1].d_full_m * 100, 1e-9);
  EXPECT_EQ(d["data"][3][0], 5.0);  // limit line at 5 cm
  EXPECT_EQ(d["data"][4][0], 10.0);

  // Window histogram: each axis's bins add up to 100 % of the windows.
  const nlohmann::json& histogram = charts[3];
  EXPECT_EQ(histogram["kind"], "histogram");
  for (int axis = 1; axis <= 3; ++axis) {
    const auto& y = histogram["data"][axis];
    double sum = 0;
    for (size_t b = 0; b + 1 < y.size(); ++b) sum += y[b].get<double>();
    EXPECT_NEAR(sum, 100.0, 1e-9) << axis;
  }
  // The Allan plot is log-log on the still segment, whose coefficients are the gyro's.
  EXPECT_TRUE(charts[4]["log_x"].get<bool>());
  EXPECT_NE(html.find("still segment"), std::string::npos);
  EXPECT_EQ(html.find("not meaningful"), std::string::npos);
  // The camera axes the verdict names are drawn.
  EXPECT_NE(html.find("aria-label=\"camera axes\""), std::string::npos);
  EXPECT_NE(html.find(">z (optical axis, to the ground)<"), std::string::npos);
  // One worst image, the shaken one, as an inline PNG.
  EXPECT_EQ(html.find("data:image/png;base64,", html.find("data:image/png;base64,") + 1),
            std::string::npos);
  EXPECT_NE(html.find("<figcaption>shaken at 6.50 s"), std::string::npos);
}

// Without still time the Allan deviation measures the flight's motion: every coefficient in the
// table is marked not meaningful, and the page says how to measure the gyro's noise.
TEST(AnalyzeReport, AllanWithoutStillTimeIsMarkedNotMeaningful) {
  const FlightLog log = StepLog(10.0, RateForGroundSmear(0.02), RateForGroundSmear(0.07));
  AnalyzeOptions options = SmallCamera();
  options.estimate_bias = false;  // no still segment searched: the whole log
  options.triggers = {{"quiet", SecondsToNs(5.0)}};
  const AnalyzeResult result = Analyze(log, options);
  ASSERT_FALSE(result.allan_on_still);
  ASSERT_TRUE(result.allan && !result.allan->empty());
  const std::string html = AnalyzeReportPage(options, result, AnalyzeReportOptions()).Html();
  size_t marked = 0;
  for (size_t at = html.find("<td>not meaningful, "); at != std::string::npos;
       at = html.find("<td>not meaningful, ", at + 1))
    ++marked;
  EXPECT_EQ(marked, 6u);  // ARW and bias instability of three axes
  EXPECT_EQ(html.find("at most &lt;"), std::string::npos);  // a bound is said once
  // Why: the bias was not searched (no still time looked for), and what to do.
  EXPECT_NE(html.find("Not meaningful: computed on the whole log (bias not estimated"),
            std::string::npos);
  EXPECT_NE(html.find("record a few seconds with the camera still"), std::string::npos);
}

TEST(AnalyzeReport, SceneIsRenderedUnderTheHeatmap) {
  const FlightLog log = StepLog(8.0, RateForGroundSmear(0.02), RateForGroundSmear(0.07));
  AnalyzeOptions options = SmallCamera();
  options.triggers = {{"shaken", SecondsToNs(6.5)}};
  options.plots->worst_images = 1;
  const AnalyzeResult result = Analyze(log, options);
  AnalyzeReportOptions report;
  const std::string plain = AnalyzeReportPage(options, result, report).Html();
  report.scene = cv::Mat(240, 320, CV_8UC3, cv::Scalar(250, 250, 250));
  report.scene_name = "white.png";
  const std::string blended = AnalyzeReportPage(options, result, report).Html();
  EXPECT_NE(blended.find("blended over white.png"), std::string::npos);
  EXPECT_NE(plain, blended);  // the picture differs
}

// A readout of one sample interval is refused, and the page says so under its flight table as the
// text does, with what would do.
TEST(AnalyzeReport, AFlightTableOfRefusedRowsSaysWhyUnderIt) {
  const FlightLog log = StepLog(10.0, RateForGroundSmear(0.02), RateForGroundSmear(0.07));
  AnalyzeOptions options = SmallCamera();
  options.rig.shutter.readout_s = 0.001;  // the log's 1 ms interval
  options.every_s = 2.0;
  const AnalyzeResult result = Analyze(log, options);
  ASSERT_TRUE(result.flight.has_value());
  const std::string html = AnalyzeReportPage(options, result, AnalyzeReportOptions{}).Html();
  EXPECT_NE(html.find("too few samples, those rows were not analysed: at 1000 Hz a window must be "
                      "longer than 2 ms"),
            std::string::npos);
}

TEST(AnalyzeReport, LongTracesAreEnveloped) {
  const FlightLog log = StepLog(30.0, RateForGroundSmear(0.02), RateForGroundSmear(0.07));
  AnalyzeOptions options = SmallCamera();
  options.every_s = 5.0;
  options.plots = AnalyzePlotOptions{100, 0};
  const AnalyzeResult result = Analyze(log, options);
  AnalyzeReportOptions report;
  const auto charts = test::ChartBlocks(AnalyzeReportPage(options, result, report).Html());
  ASSERT_GE(charts.size(), 2u);
  EXPECT_EQ(charts[0]["data"][0].size(), 200u);  // 100 buckets, min and max each
  EXPECT_EQ(charts[1]["data"][0].size(), 200u);
  EXPECT_EQ(charts[2]["data"][0].size(), 6u);  // images every 5 s of 30 s: 0, 5, ..., 25 s
}

TEST(AnalyzeReport, DrawsTheResultsPlotsAndIntegratesNothingAgain) {
  const FlightLog log = StepLog(10.0, RateForGroundSmear(0.02), RateForGroundSmear(0.07));
  AnalyzeOptions options = SmallCamera();
  options.triggers = {{"shaken", SecondsToNs(6.5)}};
  options.plots = AnalyzePlotOptions{6000, 0};  // 10001 samples: drawn one by one, no envelope
  AnalyzeResult result = Analyze(log, options);
  AnalyzeReportOptions report;
  const AnalyzeTraces& kept = *result.traces;
  const auto rate_and_angle = [&](const AnalyzeResult& r) {
    const auto charts = test::ChartBlocks(AnalyzeReportPage(options, r, report).Html());
    return std::make_pair(charts.at(0), charts.at(1));
  };
  const auto [rate, angle] = rate_and_angle(result);
  ASSERT_EQ(rate["data"][0].size(), kept.camera_rates.size());
  ASSERT_EQ(angle["data"][0].size(), kept.angles.size());
  for (size_t k = 0; k < kept.camera_rates.size(); ++k) {
    for (int a = 0; a < 3; ++a) {
      ASSERT_EQ(rate["data"][a + 1][k].get<double>(),
                kept.camera_rates[k].omega_rad_s[a] * kDegPerRad);
      ASSERT_EQ(angle["data"][a + 1][k].get<double>(), kept.angles.angle_rad[a][k] * kDegPerRad);
    }
  }
  // Plots put in the result by hand are what the page shows: it takes them, it does not compute
  // them again.
  AnalyzePlots doubled = *result.plots;
  for (auto& axis : doubled.angle_deg) {
    for (double& v : axis) v *= 2.0;
  }
  AnalyzeResult altered = result;
  altered.plots = std::make_shared<const AnalyzePlots>(std::move(doubled));
  const auto [same_rate, doubled_angle] = rate_and_angle(altered);
  EXPECT_EQ(same_rate["data"], rate["data"]);
  const size_t last = kept.angles.size() - 1;
  EXPECT_EQ(doubled_angle["data"][1][last].get<double>(),
            2.0 * kept.angles.angle_rad[0][last] * kDegPerRad);
  EXPECT_NE(kept.angles.angle_rad[0][last], 0.0);
  // A result analysed without plots has nothing to draw.
  AnalyzeOptions no_plots = options;
  no_plots.plots.reset();
  EXPECT_THROW(AnalyzeReportPage(options, Analyze(log, no_plots), report), std::invalid_argument);
  EXPECT_THROW(AnalyzeReportPage(options, AnalyzeResult(), report), std::invalid_argument);
}

// The shading and the window histograms drawn from the flight's bounded summary, against what the
// whole per-window series gives: the same flagged intervals; the histogram's upper edge within
// 0.1 % of the exact quantile (AnalyzeReportOptions::histogram_quantile) and each bin's share
// within 0.05 percentage points.
TEST(AnalyzeReport, ShadingAndHistogramsMatchTheWholeSeries) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  const FlightLog log = test::StillThenRateLog(
      20.0,
      [&](double t_s) {
        return Eigen::Vector3d(0.15 * std::sin(2 * t_s) + noise(rng),
                               0.02 * std::sin(5 * t_s) + noise(rng), noise(rng));
      },
      "noisy");
  AnalyzeOptions options = SmallCamera();
  options.every_s = 3.0;
  options.plots->worst_images = 0;
  const AnalyzeResult result = Analyze(log, options);
  // The whole series, as the report drew it before: the same flight options with series on.
  FlightOptions flight;
  flight.limits_m = options.limits_m;
  flight.windows_s = {options.rig.shutter.readout_s};
  flight.known_bias_rad_s = result.bias_rad_s;
  flight.series = true;
  flight.series_vector = false;
  const FlightSeries series = Flight(log.gyro, flight).series;
  ASSERT_GT(series.t_ns.size(), 10000u);
  AnalyzeReportOptions report;
  const auto charts = test::ChartBlocks(AnalyzeReportPage(options, result, report).Html());
  const nlohmann::json& rate = charts.at(0);
  for (size_t l = 0; l < result.flight->rows.size(); ++l) {
    const auto exact = FlaggedIntervalsS(series, result.flight->rows[l].threshold_arcsec);
    const auto& drawn = rate["shadings"][l]["intervals"];
    ASSERT_EQ(drawn.size(), exact.size()) << l;
    for (size_t i = 0; i < exact.size(); ++i) {
      EXPECT_EQ(drawn[i][0].get<double>(), exact[i].first);
      EXPECT_EQ(drawn[i][1].get<double>(), exact[i].second);
    }
  }
  ASSERT_GT(rate["shadings"][0]["intervals"].size(), 3u);
  // The exact histogram: the quantile of every range, the counts by bin.
  std::vector<double> all;
  for (int a = 0; a < 3; ++a)
    all.insert(all.end(), series.range_arcsec[a].begin(), series.range_arcsec[a].end());
  const size_t p =
      std::min(all.size() - 1, static_cast<size_t>(report.histogram_quantile * all.size()));
  std::nth_element(all.begin(), all.begin() + p, all.end());
  double upper = all[p];
  const double percentile = upper;
  for (const FlightRow& row : result.flight->rows)
    upper = std::max(upper, 1.15 * row.threshold_arcsec);
  ASSERT_EQ(upper, percentile);  // the percentile sets the edge here, not the thresholds
  const nlohmann::json& histogram = charts.at(3);
  ASSERT_EQ(histogram["kind"], "histogram");
  const int bins = report.histogram_bins;
  const double drawn_upper = histogram["data"][0][bins].get<double>();
  EXPECT_NEAR(drawn_upper, upper, 1e-3 * upper);
  const double width = upper / bins;
  double worst = 0.0;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> counts(bins, 0.0);
    for (double r : series.range_arcsec[a])
      counts[std::min(bins - 1, static_cast<int>(r / width))]++;
    for (int b = 0; b < bins; ++b) {
      const double exact = 100.0 * counts[b] / series.t_ns.size();
      const double drawn = histogram["data"][a + 1][b].get<double>();
      worst = std::max(worst, std::abs(drawn - exact));
      EXPECT_NEAR(drawn, exact, 0.05) << a << " " << b;
    }
  }
  // The last bin's label says the share of windows above the edge.
  const std::string label = histogram["x_label"];
  const size_t at = label.find("holds the ");
  ASSERT_NE(at, std::string::npos) << label;
  const double said_percent = std::stod(label.substr(at + 10));
  const double above = static_cast<double>(
      std::count_if(all.begin(), all.end(), [&](double r) { return r >= drawn_upper; }));
  EXPECT_NEAR(said_percent, 100.0 * above / all.size(), 0.1) << label;
  std::cout << "window histogram: edge " << drawn_upper << " vs " << upper
            << " arcsec, largest bin difference " << worst << " percentage points\n";
}

TEST(FlaggedIntervalsS, MergesOverlappingWindows) {
  FlightSeries series;
  series.window_s = 0.5;
  series.t_ns = {0, SecondsToNs(0.25), SecondsToNs(1.0), SecondsToNs(2.0), SecondsToNs(2.5)};
  series.range_arcsec[0] = {10, 0, 0, 0, 0};
  series.range_arcsec[1] = {0, 10, 0, 10, 0};
  series.range_arcsec[2] = {0, 0, 1, 0, 10};
  const auto intervals = FlaggedIntervalsS(series, 5.0);
  ASSERT_EQ(intervals.size(), 2u);
  EXPECT_DOUBLE_EQ(intervals[0].first, 0.0);
  EXPECT_DOUBLE_EQ(intervals[0].second, 0.75);
  EXPECT_DOUBLE_EQ(intervals[1].first, 2.0);  // touching windows merge
  EXPECT_DOUBLE_EQ(intervals[1].second, 3.0);
  EXPECT_TRUE(FlaggedIntervalsS(series, 10.0).empty());  // strictly above the threshold
}

}  // namespace
}  // namespace shutterlab
