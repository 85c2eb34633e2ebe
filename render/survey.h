#pragma once
// `shutterlab survey`: a mapping flight with exact truth, for measuring what a rolling shutter does
// to a photogrammetry pipeline and what correcting it buys. A lawnmower flight (lines north and
// south at one height and speed, photos at a front and side overlap) over a ground texture with
// relief (gentle hills and box buildings, a height grid), the camera looking straight down with
// the image's top ahead. Each photo is rendered row by row (rolling shutter: row v from the pose
// at its own instant) and as its global-shutter reference (every row from the pose at the middle
// row's instant); every pixel's ray is intersected with the terrain (the grid's bilinear surface,
// marched in quarter cells and bisected to 1e-6 m: a ray that grazes a roof's edge for less than a
// quarter cell passes over it) and the texture is sampled where it lands.
//
// World frame: x east, y north, z up, metres; the terrain's grid and the texture cover the same
// rectangle, north up. The camera frame is docs/FORMATS.md's (x right, y down, z along the view).
// Motion: the translation of the flight (constant velocity along the line) and, within each
// photo, the rotation a gyro trace gives about the middle row: R(t) = R_nadir(heading) ·
// R_int(t_mid)ᵀ R_int(t), R_int the trace (camera axes) integrated. Each photo is thus nadir at
// its middle row (a gimbal's hold), turned by the trace's motion during the readout.
//
// What a drone would write, and the truth beside it (docs/FORMATS.md "Survey"):
//   images/NAME.JPG       the rolling-shutter photos, EXIF (make, model, focal length and its
//                         35 mm equivalent, capture time, GPS) and XMP drone-dji (relative
//                         altitude, gimbal and flight attitude, flight speed north/east/down)
//   reference/NAME.JPG    the global-shutter photos from the middle row's pose, same metadata
//   flight.ulg            the gyro trace (camera axes) and a camera_capture event at each
//                         photo's first row, PX4 ULog; the height above ground; the velocity
//                         (vehicle_local_position at 10 Hz: each line's, switching halfway
//                         through the turn)
//   truth/camera.json     the camera (readout, altitude above the datum, velocity zero)
//   truth/terrain.png     the height grid, 16-bit: height_m = offset_m + value * scale_m
//   truth/terrain.json    the grid's corner, cell, scale and offset; the texture's
//   truth/ground.png      the ground texture (north up, the terrain's rectangle)
//   truth/photos.csv      per photo: times, the middle row's pose, velocity, heading, D
//   truth/poses.csv       per photo and image row: the row's instant and pose
//   survey.json           what was flown, with every option

#include "model/camera.h"
#include "sim/gyro_trace.h"
#include "sim/integrate.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// A height grid: height_m(r, c) at x = west_m + c * cell_m, y = north_m - r * cell_m (row 0 the
// northern edge), bilinear between nodes; the surface stops at the grid's edges.
struct Terrain {
  cv::Mat height_m;  // CV_64F
  double west_m = 0.0, north_m = 0.0, cell_m = 0.25;
  double min_m = 0.0, max_m = 0.0;  // over the grid

  double WidthM() const { return (height_m.cols - 1) * cell_m; }
  double DepthM() const { return (height_m.rows - 1) * cell_m; }
  // Bilinear height at (x, y); nullopt outside the grid.
  std::optional<double> HeightAt(double x_m, double y_m) const;
  // The first point where the ray from `from` along `direction` (downward: z < 0) meets the
  // surface, marched in steps of a quarter cell from the grid's top and refined by bisection to
  // 1e-6 m; nullopt when the ray leaves the grid first.
  std::optional<Eigen::Vector3d> Intersect(const Eigen::Vector3d& from,
                                           const Eigen::Vector3d& direction) const;
};

struct TerrainOptions {
  double width_m = 100.0, depth_m = 100.0;  // east-west, north-south extent
  double cell_m = 0.25;
  double hill_height_m = 3.0;  // gentle hills: a sum of smooth bumps, peak to trough about this
  int buildings = 4;           // flat-roofed boxes, 6-12 m tall, 8-16 m wide
  uint64_t seed = 1;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};
// Deterministic for the same options; the grid's south-west corner at (0, 0).
Terrain MakeTerrain(const TerrainOptions& options);

struct SurveyOptions {
  PinholeCamera camera;         // no distortion (the truth is the pinhole's)
  double readout_s = 0.030;     // first row to last
  double altitude_m = 50.0;     // above the datum (z = 0)
  double speed_mps = 5.0;       // along each line
  double front_overlap = 0.70;  // share of a photo's footprint the next photo sees again
  double side_overlap = 0.60;   // the same between lines
  int lines = 2;                // flown north, south, north, ...
  int photos_per_line = 6;
  double turn_s = 10.0;        // between lines
  double start_s = 8.0;        // the first photo's first row, on the gyro's clock
  TerrainOptions terrain;      // its extent is set to the flight's footprint plus margins
  double texture_gsd_m = 0.0;  // the ground texture's metres per pixel; 0: half the camera's
  uint64_t seed = 1;           // the terrain's and the texture's
  double jpeg_quality = 95;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// One photo's truth.
struct SurveyPhoto {
  std::string name;            // DJI_0001.JPG, ...
  int line = 0, index = 0;     // its line and place on it
  int64_t t_first_row_ns = 0;  // the gyro's clock
  int64_t t_mid_ns = 0;        // the middle row's instant: the reference's pose
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();      // at t_mid, world
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();  // world
  double heading_deg = 0.0;                                // of the image's top, from north
  double d_px = 0.0;  // docs/FORMATS.md D of the photo against its reference (rows' motion)
};

// A pose of the camera: world_from_cam and the centre, world.
struct CameraPose {
  Eigen::Matrix3d world_from_cam = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
};

// The flight's geometry, before anything is rendered: where and when each photo is taken, and
// the camera's pose at any instant of its readout.
class SurveyPlan {
 public:
  // gyro: rates in camera axes covering every photo's readout (std::invalid_argument otherwise).
  SurveyPlan(const SurveyOptions& options, const GyroTrace& gyro);
  const std::vector<SurveyPhoto>& photos() const { return photos_; }
  // The pose at offset_s after photo k's first row (row v: RowTimeOffsetS).
  CameraPose PoseAt(size_t k, double offset_s) const;
  // The rectangle every photo's footprint lies in, with a margin: terrain and texture cover it.
  double east_extent_m() const { return east_extent_m_; }
  double north_extent_m() const { return north_extent_m_; }

 private:
  SurveyOptions options_;
  std::vector<SurveyPhoto> photos_;
  OrientationTrace orientation_;                        // R_int: the trace integrated
  std::vector<Eigen::Quaterniond> mid_from_world_int_;  // per photo: R_int(t_mid)^T
  double east_extent_m_ = 0.0, north_extent_m_ = 0.0;

  friend double SurveyEndS(const SurveyOptions& options);
  SurveyPlan(const SurveyOptions& options, const std::optional<GyroTrace>& gyro);
};

// The last photo's last row, on the gyro's clock, s: what a trace must cover.
double SurveyEndS(const SurveyOptions& options);

// A rendered photo: each pixel's colour and where its ray met the ground.
struct RenderedSurveyPhoto {
  cv::Mat image;      // CV_8UC3, R G B; black where the ray leaves the terrain
  cv::Mat ground_xy;  // CV_64FC3: the ground point (x, y, z) each pixel sees; NaN where none
};
// Photo k rendered with every row at its own instant (rolling shutter) or, global_shutter, every
// row at the middle row's instant. texture: the ground (north up) over the terrain's rectangle.
RenderedSurveyPhoto RenderSurveyPhoto(const SurveyPlan& plan, size_t k, const Terrain& terrain,
                                      const cv::Mat& texture, const SurveyOptions& options,
                                      bool global_shutter);

// The displacement of each rolling-shutter pixel into the global-shutter photo (the reference's
// pixel that sees the same ground point), CV_32FC2, NaN where the ray leaves the terrain; its D is
// SurveyPhoto::d_px. Occlusion is not checked: a point hidden from the reference still projects.
cv::Mat SurveyDisplacement(const SurveyPlan& plan, size_t k, const RenderedSurveyPhoto& rolling,
                           const SurveyOptions& options);

struct SurveySummary {
  std::string out_dir;
  std::vector<SurveyPhoto> photos;
  Terrain terrain;
  double gsd_m = 0.0;              // the camera's at the datum, m/px
  std::vector<std::string> files;  // written: out_dir / each
};

// Plans, renders and writes the survey (the header's files). progress(done, total) after each
// photo. Throws std::invalid_argument for bad options, IoError for a file that cannot be written;
// the folder's files are each written whole.
SurveySummary WriteSurvey(const SurveyOptions& options, const GyroTrace& gyro,
                          const std::string& out_dir,
                          const std::function<void(size_t, size_t)>& progress = {});

}  // namespace shutterlab
