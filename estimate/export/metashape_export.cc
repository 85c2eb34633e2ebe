#include "estimate/export/metashape_export.h"

#include "model/lens_distortion.h"

#include <stdexcept>
#include <string>
#include <variant>

namespace shutterlab {

ExportOutput MetashapeExport(const ExportCamera& camera, const ExportOptions&) {
  const PinholeCamera& c = camera.truth.rig.camera;
  const auto* brown = std::get_if<BrownConrady>(&c.distortion);
  if (!brown) {
    throw std::invalid_argument(
        "Metashape's fisheye model is not confirmed to be OpenCV's: a fisheye lens is not "
        "exported to Metashape (export it --to colmap or --to kalibr)");
  }
  const auto& k = brown->coeffs;  // OpenCV's k1 k2 p1 p2 k3
  ExportOutput out;
  const auto element = [](const char* name, const std::string& value) {
    return std::string("  <") + name + ">" + value + "</" + name + ">\n";
  };
  std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  xml += "<!-- shutterlab export from " + camera.source + " -->\n<calibration>\n";
  xml += element("projection", "frame");
  xml += element("width", std::to_string(c.width));
  xml += element("height", std::to_string(c.height));
  xml += element("f", ExportNumber(c.fy));
  xml += element("cx", ExportNumber(c.cx + 0.5 - 0.5 * c.width));
  xml += element("cy", ExportNumber(c.cy + 0.5 - 0.5 * c.height));
  xml += element("b1", ExportNumber(c.fx - c.fy));
  xml += element("b2", "0");
  xml += element("k1", ExportNumber(k[0]));
  xml += element("k2", ExportNumber(k[1]));
  xml += element("k3", ExportNumber(k[4]));
  xml += element("p1", ExportNumber(k[3]));  // Metashape's P1 multiplies OpenCV's p2 terms
  xml += element("p2", ExportNumber(k[2]));
  xml += "</calibration>\n";
  out.files.push_back({"calibration.xml", xml, "Metashape's camera calibration"});
  out.notes.push_back(
      "f = fy, b1 = fx - fy; cx, cy from the image centre with the top-left "
      "corner as origin (cx_OpenCV + 0.5 - width/2)");
  out.notes.push_back("p1, p2 swapped: Metashape's P1 is OpenCV's p2");
  out.notes.push_back(
      "Metashape fits rolling-shutter compensation per photo: the readout is not "
      "part of its calibration file");
  AddSideNote("metashape", camera, &out);
  return out;
}

}  // namespace shutterlab
