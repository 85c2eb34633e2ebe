#include "io/import_io.h"

#include "io/warnings_io.h"
#include "model/camera.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

namespace shutterlab {
namespace {

using json = nlohmann::json;

json ValueJson(const ClaimValue& value) {
  if (const auto* number = std::get_if<double>(&value)) return *number;
  if (const auto* text = std::get_if<std::string>(&value)) return *text;
  if (const auto* matrix = std::get_if<Eigen::Matrix3d>(&value)) return MatrixJson(*matrix);
  if (const auto* lens = std::get_if<LensDistortion>(&value)) return DistortionJson(*lens);
  return std::get<std::map<std::string, double>>(value);
}

json ClaimsJson(const std::vector<ImportClaim>& claims) {
  json out = json::array();
  for (const ImportClaim& claim : claims)
    out.push_back({{"what", claim.what},
                   {"value", ValueJson(claim.value)},
                   {"status", ClaimStatusName(claim.status)},
                   {"source", claim.source}});
  return out;
}

json ExposuresJson(const std::vector<FrameExposure>& exposures) {
  json out = json::array();
  for (const FrameExposure& e : exposures)
    out.push_back(
        {{"frame", e.frame}, {"exposure_s", e.exposure_s ? json(*e.exposure_s) : json(nullptr)}});
  return out;
}

void AddDecoding(const VideoDecoding& decoding, json* record) {
  json& frames = (*record)["frames"];
  frames["video_samples"] = decoding.video_samples;
  frames["decoded"] = decoding.decoded;
  frames["failed_grabs"] = decoding.failed_grabs;
  frames["reader_time_mismatches"] = decoding.reader_time_mismatches;
}

void AddGopro(const GoproImportDetails& gopro, json* record) {
  json& r = *record;
  r["source"]["kind"] = "gopro_mp4";
  r["source"]["device"] = gopro.device;
  r["gyro"]["stream_name"] = gopro.stream_name;
  r["gyro"]["axis_order"] = gopro.axis_order;
  r["gyro"]["scal"] = gopro.scal;
  r["gyro"]["payload_samples"] = gopro.payload_samples;
  r["gyro"]["timing"] = gopro.timing;
  r["gyro"]["fit_max_residual_s"] = gopro.fit_max_residual_s;
  AddDecoding(gopro.decoding, &r);
  r["frames"]["times"] = gopro.times;
  // Fields that only newer cameras write: absent, not null, for a clip without them.
  if (!gopro.gyro_orin.empty()) r["gyro"]["orin"] = gopro.gyro_orin;
  if (!gopro.gyro_orio.empty()) r["gyro"]["orio"] = gopro.gyro_orio;
  if (!gopro.gyro_mtrx.empty()) r["gyro"]["mtrx"] = gopro.gyro_mtrx;
  const GoproSettings& s = gopro.settings;
  if (s.present) {
    json& j = r["settings"];
    j["model"] = s.model;
    j["firmware"] = s.firmware;
    j["fov"] = s.fov;
    j["projection"] = s.projection;
    j["stabilizer"] = s.stabilizer;
    j["stabilizer_mode"] = s.stabilizer_mode;
    j["readout_s"] = s.readout_s ? json(*s.readout_s) : json(nullptr);
    j["diagonal_fov_deg"] = s.diagonal_fov_deg ? json(*s.diagonal_fov_deg) : json(nullptr);
    j["camera_mode"] = s.camera_mode ? json(*s.camera_mode) : json(nullptr);
    j["source"] =
        "moov/udta/GPMF, DEVC \"Global Settings\" (MINF FMWR VFOV PRJT EISE EISA SROT "
        "ZFOV CMOD)";
  }
  if (!s.unreadable.empty()) r["settings_unreadable"] = s.unreadable;
  if (gopro.iori_samples > 0 || gopro.cori_samples > 0) {
    json& j = r["image_orientation"];
    j["file"] = "image_orientation.csv";
    j["iori_samples"] = gopro.iori_samples;
    j["cori_samples"] = gopro.cori_samples;
    j["frames_matched"] = gopro.orientation_frames;
    j["iori_max_deg"] = gopro.iori_max_deg;
    j["source"] =
        "GPMF IORI (image orientation relative to the body: the stabiliser's) and CORI "
        "(camera orientation), (w, x, y, z) / SCAL as written; each frame's nearest "
        "sample within half a frame period";
  }
}

void AddPhone(const PhoneImportDetails& phone, json* record) {
  json& r = *record;
  r["source"]["kind"] = "phone_folder";
  r["source"]["origin"] = phone.origin;
  r["frames"]["sof_times"] = phone.sof_times;
  r["frames"]["images_in_source"] = phone.images_in_source;
  r["frames"]["dump_sof_max_diff_s"] = phone.dump_sof_max_diff_s;
  // nlohmann writes a non-finite number as null: an unknown range.
  r["exposure_range_s"] = {phone.exposure_min_s, phone.exposure_max_s};
}

void AddVideoFile(const VideoFileImportDetails& video, json* record) {
  (*record)["source"]["kind"] = "video_file";
  AddDecoding(video.decoding, record);
}

json GyroLogJson(const GyroLogAlignment& log) {
  const GyroSync& sync = log.sync;
  json j = {{"path", log.path},
            {"format", log.format},
            {"gyro_source", log.gyro_source},
            {"log_samples", log.log_samples},
            {"log_duration_s", log.log_duration_s},
            {"method", log.method},
            {"offset_s", sync.offset_s},
            {"offset_stderr_s", sync.offset_stderr_s},
            {"rate_ppm", sync.rate_ppm ? json(*sync.rate_ppm) : json(nullptr)},
            {"rate_stderr_ppm", sync.rate_stderr_ppm ? json(*sync.rate_stderr_ppm) : json(nullptr)},
            {"reference_clip_s", sync.reference_a_s},
            {"camera_from_log", MatrixJson(sync.a_from_b)},
            {"mounting_fitted", sync.mounting_fitted},
            {"mounting_angle_deg", sync.mounting_angle_deg},
            {"peak_correlation", sync.peak_correlation},
            {"runner_up_correlation", sync.runner_up_correlation},
            {"overlap_s", sync.overlap_s},
            {"residual_rms_rad_s", sync.residual_rms_rad_s},
            {"time_offset_s", log.time_offset_s},
            {"written_span_s", {log.written_from_s, log.written_to_s}}};
  if (log.pairs > 0) {
    j["pairs"] = log.pairs;
    j["pairs_used"] = log.pairs_used;
    j["median_inliers"] = log.median_inliers;
  }
  return j;
}

}  // namespace

const char* ClaimStatusName(ClaimStatus status) {
  switch (status) {
    case ClaimStatus::kSourceClaim:
      return "source claim";
    case ClaimStatus::kInferred:
      return "inferred";
    case ClaimStatus::kSourceClaimInferred:
      return "source claim + inferred";
    case ClaimStatus::kGuess:
      return "guess";
  }
  return "guess";
}

std::string ClaimValueJson(const ClaimValue& value) { return ValueJson(value).dump(); }

std::string ImportJson(const ImportRecord& record) {
  // Objects are written with their keys sorted (nlohmann::json's std::map), whatever the order
  // they are filled in.
  json r;
  r["format"] = "import/1";
  r["source"]["path"] = record.path;
  r["time_origin_s"] = record.time_origin_s;
  r["clock"] = record.clock;
  r["gyro"]["samples"] = record.gyro_samples;
  r["gyro"]["rate_hz"] = record.gyro_rate_hz;
  r["gyro"]["columns"] = record.gyro_columns;
  r["frames"]["count"] = record.frame_count;
  r["frames"]["t_first_row"] = record.t_first_row;
  r["frames"]["outside_gyro"] = record.outside_gyro;
  r["exposure_s"] = ExposuresJson(record.exposures);
  r["claims"] = ClaimsJson(record.claims);
  r["warnings"] = WarningsToJson(record.warnings);
  if (record.lens_profile) r["lens_profile"] = LensProfileUseJson(*record.lens_profile);
  if (!record.mask_file.empty()) {
    r["mask"] = {{"file", record.mask_file}, {"source", record.mask_source}};
  }
  if (const auto* gopro = std::get_if<GoproImportDetails>(&record.details)) AddGopro(*gopro, &r);
  if (const auto* phone = std::get_if<PhoneImportDetails>(&record.details)) AddPhone(*phone, &r);
  if (const auto* video = std::get_if<VideoFileImportDetails>(&record.details))
    AddVideoFile(*video, &r);
  if (record.gyro_log) r["gyro_log"] = GyroLogJson(*record.gyro_log);
  return r.dump(2) + "\n";
}

void WriteImportJson(const std::string& path, const ImportRecord& record) {
  WriteFileAtomically(path, ImportJson(record));
}

}  // namespace shutterlab
