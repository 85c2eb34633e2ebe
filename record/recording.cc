#include "record/recording.h"

#include "sim/check.h"
#include "sim/logs/gcsv.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <cmath>

namespace shutterlab {

void RecorderOptions::Check() const {
  auto non_negative = [](double v) { return std::isfinite(v) && v >= 0; };
  SHUTTERLAB_CHECK(non_negative(duration_s)) << "duration must be >= 0 s, got " << duration_s;
  SHUTTERLAB_CHECK(non_negative(still_s)) << "still must be >= 0 s, got " << still_s;
  SHUTTERLAB_CHECK(std::isfinite(ring_s) && ring_s >= 0.05) << "ring must hold >= 0.05 s";
  SHUTTERLAB_CHECK(non_negative(read_interval_s) && read_interval_s <= 0.1)
      << "read interval must be within 0..0.1 s, got " << read_interval_s;
  SHUTTERLAB_CHECK(std::isfinite(writer_interval_s) && writer_interval_s > 0 &&
                   writer_interval_s <= 1)
      << "writer interval must be within (0, 1] s";
  SHUTTERLAB_CHECK(std::isfinite(sync_interval_s) && sync_interval_s > 0 && sync_interval_s <= 60)
      << "sync interval must be within (0, 60] s";
  SHUTTERLAB_CHECK(std::isfinite(health_check_s) && health_check_s > 0) << "health check interval";
  SHUTTERLAB_CHECK(non_negative(writer_stall.every_s) && non_negative(writer_stall.for_s))
      << "writer stall must be >= 0";
  SHUTTERLAB_CHECK(writer_stall.every_s == 0 || writer_stall.for_s < writer_stall.every_s)
      << "a writer stall must be shorter than its period";
  SHUTTERLAB_CHECK(non_negative(paper_pause.write_s)) << "paper pause must be >= 0 s";
  for (const auto& [at_s, for_s] : reader_pauses) {
    SHUTTERLAB_CHECK(non_negative(at_s) && non_negative(for_s))
        << "reader pause times must be >= 0";
  }
  SHUTTERLAB_CHECK(non_negative(debounce_s)) << "debounce must be >= 0 s";
  SHUTTERLAB_CHECK(reader_priority >= 0 && reader_priority <= 99)
      << "reader priority must be 0 (normal) or 1..99 (SCHED_FIFO), got " << reader_priority;
  SHUTTERLAB_CHECK(!trigger || !triggers_path.empty()) << "a trigger source needs a triggers file";
  SHUTTERLAB_CHECK(duration_s > 0 || stop != nullptr) << "give a duration or a stop flag";
  GcsvOrientationMatrix(orientation);
  SHUTTERLAB_CHECK(note.find_first_of("\r\n") == std::string::npos) << "note must be one line";
}

std::string RecordStatusLine(const RecordStatus& status) {
  std::string line = FormatNumber("%6.1f s", status.elapsed_s);
  for (size_t i = 0; i < status.sensors.size(); ++i) {
    const RecordStatus::Sensor& s = status.sensors[i];
    line += i == 0 ? "  " : "  |  ";
    line += FormatNumber("%.1f Hz", s.rate_hz) + "  " + std::to_string(s.gaps) + " gap(s)";
    if (s.lost > 0) line += " (" + std::to_string(s.lost) + " lost)";
    line += FormatNumber("  ring %.0f%%",
                         s.ring_capacity ? 100.0 * s.ring_high_water / s.ring_capacity : 0.0);
    line += FormatNumber("  %+.1f ppm", s.drift_ppm);
  }
  line += "  |  " + std::to_string(status.triggers) + " trigger(s)";
  line += FormatNumber("  writer stall %.0f ms", status.max_writer_stall_s * 1e3);
  return line;
}

std::string RecordSummaryText(const RecordSummary& summary) {
  std::string text = FormatNumber("recorded %.3f s", summary.duration_s) +
                     (summary.stopped ? " (stopped by signal)" : "") + "\n";
  for (size_t i = 0; i < summary.sensors.size(); ++i) {
    const SensorSummary& s = summary.sensors[i];
    text += "sensor " + std::to_string(i + 1) + ": " + GetPartInfo(s.setting.part).name + " on " +
            s.device + " -> " + s.out_path + "\n";
    text += "  setting     " + s.setting.Describe() + "\n";
    text += FormatNumber("  samples     %.0f", static_cast<double>(s.samples)) +
            FormatNumber(", achieved %.3f Hz", s.rate_hz) +
            FormatNumber(" (the part's clock %+.2f ppm", s.drift_ppm) +
            FormatNumber("; FIFO-count timestamps, read rms %.1f us)", s.timestamp_rms_us) + "\n";
    text += "  gaps        " + std::to_string(s.gaps) + ", " + std::to_string(s.lost) +
            " sample(s) lost\n";
    text +=
        FormatNumber("  buffers     ring high-water %.0f", static_cast<double>(s.ring_high_water)) +
        FormatNumber(" of %.0f samples", static_cast<double>(s.ring_capacity)) +
        FormatNumber("; longest between FIFO reads %.2f ms", s.max_read_interval_s * 1e3) + "\n";
    const Eigen::Vector3d bias_dps = s.still_bias_rad_s * 180.0 / kPi;
    const Eigen::Vector3d std_dps = s.still_std_rad_s * 180.0 / kPi;
    text += FormatNumber("  still bias  over the first %.2f s: ", s.still_span_s) +
            FormatNumber("%+.4f ", bias_dps.x()) + FormatNumber("%+.4f ", bias_dps.y()) +
            FormatNumber("%+.4f deg/s", bias_dps.z()) + FormatNumber(" (std %.4f ", std_dps.x()) +
            FormatNumber("%.4f ", std_dps.y()) + FormatNumber("%.4f deg/s)", std_dps.z()) + "\n";
  }
  for (const RecordGap& gap : summary.gaps) {
    text += "  gap: sensor " + std::to_string(gap.sensor + 1) + " " + gap.kind +
            FormatNumber(" at %.6f s, ", gap.t_s) + std::to_string(gap.lost) + " sample(s) lost\n";
  }
  for (const std::string& note : summary.notes) text += "note: " + note + "\n";
  text += FormatNumber("writer: longest away from the rings %.1f ms",
                       summary.max_writer_stall_s * 1e3) +
          "\n";
  if (summary.trigger_edges > 0 || summary.triggers > 0) {
    text += "triggers: " + std::to_string(summary.triggers) + " (" +
            std::to_string(summary.trigger_edges) + " edge(s), " +
            std::to_string(summary.trigger_bounces) + " bounce(s) ignored)\n";
  }
  return text;
}

}  // namespace shutterlab
