#include "io/colmap_model.h"

#include "sim/check.h"
#include "sim/text_file.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <string_view>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// The whitespace-separated fields of a line.
std::vector<std::string_view> Fields(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

// Calls each(line number, fields) for every line that is not a # comment (nor empty, unless
// keep_empty); the file must exist (the binary form is named where it is there instead).
void ForEachLine(const fs::path& dir, const std::string& name, bool keep_empty,
                 const std::function<void(long, const std::vector<std::string_view>&)>& each) {
  const fs::path path = dir / name;
  if (!fs::is_regular_file(path)) {
    const std::string binary = fs::path(name).replace_extension(".bin").string();
    throw IoError(IoMessage(
        path.string(), 0,
        fs::is_regular_file(dir / binary)
            ? "missing; the folder holds COLMAP's binary model: convert it with colmap "
              "model_converter --input_path DIR --output_path DIR --output_type TXT"
            : "missing: give a COLMAP text model (cameras.txt, images.txt, points3D.txt)"));
  }
  const std::string text = ReadFileToString(path.string());
  std::string_view rest = text;
  long number = 0;
  while (!rest.empty()) {
    const size_t end = rest.find('\n');
    const std::string_view line = rest.substr(0, end);
    rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 1);
    ++number;
    const std::vector<std::string_view> fields = Fields(line);
    if (fields.empty() ? !keep_empty || rest.empty() : fields[0][0] == '#') continue;
    each(number, fields);
  }
}

double Number(const fs::path& path, long line, std::string_view field, const char* what) {
  const std::optional<double> v = ParseDouble(field);
  if (!v) {
    throw IoError(IoMessage(path.string(), line,
                            std::string(what) + " is not a number ('" + std::string(field) + "')"));
  }
  return *v;
}

int64_t Integer(const fs::path& path, long line, std::string_view field, const char* what) {
  const std::optional<int64_t> v = ParseInt(field);
  if (!v) {
    throw IoError(
        IoMessage(path.string(), line,
                  std::string(what) + " is not an integer ('" + std::string(field) + "')"));
  }
  return *v;
}

}  // namespace

Eigen::Vector3d ColmapImage::CenterM() const { return -(WorldFromCam() * cam_from_world_t); }

Eigen::Matrix3d ColmapImage::WorldFromCam() const {
  return cam_from_world_q.normalized().toRotationMatrix().transpose();
}

double ColmapModel::MeanReprojectionErrorPx() const {
  double sum = 0.0;
  size_t count = 0;
  for (const ColmapPoint& p : points) {
    sum += p.error_px * p.track_length;
    count += p.track_length;
  }
  return count > 0 ? sum / count : 0.0;
}

ColmapModel ReadColmapTextModel(const std::string& dir_text) {
  const fs::path dir(dir_text);
  ColmapModel model;
  ForEachLine(dir, "cameras.txt", false,
              [&](long, const std::vector<std::string_view>&) { ++model.cameras; });
  const fs::path images = dir / "images.txt";
  // Two lines an image: its pose and name, then its 2D points (X Y POINT3D_ID; -1: none), the
  // second empty for an image without points.
  ColmapImage* last = nullptr;
  ForEachLine(dir, "images.txt", true, [&](long number, const std::vector<std::string_view>& f) {
    if (last == nullptr) {
      if (f.empty()) return;  // a blank line between images, or after the last
      if (f.size() < 10) {
        throw IoError(
            IoMessage(images.string(), number,
                      "an image line needs IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME"));
      }
      ColmapImage image;
      image.id = Integer(images, number, f[0], "IMAGE_ID");
      image.cam_from_world_q = Eigen::Quaterniond(
          Number(images, number, f[1], "QW"), Number(images, number, f[2], "QX"),
          Number(images, number, f[3], "QY"), Number(images, number, f[4], "QZ"));
      if (!(std::abs(image.cam_from_world_q.norm() - 1.0) < 1e-3)) {
        throw IoError(IoMessage(images.string(), number, "the rotation is not a unit quaternion"));
      }
      image.cam_from_world_t =
          Eigen::Vector3d(Number(images, number, f[5], "TX"), Number(images, number, f[6], "TY"),
                          Number(images, number, f[7], "TZ"));
      image.camera_id = Integer(images, number, f[8], "CAMERA_ID");
      std::string name(f[9]);
      for (size_t k = 10; k < f.size(); ++k) name += " " + std::string(f[k]);  // a name's spaces
      image.name = name;
      model.images.push_back(std::move(image));
      last = &model.images.back();
      return;
    }
    if (f.size() % 3 != 0) {
      throw IoError(IoMessage(images.string(), number, "2D points come as X Y POINT3D_ID triples"));
    }
    for (size_t k = 2; k < f.size(); k += 3) last->observations += f[k] != "-1";
    last = nullptr;
  });
  const fs::path points = dir / "points3D.txt";
  ForEachLine(dir, "points3D.txt", false, [&](long number, const std::vector<std::string_view>& f) {
    if (f.size() < 8 || (f.size() - 8) % 2 != 0) {
      throw IoError(IoMessage(points.string(), number,
                              "a point needs POINT3D_ID X Y Z R G B ERROR and (IMAGE_ID, "
                              "POINT2D_IDX) pairs"));
    }
    ColmapPoint p;
    p.id = Integer(points, number, f[0], "POINT3D_ID");
    p.xyz = Eigen::Vector3d(Number(points, number, f[1], "X"), Number(points, number, f[2], "Y"),
                            Number(points, number, f[3], "Z"));
    p.error_px = Number(points, number, f[7], "ERROR");
    p.track_length = (f.size() - 8) / 2;
    model.points.push_back(p);
  });
  return model;
}

}  // namespace shutterlab
