#pragma once
// Agisoft Metashape's camera calibration XML (as its "Export calibration" writes it, frame
// cameras): f, cx and cy as offsets from the image centre, b1 (fx - fy, Metashape's affinity), b2
// (skew, 0), k1..k3 and p1, p2 in Metashape's order, which swaps OpenCV's (Metashape's p1 is
// OpenCV's p2). Pixel coordinates from the image's top-left corner, as COLMAP's and Pix4D's:
// cx = cx_OpenCV + 0.5 - width / 2 (Agisoft's documents do not say; a half-pixel difference
// otherwise). Metashape's rolling-shutter compensation is fitted per photo, not declared: the
// readout is said in the side note only. A fisheye lens is refused: Metashape's fisheye model is
// not confirmed to be OpenCV's.

#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"

namespace shutterlab {

ExportOutput MetashapeExport(const ExportCamera& camera, const ExportOptions& options);

}  // namespace shutterlab
