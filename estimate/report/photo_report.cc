#include "estimate/report/photo_report.h"

#include "sim/text_file.h"
#include "sim/units.h"

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

// docs/photogrammetry.md's simulated surveys (COLMAP with the camera known): with a multirotor's
// rotation (six flights) the rolling-shutter photos put the cameras 0.43 to 1.10 times their median
// D on the ground off horizontally; without rotation (two flights, the translation alone) 0.24
// times, its error going into the terrain's heights instead; the corrected ones came within about
// 1 cm of the global-shutter photos'.
constexpr double kCentreErrorPerMedianDMin = 0.43, kCentreErrorPerMedianDMax = 1.10;
constexpr double kCentreErrorPerMedianDTranslation = 0.24;

// What correcting is expected to buy in a reconstruction, from that table, said as an estimate;
// nothing when no photo's D is predicted.
void ExpectedBenefit(const PhotoAnalysis& a, HtmlPage* page) {
  std::vector<double> d_m;  // each predicted photo's D on the ground
  bool rotation = false;
  for (const PhotoResult& p : a.photos) {
    if (p.d_translation_m || p.d_rotation_m)
      d_m.push_back(p.d_translation_m.value_or(0.0) + p.d_rotation_m.value_or(0.0));
    rotation = rotation || p.d_rotation_m.has_value();
  }
  if (d_m.empty()) return;
  const double median_m = Median(d_m);
  page->Heading("What correcting buys in the map (an estimate)");
  const std::string measured =
      rotation ? "In six simulated surveys with a multirotor's rotation (docs/photogrammetry.md: "
                 "COLMAP, the camera known), rolling-shutter photos put the reconstructed cameras "
                 "0.43 to 1.10 times the median D off horizontally: here " +
                     FormatNumber("%.1f", 100 * kCentreErrorPerMedianDMin * median_m) +
                     FormatNumber(" to %.1f cm. ", 100 * kCentreErrorPerMedianDMax * median_m)
               : "In two simulated surveys without rotation (docs/photogrammetry.md: COLMAP, the "
                 "camera known), where D is the translation alone, rolling-shutter photos put the "
                 "reconstructed cameras 0.24 times the median D off horizontally: here " +
                     FormatNumber("%.1f cm", 100 * kCentreErrorPerMedianDTranslation * median_m) +
                     ", and the terrain's heights off by more (9.5 to 29 cm there). ";
  page->Paragraph(
      FormatNumber("These photos' median D is %.1f cm on the ground. ", 100 * median_m) + measured +
      "Corrected with the gyro (shutterlab correct --photos DIR LOG), they came within about 1 "
      "cm of a global shutter's. An estimate from simulations of another camera, not a "
      "measurement of this flight" +
      std::string(rotation ? "."
                           : "; without the flight log D holds only the translation, and "
                             "the rotation adds to both."));
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
  ExpectedBenefit(a, &page);
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
