#pragma once
// DIR/report.html for `shutterlab analyze`: the verdict, the source and bias, camera-axis rate and
// integrated angle against time with the flagged readout windows shaded (one shade per limit),
// D per image (paper and full model) against the limit lines, histograms of the readout windows'
// per-axis ranges, the Allan deviation (of the still segment when one was found, else of the whole
// log), the flight and per-image tables, and for the worst images (by D_full) a heatmap of the
// expected displacement |d| (render/rs_warp.h DisplacementField), blended over the nadir scene
// rendered through the same frame when a scene is given. Built with estimate/report/html_report.h.
// The page draws what the analysis kept for it (AnalyzeResult::plots: the rates and angles cut to
// min/max envelopes, the worst images' frames; FlightResult::summary: the flagged windows and a
// histogram of their ranges; AnalyzeResult::allan); it integrates and analyses nothing again, and
// it is the same page whether the log was read whole (Analyze) or streamed (AnalyzeStream).

#include "estimate/paper/analyze.h"
#include "estimate/report/html_report.h"

#include <opencv2/core.hpp>

#include <string>

namespace shutterlab {

struct AnalyzeReportOptions {
  std::string log_name;    // shown in the title (e.g. the log's file name)
  cv::Mat scene;           // 8-bit RGB nadir image for the pictures; empty: heatmaps alone
  std::string scene_name;  // said in the captions
  // Where the camera and its readout came from, when the caller knows more than the rig (e.g.
  // analyze --photos: "the photos' DJI FC8482 ..., readout 16 ms (table: ...)"); shown beside it.
  std::string camera_source;
  int histogram_bins = 60;
  // The window histogram's x axis ends at this quantile of the windows' ranges (or past the
  // largest threshold): a long tail of a few violent windows would otherwise push the bulk into
  // the first bin. Those above are counted in the last bin, and its label says their share.
  double histogram_quantile = 0.95;
  int picture_width_px = 380;  // pictures are scaled to this width (scale bar included): 3 a row
  void Check() const;
};

// options: those given to the analysis (the rig; the altitude used is result.altitude_m). result
// must come from Analyze or AnalyzeStream with AnalyzeOptions::plots (throws
// std::invalid_argument otherwise: it holds what is drawn), and AnalyzeOptions::allan, else the
// Allan deviation is left out (said on the page). How many time buckets and worst images are
// drawn is the analysis's choice (AnalyzePlotOptions).
HtmlPage AnalyzeReportPage(const AnalyzeOptions& options, const AnalyzeResult& result,
                           const AnalyzeReportOptions& report);

}  // namespace shutterlab
