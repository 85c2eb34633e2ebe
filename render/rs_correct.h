#pragma once
// Rolling-shutter correction: the global-shutter view of a rolling-shutter frame, from the pose at
// one reference instant, through the same camera (docs/FORMATS.md "Correction").
//
// The inverse problem. An output pixel p (the global-shutter image, every row at the reference pose
// R_ref, c_ref) sees the ray d = R_ref K^-1 p (K^-1 undistorts) and, with a plane, the point
// X = c_ref + s d on it (z_W = depth); without a plane (rotation only) the direction d itself. In
// the rolling-shutter image that point lies at q = K R(w)^T (X - c(w)) (K distorts; rotation only:
// K R(w)^T d), where w, the row of q, is also the row whose capture time sets the pose: q solves
// q = project(X, pose(q.y)), a fixed point. It is iterated from w = p's row; each step moves w by
// the image motion during one row time, a contraction far below 1 for any frame that stays sharp
// (as render/rs_warp.h VideoMatch). Rows beyond the frame extend the first and last rows' motion
// linearly, so the map stays smooth where its source leaves the frame (no source there: masked).
//
// A frame is not solved per pixel: the exact solution on a grid of nodes is interpolated
// bilinearly, and the grid is refined until its interpolation error, checked against the exact
// solution at every cell's centre and edge midpoints, is within the tolerance. Along a row the map
// is smooth (a bilinear error peaks at those midpoints; a quadratic's exactly there): the columns'
// spacing is halved until the node rows' midpoints hold. Down a column the pose bends at every
// gyro sample (the rate is linear between samples), a kink in the map's slope: each band of rows
// is checked at its middle row and split there until it holds, so node rows crowd where the motion
// changes fast. A kink between two checked rows leaves at most twice the error its band's middle
// row shows. The tests check the map against the exact solution at every pixel. The sampler is
// the renderer's (render/warp_kernel.h).

#include "io/image_io.h"
#include "model/camera.h"
#include "model/truth_model.h"
#include "render/warp_kernel.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// Which instant the corrected image shows. kFirstRow: the capture time of image row 0, the top row
// (docs/FORMATS.md's reference image); kMidReadout: half the readout after the first row read.
enum class CorrectionReference { kFirstRow, kMidReadout };
const char* CorrectionReferenceName(CorrectionReference reference);  // "row0", "mid"
std::optional<CorrectionReference> ParseCorrectionReference(const std::string& name);

// The (fractional) image row captured at the reference instant.
double ReferenceRow(CorrectionReference reference, const RollingShutter& shutter, int height);

// The exact geometry of one frame's correction.
constexpr double kCorrectionSolveTolPx = 1e-6;

class CorrectionGeometry {
 public:
  // camera: the true intrinsics and lens; motion: one pose per image row (CameraMotion::Frame),
  // taken by value so that a caller done with it moves its rows in instead of copying them;
  // reference_row: where the output's pose is taken (ReferenceRow; fractional rows interpolate);
  // plane_depth_m: the scene plane z_W = depth in the frame's world (the ground at the altitude for
  // a nadir still), nullopt for rotation only (translation ignored).
  CorrectionGeometry(const PinholeCamera& camera, FrameMotion motion, double reference_row,
                     std::optional<double> plane_depth_m);

  // The source pixel q in the rolling-shutter image of output pixel (u, v), solved to
  // kCorrectionSolveTolPx; nullopt where the ray misses the plane, the point is behind the camera
  // or the iteration does not settle. q may lie outside the frame (no source: HasSource). The
  // iteration starts at start_row when given (a neighbour's solution: fewer steps), else at v, and
  // stops when a step moves the row by at most solve_tol_px.
  std::optional<Eigen::Vector2d> SourcePixel(double u, double v,
                                             std::optional<double> start_row = std::nullopt,
                                             double solve_tol_px = kCorrectionSolveTolPx) const;
  // Where the rolling-shutter pixel (u, v) lands in the corrected image (the forward map; its row v
  // sets the pose); nullopt where the ray misses the plane or lands behind the reference camera.
  std::optional<Eigen::Vector2d> OutputPixel(double u, double v) const;
  // True when every bilinear tap of q lies inside the frame: 0 <= x <= width-1, 0 <= y <= height-1.
  bool HasSource(const Eigen::Vector2d& q) const;

  const PinholeCamera& camera() const { return camera_; }
  bool rotation_only() const { return !plane_depth_m_.has_value(); }

 private:
  // R(row)^T and c(row) at a fractional row (extended beyond the frame).
  void PoseAtRow(double row, Eigen::Matrix3d* cam_from_world, Eigen::Vector3d* center_m) const;

  PinholeCamera camera_;
  std::optional<double> plane_depth_m_;
  std::vector<Eigen::Matrix3d> cam_from_world_;  // R(v)^T per row
  std::vector<Eigen::Vector3d> center_m_;        // c(v) per row, world frame
  Eigen::Matrix3d world_from_ref_;
  Eigen::Vector3d ref_center_m_;
};

struct CorrectionMapOptions {
  double tolerance_px = 0.01;  // largest interpolation error of the map (estimated, see the top)
  int max_cell_px = 64;        // first grid spacing; halved until the tolerance holds
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// A frame's map from output pixels to source pixels: the exact solution on a grid, interpolated.
class CorrectionMap {
 public:
  CorrectionMap(const CorrectionGeometry& geometry, const CorrectionMapOptions& options);

  int cell_px() const { return cell_px_; }
  // The largest |interpolated - exact| at the final grid's checked points, px (see the top).
  double estimated_error_px() const { return estimated_error_px_; }
  // Node rows of the final grid (more where the motion bends).
  size_t node_rows() const { return node_v_.size(); }
  // Source coordinates of output row v, columns [u0, u0 + n): fixed point (render/warp_kernel.h),
  // kInvalidFixed where there is no solution. With all_inside: whether every one of them has all
  // its bilinear taps inside the frame, when the row's pieces say so cheaply (false otherwise:
  // test each, InsideMaskBits). A piece interpolated along a cell is monotone in each coordinate
  // (float's multiply, add and rounding are), so its ends bound it.
  void SourceRowFixed(int v, int u0, int n, int* xi, int* yi, bool* all_inside = nullptr) const;
  // The same as floats (NaN where there is no solution), for bicubic sampling and for tests.
  void SourceRow(int v, int u0, int n, float* xs, float* ys) const;

  const CorrectionGeometry& geometry() const { return geometry_; }

 private:
  struct NodeRow {
    std::vector<double> x, y;  // source per node column; NaN: no solution
  };
  // The exact source at (us[i], v), each solve started at start[i] (NaN: at v).
  NodeRow SolveRow(int v, const std::vector<double>& us, const std::vector<double>& start) const;
  // Node rows for a column spacing of cell_px; false when the spacing is too wide.
  bool BuildRows(int cell_px, double tolerance_px);
  // The node arrays and look-up tables from rows_.
  void Finish();

  const CorrectionGeometry& geometry_;
  int cell_px_ = 0;
  double estimated_error_px_ = 0.0;
  double solve_tol_px_ = 0.0;
  std::map<int, NodeRow> rows_;         // while building: node rows by output row
  std::vector<int> node_u_, node_v_;    // node columns and rows (last column and row included)
  std::vector<float> node_x_, node_y_;  // source at each node, row-major; NaN: no solution
  std::vector<char> exact_cell_;  // per cell: a node without solution, solved per pixel instead
  // For SourceRowFixed: the nodes in fixed-point units, each output row's cell row and weight of
  // the node row below, each column's cell, and 1 / each cell's width.
  std::vector<float> node_x_fixed_, node_y_fixed_;
  std::vector<size_t> row_cell_, column_cell_;
  std::vector<float> row_t_, inverse_span_;
};

// The corrected image: out gets rs_image's type and the camera's size, mask (when given) the
// camera's size, set where the pixel has a source in the frame (HasSource) and clear where it has
// none (black or partial in out). Rows are split over threads (cv::parallel_for_), bit-identical
// for any count.
void CorrectFrame(const cv::Mat& rs_image, const CorrectionMap& map, Interpolation interpolation,
                  cv::Mat* out, PackedMask* mask = nullptr);

}  // namespace shutterlab
