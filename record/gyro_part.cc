#include "record/gyro_part.h"

#include "sim/check.h"
#include "sim/logs/raw_csv.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace shutterlab {
namespace {

// startup: MPU-9250 Product Specification table 1 (gyro start-up 35 ms); ICM-42688-P datasheet
// table 1 (gyro start-up from sleep 30 ms). SPI: 1 MHz for all MPU registers, 20 MHz for sensor
// and interrupt registers; the ICM-42688-P allows 24 MHz throughout.
const PartInfo kParts[] = {
    {GyroPart::kMpu9250, "MPU-9250", "mpu9250", 0x71, mpu::kWhoAmI, 512, 6, 35000000, 1000000,
     20000000, 32000.0},
    {GyroPart::kMpu6500, "MPU-6500", "mpu6500", 0x70, mpu::kWhoAmI, 512, 6, 35000000, 1000000,
     20000000, 32000.0},
    {GyroPart::kIcm42688p, "ICM-42688-P", "icm42688p", 0x47, icm::kWhoAmI, 2048, 8, 30000000,
     24000000, 24000000, 32000.0},
};

// MPU register map, CONFIG (FCHOICE_B 00): DLPF_CFG 0..7's gyro bandwidth, delay and rate.
constexpr GyroFilter kMpuDlpf[] = {
    {250.0, 0.97e-3, 8000.0, true}, {184.0, 2.9e-3, 1000.0, true},   {92.0, 3.9e-3, 1000.0, true},
    {41.0, 5.9e-3, 1000.0, true},   {20.0, 9.9e-3, 1000.0, true},    {10.0, 17.85e-3, 1000.0, true},
    {5.0, 33.48e-3, 1000.0, true},  {3600.0, 0.17e-3, 8000.0, true},
};
// FCHOICE_B x1 and 10: the filter bypassed, 32 kHz.
constexpr GyroFilter kMpuFchoiceX1 = {8800.0, 0.064e-3, 32000.0, true};
constexpr GyroFilter kMpuFchoice10 = {3600.0, 0.11e-3, 32000.0, true};

PartSetting ResolveMpu(GyroPart part, const SensorConfig& config) {
  PartSetting s;
  s.part = part;
  // FIFO rates: 32 kHz (FCHOICE_B 01, the filter bypassed: 8800 Hz bandwidth), 8 kHz (DLPF_CFG 0,
  // 250 Hz bandwidth), or 1 kHz / (1 + SMPLRT_DIV) with the widest DLPF below half the rate.
  s.fchoice_b = 0;
  if (config.rate_hz > 8000.0) {
    s.fchoice_b = 1;
  } else if (config.rate_hz > 1000.0) {
    s.dlpf_cfg = 0;
    s.smplrt_div = 0;
  } else {
    const int div =
        std::clamp(static_cast<int>(std::floor(1000.0 / config.rate_hz + 1e-9)) - 1, 0, 255);
    s.smplrt_div = static_cast<uint8_t>(div);
    const double rate = 1000.0 / (1 + div);
    s.dlpf_cfg = 6;
    for (uint8_t cfg = 1; cfg <= 6; ++cfg) {
      if (kMpuDlpf[cfg].bandwidth_hz <= rate / 2) {
        s.dlpf_cfg = cfg;
        break;
      }
    }
  }
  s.odr_hz = MpuRateHz(s.smplrt_div, s.dlpf_cfg, s.fchoice_b);
  const GyroFilter filter = MpuGyroFilter(s.dlpf_cfg, s.fchoice_b);
  s.bandwidth_hz = filter.bandwidth_hz;
  s.filter_delay_s = filter.delay_s;
  s.fs_sel = static_cast<uint8_t>(std::log2(config.range_dps / 250.0) + 0.5);
  return s;
}

PartSetting ResolveIcm(const SensorConfig& config) {
  PartSetting s;
  s.part = GyroPart::kIcm42688p;
  // The lowest rate at or above the request (codes 1..11 and 15 = 500 Hz).
  uint8_t best = 1;
  for (uint8_t code = 1; code <= 15; ++code) {
    const double rate = IcmRateHz(code);
    if (rate > 0 && rate >= config.rate_hz - 1e-9 && rate < IcmRateHz(best)) best = code;
  }
  s.icm_odr_code = best;
  s.odr_hz = IcmRateHz(best);
  const GyroFilter filter = IcmGyroFilter(s.odr_hz);
  s.bandwidth_hz = filter.bandwidth_hz;
  s.filter_delay_s = filter.delay_s;
  for (uint8_t code = 0; code < 8; ++code) {
    if (IcmRangeDps(code) == config.range_dps) s.icm_fs_code = code;
  }
  return s;
}

}  // namespace

const PartInfo& GetPartInfo(GyroPart part) {
  for (const PartInfo& info : kParts) {
    if (info.part == part) return info;
  }
  throw std::invalid_argument("unknown gyro part");
}

GyroPart ParseGyroPart(const std::string& text) {
  const std::string key = ToLower(text);
  for (const PartInfo& info : kParts) {
    if (key == info.key) return info.part;
  }
  if (key == "icm42688" || key == "icm-42688-p") return GyroPart::kIcm42688p;
  if (key == "mpu-9250") return GyroPart::kMpu9250;
  if (key == "mpu-6500") return GyroPart::kMpu6500;
  throw std::invalid_argument("unknown gyro part '" + text + "' (mpu9250, mpu6500, icm42688p)");
}

void SensorConfig::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(rate_hz) && rate_hz > 0)
      << "rate must be positive, got " << rate_hz;
  SHUTTERLAB_CHECK(range_dps == 250 || range_dps == 500 || range_dps == 1000 || range_dps == 2000)
      << "range must be 250, 500, 1000 or 2000 deg/s, got " << range_dps;
}

double MpuRateHz(uint8_t smplrt_div, uint8_t dlpf_cfg, uint8_t fchoice_b) {
  if ((fchoice_b & 3) != 0) return 32000.0;
  if ((dlpf_cfg & 7) == 0 || (dlpf_cfg & 7) == 7) return 8000.0;
  return 1000.0 / (1 + smplrt_div);
}

GyroFilter MpuGyroFilter(uint8_t dlpf_cfg, uint8_t fchoice_b) {
  if ((fchoice_b & 3) == 2) return kMpuFchoice10;
  if ((fchoice_b & 1) != 0) return kMpuFchoiceX1;
  return kMpuDlpf[dlpf_cfg & 7];
}

GyroFilter IcmGyroFilter(double odr_hz) {
  const double bandwidth_hz = std::max(400.0, odr_hz) / 4;
  return {bandwidth_hz, 1.0 / (2 * kPi * bandwidth_hz), odr_hz, false};
}

double IcmRateHz(uint8_t odr_code) {
  switch (odr_code & 0x0F) {
    case 1:
      return 32000.0;
    case 2:
      return 16000.0;
    case 3:
      return 8000.0;
    case 4:
      return 4000.0;
    case 5:
      return 2000.0;
    case 6:
      return 1000.0;
    case 7:
      return 200.0;
    case 8:
      return 100.0;
    case 9:
      return 50.0;
    case 10:
      return 25.0;
    case 11:
      return 12.5;
    case 15:
      return 500.0;
    default:
      return 0.0;
  }
}

std::string HexByte(uint8_t value) {
  char text[8];
  std::snprintf(text, sizeof(text), "0x%02X", value);
  return text;
}

double AccelLsbPerG(GyroPart part, uint8_t fs_code) {
  const int code = fs_code & 3;
  return part == GyroPart::kIcm42688p ? 2048.0 * (1 << code) : 16384.0 / (1 << code);
}

double IcmRangeDps(uint8_t fs_code) { return 2000.0 / (1 << (fs_code & 7)); }

PartSetting ResolvePartSetting(GyroPart part, const SensorConfig& config) {
  config.Check();
  const PartInfo& info = GetPartInfo(part);
  SHUTTERLAB_CHECK(config.rate_hz <= info.max_rate_hz + 1e-9)
      << info.name << " FIFO rates go up to " << info.max_rate_hz << " Hz, asked for "
      << config.rate_hz;
  PartSetting s = part == GyroPart::kIcm42688p ? ResolveIcm(config) : ResolveMpu(part, config);
  s.range_dps = config.range_dps;
  s.lsb_per_dps = RawSensitivityLsbPerDps(config.range_dps);
  return s;
}

std::string PartSetting::Describe() const {
  std::string text = FormatNumber("%.6g Hz", odr_hz);  // no commas: a .gcsv header value
  if (part == GyroPart::kIcm42688p) {
    text += " (GYRO_ODR " + std::to_string(icm_odr_code) + "; UI filter " +
            FormatNumber("%.6g", bandwidth_hz) + " Hz)";
  } else if (fchoice_b != 0) {
    text += " (FCHOICE_B " + std::to_string(fchoice_b) + ": DLPF bypassed; " +
            FormatNumber("%.6g", bandwidth_hz) + " Hz bandwidth)";
  } else {
    text += " (SMPLRT_DIV " + std::to_string(smplrt_div) + "; DLPF_CFG " +
            std::to_string(dlpf_cfg) + ": " + FormatNumber("%.6g", bandwidth_hz) + " Hz bandwidth)";
  }
  text += FormatNumber("; delay %.3g ms", filter_delay_s * 1e3);
  if (part == GyroPart::kIcm42688p) text += " (modelled)";
  return text + "; +-" + std::to_string(range_dps) + " deg/s (" +
         FormatNumber("%.4g", lsb_per_dps) + " LSB per deg/s)";
}

}  // namespace shutterlab
