#pragma once
// Gyroflow lens profiles (github.com/gyroflow/lens_profiles, CC0: about 9,800 community and
// official calibrations, the JSON that Gyroflow's lens calibrator writes): one camera mode's
// intrinsics, OpenCV fisheye distortion (or, rarely, OpenCV's standard model), calibration size,
// frame rate and often the frame readout time. `--lens-profile FILE` of render, analyze, import and
// validate reads one and scales it to the images at hand (docs/FORMATS.md "Lens profile"). The same
// option reads a Gyroflow project (.gyroflow: its "calibration_data" is a profile, and its
// "stabilization" frame_readout_time and frame_readout_direction win over the profile's) and
// OpenSfM's cameras (io/opensfm_camera.h), each as a profile.
//
// Fields read (Gyroflow src/core/lens_profile.rs names them; missing ones take Gyroflow's
// defaults): name, camera_brand, camera_model, lens_model, calibrated_by, official, fps,
// calib_dimension {w, h}, fisheye_params {camera_matrix, distortion_coeffs, RMS_error} with
// use_opencv_fisheye / distortion_model null or "opencv_fisheye", calib_params with
// use_opencv_standard / distortion_model "opencv_standard", frame_readout_time (ms; Gyroflow's
// negative value means the rows are read bottom to top), compatible_settings [{width, height, fps,
// frame_readout_time}], input_horizontal_stretch / input_vertical_stretch (must be 1), digital_lens
// (must be null). Another distortion model (poly3, poly5, ptlens, ...), a digital lens (GoPro
// SuperView, ...) or a stretched input is refused with a one-line error naming it.

#include "model/camera.h"
#include "sim/readout_direction.h"

#include <nlohmann/json_fwd.hpp>

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// A frame readout a profile states: for its own mode, or for one of its compatible settings.
struct ProfileReadout {
  int width = 0, height = 0;        // the mode's image size, px
  double fps = 0.0;                 // its frame rate (0: not stated)
  std::optional<double> readout_s;  // |frame_readout_time| / 1000; nullopt when null, absent or 0
  ReadoutDirection direction = ReadoutDirection::kTopToBottom;  // bottom_to_top where negative
};

struct LensProfile {
  std::string path;
  std::string name;  // "name", or brand, model and lens when it has none
  std::string calibrated_by;
  bool official = false;
  double rms_error_px = 0.0;  // the calibration's reprojection error at calib_dimension
  PinholeCamera camera;       // at the calibration size (camera.width, camera.height)
  ProfileReadout mode;        // the calibrated mode's size, fps and readout
  std::vector<ProfileReadout> compatible;  // compatible_settings, in file order
};

// Reads a profile; throws IoError("PATH: problem") for malformed JSON, a missing or impossible
// calibration (no 3x3 camera matrix, a non-positive focal length or size, the wrong number of
// coefficients) and for what shutterlab does not model (see the top of this file).
LensProfile ReadLensProfile(const std::string& path);

// What a profile gave an image: the camera scaled to it, and the readout, with where each came
// from, for the outputs that must say so.
struct LensProfileUse {
  std::string path, name;
  int calib_width = 0, calib_height = 0;  // the profile's calibration size
  int width = 0, height = 0;              // the image's
  double scale_x = 1.0, scale_y = 1.0;    // image px per calibration px
  bool aspect_differs = false;            // scale_x and scale_y differ by more than 0.1 %
  PinholeCamera camera;                   // the profile's camera at the image size
  // The profile's readout for this image, when it states one; ApplyLensProfile clears it when the
  // caller keeps its own: afterwards, the readout the rig took from the profile.
  std::optional<ProfileReadout> readout;
  std::vector<std::string> notes;  // one line each, for a person
};

// Scales the profile's camera to width x height: fx, fy by the size ratios, the principal point
// so that the same scene point keeps its place ((c + 0.5) s - 0.5: pixel centres at integers, as
// OpenCV's calibration has them), the distortion unchanged (it acts on normalised coordinates).
// The readout: a compatible setting of exactly this size (and, when fps is given, this frame rate
// within 1 %) first, else the profile's own mode's (a downscaled copy of a recording keeps its
// readout). Notes say what was scaled, whether the aspect differs (then x and y are scaled apart:
// a stretch; a crop would make the focal length off by the aspect difference), and which readout
// was used or that none is stated.
LensProfileUse ScaleLensProfile(const LensProfile& profile, int width, int height,
                                std::optional<double> fps = std::nullopt);

// Puts a scaled profile into a rig: its camera (size unchanged) and, where it states one, its
// readout and direction; adds to use->notes what the rig declared before. keep_readout: the
// caller's own readout wins (a `--readout` typed by the user, a camera's SROT).
void ApplyLensProfile(LensProfileUse* use, RigModel* rig, bool keep_readout = false);

// The use as the --json outputs and validate's report carry it: {"path", "name",
// "calibration_size": [w, h], "image_size": [w, h], "scale": [sx, sy], "aspect_differs",
// "readout_s" (null when none), "readout_source", "notes"}.
nlohmann::json LensProfileUseJson(const LensProfileUse& use);

}  // namespace shutterlab
