#pragma once
// `shutterlab export SOURCE --to FORMAT --out DIR`: the camera, readout, time offset and lens that
// shutterlab found (estimate/export/export_camera.h) in the files another tool reads. One table
// of formats; each writer is a pure function from the camera to its files' text (its own unit,
// which says every convention it converts), so that nothing is written before everything is made
// (estimate/export/export_output.h WriteExport). docs/FORMATS.md "Exports" lists every field.

#include "estimate/export/export_camera.h"
#include "estimate/export/export_output.h"

#include <string>
#include <vector>

namespace shutterlab {

struct ExportFormat {
  const char* name;  // --to NAME
  const char* what;  // for --help
  ExportOutput (*write)(const ExportCamera& camera, const ExportOptions& options);
};
// colmap, odm, kalibr, gyroflow, metashape, pix4d, vins.
const std::vector<ExportFormat>& ExportFormats();
// The format named (case-insensitive); throws std::invalid_argument naming the text and the
// formats.
const ExportFormat& FindExportFormat(const std::string& name);

}  // namespace shutterlab
