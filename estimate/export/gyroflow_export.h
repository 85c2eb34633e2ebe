#pragma once
// Gyroflow: the camera as a lens profile (lens_profile.json: calib_dimension, fisheye_params or
// calib_params with camera_matrix and distortion_coeffs under distortion_model opencv_fisheye or
// opencv_standard, asymmetrical true so that Gyroflow keeps the principal point instead of the
// image centre, frame_readout_time in ms, negative when the rows are read bottom to top), and the
// settings of a project (project.gyroflow: calibration_data, stabilization's frame_readout_time
// and frame_readout_direction, the sync offset). Gyroflow times a frame's rows from its middle
// row (frame_transform.rs: start = timestamp - readout / 2) and reads its gyro at video time -
// offset (gyro_source.rs), so offset_ms = -1000 (time_offset_s + readout_s / 2) for shutterlab's
// first-row frame times. The gyro's mounting goes into gyro_source (imu_orientation and rotation,
// onto Gyroflow's camera axes: x right, y up, z back), read from Gyroflow's source, not checked
// against Gyroflow itself.

#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"

namespace shutterlab {

ExportOutput GyroflowExport(const ExportCamera& camera, const ExportOptions& options);

}  // namespace shutterlab
