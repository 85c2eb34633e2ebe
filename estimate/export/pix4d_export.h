#pragma once
// Pix4D's Open Photogrammetry Format (github.com/Pix4D/opf-spec): calibrated_cameras.json, an
// "application/opf-calibrated-cameras+json" 1.0 file with the camera as one sensor of perspective
// internals: principal_point_px from the top-left corner of the top-left pixel (OpenCV's cx +
// 0.5), one focal_length_px, radial_distortion [R1, R2, R3] = OpenCV's [k1, k2, k3] and
// tangential_distortion [T1, T2] = [p1, p2] (Pix4D's opf2colmap writes them to COLMAP's
// FULL_OPENCV as they are). OPF has no field for the readout: it goes into the sensor's extension
// SHUTTERLAB_rolling_shutter (OPF's extension naming, VENDOR_extname). Refused: a fisheye lens
// (OPF's fisheye is Pix4D's polynomial model, not OpenCV's) and fx != fy (one focal length;
// --force writes their mean). From an analyze --photos result also input_cameras.json and
// camera_list.json: the sensor (its pixel size from a photo's EXIF focal length in mm, its shutter
// type from the readout) and a capture a photo (docs/FORMATS.md, "Exports"). Not written: the
// per-image "rolling_shutter" 3-vector of calibrated cameras and the XMP Camera:LineReadoutTime,
// whose meaning and unit Pix4D does not document.

#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"

namespace shutterlab {

ExportOutput Pix4dExport(const ExportCamera& camera, const ExportOptions& options);

}  // namespace shutterlab
