#pragma once
// `analyze --photos DIR --out OUT` without a log: report.html for a person, the same photos and
// verdict as the terminal's table, each D beside its ground sampling, and what the photogrammetry
// tool's own rolling-shutter option already removes.

#include "estimate/paper/photo_analysis.h"
#include "estimate/report/html_report.h"
#include "io/photo_set.h"

namespace shutterlab {

HtmlPage PhotoReportPage(const PhotoSet& set, const PhotoAnalysis& analysis);

}  // namespace shutterlab
