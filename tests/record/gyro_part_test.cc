// The gyro parts' facts and register arithmetic, from the datasheets: part names on the command
// line, WHO_AM_I and FIFO packet sizes, the rates the MPU's and the ICM's registers give, the MPU's
// low-pass choice for a rate, and the setting described in one header line. (How a requested rate
// and range resolve is also checked in device_spec_test.cc.)

#include "record/gyro_part.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace shutterlab {
namespace {

PartSetting GyroPartSettingAt(GyroPart part, double rate_hz, int range_dps = 250) {
  SensorConfig config;
  config.rate_hz = rate_hz;
  config.range_dps = range_dps;
  return ResolvePartSetting(part, config);
}

TEST(GyroPart, ParsesKeysAndDatasheetNamesInAnyCase) {
  EXPECT_EQ(ParseGyroPart("mpu9250"), GyroPart::kMpu9250);
  EXPECT_EQ(ParseGyroPart("MPU-9250"), GyroPart::kMpu9250);
  EXPECT_EQ(ParseGyroPart("Mpu6500"), GyroPart::kMpu6500);
  EXPECT_EQ(ParseGyroPart("mpu-6500"), GyroPart::kMpu6500);
  EXPECT_EQ(ParseGyroPart("icm42688p"), GyroPart::kIcm42688p);
  EXPECT_EQ(ParseGyroPart("ICM42688"), GyroPart::kIcm42688p);
  EXPECT_EQ(ParseGyroPart("ICM-42688-P"), GyroPart::kIcm42688p);
  for (const char* bad : {"", "bmi088", "mpu92500", "icm"}) {
    EXPECT_THROW(ParseGyroPart(bad), std::invalid_argument) << bad;
  }
}

TEST(GyroPart, InfoHoldsTheDatasheetsWhoAmIAndFifoPackets) {
  const PartInfo& mpu9250 = GetPartInfo(GyroPart::kMpu9250);
  const PartInfo& mpu6500 = GetPartInfo(GyroPart::kMpu6500);
  const PartInfo& icm = GetPartInfo(GyroPart::kIcm42688p);
  EXPECT_EQ(mpu9250.who_am_i, 0x71);  // MPU-9250 register map rev 1.6, register 117
  EXPECT_EQ(mpu6500.who_am_i, 0x70);
  EXPECT_EQ(icm.who_am_i, 0x47);  // ICM-42688-P DS-000347, WHO_AM_I
  EXPECT_EQ(mpu9250.who_am_i_reg, 0x75);
  EXPECT_EQ(icm.who_am_i_reg, 0x75);
  // The MPU FIFO holds gyro x, y, z only: 3 int16; the ICM's packet 1 adds a header byte and a
  // one-byte temperature.
  EXPECT_EQ(mpu9250.packet_bytes, 3 * 2);
  EXPECT_EQ(icm.packet_bytes, 1 + 3 * 2 + 1);
  EXPECT_EQ(mpu9250.fifo_bytes / mpu9250.packet_bytes, 85);  // 512 bytes: 10.6 ms at 8 kHz
  EXPECT_EQ(icm.fifo_bytes / icm.packet_bytes, 256);         // 2 KiB: 8 ms at 32 kHz
  EXPECT_STREQ(GetPartInfo(ParseGyroPart(icm.key)).name, icm.name);
}

TEST(GyroPart, MpuRateFollowsFchoiceDlpfAndDivider) {
  EXPECT_EQ(MpuRateHz(0, 0, 0), 8000.0);  // DLPF_CFG 0: 8 kHz whatever the divider
  EXPECT_EQ(MpuRateHz(9, 0, 0), 8000.0);
  EXPECT_EQ(MpuRateHz(0, 7, 0), 8000.0);
  EXPECT_EQ(MpuRateHz(0, 1, 1), 32000.0);  // FCHOICE_B bypasses the DLPF
  EXPECT_EQ(MpuRateHz(0, 3, 2), 32000.0);
  EXPECT_EQ(MpuRateHz(0, 1, 0), 1000.0);
  EXPECT_EQ(MpuRateHz(4, 2, 0), 200.0);
  EXPECT_EQ(MpuRateHz(255, 6, 0), 1000.0 / 256);
}

TEST(GyroPart, IcmOdrCodesHalveFrom32KilohertzAndReservedCodesAreZero) {
  for (uint8_t code = 1; code <= 6; ++code) {
    EXPECT_EQ(IcmRateHz(code), 32000.0 / (1 << (code - 1))) << int{code};  // 32 kHz .. 1 kHz
  }
  for (uint8_t code = 7; code <= 11; ++code) {
    EXPECT_EQ(IcmRateHz(code), 200.0 / (1 << (code - 7))) << int{code};  // 200 Hz .. 12.5 Hz
  }
  EXPECT_EQ(IcmRateHz(15), 500.0);
  for (uint8_t code : {0, 12, 13, 14}) EXPECT_EQ(IcmRateHz(code), 0.0) << int{code};
  EXPECT_EQ(IcmRateHz(0x23), IcmRateHz(3));  // the range bits above are ignored
  for (uint8_t code = 0; code < 4; ++code) {
    EXPECT_EQ(IcmRangeDps(code), 2000.0 / (1 << code));  // 2000, 1000, 500, 250 deg/s
  }
}

TEST(GyroPart, MpuLowPassIsTheWidestBelowHalfTheRate) {
  struct Case {
    double rate_hz;
    int smplrt_div, dlpf_cfg;
    double bandwidth_hz;
  };
  // DLPF_CFG 1..6: 184, 92, 41, 20, 10, 5 Hz (register map, CONFIG); 8 kHz: DLPF_CFG 0, 250 Hz.
  for (const Case& c :
       {Case{8000, 0, 0, 250}, Case{1000, 0, 1, 184}, Case{500, 1, 1, 184}, Case{200, 4, 2, 92},
        Case{100, 9, 3, 41}, Case{50, 19, 4, 20}, Case{25, 39, 5, 10}}) {
    const PartSetting s = GyroPartSettingAt(GyroPart::kMpu9250, c.rate_hz);
    EXPECT_EQ(s.smplrt_div, c.smplrt_div) << c.rate_hz;
    EXPECT_EQ(s.dlpf_cfg, c.dlpf_cfg) << c.rate_hz;
    EXPECT_EQ(s.fchoice_b, 0) << c.rate_hz;
    EXPECT_EQ(s.bandwidth_hz, c.bandwidth_hz) << c.rate_hz;
    EXPECT_LE(s.bandwidth_hz, std::max(250.0, s.odr_hz / 2)) << c.rate_hz;
  }
}

TEST(GyroPart, RequestsBelowThePartsSlowestRateGetTheSlowest) {
  const PartSetting mpu = GyroPartSettingAt(GyroPart::kMpu6500, 2.0);
  EXPECT_EQ(mpu.smplrt_div, 255);  // the divider's largest value
  EXPECT_DOUBLE_EQ(mpu.odr_hz, 1000.0 / 256);
  const PartSetting icm = GyroPartSettingAt(GyroPart::kIcm42688p, 5.0);
  EXPECT_EQ(icm.odr_hz, 12.5);
  EXPECT_EQ(IcmRateHz(icm.icm_odr_code), 12.5);
  EXPECT_EQ(GyroPartSettingAt(GyroPart::kIcm42688p, 200.0).odr_hz, 200.0);
  EXPECT_EQ(GyroPartSettingAt(GyroPart::kIcm42688p, 200.5).odr_hz, 500.0);  // code 15
}

TEST(GyroPart, ConfigCheckRefusesABadRateOrRange) {
  SensorConfig config;
  EXPECT_NO_THROW(config.Check());
  for (double rate : {0.0, -100.0, std::numeric_limits<double>::quiet_NaN(),
                      std::numeric_limits<double>::infinity()}) {
    config.rate_hz = rate;
    try {
      config.Check();
      ADD_FAILURE() << "rate " << rate << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("rate"), std::string::npos) << e.what();
    }
  }
  config.rate_hz = 1000;
  for (int range : {0, 125, 300, 4000}) {
    config.range_dps = range;
    EXPECT_THROW(config.Check(), std::invalid_argument) << range;
  }
}

TEST(GyroPart, HexByteWritesTwoUpperCaseDigits) {
  EXPECT_EQ(HexByte(0x71), "0x71");
  EXPECT_EQ(HexByte(0x0A), "0x0A");
  EXPECT_EQ(HexByte(0x00), "0x00");
  EXPECT_EQ(HexByte(0xFF), "0xFF");
}

TEST(GyroPart, DescribeGivesRateFilterAndRangeOnOneCommaFreeLine) {
  const std::string mpu = GyroPartSettingAt(GyroPart::kMpu9250, 200.0, 500).Describe();
  EXPECT_EQ(mpu,
            "200 Hz (SMPLRT_DIV 4; DLPF_CFG 2: 92 Hz bandwidth); delay 3.9 ms; +-500 deg/s (65.5 "
            "LSB per deg/s)");
  const std::string icm = GyroPartSettingAt(GyroPart::kIcm42688p, 32000.0, 2000).Describe();
  EXPECT_EQ(icm,
            "32000 Hz (GYRO_ODR 1; UI filter 8000 Hz); delay 0.0199 ms (modelled); +-2000 deg/s "
            "(16.4 LSB per deg/s)");
  const std::string fastest = GyroPartSettingAt(GyroPart::kMpu9250, 32000.0).Describe();
  EXPECT_EQ(fastest,
            "32000 Hz (FCHOICE_B 1: DLPF bypassed; 8800 Hz bandwidth); delay 0.064 ms; +-250 "
            "deg/s (131 LSB per deg/s)");
  const std::string third = GyroPartSettingAt(GyroPart::kMpu6500, 300.0).Describe();  // 333.3 Hz
  for (const std::string& text : {mpu, icm, fastest, third}) {
    EXPECT_EQ(text.find_first_of(",\n"), std::string::npos) << text;  // a .gcsv header value
  }
}

}  // namespace
}  // namespace shutterlab
