#include "estimate/report/analysis_json.h"

#include "sim/gyro_trace.h"

namespace shutterlab {
namespace {}  // namespace

nlohmann::ordered_json NoiseToJson(const NoiseResult& result) {
  nlohmann::ordered_json j;
  j["window_samples"] = result.window_samples;
  j["windows"] = result.windows;
  j["samples"] = result.samples_analysed;
  j["rate_hz"] = result.rate_hz;
  nlohmann::ordered_json axes;
  for (int a = 0; a < 3; ++a) {
    const AxisNoise& n = result.axes[a];
    nlohmann::ordered_json axis;
    axis["sigma_mean_arcsec"] = n.sigma_mean_arcsec;
    axis["sigma_max_arcsec"] = n.sigma_max_arcsec;
    axis["range_mean_arcsec"] = n.range_mean_arcsec;
    axis["range_max_arcsec"] = n.range_max_arcsec;
    axis["sigma_rms_arcsec"] = n.sigma_rms_arcsec;
    axis["bias_rad_s"] = result.bias.bias_rad_s[a];
    if (!result.allan.empty()) {
      const AllanCoefficients& c = result.allan.axes[a];
      axis["arw_deg_sqrt_h"] = c.arw_deg_sqrt_h;
      axis["arw_rad_s_sqrt_hz"] = c.arw_rad_s_sqrt_hz;
      axis["bias_instability_deg_h"] = c.bias_instability_deg_h;
      axis["bias_instability_tau_s"] = c.bias_instability_tau_s;
      axis["bias_instability_upper_bound"] = c.bias_instability_upper_bound;
    }
    axes[kAxisNames[a]] = axis;
  }
  j["axes"] = axes;
  if (!result.allan.not_computed.empty()) j["allan_not_computed"] = result.allan.not_computed;
  return j;
}

nlohmann::ordered_json SensorPairToJson(const SensorPair& pair, const std::string& second_path) {
  nlohmann::ordered_json j;
  j["second_log"] = second_path;
  j["paired"] = pair.paired;
  j["unpaired"] = pair.unpaired;
  // --sync-second: the second's clock = the first's + this; null when both ran on one clock.
  j["clock_offset_s"] = pair.clock_offset_s ? nlohmann::ordered_json(*pair.clock_offset_s)
                                            : nlohmann::ordered_json(nullptr);
  j["clock_offset_stderr_s"] = pair.clock_offset_s
                                   ? nlohmann::ordered_json(pair.clock_offset_stderr_s)
                                   : nlohmann::ordered_json(nullptr);
  j["mounting_fitted"] = pair.mounting_fitted;
  j["mounting_angle_deg"] = pair.mounting_angle_deg;
  j["mounting_signal_ratio"] = pair.mounting_signal_ratio;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (int r = 0; r < 3; ++r)
    rows.push_back({pair.a_from_b(r, 0), pair.a_from_b(r, 1), pair.a_from_b(r, 2)});
  j["a_from_b"] = rows;
  j["weights_first"] = {pair.weight_a.x(), pair.weight_a.y(), pair.weight_a.z()};
  j["weights_from_still"] = pair.weights_from_still;
  j["difference_rms_rad_s"] = pair.residual_rms_rad_s;
  return j;
}

nlohmann::ordered_json NoisePairToJson(const SensorPair& pair, const std::string& second_path,
                                       const NoiseResult& first, const NoiseResult& second,
                                       const NoiseResult& fused) {
  nlohmann::ordered_json j = SensorPairToJson(pair, second_path);
  j["first"] = NoiseToJson(first);
  j["second"] = NoiseToJson(second);
  const NoisePairGain g = FusedNoiseGain(first, second, fused);
  auto xyz = [](const double(&v)[3]) { return nlohmann::ordered_json::array({v[0], v[1], v[2]}); };
  j["gain"] = {{"sigma_vs_first", xyz(g.sigma_vs_first)},
               {"sigma_vs_second", xyz(g.sigma_vs_second)},
               {"arw_vs_first", xyz(g.arw_vs_first)},
               {"arw_vs_second", xyz(g.arw_vs_second)}};
  return j;
}

nlohmann::ordered_json RecordSummaryToJson(const RecordSummary& summary,
                                           const std::string& triggers_path) {
  auto xyz = [](const Eigen::Vector3d& v) {
    return nlohmann::ordered_json::array({v.x(), v.y(), v.z()});
  };
  nlohmann::ordered_json j;
  j["format"] = "record/1";
  j["duration_s"] = summary.duration_s;
  j["t0_clock_ns"] = summary.t0_clock_ns;
  j["stopped_by_signal"] = summary.stopped;
  j["max_writer_stall_s"] = summary.max_writer_stall_s;
  nlohmann::ordered_json sensors = nlohmann::ordered_json::array();
  for (const SensorSummary& s : summary.sensors) {
    nlohmann::ordered_json sensor;
    sensor["part"] = GetPartInfo(s.setting.part).name;
    sensor["device"] = s.device;
    sensor["out"] = s.out_path;
    sensor["odr_hz"] = s.setting.odr_hz;
    sensor["range_dps"] = s.setting.range_dps;
    sensor["samples"] = s.samples;
    sensor["rate_hz"] = s.rate_hz;
    sensor["drift_ppm"] = s.drift_ppm;
    sensor["timestamp_rms_us"] = s.timestamp_rms_us;
    sensor["gaps"] = s.gaps;
    sensor["samples_lost"] = s.lost;
    sensor["ring_high_water"] = s.ring_high_water;
    sensor["ring_capacity"] = s.ring_capacity;
    sensor["max_read_interval_s"] = s.max_read_interval_s;
    sensor["still_s"] = s.still_span_s;
    sensor["still_bias_rad_s"] = xyz(s.still_bias_rad_s);
    sensor["still_std_rad_s"] = xyz(s.still_std_rad_s);
    sensors.push_back(sensor);
  }
  j["sensors"] = sensors;
  nlohmann::ordered_json gaps = nlohmann::ordered_json::array();
  for (const RecordGap& gap : summary.gaps) {
    gaps.push_back(
        {{"sensor", gap.sensor + 1}, {"t_s", gap.t_s}, {"lost", gap.lost}, {"kind", gap.kind}});
  }
  j["gaps"] = gaps;
  if (!triggers_path.empty()) {
    j["triggers"] = {{"file", triggers_path},
                     {"count", summary.triggers},
                     {"edges", summary.trigger_edges},
                     {"bounces", summary.trigger_bounces},
                     {"other_polarity", summary.trigger_other_polarity},
                     {"t_s", summary.trigger_t_s}};
  }
  j["notes"] = summary.notes;
  return j;
}

nlohmann::ordered_json AccuracyToJson(const AccuracyResult& result) {
  nlohmann::ordered_json j;
  j["reference_deg"] = result.reference_deg;
  nlohmann::ordered_json rotations = nlohmann::ordered_json::array();
  for (const DetectedRotation& r : result.rotations) {
    nlohmann::ordered_json item;
    item["before_arcsec"] = {r.before_arcsec.x(), r.before_arcsec.y(), r.before_arcsec.z()};
    item["after_arcsec"] = {r.after_arcsec.x(), r.after_arcsec.y(), r.after_arcsec.z()};
    item["theta_arcsec"] = r.theta_arcsec;
    item["difference_arcsec"] = r.difference_arcsec;
    item["theta_vector_arcsec"] = r.theta_vector_arcsec;
    item["theta_so3_arcsec"] = r.theta_so3_arcsec;
    item["t_start_s"] = r.t_start_s;
    item["t_end_s"] = r.t_end_s;
    rotations.push_back(item);
  }
  j["rotations"] = rotations;
  j["average_samples"] = result.average_samples;
  j["difference_mean_arcsec"] = result.difference_mean_arcsec;
  j["difference_std_arcsec"] = result.difference_std_arcsec;
  j["noise_level_rad_s"] = result.noise_level_rad_s;
  j["enter_rad_s"] = result.enter_rad_s;
  j["exit_rad_s"] = result.exit_rad_s;
  j["skipped_t_s"] = result.skipped_t_s;
  return j;
}

nlohmann::json FlightToJson(const FlightResult& result) {
  nlohmann::json rows = nlohmann::json::array();
  for (const FlightRow& row : result.rows) {
    nlohmann::json r = {{"limit_m", row.limit_m},
                        {"window_s", row.window_s},
                        {"threshold_arcsec", row.threshold_arcsec},
                        {"too_few_samples", row.too_few_samples},
                        {"windows", row.windows},
                        {"flagged_percent", row.flagged_percent},
                        {"flagged_percent_axis",
                         {{"x", row.flagged_percent_axis[0]},
                          {"y", row.flagged_percent_axis[1]},
                          {"z", row.flagged_percent_axis[2]}}}};
    if (result.vector_criterion) {
      r["flagged_percent_vector"] = row.flagged_percent_vector;
      r["flagged_vector_only"] = row.flagged_vector_only;
      r["flagged_axis_only"] = row.flagged_axis_only;
    } else {
      r["flagged_percent_vector"] = nullptr;
    }
    rows.push_back(std::move(r));
  }
  const auto& b = result.bias.bias_rad_s;
  return {{"altitude_m", result.altitude_m},
          {"noise_allowance_arcsec", result.noise_allowance_arcsec},
          {"windows_total", result.windows_total},
          {"samples", result.samples},
          {"sample_interval_s", result.sample_interval_s},
          {"bias_rad_s", {b.x(), b.y(), b.z()}},
          {"rows", rows}};
}

nlohmann::json AssumptionsToJson(const std::vector<Assumption>& assumptions) {
  nlohmann::json out = nlohmann::json::array();
  for (const Assumption& a : assumptions) {
    out.push_back({{"what", a.what}, {"taken", a.taken}, {"why", a.why}, {"give", a.give}});
  }
  return out;
}

nlohmann::json AnalyzeToJson(const AnalyzeResult& result) {
  nlohmann::json json;
  json["source"] = {{"format", result.format},   {"gyro", result.gyro_source},
                    {"samples", result.samples}, {"duration_s", result.duration_s},
                    {"rate_hz", result.rate_hz}, {"gaps", result.gaps}};
  json["warnings"] = WarningsToJson(result.log_warnings);
  json["flight"] = result.flight ? FlightToJson(*result.flight) : nlohmann::json(nullptr);
  if (!result.flight) json["flight_problem"] = result.flight_problem;
  json["bias"] = {{"estimated", result.bias_estimated},
                  {"from_still_segment", result.bias_from_still},
                  {"rad_s", {result.bias_rad_s.x(), result.bias_rad_s.y(), result.bias_rad_s.z()}}};
  if (result.bias_from_still) {
    json["bias"]["segment_s"] = {result.still_segment.begin_s, result.still_segment.end_s};
    json["bias"]["segment_given"] = result.bias_segment_given;
  }
  json["camera"] = {{"altitude_m", result.altitude_m},
                    {"altitude_source", result.altitude_source},
                    {"altitude_method", result.altitude_method},
                    {"readout_s", result.readout_s}};
  json["triggers"] = result.trigger_source;
  json["assumptions"] = AssumptionsToJson(result.assumptions);
  nlohmann::json images = nlohmann::json::array();
  for (const ImageResult& image : result.images) {
    nlohmann::json entry;
    entry["name"] = image.name;
    entry["t"] = image.t_ns * 1e-9;
    entry["trigger_t"] = image.trigger_t_ns * 1e-9;
    entry["in_trace"] = image.in_trace;
    nlohmann::json flagged = nlohmann::json::object();
    if (image.too_few_samples) entry["too_few_samples"] = true;  // absent: false
    if (image.judged()) {
      entry["D_paper_m"] = image.d_paper_m;
      entry["D_full_m"] = image.d_full_m;
      entry["D_full_px"] = image.d_full_px;
      entry["range_arcsec"] = image.range_arcsec;
      entry["dominant_axis"] = kAxisNames[image.dominant_axis];
      for (size_t l = 0; l < result.limits_m.size(); ++l) {
        flagged[LimitKey(result.limits_m[l])] = static_cast<bool>(image.flagged[l]);
      }
    } else {
      entry["D_paper_m"] = nullptr;
      entry["D_full_m"] = nullptr;
      for (double limit : result.limits_m) flagged[LimitKey(limit)] = nullptr;
    }
    entry["flagged"] = flagged;
    images.push_back(std::move(entry));
  }
  json["images"] = std::move(images);
  const AnalyzeVerdict& v = result.verdict;
  json["verdict"] = {{"images_in_trace", v.images_in_trace},
                     {"flagged_percent", v.share_percent},
                     {"axis_to_stabilise", v.axis_to_stabilise < 0
                                               ? nlohmann::json(nullptr)
                                               : nlohmann::json(kAxisNames[v.axis_to_stabilise])},
                     {"fast_readout_s", v.fast_readout_s},
                     {"flagged_percent_fast_readout", v.share_fast_readout_percent},
                     {"flagged_percent_half_altitude", v.share_half_altitude_percent},
                     {"line", v.line}};
  if (v.images_too_few_samples > 0)
    json["verdict"]["images_too_few_samples"] = v.images_too_few_samples;
  return json;
}

}  // namespace shutterlab
