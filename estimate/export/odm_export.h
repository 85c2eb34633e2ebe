#pragma once
// OpenDroneMap and OpenSfM: the camera as OpenSfM's camera_models_overrides.json (key "all": every
// camera of the project; projection "brown" or "fisheye_opencv"; focal lengths and principal
// point normalised as OpenSfM's geometry does: origin at the image centre, the larger side 1, the
// top-left pixel's centre at (0.5, 0.5) - so focal_x = fx / S, c_x = (cx + 0.5 - W / 2) / S with
// S = max(W, H)); ODM's rolling-shutter options (odm_args.txt: --rolling-shutter
// --rolling-shutter-readout MS, whole milliseconds); the photos not flagged, by path, as ODM's
// image_list.txt. ODM's correction (OpenSfM rs_correct) times rows from the image centre and reads
// top to bottom: a readout read bottom to top is refused. Its readout is a duration, so the row a
// frame's time refers to does not enter.

#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"

namespace shutterlab {

ExportOutput OdmExport(const ExportCamera& camera, const ExportOptions& options);

}  // namespace shutterlab
