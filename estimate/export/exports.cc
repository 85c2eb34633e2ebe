#include "estimate/export/exports.h"

#include "estimate/export/colmap_export.h"
#include "estimate/export/gyroflow_export.h"
#include "estimate/export/kalibr_export.h"
#include "estimate/export/metashape_export.h"
#include "estimate/export/odm_export.h"
#include "estimate/export/pix4d_export.h"
#include "estimate/export/vins_export.h"
#include "sim/text_file.h"

#include <stdexcept>

namespace shutterlab {

const std::vector<ExportFormat>& ExportFormats() {
  static const std::vector<ExportFormat> formats = {
      {"colmap", "COLMAP text model (cameras.txt), feature_extractor options, image list",
       ColmapExport},
      {"odm", "OpenDroneMap / OpenSfM: camera_models_overrides.json, the rolling-shutter options",
       OdmExport},
      {"kalibr", "Kalibr camchain-imucam.yaml (time shift, line delay, T_cam_imu)", KalibrExport},
      {"gyroflow", "Gyroflow lens profile and project settings (readout, sync offset)",
       GyroflowExport},
      {"metashape", "Agisoft Metashape calibration XML", MetashapeExport},
      {"pix4d", "Pix4D's OPF calibrated camera (the readout in an extension)", Pix4dExport},
      {"vins", "VINS-Mono / VINS-Fusion camera and config (td, rolling_shutter_tr, extrinsics)",
       VinsExport},
  };
  return formats;
}

const ExportFormat& FindExportFormat(const std::string& name) {
  const std::string lower = ToLower(name);
  std::string names;
  for (const ExportFormat& format : ExportFormats()) {
    if (lower == format.name) return format;
    names += (names.empty() ? "" : ", ") + std::string(format.name);
  }
  throw std::invalid_argument("unknown export format '" + name + "' (" + names + ")");
}

}  // namespace shutterlab
