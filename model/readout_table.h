#pragma once
// Rolling-shutter readout times of common drone cameras, for when nothing better is known: not the
// user (--readout), not camera.json, not a lens profile, not the file.
//
// Source: OpenDroneMap's readout database, `RS_DATABASE` in opendm/rollingshutter.py of
// github.com/OpenDroneMap/ODM at commit 32cfaacfe15ae0a037da25c8e544b92ddf875342 (last change to
// the table 5f05b988, 2026-03-25). ODM is AGPL-3.0; only the numbers (facts: camera -> readout in
// ms, and the megapixel ranges of the cameras whose readout depends on the photo mode) are taken
// over, typed in again; no code was copied. The values were measured by ODM's community with
// OpenDroneMap/RSCalibration (a filmed blinking LED) and are unverified: priors, not ground truth.
// Every output that used one says so (ReadoutLookup::Citation).

#include <optional>
#include <string>

namespace shutterlab {

struct ReadoutLookup {
  double readout_s = 0.0;
  std::string key;        // the table's key: EXIF "make model", trimmed, lower case
  std::string camera;     // the camera's common name, e.g. "Mini 4 Pro"
  std::string condition;  // the photo mode's megapixel range, e.g. "9.1 MP < 12 MP"; empty if any
  // One line for outputs: "table: dji fc8482 (Mini 4 Pro) 16 ms for < 12 MP, OpenDroneMap's
  // rolling-shutter database (community-measured)".
  std::string Citation() const;
};

// The table's key for an EXIF make and model: "<make> <model>", each trimmed, lower case (ODM's
// make_model_key).
std::string ReadoutTableKey(const std::string& make, const std::string& model);

// The readout for a camera and the megapixels of its photo mode (width * height / 1e6 of the
// camera's own image: EXIF PixelXDimension x PixelYDimension, not a downscaled copy's pixels);
// nullopt when the camera is not in the table.
std::optional<ReadoutLookup> LookUpReadout(const std::string& make, const std::string& model,
                                           double megapixels);

// The number of rows in the table (35 for the cited commit), for the test that checks it against
// the facts file.
size_t ReadoutTableRows();

}  // namespace shutterlab
