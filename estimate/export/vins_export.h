#pragma once
// VINS-Mono / VINS-Fusion's camera and estimator settings (HKUST-Aerial-Robotics, config/*.yaml,
// read by OpenCV's cv::FileStorage): the camera as camodocal's PINHOLE (projection_parameters fx,
// fy, cx, cy and distortion_parameters k1, k2, p1, p2: OpenCV's pixel centres and terms without
// k3) or KANNALA_BRANDT (projection_parameters k2..k5 = OpenCV's fisheye k1..k4, mu, mv, u0, v0);
// extrinsicRotation imu^R_cam = R_GC = R_CG^T; td with "image clock + td = IMU clock", and
// rolling_shutter_tr, the readout (s). VINS times a row from the middle of the image
// (projection_td_factor.cpp: td + tr / ROW * (row - ROW / 2)), shutterlab from the first row, so
// td = time_offset_s + readout_s / 2. A k3, a bottom-to-top readout and a clock rate, which the
// file cannot hold, are refused.

#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"

namespace shutterlab {

ExportOutput VinsExport(const ExportCamera& camera, const ExportOptions& options);

}  // namespace shutterlab
