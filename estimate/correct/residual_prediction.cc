#include "estimate/correct/residual_prediction.h"

#include "sim/check.h"
#include "sim/so3.h"
#include "sim/units.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace shutterlab {
namespace {

// A point on the output grid with its source under the model.
struct GridPoint {
  int column = 0;        // grid column, for D
  Eigen::Vector2d p, q;  // output pixel, its source
};

std::vector<double> GridAt(int size, int count) {
  std::vector<double> at;
  for (int k = 0; k < count; ++k) at.push_back((size - 1) * static_cast<double>(k) / (count - 1));
  return at;
}

// docs/FORMATS.md's D of displacements grouped by column: the largest diameter within a column.
// A column's points are consecutive (the grid is built column by column), so only pairs within a
// run of one column are compared: 33 times fewer than all pairs on the default grid.
double ColumnDiameter(const std::vector<int>& column, const std::vector<Eigen::Vector2d>& d) {
  // Squared distances compared, one square root at the end: the same number (norm() is the root
  // of squaredNorm(), and a root keeps the order).
  double best_sq = 0.0;
  for (size_t run_start = 0, run_end = 0; run_start < d.size(); run_start = run_end) {
    while (run_end < d.size() && column[run_end] == column[run_start]) ++run_end;
    for (size_t a = run_start; a < run_end; ++a) {
      for (size_t b = a + 1; b < run_end; ++b)
        best_sq = std::max(best_sq, (d[a] - d[b]).squaredNorm());
    }
  }
  return std::sqrt(best_sq);
}

// The model with each effect's parameters drawn from its covariance.
TrueModel DrawModel(const CorrectionModel& model, std::mt19937_64* rng) {
  TrueModel drawn = model.model;
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const EffectUncertainty& u : model.uncertainty) {
    // covariance = V diag(l) V^T: delta = V sqrt(l) z (negative eigenvalues of a nearly singular
    // covariance read as 0).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(u.covariance);
    Eigen::VectorXd z(u.covariance.rows());
    for (int i = 0; i < z.size(); ++i) {
      z[i] = std::sqrt(std::max(0.0, eigen.eigenvalues()[i])) * normal(*rng);
    }
    const Eigen::VectorXd delta = eigen.eigenvectors() * z;
    Spec(u.effect).apply_delta(delta.data(), &drawn);
  }
  return drawn;
}

}  // namespace

std::vector<Eigen::Vector3d> GyroNoiseAnglesRad(const TrueModel& model, int64_t t_first_row_ns,
                                                int start_row, double density_rad_s_sqrt_hz,
                                                const std::vector<bool>& rows,
                                                std::mt19937_64* rng) {
  const int height = static_cast<int>(rows.size());
  SHUTTERLAB_CHECK(start_row >= 0 && start_row < height)
      << "the noise walk starts at row " << start_row << " of " << height;
  std::vector<Eigen::Vector3d> angles(height, Eigen::Vector3d::Zero());
  std::normal_distribution<double> normal(0.0, 1.0);
  // Away from start_row, one step from each marked row to the next: the rows between add
  // independent normal steps whose variances sum to density^2 times the time between the two
  // (rows are read in time order), the same distribution as stepping through every row.
  const auto walk = [&](int step) {
    Eigen::Vector3d angle = Eigen::Vector3d::Zero();
    double last_s = model.RowGyroOffsetS(t_first_row_ns, start_row);
    for (int v = start_row + step; v >= 0 && v < height; v += step) {
      if (!rows[v]) continue;
      const double t_s = model.RowGyroOffsetS(t_first_row_ns, v);
      const double sd = density_rad_s_sqrt_hz * std::sqrt(std::abs(t_s - last_s));
      angle += sd * Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng));
      angles[v] = angle;
      last_s = t_s;
    }
  };
  walk(1);
  walk(-1);
  return angles;
}

namespace {

// D of the model's displacement of each rolling-shutter grid pixel into the corrected view.
double DBefore(const CorrectionGeometry& geometry, const std::vector<double>& us,
               const std::vector<double>& vs) {
  std::vector<int> column;
  std::vector<Eigen::Vector2d> d;
  for (size_t i = 0; i < us.size(); ++i) {
    for (double v : vs) {
      const std::optional<Eigen::Vector2d> p = geometry.OutputPixel(us[i], v);
      if (!p) continue;
      column.push_back(static_cast<int>(i));
      d.push_back(*p - Eigen::Vector2d(us[i], v));
    }
  }
  return ColumnDiameter(column, d);
}

// Turns the rows marked in `rows` by the gyro's noise walk, zero at the reference row. The walk is
// drawn at those rows whichever rows `motion` has filled: a twin's other rows are never read.
void TurnByGyroNoise(const TrueModel& truth, int64_t t_first_row_ns, double reference_row,
                     double density_rad_s_sqrt_hz, const std::vector<bool>& rows,
                     std::mt19937_64* rng, FrameMotion* motion) {
  const int last_row = static_cast<int>(rows.size()) - 1;
  const int start = std::clamp(static_cast<int>(std::lround(reference_row)), 0, last_row);
  const std::vector<Eigen::Vector3d> angles =
      GyroNoiseAnglesRad(truth, t_first_row_ns, start, density_rad_s_sqrt_hz, rows, rng);
  for (int v = 0; v <= last_row; ++v) {
    if (rows[v] && v != start) {
      motion->world_from_cam[v] = motion->world_from_cam[v] * ExpSO3(angles[v]).toRotationMatrix();
    }
  }
}

struct DrawResidual {
  double d_px = 0.0, rms_px = 0.0;
};

// Throws std::out_of_range, as CameraMotion::Frame would, when the gyro trace does not hold the
// model's readout of the frame: a caller's frame (from a longer trace) is not checked against it.
void RequireReadoutInTrace(const TrueModel& model, const GyroTrace& gyro, int64_t t_first_row_ns) {
  for (const int row : {0, model.rig.camera.height - 1}) {
    const int64_t t_ns =
        t_first_row_ns +
        static_cast<int64_t>(std::floor(model.RowGyroOffsetS(t_first_row_ns, row) * 1e9));
    if (gyro.empty() || t_ns < gyro.t_begin_ns() || t_ns > gyro.t_end_ns()) {
      throw std::out_of_range("the frame's readout leaves the gyro trace given for its prediction");
    }
  }
}

// The output grid's points whose source under the geometry has every tap inside the frame.
std::vector<GridPoint> GridWithSources(const CorrectionGeometry& geometry,
                                       const std::vector<double>& us,
                                       const std::vector<double>& vs) {
  std::vector<GridPoint> grid;
  for (size_t i = 0; i < us.size(); ++i) {
    for (double v : vs) {
      const std::optional<Eigen::Vector2d> q = geometry.SourcePixel(us[i], v);
      if (q && geometry.HasSource(*q)) grid.push_back({static_cast<int>(i), {us[i], v}, *q});
    }
  }
  return grid;
}

// The draws' D and root mean square into out: their medians, and D's 90th percentile.
void SummariseDraws(std::vector<double> d_after, std::vector<double> rms_after,
                    ResidualPrediction* out) {
  out->draws = static_cast<int>(d_after.size());
  if (out->draws == 0) return;
  std::sort(d_after.begin(), d_after.end());
  out->d_after_px = UpperMedian(d_after);
  out->d_after_p90_px =
      d_after[std::min(d_after.size() - 1, static_cast<size_t>(0.9 * d_after.size()))];
  out->rms_after_px = UpperMedian(rms_after);
}

// The corrected grid's displacement r against what the drawn truth shows (r, scratch, one a grid
// point): its D and root mean square.
DrawResidual ResidualOfDraw(const CorrectionGeometry& truth_geometry,
                            const std::vector<GridPoint>& grid, const std::vector<int>& column,
                            std::vector<Eigen::Vector2d>* r) {
  double sum_sq = 0.0;
  size_t n = 0;
  for (size_t k = 0; k < grid.size(); ++k) {
    const std::optional<Eigen::Vector2d> seen =
        truth_geometry.OutputPixel(grid[k].q.x(), grid[k].q.y());
    (*r)[k] = seen ? Eigen::Vector2d(*seen - grid[k].p) : Eigen::Vector2d::Zero();
    if (seen) {
      sum_sq += (*r)[k].squaredNorm();
      ++n;
    }
  }
  return {ColumnDiameter(column, *r), n > 0 ? std::sqrt(sum_sq / n) : 0.0};
}

}  // namespace

void ResidualPredictionOptions::Check() const {
  SHUTTERLAB_CHECK(draws >= 1 && draws <= 10000)
      << "draws must be 1 to 10000 (got " << draws << ")";
  SHUTTERLAB_CHECK(grid_columns >= 2 && grid_rows >= 2) << "the grid needs two rows and columns";
}

ResidualPrediction PredictResidual(const CorrectionModel& model, const GyroTrace& gyro,
                                   int64_t t_first_row_ns, const CorrectionSetting& setting,
                                   const ResidualPredictionOptions& options,
                                   const FrameMotion* model_frame) {
  options.Check();
  const TrueModel& hat = model.model;
  const PinholeCamera& camera = hat.rig.camera;
  // The model's trace integrated only when needed: a caller's frame and draws of the model itself
  // need none.
  std::optional<CameraMotion> hat_motion_storage;
  const auto hat_motion = [&]() -> const CameraMotion& {
    if (!hat_motion_storage) hat_motion_storage.emplace(gyro, hat);
    return *hat_motion_storage;
  };
  FrameMotion own_frame;
  if (model_frame) {
    RequireReadoutInTrace(hat, gyro, t_first_row_ns);
  } else {
    own_frame = hat_motion().Frame(t_first_row_ns);
    model_frame = &own_frame;
  }
  const FrameMotion& hat_frame = *model_frame;
  const CorrectionGeometry geometry(camera, hat_frame,
                                    ReferenceRow(setting.reference, hat.rig.shutter, camera.height),
                                    setting.plane_depth_m);
  const std::vector<double> us = GridAt(camera.width, options.grid_columns);
  const std::vector<double> vs = GridAt(camera.height, options.grid_rows);
  ResidualPrediction out;
  out.d_before_px = DBefore(geometry, us, vs);
  const std::vector<GridPoint> grid = GridWithSources(geometry, us, vs);
  // The rows a draw's poses are read at: the two around each grid point's source row
  // (CorrectionGeometry::OutputPixel interpolates between them) and around the reference row. Each
  // draw computes those alone, a few hundred of a 12 MP frame's 3000, as Frame computes them.
  const int last_row = camera.height - 1;
  std::vector<bool> rows_read(camera.height, false);
  const auto read_around = [&](int row) {
    const int r0 = std::clamp(row, 0, std::max(0, last_row - 1));
    rows_read[r0] = true;
    rows_read[std::min(r0 + 1, last_row)] = true;
  };
  for (const GridPoint& g : grid) read_around(static_cast<int>(std::floor(g.q.y())));
  // Two streams: the model's draws are the same whatever the gyro's noise (and the rows it is
  // drawn at) is.
  std::mt19937_64 rng(options.seed ^ static_cast<uint64_t>(t_first_row_ns));
  std::mt19937_64 noise_rng(rng());
  std::vector<double> d_after, rms_after;
  std::vector<int> column(grid.size());
  for (size_t k = 0; k < grid.size(); ++k) column[k] = grid[k].column;
  std::vector<Eigen::Vector2d> r(grid.size());
  // A model without uncertainty and a gyro without noise draw the same truth every time (no
  // random number is used): one draw stands for all of them, as it would come out of each (a
  // camera.json without covariances over a noiseless synthetic log; a real log has noise).
  const bool every_draw_same = model.uncertainty.empty() && !(model.gyro_noise_rad_s_sqrt_hz > 0);
  const int distinct_draws = every_draw_same ? 1 : options.draws;
  // A model without uncertainty draws itself every time: each draw's poses are the model's frame
  // (FrameAtRows fills the rows read exactly as Frame does; the others are never read), turned by
  // the draw's own gyro noise.
  const bool every_truth_the_model = model.uncertainty.empty() && !options.every_row;
  for (int draw = 0; draw < distinct_draws; ++draw) {
    const TrueModel truth = DrawModel(model, &rng);
    const double reference_row = ReferenceRow(setting.reference, truth.rig.shutter, camera.height);
    read_around(static_cast<int>(reference_row));
    // A draw whose rates are the model's (no drawn effect moves the mounting, the gyro's scale or
    // bias) shares the model's integrated trace: exactly the trace it would integrate.
    const bool same_rates = truth.SameCamRates(hat) && !options.every_row;
    FrameMotion truth_motion;
    try {
      if (every_truth_the_model) {
        truth_motion = hat_frame;
      } else {
        const CameraMotion truth_camera =
            same_rates ? CameraMotion(truth, hat_motion()) : CameraMotion(gyro, truth);
        truth_motion = options.every_row ? truth_camera.Frame(t_first_row_ns)
                                         : truth_camera.FrameAtRows(t_first_row_ns, rows_read);
      }
    } catch (const std::out_of_range&) {
      continue;  // this draw's readout leaves the trace around the frame
    }
    if (model.gyro_noise_rad_s_sqrt_hz > 0) {
      TurnByGyroNoise(truth, t_first_row_ns, reference_row, model.gyro_noise_rad_s_sqrt_hz,
                      rows_read, &noise_rng, &truth_motion);
    }
    const CorrectionGeometry truth_geometry(truth.rig.camera, std::move(truth_motion),
                                            reference_row, setting.plane_depth_m);
    const DrawResidual residual = ResidualOfDraw(truth_geometry, grid, column, &r);
    d_after.push_back(residual.d_px);
    rms_after.push_back(residual.rms_px);
  }
  if (every_draw_same && !d_after.empty()) {
    d_after.assign(options.draws, d_after.front());
    rms_after.assign(options.draws, rms_after.front());
  }
  SummariseDraws(std::move(d_after), std::move(rms_after), &out);
  return out;
}

}  // namespace shutterlab
