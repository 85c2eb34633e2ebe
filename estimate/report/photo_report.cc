#include "estimate/report/photo_report.h"

#include "sim/text_file.h"

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

std::string Cell(const std::optional<double>& value, const char* format, double scale = 1.0) {
  return value ? FormatNumber(format, *value * scale) : "-";
}

// The photo's row: what was read, D in pixels and on the ground, the ground a pixel covers, and
// the flags or why there are none.
std::vector<std::string> PhotoRow(const PhotoRecord& r, const PhotoResult& p,
                                  const PhotoAnalysis& a) {
  if (!r.ok()) return {r.name, "", "", "", "", "", "", "excluded: " + r.error};
  std::optional<double> gsd_m;
  if (r.altitude_m && r.focal_px) gsd_m = *r.altitude_m / *r.focal_px;
  std::string flags;
  for (size_t l = 0; l < p.flagged.size(); ++l) {
    if (p.flagged[l].value_or(false))
      flags += (flags.empty() ? "over " : ", ") + FormatNumber("%g cm", a.limits_m[l] * 100.0);
  }
  if (flags.empty()) {
    flags = p.flagged.empty() || !p.flagged[0]
                ? "not predicted: no " + (r.missing.empty() ? std::string("speed") : r.missing[0])
                : "under every limit";
  }
  std::optional<double> total_px;
  if (p.d_translation_px || p.d_rotation_px)
    total_px = p.d_translation_px.value_or(0.0) + p.d_rotation_px.value_or(0.0);
  std::optional<double> total_m;
  if (p.d_translation_m || p.d_rotation_m)
    total_m = p.d_translation_m.value_or(0.0) + p.d_rotation_m.value_or(0.0);
  const std::string readout = r.readout_s ? FormatNumber("%g ms", *r.readout_s * 1e3) + " (" +
                                                ReadoutOriginName(r.readout_origin) + ")"
                                          : "-";
  return {r.name,
          Cell(r.altitude_m, "%.1f"),
          Cell(r.ground_speed_m_s, "%.1f"),
          readout,
          Cell(total_px, "%.2f"),
          Cell(total_m, "%.1f", 100.0),
          Cell(gsd_m, "%.2f", 100.0),
          flags};
}

}  // namespace

HtmlPage PhotoReportPage(const PhotoSet& set, const PhotoAnalysis& a) {
  HtmlPage page("Photos of " + a.source);
  page.BeginBox(a.excluded == 0                    ? "ok"
                : 2 * a.excluded > a.photos.size() ? "problem"
                                                   : "attention");
  page.Paragraph(a.verdict);
  page.EndBox();
  page.Paragraph(
      "D: how far the ground moved in the photo while its rows were read (the translation part: "
      "speed x readout x focal length / altitude, a nadir camera over flat ground). Without a "
      "flight log the rotation part is unknown: give the log too (analyze --photos DIR LOG).");
  std::vector<std::vector<std::string>> rows;
  for (size_t i = 0; i < a.photos.size(); ++i)
    rows.push_back(PhotoRow(set.photos[i], a.photos[i], a));
  page.Table(
      {"photo", "altitude m", "speed m/s", "readout", "D px", "D cm", "ground cm/px", "flagged"},
      rows);
  page.Heading("What your photogrammetry tool already removes");
  page.Paragraph(
      "OpenDroneMap's --rolling-shutter (with --rolling-shutter-readout, the readout in ms) "
      "corrects each photo for the camera's travel between shots, spread over its readout: the "
      "translation part above. The rotation part (the camera turning during the readout) it "
      "cannot know; the gyro can: analyze the photos with their flight log to see it. Pix4D and "
      "Metashape have rolling-shutter options of their own; their manuals say what they fit.");
  return page;
}

}  // namespace shutterlab
