#pragma once
// An OpenSfM camera (ODM's camera models: opensfm/cameras.json, camera_models_overrides.json, the
// reconstruction's "cameras"; OpenSfM doc/source/geometry.rst) as shutterlab's camera, which
// io/lens_profile.h makes a profile of, so that `--lens-profile` takes the camera ODM calibrated:
// {"KEY": {"projection_type", "width", "height",
// ...}} with one camera, or the key "all". Normalised by S = max(width, height) from the image
// centre with OpenSfM's half pixel: fx = focal_x S, cx = c_x S + width / 2 - 0.5 (OpenCV's pixel
// centres, as shutterlab's). Projections read: perspective (focal, k1, k2), brown (focal_x,
// focal_y, c_x, c_y, k1, k2, k3, p1, p2: OpenCV's terms), fisheye (focal, k1, k2: OpenCV's fisheye
// with k3 = k4 = 0) and fisheye_opencv (focal_x, focal_y, c_x, c_y, k1..k4); any other is refused.
// OpenSfM's cameras carry no readout.

#include "model/camera.h"

#include <nlohmann/json_fwd.hpp>

#include <string>

namespace shutterlab {

// True when j looks like OpenSfM's cameras: an object whose every value is an object with a
// "projection_type".
bool IsOpenSfmCameras(const nlohmann::json& j);

struct OpenSfmCamera {
  std::string key;       // its key in the file ("all", "v2 dji fc6310 ...")
  PinholeCamera camera;  // at its own size (width x height)
};

// The one camera of j (or its "all"); throws IoError("PATH: problem") for several cameras, a
// projection shutterlab does not model, or a missing or impossible field.
OpenSfmCamera ReadOpenSfmCamera(const nlohmann::json& j, const std::string& path);

}  // namespace shutterlab
