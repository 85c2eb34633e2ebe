#pragma once
// What a photo's file says about its capture, as written: EXIF, XMP (DJI's `drone-dji` namespace)
// and the maker note of older DJI Phantoms. Read through exiv2, which links PRIVATE to
// shutterlab_render and is used only in io/photo_metadata.cc, as OpenImageIO is only in
// io/image_io.cc.
//
// Why exiv2 and not OpenImageIO (which reads EXIF and XMP too): OpenImageIO folds XMP's tiff:Make
// and tiff:Model over EXIF's Make and Model, so a Mavic 2 Pro photo (EXIF "Hasselblad"
// "L1D-20c", XMP "DJI" "Test_Pro") reads as "DJI Test_Pro" and its readout is not found; exiv2
// keeps the two apart and gives the maker note's bytes (neither library decodes DJI's maker note;
// its ten tags, all inline values of one IFD, are decoded here after ExifTool's DJI tag table).
//
// Nothing here is derived or guessed: io/photo_set.h turns these facts into a camera, a
// capture time and a readout, and says where each came from.

#include "sim/civil_time.h"

#include <Eigen/Core>

#include <optional>
#include <string>

namespace shutterlab {

// Euler angles as DJI writes them: degrees, NED frame, rotation order Z (yaw), Y (pitch), X (roll);
// gimbal pitch -90 looks straight down.
struct AttitudeDeg {
  double roll_deg = 0.0, pitch_deg = 0.0, yaw_deg = 0.0;
};

// A gimbal's attitude as a rotation, NED from DJI's gimbal frame (x the optical axis, y image
// right, z image down: the frame at pitch 0), Z-Y-X: yaw, then pitch, then roll. The camera's
// axes of docs/FORMATS.md (x right, y down, z along the view) are its columns 1, 2 and 0.
Eigen::Matrix3d NedFromGimbal(const AttitudeDeg& attitude);

struct PhotoMetadata {
  std::string make, model;  // EXIF IFD0 Make and Model, trailing spaces and NULs removed
  // The pixels in the file (exiv2's pixelWidth/pixelHeight: the JPEG frame header, TIFF's tags).
  int width = 0, height = 0;
  // EXIF PixelXDimension / PixelYDimension: the size the camera wrote, which stays that of the
  // sensor mode when the file was later downscaled. 0 when absent.
  int exif_width = 0, exif_height = 0;
  std::optional<double> focal_length_mm;    // EXIF FocalLength
  std::optional<double> focal_length_35mm;  // EXIF FocalLengthIn35mmFilm (0 = unknown: absent)
  // EXIF FocalPlaneXResolution converted to pixels per mm with FocalPlaneResolutionUnit.
  std::optional<double> focal_plane_px_per_mm;
  // XMP drone-dji:CalibratedFocalLength, pixels of the camera's full-size image (DJI enterprise).
  std::optional<double> calibrated_focal_px;
  std::optional<double> exposure_s;  // EXIF ExposureTime
  // EXIF DateTimeOriginal + SubSecTimeOriginal + OffsetTimeOriginal (DateTime and its SubSecTime /
  // OffsetTime when there is no DateTimeOriginal). capture_time_problem says why it is empty when
  // a date was written but could not be read.
  std::optional<ClockFace> capture_time;
  std::string capture_time_text;  // as written, for messages
  std::string capture_time_problem;
  // Drone flight state at the capture (XMP drone-dji, else DJI's maker note).
  std::optional<double> relative_altitude_m;  // above the take-off point
  std::optional<double> absolute_altitude_m;
  std::optional<AttitudeDeg> gimbal;  // camera attitude
  std::optional<AttitudeDeg> flight;  // aircraft attitude
  // Aircraft velocity, m/s: x north, y east, z vertical as written (DJI documents the sign of
  // neither; shutterlab uses only the horizontal part).
  std::optional<Eigen::Vector3d> speed_m_s;
  std::string flight_state_source;                    // "XMP drone-dji", "DJI maker note", or empty
  std::optional<double> latitude_deg, longitude_deg;  // EXIF GPS, when written and not 0,0
  // EXIF GPSAltitude, m above sea level (GPSAltitudeRef 1: below), when written with a position.
  std::optional<double> gps_altitude_m;
};

// Reads the metadata of a JPEG, TIFF, DNG, ... (any format exiv2 reads). Throws IoError("PATH:
// problem") when the file cannot be opened or is not an image exiv2 knows; a file without
// metadata gives a PhotoMetadata with only its size. Thread-safe.
PhotoMetadata ReadPhotoMetadata(const std::string& path);

}  // namespace shutterlab
