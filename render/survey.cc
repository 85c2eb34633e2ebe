#include "render/survey.h"

#include "io/image_io.h"
#include "render/ground_texture.h"
#include "render/rs_warp.h"
#include "render/warp_kernel.h"
#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/integrate.h"
#include "sim/logs/ulog_write.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
// The photos' clock face at gyro time 0: a date, so that capture times read as a real camera's.
constexpr int64_t kUtcAtGyroZeroNs = 1'780'308'000'000'000'000;  // 2026-06-01 10:00:00 UTC
// Where the flight's local frame sits on the globe (for the photos' GPS tags): a field in
// Switzerland, near enough to the equator's scale that x, y convert by the sphere's metres.
constexpr double kLatitudeDeg = 47.0, kLongitudeDeg = 8.0;
// The sensor's width the photos' FocalLength (mm) is written for: a 1/2.3" sensor's.
constexpr double kSensorWidthMm = 6.17;

// Uniform in [0, 1) from a 64-bit generator, the same on every standard library.
double Uniform(std::mt19937_64* rng) { return static_cast<double>((*rng)() >> 11) * 0x1.0p-53; }
double Uniform(std::mt19937_64* rng, double lo, double hi) { return lo + (hi - lo) * Uniform(rng); }

// world_from_cam of a nadir camera whose image top points along heading (deg from north, east
// positive): x (right) = heading + 90 deg, y (down) = heading + 180 deg, z (view) = down.
Eigen::Matrix3d NadirWorldFromCam(double heading_deg) {
  const double h = heading_deg * kRadPerDeg;
  Eigen::Matrix3d r;
  r.col(0) = Eigen::Vector3d(std::cos(h), -std::sin(h), 0.0);
  r.col(1) = Eigen::Vector3d(-std::sin(h), -std::cos(h), 0.0);
  r.col(2) = Eigen::Vector3d(0.0, 0.0, -1.0);
  return r;
}

std::string Signed(double v, const char* format = "%+.2f") { return FormatNumber(format, v); }

// EXIF's rational degrees, minutes, seconds.
std::string DegreesMinutesSeconds(double deg) {
  const double a = std::abs(deg);
  const int d = static_cast<int>(a);
  const int m = static_cast<int>((a - d) * 60.0);
  const double s = ((a - d) * 60.0 - m) * 60.0;
  return std::to_string(d) + "/1 " + std::to_string(m) + "/1 " +
         std::to_string(std::llround(s * 10000)) + "/10000";
}

}  // namespace

std::optional<double> Terrain::HeightAt(double x_m, double y_m) const {
  const double c = (x_m - west_m) / cell_m, r = (north_m - y_m) / cell_m;
  if (!(c >= 0 && r >= 0 && c <= height_m.cols - 1 && r <= height_m.rows - 1)) return std::nullopt;
  const int c0 = std::min(static_cast<int>(c), height_m.cols - 2);
  const int r0 = std::min(static_cast<int>(r), height_m.rows - 2);
  const double fc = c - c0, fr = r - r0;
  const double* top = height_m.ptr<double>(r0) + c0;
  const double* bottom = height_m.ptr<double>(r0 + 1) + c0;
  return (1 - fr) * ((1 - fc) * top[0] + fc * top[1]) +
         fr * ((1 - fc) * bottom[0] + fc * bottom[1]);
}

std::optional<Eigen::Vector3d> Terrain::Intersect(const Eigen::Vector3d& from,
                                                  const Eigen::Vector3d& direction) const {
  if (!(direction.z() < 0)) return std::nullopt;  // at or above the horizon: no ground
  const Eigen::Vector3d d = direction.normalized();
  // Above the highest point nothing can be hit: start there.
  double s = from.z() > max_m ? (from.z() - max_m) / -d.z() : 0.0;
  const double step = 0.25 * cell_m / std::max(std::hypot(d.x(), d.y()), -d.z());
  // Below the surface: the ray's height minus the ground's; nullopt outside the grid.
  const auto below = [&](double at) -> std::optional<bool> {
    const Eigen::Vector3d p = from + at * d;
    const std::optional<double> h = HeightAt(p.x(), p.y());
    if (!h) return std::nullopt;
    return p.z() <= *h;
  };
  std::optional<bool> hit = below(s);
  if (!hit) return std::nullopt;
  if (*hit) return from + s * d;  // starts under the surface (a camera inside a building)
  while (true) {
    const double next = s + step;
    hit = below(next);
    if (!hit) return std::nullopt;
    if (*hit) {
      double lo = s, hi = next;  // lo above, hi below
      while (hi - lo > 1e-6) {
        const double mid = 0.5 * (lo + hi);
        (*below(mid) ? hi : lo) = mid;
      }
      return from + hi * d;
    }
    s = next;
    if (from.z() + s * d.z() < min_m - 1.0) return std::nullopt;  // passed under the lowest point
  }
}

void TerrainOptions::Check() const {
  SHUTTERLAB_CHECK(width_m > 0 && depth_m > 0 && width_m < 1e5 && depth_m < 1e5)
      << "the terrain's extent must be positive (below 100 km)";
  SHUTTERLAB_CHECK(cell_m > 0 && width_m / cell_m < 20000 && depth_m / cell_m < 20000)
      << "the terrain's cell must be positive, at most 20000 cells a side";
  SHUTTERLAB_CHECK(hill_height_m >= 0 && hill_height_m < 1000) << "--hills must be 0 to 1 km";
  SHUTTERLAB_CHECK(buildings >= 0 && buildings <= 1000) << "--buildings must be 0 to 1000";
}

Terrain MakeTerrain(const TerrainOptions& options) {
  options.Check();
  Terrain t;
  t.cell_m = options.cell_m;
  const int cols = static_cast<int>(std::ceil(options.width_m / options.cell_m)) + 1;
  const int rows = static_cast<int>(std::ceil(options.depth_m / options.cell_m)) + 1;
  t.west_m = 0.0;
  t.north_m = (rows - 1) * options.cell_m;
  t.height_m = cv::Mat(rows, cols, CV_64F, cv::Scalar(0.0));
  std::mt19937_64 rng(options.seed * 0x9E3779B97F4A7C15ULL + 7);
  // Hills: six smooth bumps up and down, 15-30 m wide.
  struct Bump {
    double x, y, sigma, height;
  };
  std::vector<Bump> bumps;
  for (int k = 0; k < 6; ++k) {
    bumps.push_back({Uniform(&rng, 0, options.width_m), Uniform(&rng, 0, options.depth_m),
                     Uniform(&rng, 15, 30),
                     (k % 2 == 0 ? 0.5 : -0.5) * options.hill_height_m * Uniform(&rng, 0.6, 1.0)});
  }
  for (int r = 0; r < rows; ++r) {
    double* row = t.height_m.ptr<double>(r);
    for (int c = 0; c < cols; ++c) {
      const double x = c * t.cell_m, y = t.north_m - r * t.cell_m;
      double h = 0.0;
      for (const Bump& b : bumps) {
        h += b.height *
             std::exp(-((x - b.x) * (x - b.x) + (y - b.y) * (y - b.y)) / (2 * b.sigma * b.sigma));
      }
      row[c] = h;
    }
  }
  // Buildings: flat roofs 6-12 m above the ground at their centre, away from the edges.
  for (int k = 0; k < options.buildings; ++k) {
    const double w = Uniform(&rng, 8, 16), d = Uniform(&rng, 8, 16);
    const double x = Uniform(&rng, 0.15, 0.85) * options.width_m;
    const double y = Uniform(&rng, 0.15, 0.85) * options.depth_m;
    const double roof = *t.HeightAt(x, y) + Uniform(&rng, 6, 12);
    for (int r = 0; r < rows; ++r) {
      const double yy = t.north_m - r * t.cell_m;
      if (std::abs(yy - y) > 0.5 * d) continue;
      double* row = t.height_m.ptr<double>(r);
      for (int c = 0; c < cols; ++c) {
        if (std::abs(c * t.cell_m - x) <= 0.5 * w) row[c] = std::max(row[c], roof);
      }
    }
  }
  cv::minMaxLoc(t.height_m, &t.min_m, &t.max_m);
  return t;
}

void SurveyOptions::Check() const {
  SHUTTERLAB_CHECK(camera.width >= 16 && camera.height >= 16 && camera.width <= 20000 &&
                   camera.height <= 20000)
      << "the camera must be 16 to 20000 px a side";
  SHUTTERLAB_CHECK(camera.fx > 0 && camera.fy > 0) << "the focal length must be positive";
  SHUTTERLAB_CHECK(readout_s >= 0 && readout_s < 1) << "--readout must be 0 to 1 s";
  SHUTTERLAB_CHECK(altitude_m > 0 && altitude_m < 10000) << "--altitude must be 0 to 10 km";
  SHUTTERLAB_CHECK(speed_mps >= 0 && speed_mps <= 100) << "--speed must be 0 to 100 m/s";
  SHUTTERLAB_CHECK(front_overlap >= 0 && front_overlap < 1 && side_overlap >= 0 && side_overlap < 1)
      << "--front-overlap and --side-overlap are fractions from 0 up to (not including) 1";
  SHUTTERLAB_CHECK(lines >= 1 && lines <= 100 && photos_per_line >= 1 && photos_per_line <= 1000)
      << "--lines must be 1 to 100, --photos-per-line 1 to 1000";
  SHUTTERLAB_CHECK(speed_mps > 0 || photos_per_line == 1)
      << "--speed 0 m/s takes one photo a line (the photos would coincide)";
  SHUTTERLAB_CHECK(turn_s >= 0 && start_s >= 0) << "the turn and start times must be 0 or more";
  SHUTTERLAB_CHECK(texture_gsd_m >= 0) << "the texture's ground sample distance must be 0 or more";
  SHUTTERLAB_CHECK(jpeg_quality >= 1 && jpeg_quality <= 100) << "--jpeg-quality must be 1 to 100";
  SHUTTERLAB_CHECK(altitude_m > terrain.hill_height_m + (terrain.buildings > 0 ? 15.0 : 0.0))
      << "--altitude must clear the hills and the buildings (up to 15 m above them)";
}

double SurveyEndS(const SurveyOptions& options) {
  const SurveyPlan plan(options, std::nullopt);
  return plan.photos().back().t_first_row_ns * 1e-9 + options.readout_s;
}

SurveyPlan::SurveyPlan(const SurveyOptions& options, const GyroTrace& gyro)
    : SurveyPlan(options, std::optional<GyroTrace>(gyro)) {}

SurveyPlan::SurveyPlan(const SurveyOptions& options, const std::optional<GyroTrace>& gyro)
    : options_(options) {
  options.Check();
  const double gsd_m = options.altitude_m / options.camera.fy;
  const double along_m = options.camera.height * gsd_m;
  const double across_m = options.camera.width * options.altitude_m / options.camera.fx;
  const double base_m = along_m * (1 - options.front_overlap);
  const double spacing_m = across_m * (1 - options.side_overlap);
  // A margin for the footprint's turn and the rows' motion: a quarter of the larger side.
  const double margin_m = 0.25 * std::max(along_m, across_m);
  const int n = options.photos_per_line;
  east_extent_m_ = 2 * margin_m + across_m + (options.lines - 1) * spacing_m;
  north_extent_m_ = 2 * margin_m + along_m + (n - 1) * base_m;
  const double line_s = options.speed_mps > 0 ? (n - 1) * base_m / options.speed_mps : 0.0;
  for (int j = 0; j < options.lines; ++j) {
    const bool north = j % 2 == 0;
    for (int i = 0; i < n; ++i) {
      SurveyPhoto p;
      p.line = j;
      p.index = i;
      p.heading_deg = north ? 0.0 : 180.0;
      const int along_index = north ? i : n - 1 - i;
      p.center_m =
          Eigen::Vector3d(margin_m + 0.5 * across_m + j * spacing_m,
                          margin_m + 0.5 * along_m + along_index * base_m, options.altitude_m);
      p.velocity_mps = Eigen::Vector3d(0.0, north ? options.speed_mps : -options.speed_mps, 0.0);
      const double t_mid_s = options.start_s + 0.5 * options.readout_s +
                             j * (line_s + options.turn_s) +
                             (options.speed_mps > 0 ? i * base_m / options.speed_mps : 0.0);
      p.t_mid_ns = SecondsToNs(t_mid_s);
      p.t_first_row_ns = p.t_mid_ns - SecondsToNs(0.5 * options.readout_s);
      p.name = FormatNumber("DJI_%04.0f.JPG", static_cast<double>(photos_.size() + 1));
      photos_.push_back(p);
    }
  }
  if (!gyro) return;  // the times only (SurveyEndS)
  SHUTTERLAB_CHECK(
      !gyro->empty() && gyro->samples().front().t_ns <= photos_.front().t_first_row_ns &&
      gyro->samples().back().t_ns >= photos_.back().t_first_row_ns + SecondsToNs(options.readout_s))
      << "the gyro trace must cover every photo's readout (the flight takes "
      << FormatNumber("%.1f s", photos_.back().t_mid_ns * 1e-9) << ")";
  orientation_ = OrientationTrace(*gyro);
  for (const SurveyPhoto& p : photos_) {
    mid_from_world_int_.push_back(orientation_.WorldFromBodyAt(p.t_mid_ns).conjugate());
  }
}

CameraPose SurveyPlan::PoseAt(size_t k, double offset_s) const {
  const SurveyPhoto& p = photos_.at(k);
  const int64_t t_ns = p.t_first_row_ns + SecondsToNs(offset_s);
  const Eigen::Quaterniond mid_from_t = mid_from_world_int_[k] * orientation_.WorldFromBodyAt(t_ns);
  CameraPose pose;
  pose.world_from_cam =
      NadirWorldFromCam(p.heading_deg) * mid_from_t.normalized().toRotationMatrix();
  pose.center_m = p.center_m + p.velocity_mps * ((t_ns - p.t_mid_ns) * 1e-9);
  return pose;
}

namespace {

// The ground texture's metres per pixel: given, or half the camera's at the datum.
double TextureGsd(const SurveyOptions& options) {
  return options.texture_gsd_m > 0 ? options.texture_gsd_m
                                   : 0.5 * options.altitude_m / options.camera.fx;
}

double MidOffsetS(const SurveyPhoto& p) { return (p.t_mid_ns - p.t_first_row_ns) * 1e-9; }

// What a DJI drone writes into a photo, for photo p (heading, speed, position, time).
void PhotoMetadataFor(const SurveyPhoto& p, const SurveyOptions& options, MetadataFields* exif,
                      MetadataFields* xmp) {
  const PinholeCamera& camera = options.camera;
  const double focal_px = 0.5 * (camera.fx + camera.fy);
  const double focal_mm = focal_px * kSensorWidthMm / camera.width;
  const double focal_35mm = focal_px / std::hypot(camera.width, camera.height) * 43.27;
  const int64_t utc_ns = kUtcAtGyroZeroNs + p.t_first_row_ns;
  std::string date = UtcText(utc_ns);  // "2026-06-01 10:00:08.000"
  const std::string sub_second = date.substr(20, 3);
  date = date.substr(0, 19);
  date[4] = date[7] = ':';
  const double latitude = kLatitudeDeg + p.center_m.y() / kMetresPerDegree;
  const double longitude =
      kLongitudeDeg + p.center_m.x() / (kMetresPerDegree * std::cos(kLatitudeDeg * kRadPerDeg));
  *exif = {
      {"Exif.Image.Make", "shutterlab"},
      {"Exif.Image.Model", "survey"},
      {"Exif.Photo.FocalLength", std::to_string(std::llround(focal_mm * 1000)) + "/1000"},
      {"Exif.Photo.FocalLengthIn35mmFilm", std::to_string(std::lround(focal_35mm))},
      {"Exif.Photo.DateTimeOriginal", date},
      {"Exif.Photo.SubSecTimeOriginal", sub_second},
      {"Exif.Photo.OffsetTimeOriginal", "+00:00"},
      {"Exif.Photo.ExposureTime", "1/1000"},
      {"Exif.Photo.PixelXDimension", std::to_string(camera.width)},
      {"Exif.Photo.PixelYDimension", std::to_string(camera.height)},
      {"Exif.GPSInfo.GPSVersionID", "2 3 0 0"},
      {"Exif.GPSInfo.GPSLatitudeRef", latitude >= 0 ? "N" : "S"},
      {"Exif.GPSInfo.GPSLatitude", DegreesMinutesSeconds(latitude)},
      {"Exif.GPSInfo.GPSLongitudeRef", longitude >= 0 ? "E" : "W"},
      {"Exif.GPSInfo.GPSLongitude", DegreesMinutesSeconds(longitude)},
      {"Exif.GPSInfo.GPSAltitudeRef", "0"},
      {"Exif.GPSInfo.GPSAltitude", std::to_string(std::llround(p.center_m.z() * 1000)) + "/1000"}};
  // DJI: yaw in -180..180 from north, speeds north, east and down, m/s.
  const double yaw = p.heading_deg > 180 ? p.heading_deg - 360 : p.heading_deg;
  *xmp = {{"Xmp.drone-dji.CalibratedFocalLength", FormatNumber("%.3f", focal_px)},
          {"Xmp.drone-dji.RelativeAltitude", Signed(p.center_m.z())},
          {"Xmp.drone-dji.AbsoluteAltitude", Signed(p.center_m.z())},
          {"Xmp.drone-dji.GimbalRollDegree", "+0.00"},
          {"Xmp.drone-dji.GimbalPitchDegree", "-90.00"},
          {"Xmp.drone-dji.GimbalYawDegree", Signed(yaw)},
          {"Xmp.drone-dji.FlightRollDegree", "+0.00"},
          {"Xmp.drone-dji.FlightPitchDegree", "+0.00"},
          {"Xmp.drone-dji.FlightYawDegree", Signed(yaw)},
          {"Xmp.drone-dji.FlightXSpeed", Signed(p.velocity_mps.y())},
          {"Xmp.drone-dji.FlightYSpeed", Signed(p.velocity_mps.x())},
          {"Xmp.drone-dji.FlightZSpeed", Signed(-p.velocity_mps.z())}};
}

// The flight's velocity as a PX4 log's navigation would give it (north, east, down), at 10 Hz over
// the gyro trace: each line's own, switching to the next line's halfway through the turn between
// them (the turn itself is not flown: no photo is taken in it).
std::vector<VelocitySample> SurveyNavigation(const SurveyPlan& plan, const GyroTrace& gyro) {
  constexpr int64_t kPeriodNs = 100'000'000;
  const std::vector<SurveyPhoto>& photos = plan.photos();
  std::vector<VelocitySample> out;
  size_t k = 0;  // the photo nearest in time: its line is flown
  for (int64_t t_ns = gyro.samples().front().t_ns; t_ns <= gyro.samples().back().t_ns;
       t_ns += kPeriodNs) {
    while (k + 1 < photos.size() && t_ns > (photos[k].t_mid_ns + photos[k + 1].t_mid_ns) / 2) ++k;
    const Eigen::Vector3d& v = photos[k].velocity_mps;  // east, north, up
    out.push_back({t_ns, Eigen::Vector3d(v.y(), v.x(), -v.z())});
  }
  return out;
}

// What the flight's ULog holds beside the gyro and the camera events: the height above ground and
// the navigation's velocity.
ULogWriteOptions SurveyLogOptions(const SurveyPlan& plan, const GyroTrace& gyro,
                                  const SurveyOptions& options) {
  ULogWriteOptions ulog;
  ulog.altitude_above_ground_m = options.altitude_m;
  ulog.velocity = SurveyNavigation(plan, gyro);
  return ulog;
}

// ",qw,qx,qy,qz" of a rotation (world_from_cam).
std::string QuaternionCsv(const Eigen::Matrix3d& rotation) {
  const Eigen::Quaterniond q(rotation);
  return FormatNumber(",%.12f", q.w()) + FormatNumber(",%.12f", q.x()) +
         FormatNumber(",%.12f", q.y()) + FormatNumber(",%.12f", q.z());
}

std::string PoseCsvRow(const std::string& name, int row, double t_s, const CameraPose& pose) {
  return name + "," + std::to_string(row) + FormatNumber(",%.9f", t_s) +
         FormatNumber(",%.6f", pose.center_m.x()) + FormatNumber(",%.6f", pose.center_m.y()) +
         FormatNumber(",%.6f", pose.center_m.z()) + QuaternionCsv(pose.world_from_cam) + "\n";
}

// truth/terrain.png, terrain.json and ground.png.
void WriteTerrainTruth(const fs::path& out, const Terrain& terrain, const cv::Mat& texture,
                       double texture_gsd_m) {
  // The heights in millimetres (or finer) above the lowest point, 16 bits.
  const double scale_m = std::max(0.001, (terrain.max_m - terrain.min_m) / 65535.0);
  cv::Mat heights;
  terrain.height_m.convertTo(heights, CV_16U, 1.0 / scale_m, -terrain.min_m / scale_m);
  WriteImage((out / "truth/terrain.png").string(), heights);
  WriteImage((out / "truth/ground.png").string(), texture);
  const nlohmann::json terrain_json = {
      {"format", "terrain/1"},
      {"heights", "terrain.png"},
      {"height_m", "offset_m + value * scale_m (bilinear between nodes)"},
      {"offset_m", terrain.min_m},
      {"scale_m", scale_m},
      {"node", "row r, column c at x = west_m + c * cell_m, y = north_m - r * cell_m"},
      {"west_m", terrain.west_m},
      {"north_m", terrain.north_m},
      {"cell_m", terrain.cell_m},
      {"rows", terrain.height_m.rows},
      {"cols", terrain.height_m.cols},
      {"min_m", terrain.min_m},
      {"max_m", terrain.max_m},
      {"texture",
       {{"image", "ground.png"},
        {"gsd_m", texture_gsd_m},
        {"pixel",
         "column c, row r centred on x = west_m + (c + 0.5) gsd_m, y = north_m - (r + "
         "0.5) gsd_m"}}}};
  WriteFileAtomically((out / "truth/terrain.json").string(), terrain_json.dump(2) + "\n");
}

// survey.json: what was flown.
nlohmann::json SurveyJson(const SurveyOptions& options, const SurveySummary& summary) {
  const Terrain& terrain = summary.terrain;
  return {{"format", "survey/1"},
          {"frame", "x east, y north, z up, m; camera x right, y down, z along the view"},
          {"camera",
           {{"width", options.camera.width},
            {"height", options.camera.height},
            {"fx", options.camera.fx},
            {"fy", options.camera.fy},
            {"readout_s", options.readout_s}}},
          {"altitude_m", options.altitude_m},
          {"speed_mps", options.speed_mps},
          {"front_overlap", options.front_overlap},
          {"side_overlap", options.side_overlap},
          {"lines", options.lines},
          {"photos_per_line", options.photos_per_line},
          {"turn_s", options.turn_s},
          {"gsd_m", summary.gsd_m},
          {"terrain",
           {{"hill_height_m", options.terrain.hill_height_m},
            {"buildings", options.terrain.buildings},
            {"cell_m", options.terrain.cell_m},
            {"min_m", terrain.min_m},
            {"max_m", terrain.max_m}}},
          {"seed", options.seed},
          {"photos", summary.photos.size()},
          {"utc_at_gyro_zero", UtcText(kUtcAtGyroZeroNs)},
          {"origin", {{"latitude_deg", kLatitudeDeg}, {"longitude_deg", kLongitudeDeg}}}};
}

}  // namespace

RenderedSurveyPhoto RenderSurveyPhoto(const SurveyPlan& plan, size_t k, const Terrain& terrain,
                                      const cv::Mat& texture, const SurveyOptions& options,
                                      bool global_shutter) {
  const PinholeCamera& camera = options.camera;
  const RollingShutter shutter{options.readout_s, ReadoutDirection::kTopToBottom};
  const double mid_offset_s = MidOffsetS(plan.photos().at(k));
  const double gsd_m = TextureGsd(options);
  RenderedSurveyPhoto out;
  out.image = cv::Mat(camera.height, camera.width, CV_8UC3);
  out.ground_xy = cv::Mat(camera.height, camera.width, CV_64FC3);
  cv::parallel_for_(cv::Range(0, camera.height), [&](const cv::Range& range) {
    std::vector<int> xi(camera.width), yi(camera.width);
    for (int v = range.start; v < range.end; ++v) {
      const CameraPose pose =
          plan.PoseAt(k, global_shutter ? mid_offset_s : shutter.RowTimeOffsetS(v, camera.height));
      cv::Vec3d* ground = out.ground_xy.ptr<cv::Vec3d>(v);
      for (int u = 0; u < camera.width; ++u) {
        const Eigen::Vector3d ray = pose.world_from_cam * camera.CamFromImg(Eigen::Vector2d(u, v));
        const std::optional<Eigen::Vector3d> x = terrain.Intersect(pose.center_m, ray);
        if (!x) {
          ground[u] = cv::Vec3d(kNan, kNan, kNan);
          xi[u] = yi[u] = kInvalidFixed;
          continue;
        }
        ground[u] = cv::Vec3d(x->x(), x->y(), x->z());
        // Texture pixel (col, row) is centred on x = west + (col + 0.5) gsd, y = north - ...
        xi[u] = ToFixed(static_cast<float>((x->x() - terrain.west_m) / gsd_m - 0.5));
        yi[u] = ToFixed(static_cast<float>((terrain.north_m - x->y()) / gsd_m - 0.5));
      }
      SampleRowFixed(texture, xi.data(), yi.data(), camera.width, out.image.ptr<uchar>(v));
    }
  });
  return out;
}

cv::Mat SurveyDisplacement(const SurveyPlan& plan, size_t k, const RenderedSurveyPhoto& rolling,
                           const SurveyOptions& options) {
  const PinholeCamera& camera = options.camera;
  const CameraPose reference = plan.PoseAt(k, MidOffsetS(plan.photos().at(k)));
  const Eigen::Matrix3d cam_from_world = reference.world_from_cam.transpose();
  cv::Mat field(camera.height, camera.width, CV_32FC2, cv::Scalar::all(NAN));
  for (int v = 0; v < camera.height; ++v) {
    const cv::Vec3d* ground = rolling.ground_xy.ptr<cv::Vec3d>(v);
    cv::Vec2f* d = field.ptr<cv::Vec2f>(v);
    for (int u = 0; u < camera.width; ++u) {
      if (std::isnan(ground[u][0])) continue;
      const Eigen::Vector3d x(ground[u][0], ground[u][1], ground[u][2]);
      const std::optional<Eigen::Vector2d> q =
          camera.ImgFromCam(cam_from_world * (x - reference.center_m));
      if (q) d[u] = cv::Vec2f(static_cast<float>(q->x() - u), static_cast<float>(q->y() - v));
    }
  }
  return field;
}

SurveySummary WriteSurvey(const SurveyOptions& options, const GyroTrace& gyro,
                          const std::string& out_dir,
                          const std::function<void(size_t, size_t)>& progress) {
  const SurveyPlan plan(options, gyro);
  TerrainOptions terrain_options = options.terrain;
  terrain_options.width_m = plan.east_extent_m();
  terrain_options.depth_m = plan.north_extent_m();
  terrain_options.seed = options.seed;
  SurveySummary summary;
  summary.out_dir = out_dir;
  summary.terrain = MakeTerrain(terrain_options);
  const Terrain& terrain = summary.terrain;
  summary.gsd_m = options.altitude_m / options.camera.fx;
  GroundTextureOptions texture_options;
  // The camera must stay above the ground it flies over, with room for the rows' motion.
  SHUTTERLAB_CHECK(options.altitude_m > terrain.max_m + 5.0)
      << "--altitude " << options.altitude_m
      << " m does not clear the terrain, whose highest point is "
      << FormatNumber("%.1f m", terrain.max_m) << ": fly higher, or lower --hills";
  const double texture_gsd_m = TextureGsd(options);
  SHUTTERLAB_CHECK(terrain.WidthM() / texture_gsd_m <= 16384 &&
                   terrain.DepthM() / texture_gsd_m <= 16384)
      << "the flight covers " << FormatNumber("%.0f", terrain.WidthM()) << " x "
      << FormatNumber("%.0f m", terrain.DepthM()) << ", over 16384 texture pixels a side at "
      << FormatNumber("%.3f m", texture_gsd_m) << ": fewer --lines or --photos-per-line";
  texture_options.ground_sample_distance_m = texture_gsd_m;
  texture_options.width_px = static_cast<int>(std::ceil(terrain.WidthM() / texture_gsd_m));
  texture_options.height_px = static_cast<int>(std::ceil(terrain.DepthM() / texture_gsd_m));
  texture_options.seed = options.seed;
  const cv::Mat texture = MakeGroundTexture(texture_options);

  const fs::path out(out_dir);
  for (const char* folder : {"images", "reference", "truth"}) {
    std::error_code ec;
    fs::create_directories(out / folder, ec);
    if (ec) throw IoError(IoMessage((out / folder).string(), 0, "cannot create: " + ec.message()));
  }
  const int quality = static_cast<int>(std::lround(options.jpeg_quality));
  const RollingShutter shutter{options.readout_s, ReadoutDirection::kTopToBottom};
  std::string poses = "photo,row,t_s,x_m,y_m,z_m,qw,qx,qy,qz\n";
  std::string photos_csv =
      "photo,line,index,t_first_row_s,t_mid_s,x_m,y_m,z_m,qw,qx,qy,qz,heading_deg,vx_mps,"
      "vy_mps,vz_mps,D_px\n";
  std::vector<CameraEvent> events;
  for (size_t k = 0; k < plan.photos().size(); ++k) {
    SurveyPhoto photo = plan.photos()[k];
    const RenderedSurveyPhoto rolling =
        RenderSurveyPhoto(plan, k, terrain, texture, options, false);
    const RenderedSurveyPhoto global = RenderSurveyPhoto(plan, k, terrain, texture, options, true);
    photo.d_px = FrameDistortionPx(SurveyDisplacement(plan, k, rolling, options));
    MetadataFields exif, xmp;
    PhotoMetadataFor(photo, options, &exif, &xmp);
    WriteImageWithMetadata((out / "images" / photo.name).string(), rolling.image, quality, exif,
                           xmp);
    WriteImageWithMetadata((out / "reference" / photo.name).string(), global.image, quality, exif,
                           xmp);
    for (int v = 0; v < options.camera.height; ++v) {
      const double offset_s = shutter.RowTimeOffsetS(v, options.camera.height);
      poses += PoseCsvRow(photo.name, v, photo.t_first_row_ns * 1e-9 + offset_s,
                          plan.PoseAt(k, offset_s));
    }
    photos_csv +=
        photo.name + "," + std::to_string(photo.line) + "," + std::to_string(photo.index) +
        FormatNumber(",%.9f", photo.t_first_row_ns * 1e-9) +
        FormatNumber(",%.9f", photo.t_mid_ns * 1e-9) + FormatNumber(",%.6f", photo.center_m.x()) +
        FormatNumber(",%.6f", photo.center_m.y()) + FormatNumber(",%.6f", photo.center_m.z()) +
        QuaternionCsv(plan.PoseAt(k, MidOffsetS(photo)).world_from_cam) +
        FormatNumber(",%g", photo.heading_deg) + FormatNumber(",%g", photo.velocity_mps.x()) +
        FormatNumber(",%g", photo.velocity_mps.y()) + FormatNumber(",%g", photo.velocity_mps.z()) +
        FormatNumber(",%.4f", photo.d_px) + "\n";
    events.push_back({photo.t_first_row_ns, static_cast<int64_t>(k), ""});
    summary.photos.push_back(photo);
    if (progress) progress(k + 1, plan.photos().size());
  }
  WriteULog((out / "flight.ulg").string(), gyro, events, SurveyLogOptions(plan, gyro, options));

  RigModel rig;
  rig.camera = options.camera;
  rig.shutter = shutter;
  rig.altitude_m = options.altitude_m;
  WriteRigModel((out / "truth/camera.json").string(), rig);
  WriteTerrainTruth(out, terrain, texture, texture_gsd_m);
  WriteFileAtomically((out / "truth/photos.csv").string(), photos_csv);
  WriteFileAtomically((out / "truth/poses.csv").string(), poses);

  const nlohmann::json flown = SurveyJson(options, summary);
  WriteFileAtomically((out / "survey.json").string(), flown.dump(2) + "\n");
  for (const SurveyPhoto& p : summary.photos) {
    summary.files.push_back((out / "images" / p.name).string());
    summary.files.push_back((out / "reference" / p.name).string());
  }
  for (const char* f :
       {"flight.ulg", "truth/camera.json", "truth/terrain.png", "truth/terrain.json",
        "truth/ground.png", "truth/photos.csv", "truth/poses.csv", "survey.json"}) {
    summary.files.push_back((out / f).string());
  }
  return summary;
}

}  // namespace shutterlab
