#pragma once
// What an export writes: files made whole in memory first (their text), then written each whole
// or not at all; the side note shutterlab_export.txt that says where every value came from and
// how it was converted; the refusals shared by every format.

#include "estimate/export/export_camera.h"

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// One file of an export: its name relative to the output folder, its text, what it is for.
struct ExportFile {
  std::string name;
  std::string text;
  std::string what;
};

struct ExportOutput {
  std::vector<ExportFile> files;   // the side note last
  std::vector<std::string> notes;  // the conversions made and what the format does not carry
};

struct ExportOptions {
  // Write a value the source marks as not determined (its standard error is not a number), and
  // leave out what the format cannot carry; without it either is refused in one line.
  bool force = false;
};

// A number as every export writes it: the shortest text that reads back to the same double.
std::string ExportNumber(double value);

// Refuses (std::invalid_argument, one line naming the value, why, and --force) a value the data
// did not determine (ExportCamera::undetermined, by effect name), unless options.force; says so
// in *notes when forced.
void RequireDetermined(const ExportCamera& camera, const std::string& name,
                       const ExportOptions& options, std::vector<std::string>* notes);

// Refuses (std::invalid_argument, "... (--force writes the rest)") what the format cannot carry,
// unless options.force; then notes it.
void RequireCarried(bool carried, const std::string& what, const ExportOptions& options,
                    std::vector<std::string>* notes);

// What a camera-IMU file needs of the gyro (Kalibr's chain, VINS's config): a source that relates
// a gyro to the camera, a time offset and a mounting the data determined, and no clock rate (the
// file's offset, `offset_name`, is constant); each refused as RequireCarried and RequireDetermined
// do. tool names the file's reader in the messages.
void RequireGyroRelation(const ExportCamera& camera, const std::string& tool,
                         const std::string& offset_name, const ExportOptions& options,
                         std::vector<std::string>* notes);

// Notes that the gyro's fitted scale and bias, when not the identity, are not part of `file`.
void NoteGyroCalibrationNotCarried(const ExportCamera& camera, const std::string& file,
                                   std::vector<std::string>* notes);

// Appends shutterlab_export.txt: the format, the source, the camera as shutterlab holds it, and
// every note. Call last.
void AddSideNote(const char* format, const ExportCamera& camera, ExportOutput* output);

// Writes every file into out_dir (created when missing), each whole or not at all. Returns the
// paths written, in order.
std::vector<std::string> WriteExport(const ExportOutput& output, const std::string& out_dir);

}  // namespace shutterlab
