#include "sim/logs/gopro_telemetry.h"

#include "sim/check.h"
#include "sim/logs/gpmf.h"
#include "sim/logs/mp4.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace shutterlab {

bool HasGoproTelemetry(const std::string& mp4_path) {
  const Mp4File mp4(mp4_path);
  return mp4.FindTrack("meta", "gpmd") != nullptr;
}

namespace {

// A quaternion stream, or nothing where the firmware writes none (or one that is not 4 wide).
GoproQuaternions ReadQuaternions(Mp4File& mp4, const Mp4Track& track, const std::string& key) {
  GoproQuaternions out;
  try {
    const GpmfTrackStream stream = ReadGpmfTrackStream(mp4, track, key);
    if (stream.elements != 4) return out;
    for (size_t i = 0; i < stream.samples(); ++i) {
      out.t_s.push_back(stream.TimeS(i));
      out.wxyz.push_back({stream.values[4 * i], stream.values[4 * i + 1], stream.values[4 * i + 2],
                          stream.values[4 * i + 3]});
    }
  } catch (const IoError&) {
    // Cameras before the HERO8 write no CORI / IORI.
  }
  return out;
}

// A 3-axis stream on the camera's axes (GpmfAxisOrder), sample i at values[3 i .. 3 i + 2].
Eigen::Vector3d OnCameraAxes(const AxisOrder& order, const double* stored) {
  Eigen::Vector3d out;
  for (int a = 0; a < 3; ++a) {
    out[a] = order.calibration
                 ? (*order.calibration)(a, 0) * stored[0] + (*order.calibration)(a, 1) * stored[1] +
                       (*order.calibration)(a, 2) * stored[2]
                 : order.sign[a] * stored[order.column[a]];
  }
  return out;
}

// The mean of ACCL on the camera's axes; nullopt where there is none. ACCL's own ORIN where it has
// one, else the gyro's order: the HERO5 stores both as Z, X, Y (gpmf-parser's README) but names
// only the gyro's ("Accelerometer (up/down, right/left, forward/back)").
std::optional<Eigen::Vector3d> AccelMean(Mp4File& mp4, const Mp4Track& track,
                                         const AxisOrder& gyro_order) {
  try {
    const GpmfTrackStream accl = ReadGpmfTrackStream(mp4, track, "ACCL");
    if (accl.elements != 3 || accl.samples() == 0) return std::nullopt;
    const AxisOrder order =
        accl.first.orientation.empty() ? gyro_order : GpmfAxisOrder(accl.first, mp4.path());
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < accl.samples(); ++i) sum += OnCameraAxes(order, &accl.values[3 * i]);
    return sum / static_cast<double>(accl.samples());
  } catch (const IoError&) {
    return std::nullopt;
  }
}

// The first number of a numeric KLV; nullopt for another type.
std::optional<double> FirstNumber(const GpmfKlv& klv, const std::string& path) {
  if (klv.type == 'c' || klv.type == 'F' || klv.type == 0 || klv.repeat == 0) return std::nullopt;
  const std::vector<double> values = GpmfValues(klv, path);
  return values.empty() ? std::nullopt : std::optional<double>(values.front());
}

}  // namespace

GoproSettings ReadGoproSettings(Mp4File& mp4) {
  GoproSettings s;
  const Mp4UserBox* box = mp4.FindUserBox("GPMF");
  if (!box) return s;
  const std::string& path = mp4.path();
  for (const GpmfKlv& devc : ParseGpmf(box->body, box->file_offset, path)) {
    if (devc.key != "DEVC" || devc.type != 0) continue;
    bool global = false;
    for (const GpmfKlv& item : devc.children) {
      if (item.key == "DVNM" && item.type == 'c') global = GpmfString(item) == "Global Settings";
    }
    if (!global) continue;
    s.present = true;
    for (const GpmfKlv& item : devc.children) {
      const std::string text = item.type == 'c' ? GpmfString(item) : "";
      if (item.key == "MINF") s.model = text;
      if (item.key == "FMWR") s.firmware = text;
      if (item.key == "VFOV") s.fov = text;
      if (item.key == "EISE") s.stabilizer = text;
      if (item.key == "EISA") s.stabilizer_mode = text;
      if (item.key == "PRJT" && item.type == 'F') s.projection = std::string(item.data);
      if (item.key == "CMOD") s.camera_mode = FirstNumber(item, path);
      if (item.key == "ZFOV") s.diagonal_fov_deg = FirstNumber(item, path);
      if (item.key == "SROT") {
        const std::optional<double> ms = FirstNumber(item, path);
        if (ms && *ms > 0 && *ms < 1000) s.readout_s = *ms * 1e-3;
      }
    }
    break;
  }
  return s;
}

GoproTelemetry ReadGoproTelemetry(const std::string& mp4_path) {
  Mp4File mp4(mp4_path);
  const Mp4Track* track = mp4.FindTrack("meta", "gpmd");
  if (!track) throw IoError(IoMessage(mp4_path, -1, "no GoPro 'gpmd' metadata track"));
  const GpmfTrackStream gyro = ReadGpmfTrackStream(mp4, *track, "GYRO");
  if (gyro.elements != 3)
    throw IoError(IoMessage(mp4_path, -1,
                            "GYRO has " + std::to_string(gyro.elements) + " elements, 3 expected"));
  const AxisOrder order = GpmfAxisOrder(gyro.first, mp4_path);
  GoproTelemetry out;
  out.gyro_name = gyro.first.name;
  out.device = gyro.first.device;
  out.axis_order_source = order.source;
  out.gyro_scale = gyro.first.scale;
  out.gyro_payload_samples = gyro.payload_samples;
  out.gyro_rate_hz = gyro.rate_hz;
  out.gyro_fit_max_residual_s = gyro.fit_max_residual_s;
  out.gyro_orin = gyro.first.orientation;
  out.gyro_orio = gyro.first.orientation_out;
  out.gyro_mtrx = gyro.first.matrix;
  std::vector<GyroSample> samples(gyro.samples());
  for (size_t i = 0; i < samples.size(); ++i) {
    samples[i].t_ns = SecondsToNs(gyro.TimeS(i));
    samples[i].omega_rad_s = OnCameraAxes(order, &gyro.values[3 * i]);
  }
  out.gyro = GyroTrace(std::move(samples));
  try {
    const GpmfTrackStream shut = ReadGpmfTrackStream(mp4, *track, "SHUT");
    for (size_t i = 0; i < shut.samples(); ++i) {
      out.shutter_s.push_back(shut.values[i * shut.elements]);
      out.shutter_t_s.push_back(shut.TimeS(i));
    }
  } catch (const IoError&) {
    // Older firmware writes no SHUT: exposure is then unknown, which the importer records.
  }
  out.accel_mean_mps2 = AccelMean(mp4, *track, order);
  out.camera_orientation = ReadQuaternions(mp4, *track, "CORI");
  out.image_orientation = ReadQuaternions(mp4, *track, "IORI");
  try {
    out.settings = ReadGoproSettings(mp4);
  } catch (const IoError& e) {
    // Optional metadata: the clip imports without it, and says what was lost.
    out.settings = GoproSettings();
    out.settings.unreadable = e.what();
  }
  return out;
}

FlightLog ReadGoproFlightLog(const std::string& mp4_path) {
  GoproTelemetry telemetry = ReadGoproTelemetry(mp4_path);
  FlightLog log;
  log.format = "gopro";
  log.gyro_source = "GPMF GYRO '" + telemetry.gyro_name + "' (" + telemetry.axis_order_source + ")";
  log.gyro_sources_available = {log.gyro_source};
  log.gyro = std::move(telemetry.gyro);
  if (!telemetry.settings.unreadable.empty()) {
    log.warnings.push_back(
        {"corrupt", "global settings unreadable: " + telemetry.settings.unreadable, {}, {}});
  }
  return log;
}

std::vector<double> ReadVideoFrameTimesS(const std::string& mp4_path) {
  const Mp4File mp4(mp4_path);
  const Mp4Track* video = mp4.FindTrack("vide", "");
  if (!video || video->size() == 0) throw IoError(IoMessage(mp4_path, -1, "no video track"));
  std::vector<double> frame_times_s;
  for (size_t i = 0; i < video->size(); ++i) frame_times_s.push_back(video->PresentationTimeS(i));
  std::sort(frame_times_s.begin(), frame_times_s.end());
  return frame_times_s;
}

std::optional<double> NearestShutterS(const GoproTelemetry& telemetry, double t_s,
                                      double period_s) {
  const auto& ts = telemetry.shutter_t_s;
  if (ts.empty()) return std::nullopt;
  const size_t k = std::lower_bound(ts.begin(), ts.end(), t_s) - ts.begin();
  size_t best = std::min(k, ts.size() - 1);
  if (k > 0 && std::abs(ts[k - 1] - t_s) < std::abs(ts[best] - t_s)) best = k - 1;
  if (std::abs(ts[best] - t_s) <= period_s) return telemetry.shutter_s[best];
  return std::nullopt;
}

}  // namespace shutterlab
