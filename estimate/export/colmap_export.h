#pragma once
// COLMAP (doc/format.rst, src/colmap/sensor/models.h): a text model whose cameras.txt holds the
// camera (OPENCV, FULL_OPENCV when k3 is not 0, or OPENCV_FISHEYE), with empty images.txt and
// points3D.txt so that `colmap model_converter` reads it; the same camera as feature_extractor's
// --ImageReader.camera_model / camera_params (colmap_args.txt); the photos not flagged as
// image_list.txt (--image_list_path). COLMAP puts the top-left pixel's centre at (0.5, 0.5): its
// cx, cy are OpenCV's plus 0.5. It has no rolling-shutter model: the readout is said in comment
// lines of cameras.txt and in the side note, not used.

#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"

namespace shutterlab {

ExportOutput ColmapExport(const ExportCamera& camera, const ExportOptions& options);

}  // namespace shutterlab
