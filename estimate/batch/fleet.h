#pragma once
// The fleet's page: every item of a batch read back from its folder (made.json and what its jobs
// wrote) into one row, then OUT/fleet.csv and OUT/fleet.html: per item its verdict, the share of
// its images over each limit, its worst images, the camera and readout used and where they came
// from, warnings and a link to its own report; per group (drone or camera) the spread over its
// flights; and, in words, the flights to correct or fly again first.

#include "estimate/batch/manifest.h"

#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

struct FleetRow {
  std::string id, group;
  std::string input;      // "log", "photos", "photos + log", "clip", "dataset"
  std::string status;     // "done", "failed", "not made"
  std::string error;      // a failed item's line
  bool has_gyro = false;  // a log or a clip: the rotation part is known, and correctable
  size_t judged = 0;      // images or photos with a D
  std::vector<double> limits_m;
  std::vector<double> share_over;  // per limit, 0..1; empty when nothing was judged
  std::vector<std::pair<std::string, double>> worst;  // up to 3: name, D in m, largest first
  double readout_s;                                   // NaN when unknown
  std::string readout_source;  // "assumed", "given", "16ms from table", "camera.json", ...
  std::string camera;          // "1280 x 960 px, f 1100 px", "DJI FC8482 4032 x 2268 px"
  std::vector<std::string> warnings;
  std::string verdict;  // the command's own verdict line
  std::string report;   // its page, relative to OUT ("" when none)
};

// Reads every item of the manifest from OUT/items/ID; an item with no folder is "not made", one
// whose results cannot be read says so in `warnings`.
std::vector<FleetRow> ReadFleet(const BatchManifest& manifest, const std::string& out_dir);

// The sentences of the page's "first" list: the items to correct or fly again first (the largest
// share over the largest limit), what each needs, and the failed items.
std::vector<std::string> FleetAdvice(const std::vector<FleetRow>& rows);

// Writes OUT/fleet.csv and OUT/fleet.html, each whole or not at all; returns their paths.
std::vector<std::string> WriteFleetSummary(const std::vector<FleetRow>& rows,
                                           const std::string& out_dir);

}  // namespace shutterlab
