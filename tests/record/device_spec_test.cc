// What `record --device` accepts, and how a requested rate and range become the part's registers
// (the rates each part offers, from the datasheets' tables).

#include "record/device_spec.h"

#include "record/gyro_part.h"

#include <gtest/gtest.h>

namespace shutterlab {
namespace {

TEST(DeviceSpec, ParsesEmulatedAndSpidevDevices) {
  const DeviceSpec emulated =
      ParseDeviceSpec("emulate:trace.csv,part=icm42688p,rate=32kHz,ppm=-12.5");
  EXPECT_TRUE(emulated.emulate);
  EXPECT_EQ(emulated.path, "trace.csv");
  EXPECT_EQ(emulated.part, GyroPart::kIcm42688p);
  EXPECT_EQ(emulated.rate_hz, 32000.0);
  EXPECT_EQ(emulated.ppm, -12.5);
  const DeviceSpec spi = ParseDeviceSpec("/dev/spidev1.0,range=500deg/s,mode=3");
  EXPECT_FALSE(spi.emulate);
  EXPECT_EQ(spi.path, "/dev/spidev1.0");
  EXPECT_EQ(spi.range_dps, 500);
  EXPECT_EQ(spi.spi_mode, 3);
  EXPECT_EQ(ParseDeviceSpec("spi:/dev/spidev0.0").path, "/dev/spidev0.0");
}

TEST(DeviceSpec, RefusesWhatItDoesNotKnow) {
  for (const char* bad :
       {"emulate:", "emulate:t.csv,colour=red", "/dev/spidev0.0,ppm=40", "emulate:t.csv,mode=3",
        "emulate:t.csv,rate=fast", "emulate:t.csv,rate=8000", "emulate:t.csv,range=250",
        "emulate:t.csv,part=bmi088", "/dev/spidev0.0,mode=1"}) {
    EXPECT_THROW(ParseDeviceSpec(bad), std::invalid_argument) << bad;
  }
}

TEST(GyroPart, RatesAreTheLowestThePartOffersAtOrAboveTheRequest) {
  SensorConfig config;
  struct Case {
    GyroPart part;
    double asked_hz, odr_hz;
  };
  // MPU: 32 kHz (FCHOICE_B), 8 kHz (DLPF_CFG 0) or 1 kHz / (1 + SMPLRT_DIV); ICM: its GYRO_ODR
  // table.
  for (const Case& c :
       {Case{GyroPart::kMpu9250, 32000, 32000}, Case{GyroPart::kMpu6500, 16000, 32000},
        Case{GyroPart::kMpu9250, 8000, 8000}, Case{GyroPart::kMpu9250, 3000, 8000},
        Case{GyroPart::kMpu9250, 1000, 1000}, Case{GyroPart::kMpu9250, 300, 1000.0 / 3},
        Case{GyroPart::kMpu6500, 500, 500}, Case{GyroPart::kIcm42688p, 32000, 32000},
        Case{GyroPart::kIcm42688p, 3000, 4000}, Case{GyroPart::kIcm42688p, 600, 1000},
        Case{GyroPart::kIcm42688p, 400, 500}}) {
    config.rate_hz = c.asked_hz;
    const PartSetting setting = ResolvePartSetting(c.part, config);
    EXPECT_DOUBLE_EQ(setting.odr_hz, c.odr_hz) << GetPartInfo(c.part).name << " at " << c.asked_hz;
    if (c.part != GyroPart::kIcm42688p) {
      EXPECT_DOUBLE_EQ(MpuRateHz(setting.smplrt_div, setting.dlpf_cfg, setting.fchoice_b),
                       c.odr_hz);
      EXPECT_LE(setting.bandwidth_hz, std::max(250.0, c.odr_hz / 2));  // no alias-prone filter
    } else {
      EXPECT_DOUBLE_EQ(IcmRateHz(setting.icm_odr_code), c.odr_hz);
    }
  }
  config.rate_hz = 40000;
  EXPECT_THROW(ResolvePartSetting(GyroPart::kMpu9250, config), std::invalid_argument);
  config.rate_hz = 8000;
  config.range_dps = 300;
  EXPECT_THROW(ResolvePartSetting(GyroPart::kIcm42688p, config), std::invalid_argument);
}

TEST(GyroPart, RangesGiveTheDatasheetSensitivity) {
  SensorConfig config;
  const double lsb[] = {131.0, 65.5, 32.8, 16.4};
  int i = 0;
  for (int range : {250, 500, 1000, 2000}) {
    config.range_dps = range;
    const PartSetting mpu = ResolvePartSetting(GyroPart::kMpu9250, config);
    const PartSetting icm = ResolvePartSetting(GyroPart::kIcm42688p, config);
    EXPECT_EQ(mpu.fs_sel, i);                        // GYRO_FS_SEL 0..3
    EXPECT_EQ(IcmRangeDps(icm.icm_fs_code), range);  // 2000 / 2^code
    EXPECT_EQ(mpu.lsb_per_dps, lsb[i]);
    EXPECT_EQ(icm.lsb_per_dps, lsb[i]);
    ++i;
  }
}

}  // namespace
}  // namespace shutterlab
