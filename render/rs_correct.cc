#include "render/rs_correct.h"

#include "sim/check.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

namespace shutterlab {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// A node whose source lies farther than this outside the frame is clamped to it: it has no source
// either way, and the fixed-point coordinates stay far inside int's range.
constexpr double kFarPx = 1e6;
// The fixed point is given up when the row runs this many frame heights away, or after this many
// steps (a contraction below 0.5 halves the step each time: 1e-6 px in ~40 steps from 1e6).
constexpr double kLostRows = 100.0;
constexpr int kMaxSolveSteps = 60;

}  // namespace

const char* CorrectionReferenceName(CorrectionReference reference) {
  return reference == CorrectionReference::kFirstRow ? "row0" : "mid";
}

std::optional<CorrectionReference> ParseCorrectionReference(const std::string& name) {
  if (name == "row0") return CorrectionReference::kFirstRow;
  if (name == "mid") return CorrectionReference::kMidReadout;
  return std::nullopt;
}

double ReferenceRow(CorrectionReference reference, const RollingShutter& shutter, int height) {
  if (reference == CorrectionReference::kFirstRow) return 0.0;
  // RowTimeOffsetS(row) = read_index * readout / height: half the readout is read index height/2.
  const double read_index = 0.5 * height;
  return shutter.direction == ReadoutDirection::kTopToBottom ? read_index
                                                             : (height - 1) - read_index;
}

CorrectionGeometry::CorrectionGeometry(const PinholeCamera& camera, FrameMotion motion,
                                       double reference_row, std::optional<double> plane_depth_m)
    : camera_(camera), plane_depth_m_(plane_depth_m) {
  const int height = camera.height;
  SHUTTERLAB_CHECK(static_cast<int>(motion.world_from_cam.size()) == height &&
                   static_cast<int>(motion.cam_center_m.size()) == height)
      << "frame motion has " << motion.world_from_cam.size() << " rows, the camera " << height;
  SHUTTERLAB_CHECK(reference_row >= 0 && reference_row <= height - 1)
      << "reference row " << reference_row << " outside the frame";
  SHUTTERLAB_CHECK(!plane_depth_m || (*plane_depth_m > 0 && std::isfinite(*plane_depth_m)))
      << "plane depth must be positive";
  world_from_ref_ = motion.WorldFromCamAtRow(reference_row);
  ref_center_m_ = motion.CamCenterAtRow(reference_row);
  // The rows turned in place: a prediction builds one geometry a draw, and a 12 MP frame's rows
  // copied are 300 kB each time.
  center_m_ = std::move(motion.cam_center_m);
  cam_from_world_ = std::move(motion.world_from_cam);
  for (Eigen::Matrix3d& r : cam_from_world_) r.transposeInPlace();
}

void CorrectionGeometry::PoseAtRow(double row, Eigen::Matrix3d* cam_from_world,
                                   Eigen::Vector3d* center_m) const {
  const int last = static_cast<int>(cam_from_world_.size()) - 1;
  if (last == 0) {
    *cam_from_world = cam_from_world_[0];
    *center_m = center_m_[0];
    return;
  }
  // Linear between neighbouring rows, and the first and last row pairs' change carried on beyond
  // the frame. Against the slerp of FrameMotion::WorldFromCamAtRow this differs by
  // a (1 - a) / 2 (theta^2 I - theta theta^T), theta the row-to-row rotation vector: the part along
  // I only scales the point, which the projection divides away; the rest is below theta^2 / 8 rad,
  // ~1e-11 rad for a frame that stays sharp.
  const int r0 = std::clamp(static_cast<int>(std::floor(row)), 0, last - 1);
  const double a = row - r0;
  *cam_from_world = cam_from_world_[r0] + a * (cam_from_world_[r0 + 1] - cam_from_world_[r0]);
  *center_m = center_m_[r0] + a * (center_m_[r0 + 1] - center_m_[r0]);
}

std::optional<Eigen::Vector2d> CorrectionGeometry::SourcePixel(double u, double v,
                                                               std::optional<double> start_row,
                                                               double solve_tol_px) const {
  const Eigen::Vector3d ray = world_from_ref_ * camera_.CamFromImg(Eigen::Vector2d(u, v));
  Eigen::Vector3d point = ray;
  if (plane_depth_m_) {
    const double s = (*plane_depth_m_ - ref_center_m_.z()) / ray.z();
    if (!(s > 0) || !std::isfinite(s)) return std::nullopt;
    point = ref_center_m_ + s * ray;
  }
  const double lost = kLostRows * camera_.height;
  double w = start_row && std::isfinite(*start_row) ? *start_row : v;
  Eigen::Matrix3d cam_from_world;
  Eigen::Vector3d center_m;
  for (int step = 0; step < kMaxSolveSteps; ++step) {
    PoseAtRow(w, &cam_from_world, &center_m);
    const Eigen::Vector3d p_in_cam = plane_depth_m_
                                         ? Eigen::Vector3d(cam_from_world * (point - center_m))
                                         : Eigen::Vector3d(cam_from_world * point);
    const std::optional<Eigen::Vector2d> q = camera_.ImgFromCam(p_in_cam);
    if (!q || !q->allFinite() || std::abs(q->y()) > lost) return std::nullopt;
    if (std::abs(q->y() - w) <= solve_tol_px) return q;
    w = q->y();
  }
  return std::nullopt;
}

std::optional<Eigen::Vector2d> CorrectionGeometry::OutputPixel(double u, double v) const {
  Eigen::Matrix3d cam_from_world;
  Eigen::Vector3d center;
  PoseAtRow(v, &cam_from_world, &center);
  const Eigen::Vector3d ray =
      cam_from_world.transpose() * camera_.CamFromImg(Eigen::Vector2d(u, v));
  if (!plane_depth_m_) return camera_.ImgFromCam(world_from_ref_.transpose() * ray);
  const double s = (*plane_depth_m_ - center.z()) / ray.z();
  if (!(s > 0) || !std::isfinite(s)) return std::nullopt;
  return camera_.ImgFromCam(world_from_ref_.transpose() * (center + s * ray - ref_center_m_));
}

bool CorrectionGeometry::HasSource(const Eigen::Vector2d& q) const {
  return q.x() >= 0 && q.x() <= camera_.width - 1 && q.y() >= 0 && q.y() <= camera_.height - 1;
}

void CorrectionMapOptions::Check() const {
  SHUTTERLAB_CHECK(tolerance_px > 0 && std::isfinite(tolerance_px))
      << "map tolerance must be positive (got " << tolerance_px << " px)";
  SHUTTERLAB_CHECK(max_cell_px >= 2 && max_cell_px <= 1024)
      << "map cell must be 2 to 1024 px (got " << max_cell_px << ")";
}

CorrectionMap::CorrectionMap(const CorrectionGeometry& geometry,
                             const CorrectionMapOptions& options)
    : geometry_(geometry) {
  options.Check();
  // Nodes and checks are solved to 1 % of the tolerance: the map's own error is what is checked.
  solve_tol_px_ = 0.01 * options.tolerance_px;
  for (int cell = options.max_cell_px;; cell /= 2) {
    if (BuildRows(cell, options.tolerance_px) || cell <= 2) break;
  }
  Finish();
}

CorrectionMap::NodeRow CorrectionMap::SolveRow(int v, const std::vector<double>& us,
                                               const std::vector<double>& start) const {
  NodeRow row;
  row.x.assign(us.size(), NAN);
  row.y.assign(us.size(), NAN);
  for (size_t i = 0; i < us.size(); ++i) {
    std::optional<double> from;
    if (std::isfinite(start[i])) from = start[i];
    const std::optional<Eigen::Vector2d> q = geometry_.SourcePixel(us[i], v, from, solve_tol_px_);
    if (!q) continue;
    row.x[i] = std::clamp(q->x(), -kFarPx, kFarPx);
    row.y[i] = std::clamp(q->y(), -kFarPx, kFarPx);
  }
  return row;
}

bool CorrectionMap::BuildRows(int cell_px, double tolerance_px) {
  cell_px_ = cell_px;
  const PinholeCamera& camera = geometry_.camera();
  const auto uniform = [cell_px](int size) {
    std::vector<int> at;
    for (int x = 0; x < size - 1; x += cell_px) at.push_back(x);
    at.push_back(size - 1);
    return at;
  };
  node_u_ = uniform(camera.width);
  std::vector<double> us(node_u_.begin(), node_u_.end()), mids;
  for (size_t i = 0; i + 1 < node_u_.size(); ++i) mids.push_back(0.5 * (us[i] + us[i + 1]));
  rows_.clear();
  estimated_error_px_ = 0.0;
  // Uniform node rows first, each started from the row above moved down with it.
  std::vector<double> start(us.size(), NAN);
  int previous = 0;
  for (int v : uniform(camera.height)) {
    for (size_t i = 0; i < us.size() && !rows_.empty(); ++i) {
      start[i] = rows_.rbegin()->second.y[i] + (v - previous);
    }
    rows_[v] = SolveRow(v, us, start);
    previous = v;
  }
  // Along a row the map is smooth: its error at the cells' midpoints on the node rows decides the
  // columns' spacing.
  for (const auto& [v, row] : rows_) {
    std::vector<double> guess(mids.size());
    for (size_t i = 0; i < mids.size(); ++i) guess[i] = 0.5 * (row.y[i] + row.y[i + 1]);
    const NodeRow exact = SolveRow(v, mids, guess);
    for (size_t i = 0; i < mids.size(); ++i) {
      const double dx = 0.5 * (row.x[i] + row.x[i + 1]) - exact.x[i];
      const double dy = guess[i] - exact.y[i];
      if (std::isfinite(dx) && std::isfinite(dy)) {
        estimated_error_px_ = std::max(estimated_error_px_, std::hypot(dx, dy));
      }
    }
  }
  if (estimated_error_px_ > tolerance_px) return false;
  // Down the columns the pose is only piecewise smooth (the gyro's rate bends at every sample):
  // each band of rows is checked at its middle row, at the node columns and the cells' centres,
  // and split there (the checked row becomes a node row) until its error is within tolerance.
  std::vector<std::pair<int, int>> bands;
  for (auto it = rows_.begin(); std::next(it) != rows_.end(); ++it) {
    bands.emplace_back(it->first, std::next(it)->first);
  }
  std::vector<double> both = us;
  both.insert(both.end(), mids.begin(), mids.end());
  while (!bands.empty()) {
    const auto [top, bottom] = bands.back();
    bands.pop_back();
    if (bottom - top <= 1) continue;
    const int middle = (top + bottom) / 2;
    const double t = static_cast<double>(middle - top) / (bottom - top);
    const NodeRow& a = rows_.at(top);
    const NodeRow& b = rows_.at(bottom);
    // The band's interpolation at the middle row: node columns, then the cells' centres.
    NodeRow interpolated;
    for (size_t i = 0; i < us.size(); ++i) {
      interpolated.x.push_back((1 - t) * a.x[i] + t * b.x[i]);
      interpolated.y.push_back((1 - t) * a.y[i] + t * b.y[i]);
    }
    for (size_t i = 0; i < mids.size(); ++i) {
      interpolated.x.push_back(0.5 * (interpolated.x[i] + interpolated.x[i + 1]));
      interpolated.y.push_back(0.5 * (interpolated.y[i] + interpolated.y[i + 1]));
    }
    const NodeRow exact = SolveRow(middle, both, interpolated.y);
    double band_error = 0.0;
    for (size_t i = 0; i < both.size(); ++i) {
      const double e = std::hypot(interpolated.x[i] - exact.x[i], interpolated.y[i] - exact.y[i]);
      if (std::isfinite(e)) band_error = std::max(band_error, e);
    }
    if (band_error <= tolerance_px) {
      estimated_error_px_ = std::max(estimated_error_px_, band_error);
      continue;
    }
    NodeRow node_row;
    node_row.x.assign(exact.x.begin(), exact.x.begin() + us.size());
    node_row.y.assign(exact.y.begin(), exact.y.begin() + us.size());
    rows_[middle] = std::move(node_row);
    bands.emplace_back(top, middle);
    bands.emplace_back(middle, bottom);
  }
  return true;
}

void CorrectionMap::Finish() {
  const PinholeCamera& camera = geometry_.camera();
  const size_t columns = node_u_.size();
  node_v_.clear();
  node_x_.clear();
  node_y_.clear();
  for (const auto& [v, row] : rows_) {
    node_v_.push_back(v);
    for (size_t i = 0; i < columns; ++i) {
      node_x_.push_back(static_cast<float>(row.x[i]));
      node_y_.push_back(static_cast<float>(row.y[i]));
    }
  }
  rows_.clear();
  const double one = 1 << kSampleFracBits;
  node_x_fixed_.resize(node_x_.size());
  node_y_fixed_.resize(node_y_.size());
  for (size_t k = 0; k < node_x_.size(); ++k) {
    node_x_fixed_[k] = static_cast<float>(node_x_[k] * one);
    node_y_fixed_[k] = static_cast<float>(node_y_[k] * one);
  }
  // Per output row its cell row and the weight of the row below; per column its cell.
  row_cell_.resize(camera.height);
  row_t_.resize(camera.height);
  for (size_t j = 0; j < node_v_.size(); ++j) {
    const int begin = node_v_[j];
    const int end = j + 1 < node_v_.size() ? node_v_[j + 1] : camera.height;
    const double span = j + 1 < node_v_.size() ? node_v_[j + 1] - node_v_[j] : 1.0;
    for (int v = begin; v < end; ++v) {
      // The last node row belongs to the cell above it (weight 1), as every other cell's bottom.
      const bool last = j + 1 == node_v_.size() && j > 0;
      row_cell_[v] = last ? j - 1 : j;
      row_t_[v] = last ? 1.0f : static_cast<float>((v - begin) / span);
    }
  }
  column_cell_.resize(camera.width);
  inverse_span_.assign(std::max<size_t>(1, columns - 1), 0.0f);
  for (size_t i = 0; i + 1 < columns; ++i) {
    inverse_span_[i] = 1.0f / static_cast<float>(node_u_[i + 1] - node_u_[i]);
    for (int u = node_u_[i]; u < node_u_[i + 1]; ++u) column_cell_[u] = i;
  }
  column_cell_[camera.width - 1] = columns >= 2 ? columns - 2 : 0;
  const size_t cells_u = std::max<size_t>(1, columns - 1);
  exact_cell_.assign(cells_u * std::max<size_t>(1, node_v_.size() - 1), 0);
  for (size_t j = 0; j + 1 < std::max<size_t>(2, node_v_.size()); ++j) {
    for (size_t i = 0; i < cells_u; ++i) {
      const size_t j1 = std::min(j + 1, node_v_.size() - 1), i1 = std::min(i + 1, columns - 1);
      const bool missing =
          std::isnan(node_x_[j * columns + i]) || std::isnan(node_x_[j * columns + i1]) ||
          std::isnan(node_x_[j1 * columns + i]) || std::isnan(node_x_[j1 * columns + i1]);
      exact_cell_[j * cells_u + i] = missing ? 1 : 0;
    }
  }
}

void CorrectionMap::SourceRow(int v, int u0, int n, float* xs, float* ys) const {
  const size_t columns = node_u_.size();
  const size_t cells_u = std::max<size_t>(1, columns - 1);
  double t = 0;
  size_t j =
      static_cast<size_t>(std::upper_bound(node_v_.begin(), node_v_.end(), v) - node_v_.begin());
  j = std::clamp<size_t>(j, 1, std::max<size_t>(1, node_v_.size() - 1)) - 1;
  const size_t j1 = std::min(j + 1, node_v_.size() - 1);
  if (j1 != j) t = static_cast<double>(v - node_v_[j]) / (node_v_[j1] - node_v_[j]);
  const auto node_at = [&](const std::vector<float>& nodes, size_t i) {
    return (1 - t) * nodes[j * columns + i] + t * nodes[j1 * columns + i];
  };
  size_t i =
      static_cast<size_t>(std::upper_bound(node_u_.begin(), node_u_.end(), u0) - node_u_.begin());
  i = std::clamp<size_t>(i, 1, cells_u) - 1;
  for (int u = u0; u < u0 + n;) {
    const size_t i1 = std::min(i + 1, columns - 1);
    const int end = std::min(u0 + n, i1 == i ? u0 + n : node_u_[i1] + 1);
    if (exact_cell_[j * cells_u + i]) {
      for (; u < end; ++u) {
        const std::optional<Eigen::Vector2d> q = geometry_.SourcePixel(u, v);
        const bool usable = q && std::abs(q->x()) < kFarPx && std::abs(q->y()) < kFarPx;
        xs[u - u0] = usable ? static_cast<float>(q->x()) : kNaN;
        ys[u - u0] = usable ? static_cast<float>(q->y()) : kNaN;
      }
    } else {
      const double x0 = node_at(node_x_, i), y0 = node_at(node_y_, i);
      const double span = i1 == i ? 1.0 : node_u_[i1] - node_u_[i];
      const double dx = i1 == i ? 0.0 : (node_at(node_x_, i1) - x0) / span;
      const double dy = i1 == i ? 0.0 : (node_at(node_y_, i1) - y0) / span;
      for (; u < end; ++u) {
        xs[u - u0] = static_cast<float>(x0 + (u - node_u_[i]) * dx);
        ys[u - u0] = static_cast<float>(y0 + (u - node_u_[i]) * dy);
      }
    }
    if (i + 1 < cells_u) ++i;
  }
}

void CorrectionMap::SourceRowFixed(int v, int u0, int n, int* xi, int* yi, bool* all_inside) const {
  // Within a cell the interpolated coordinates are linear in u: a + u b, in fixed-point units
  // (|values| < 2^27 with kFarPx: float keeps ~1/2000 px), four at a time.
  const size_t columns = node_u_.size();
  const size_t cells_u = std::max<size_t>(1, columns - 1);
  const size_t j = row_cell_[v], j1 = std::min(j + 1, node_v_.size() - 1);
  const float t = row_t_[v];
  const float* top_x = &node_x_fixed_[j * columns];
  const float* top_y = &node_y_fixed_[j * columns];
  const float* bottom_x = &node_x_fixed_[j1 * columns];
  const float* bottom_y = &node_y_fixed_[j1 * columns];
  size_t i = column_cell_[u0];
  float xs[64], ys[64];
  const int width = geometry_.camera().width, height = geometry_.camera().height;
  const auto inside = [&](int k) { return TapsInside(xi[k], yi[k], width, height); };
  bool pieces_inside = true;
  for (int u = u0; u < u0 + n; ++i) {
    const size_t i1 = std::min(i + 1, columns - 1);
    const int end = std::min(u0 + n, i + 1 >= cells_u ? u0 + n : node_u_[i1] + 1);
    if (exact_cell_[j * cells_u + i]) {
      for (; u < end; u += 64) {
        const int count = std::min(64, end - u);
        SourceRow(v, u, count, xs, ys);
        for (int k = 0; k < count; ++k) {
          xi[u - u0 + k] = ToFixed(xs[k]);
          yi[u - u0 + k] = ToFixed(ys[k]);
        }
      }
      u = end;
      pieces_inside = false;
      continue;
    }
    const float x0 = top_x[i] + t * (bottom_x[i] - top_x[i]);
    const float y0 = top_y[i] + t * (bottom_y[i] - top_y[i]);
    const float bx = (top_x[i1] + t * (bottom_x[i1] - top_x[i1]) - x0) * inverse_span_[i];
    const float by = (top_y[i1] + t * (bottom_y[i1] - top_y[i1]) - y0) * inverse_span_[i];
    const float offset = static_cast<float>(u - node_u_[i]);
    const float ax = x0 + offset * bx, ay = y0 + offset * by;
    LinearFixedRows(ax, bx, ay, by, end - u, xi + (u - u0), yi + (u - u0));
    pieces_inside = pieces_inside && inside(u - u0) && inside(end - 1 - u0);
    u = end;
  }
  if (all_inside) *all_inside = pieces_inside;
}

namespace {

// InsideMaskBits for float coordinates (NaN: no source).
void MaskBitsFloat(const float* xs, const float* ys, int n, int width, int height, uint8_t* bits) {
  std::memset(bits, 0, (n + 7) / 8);
  for (int k = 0; k < n; ++k) {
    if (xs[k] >= 0 && xs[k] <= width - 1 && ys[k] >= 0 && ys[k] <= height - 1) SetMaskBit(k, bits);
  }
}

}  // namespace

void CorrectFrame(const cv::Mat& rs_image, const CorrectionMap& map, Interpolation interpolation,
                  cv::Mat* out, PackedMask* mask) {
  const PinholeCamera& camera = map.geometry().camera();
  const int width = camera.width, height = camera.height;
  SHUTTERLAB_CHECK(rs_image.cols == width && rs_image.rows == height)
      << "image is " << rs_image.cols << "x" << rs_image.rows << ", the camera " << width << "x"
      << height;
  const int depth = rs_image.depth();
  SHUTTERLAB_CHECK(depth == CV_8U || depth == CV_16U || depth == CV_32F)
      << "image must be 8U, 16U or 32F";
  SHUTTERLAB_CHECK(rs_image.channels() <= 4) << "image has more than 4 channels";
  out->create(height, width, rs_image.type());
  if (mask) {
    mask->width = width;
    mask->bits.create(height, (width + 7) / 8, CV_8UC1);
  }
  const bool fixed = interpolation == Interpolation::kBilinear && depth != CV_32F;
  constexpr int kChunk = 512;  // columns per pass: 4 KiB of coordinates, kept in L1
  static_assert(kChunk % 8 == 0, "each pass starts a byte of the mask");
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    std::vector<int> xi(kChunk), yi(kChunk);
    std::vector<float> xs(kChunk), ys(kChunk);
    for (int v = rows.start; v < rows.end; ++v) {
      for (int u0 = 0; u0 < width; u0 += kChunk) {
        const int n = std::min(kChunk, width - u0);
        uchar* row_out = out->ptr(v) + u0 * out->elemSize();
        if (fixed) {
          bool all_inside = false;
          map.SourceRowFixed(v, u0, n, xi.data(), yi.data(), &all_inside);
          SampleRowFixed(rs_image, xi.data(), yi.data(), n, row_out);
          uint8_t* bits = mask ? mask->bits.ptr(v) + u0 / 8 : nullptr;
          if (bits && all_inside) {
            SetFirstMaskBits(n, bits);
          } else if (bits) {
            InsideMaskBits(xi.data(), yi.data(), n, width, height, bits);
          }
        } else {
          map.SourceRow(v, u0, n, xs.data(), ys.data());
          SampleRowFloat(rs_image, xs.data(), ys.data(), n, interpolation, row_out);
          if (mask) {
            MaskBitsFloat(xs.data(), ys.data(), n, width, height, mask->bits.ptr(v) + u0 / 8);
          }
        }
      }
    }
  });
}

}  // namespace shutterlab
