#pragma once
// Kalibr's camchain-imucam.yaml (kalibr_common/ConfigReader.py): cam0 with camera_model pinhole,
// intrinsics [fu, fv, pu, pv] (OpenCV's pixel centres, as Kalibr's), distortion radtan [k1, k2,
// p1, p2] (OpenCV's terms without k3) or equidistant [k1..k4] (OpenCV's fisheye), resolution,
// T_cam_imu (the gyro-to-camera rotation R_CG, no translation), timeshift_cam_imu (t_imu = t_cam
// + shift: shutterlab's time_offset_s) and line_delay_nanoseconds (Kalibr's rolling shutter times
// row v at v * line delay after the frame's time: the first row, as shutterlab's). A k3, a
// bottom-to-top readout and a clock rate, which the file cannot hold, are refused.

#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"

namespace shutterlab {

ExportOutput KalibrExport(const ExportCamera& camera, const ExportOptions& options);

}  // namespace shutterlab
