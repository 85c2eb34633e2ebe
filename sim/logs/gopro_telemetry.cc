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
  std::vector<GyroSample> samples(gyro.samples());
  for (size_t i = 0; i < samples.size(); ++i) {
    samples[i].t_ns = SecondsToNs(gyro.TimeS(i));
    for (int a = 0; a < 3; ++a)
      samples[i].omega_rad_s[a] = order.sign[a] * gyro.values[3 * i + order.column[a]];
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
  return out;
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
