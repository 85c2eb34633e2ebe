// The gyro driver on the register-level emulators, in virtual time: the configuration registers it
// writes for a rate and range (and at what SPI clock), WHO_AM_I refusals naming what answered, FIFO
// reads decoded to exactly the counts the emulator played, a full FIFO reported and flushed, and a
// brown-out seen as bad data and an unhealthy part until it is configured again.

#include "record/gyro_driver.h"

#include "record/sensor_emulator.h"
#include "sim/check.h"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kDriverStartNs = 3000000000;  // the virtual clock's start

// An 8 kHz trace whose counts change every sample, so that a sample lost, doubled or out of
// order shows.
GyroTrace DriverTestTrace() {
  std::vector<GyroSample> samples;
  for (int64_t j = 0; j < 16000; ++j) {
    const double t = j / 8000.0;
    samples.push_back(
        {j * 125000, Eigen::Vector3d(0.8 * std::sin(7.0 * t) + 1e-3 * (j % 50),
                                     -0.5 * std::cos(3.0 * t), 0.3 + 2e-3 * (j % 17))});
  }
  return GyroTrace(std::move(samples));
}

// Passes every transfer on to the emulator and keeps the register writes and the fastest clock.
class DriverSpyBus : public SpiTransport {
 public:
  explicit DriverSpyBus(SensorEmulator* part) : part_(part) {}
  void Transfer(const uint8_t* tx, uint8_t* rx, size_t n, uint32_t speed_hz) override {
    if ((tx[0] & 0x80) == 0 && n == 2) {
      writes.push_back({tx[0], tx[1]});
      max_write_hz = std::max(max_write_hz, speed_hz);
    }
    part_->Transfer(tx, rx, n, speed_hz);
  }
  std::string Name() const override { return part_->Name(); }
  // The last value written to address, or -1.
  int LastWrite(uint8_t address) const {
    int value = -1;
    for (const auto& [a, v] : writes) value = a == address ? v : value;
    return value;
  }
  std::vector<std::pair<uint8_t, uint8_t>> writes;
  uint32_t max_write_hz = 0;

 private:
  SensorEmulator* part_;
};

struct DriverRig {
  explicit DriverRig(GyroPart part, std::optional<uint8_t> who_am_i = std::nullopt,
                     std::vector<std::pair<int64_t, int64_t>> brownouts = {})
      : clock(kDriverStartNs),
        emulator(DriverTestTrace(), &clock,
                 [&] {
                   EmulatorOptions options;
                   options.part = part;
                   options.who_am_i = who_am_i;
                   options.brownouts = std::move(brownouts);
                   options.keep_truth = true;
                   return options;
                 }()),
        bus(&emulator) {}
  VirtualClock clock;
  SensorEmulator emulator;
  DriverSpyBus bus;
};

SensorConfig DriverConfig(double rate_hz, int range_dps) {
  SensorConfig config;
  config.rate_hz = rate_hz;
  config.range_dps = range_dps;
  return config;
}

// Reads the FIFO every read_every_ns until end_ns and checks that the samples are the emulator's,
// in order, from FIFO sample `first` on; returns how many were read.
size_t ReadAndCompareWithTruth(DriverRig& rig, GyroDriver& driver, size_t first,
                               int64_t read_every_ns, int64_t end_ns) {
  FifoRead read;
  size_t next = first;
  while (rig.clock.NowNs() + read_every_ns <= end_ns) {
    rig.clock.SleepUntilNs(rig.clock.NowNs() + read_every_ns);
    driver.ReadFifo(rig.clock, &read);
    EXPECT_FALSE(read.overflow);
    EXPECT_FALSE(read.bad_data);
    for (const auto& counts : read.samples) {
      if (next >= rig.emulator.fifo_samples()) {
        ADD_FAILURE() << "read more samples than the part produced";
        return next - first;
      }
      EXPECT_EQ(counts, rig.emulator.FifoSampleCounts(next)) << "FIFO sample " << next;
      ++next;
    }
  }
  return next - first;
}

TEST(GyroDriver, ConfiguresTheMpuRegistersForTheRateAndRange) {
  DriverRig rig(GyroPart::kMpu9250);
  GyroDriver driver(&rig.bus, GyroPart::kMpu9250);
  const PartSetting setting = driver.Configure(DriverConfig(200, 500), rig.clock);
  EXPECT_EQ(setting.odr_hz, 200.0);
  ASSERT_FALSE(rig.bus.writes.empty());
  EXPECT_EQ(rig.bus.writes.front(), std::make_pair(mpu::kPwrMgmt1, mpu::kPwrMgmt1Reset));
  // 200 Hz = 1 kHz / (1 + 4) with DLPF_CFG 2 (92 Hz, below half the rate); +-500 deg/s is
  // GYRO_FS_SEL 1; the FIFO takes gyro x, y, z and stops when full.
  EXPECT_EQ(rig.bus.LastWrite(mpu::kSmplrtDiv), 4);
  EXPECT_EQ(rig.bus.LastWrite(mpu::kConfig), mpu::kConfigFifoModeStop | 2);
  EXPECT_EQ(rig.bus.LastWrite(mpu::kGyroConfig), 1 << 3);
  EXPECT_EQ(rig.bus.LastWrite(mpu::kFifoEn), mpu::kFifoGyroXyz);
  EXPECT_EQ(rig.bus.LastWrite(mpu::kIntEnable), mpu::kFifoOverflowBit);
  EXPECT_EQ(rig.bus.LastWrite(mpu::kPwrMgmt2), 0);  // every gyro axis on
  // The part keeps them: read back through the bus.
  EXPECT_EQ(ReadRegister(rig.emulator, mpu::kSmplrtDiv, 1000000), 4);
  EXPECT_EQ(ReadRegister(rig.emulator, mpu::kUserCtrl, 1000000),
            mpu::kUserCtrlFifoEn | mpu::kUserCtrlI2cIfDis);
  EXPECT_LE(rig.bus.max_write_hz, 1000000u);  // MPU registers are written at 1 MHz at most
  EXPECT_TRUE(driver.Healthy());
  // The reset is waited for on the clock: the configuration comes after the part's reset time.
  EXPECT_GE(rig.clock.NowNs(), kDriverStartNs + driver.ResetWaitNs());
}

TEST(GyroDriver, ConfiguresTheIcmRegistersForTheRateAndRange) {
  DriverRig rig(GyroPart::kIcm42688p);
  GyroDriver driver(&rig.bus, GyroPart::kIcm42688p);
  const PartSetting setting = driver.Configure(DriverConfig(8000, 1000), rig.clock);
  EXPECT_EQ(setting.odr_hz, 8000.0);
  // GYRO_CONFIG0: GYRO_FS_SEL 1 (2000 / 2 = 1000 deg/s) in bits 7:5, GYRO_ODR 3 (8 kHz).
  EXPECT_EQ(ReadRegister(rig.emulator, icm::kGyroConfig0, 1000000), 1 << 5 | 3);
  EXPECT_EQ(ReadRegister(rig.emulator, icm::kFifoConfig1, 1000000), icm::kFifoGyroTemp);
  EXPECT_EQ(ReadRegister(rig.emulator, icm::kFifoConfig, 1000000), icm::kFifoModeStopOnFull);
  EXPECT_EQ(ReadRegister(rig.emulator, icm::kPwrMgmt0, 1000000), icm::kGyroModeLowNoise);
  EXPECT_EQ(rig.bus.LastWrite(icm::kIntfConfig0), icm::kIntfConfig0Default);  // big-endian
  EXPECT_EQ(rig.bus.writes[0], std::make_pair(icm::kBankSel, uint8_t{0}));
  EXPECT_EQ(rig.bus.writes[1], std::make_pair(icm::kDeviceConfig, uint8_t{0x01}));  // soft reset
  EXPECT_TRUE(driver.Healthy());
}

TEST(GyroDriver, AWrongWhoAmIIsRefusedNamingWhatAnswered) {
  struct Case {
    GyroPart on_bus;
    std::optional<uint8_t> who_am_i;
    GyroPart configured;
    std::string expected;
  };
  for (const Case& c :
       {Case{GyroPart::kIcm42688p, std::nullopt, GyroPart::kMpu9250,
             "WHO_AM_I is 0x47, expected 0x71 (MPU-9250): that is an ICM-42688-P (part=icm42688p)"},
        Case{GyroPart::kMpu9250, std::nullopt, GyroPart::kMpu6500,
             "WHO_AM_I is 0x71, expected 0x70 (MPU-6500): that is an MPU-9250"},
        Case{GyroPart::kMpu9250, uint8_t{0x00}, GyroPart::kMpu9250, "0x00, expected 0x71"},
        Case{GyroPart::kMpu9250, uint8_t{0x12}, GyroPart::kMpu9250, "not a part the recorder"}}) {
    DriverRig rig(c.on_bus, c.who_am_i);
    GyroDriver driver(&rig.bus, c.configured);
    try {
      driver.Configure(DriverConfig(1000, 250), rig.clock);
      ADD_FAILURE() << "accepted " << c.expected;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
      if (c.who_am_i == 0x00) {
        EXPECT_NE(std::string(e.what()).find("no part answers"), std::string::npos) << e.what();
      }
    }
  }
}

TEST(GyroDriver, MpuFifoReadsDecodeToTheCountsThePartPlayed) {
  DriverRig rig(GyroPart::kMpu9250);
  GyroDriver driver(&rig.bus, GyroPart::kMpu9250);
  driver.Configure(DriverConfig(8000, 250), rig.clock);
  const size_t first = rig.emulator.fifo_samples();  // what the configuration flushed
  const int64_t end_ns = rig.clock.NowNs() + 200000000;
  const size_t read = ReadAndCompareWithTruth(rig, driver, first, 2000000, end_ns);
  // 200 ms at 8 kHz, less what is still in the FIFO at the end (under a read interval's worth).
  EXPECT_NEAR(static_cast<double>(read), 1600.0, 16.0);
  EXPECT_EQ(rig.emulator.samples_dropped(), 0u);
}

TEST(GyroDriver, IcmFifoReadsDecodeToTheCountsThePartPlayedAt32Kilohertz) {
  DriverRig rig(GyroPart::kIcm42688p);
  GyroDriver driver(&rig.bus, GyroPart::kIcm42688p);
  driver.Configure(DriverConfig(32000, 2000), rig.clock);
  // The gyro starts 30 ms after the power-up write: read from then on.
  rig.clock.SleepUntilNs(rig.clock.NowNs() + 30000000);
  const size_t first = rig.emulator.fifo_samples();
  const size_t read =
      ReadAndCompareWithTruth(rig, driver, first, 1000000, rig.clock.NowNs() + 100000000);
  EXPECT_NEAR(static_cast<double>(read), 3200.0, 32.0);  // 100 ms at 32 kHz, less a read's worth
  EXPECT_EQ(rig.emulator.samples_dropped(), 0u);
}

TEST(GyroDriver, AFullFifoIsReportedAsOverflowAndFlushed) {
  DriverRig rig(GyroPart::kMpu9250);
  GyroDriver driver(&rig.bus, GyroPart::kMpu9250);
  driver.Configure(DriverConfig(8000, 250), rig.clock);
  const size_t first = rig.emulator.fifo_samples();
  rig.clock.SleepUntilNs(rig.clock.NowNs() + 20000000);  // 160 samples: the FIFO holds 85
  FifoRead read;
  driver.ReadFifo(rig.clock, &read);
  EXPECT_TRUE(read.overflow);
  EXPECT_FALSE(read.bad_data);
  ASSERT_EQ(read.samples.size(), 85u);
  for (size_t i = 0; i < 85; ++i) {
    EXPECT_EQ(read.samples[i], rig.emulator.FifoSampleCounts(first + i)) << "sample " << i;
  }
  EXPECT_GT(rig.emulator.samples_dropped(), 0u);
  driver.ReadFifo(rig.clock, &read);  // at once: the flushed FIFO is empty and the flag cleared
  EXPECT_FALSE(read.overflow);
  EXPECT_TRUE(read.samples.empty());
}

TEST(GyroDriver, AFifoFilledToTheBrimCountsAsOverflowBeforeTheInterrupt) {
  DriverRig rig(GyroPart::kMpu9250);
  GyroDriver driver(&rig.bus, GyroPart::kMpu9250);
  driver.Configure(DriverConfig(8000, 250), rig.clock);
  const size_t first = rig.emulator.fifo_samples();
  // Step until the FIFO holds exactly 85 samples (510 of 512 bytes): nothing lost yet, but the
  // next sample would be, so the read cannot vouch for what follows.
  while (rig.emulator.fifo_samples() < first + 85) {
    rig.clock.SleepUntilNs(rig.clock.NowNs() + 10000);
    ReadRegister(rig.emulator, mpu::kWhoAmI, 1000000);  // the part produces on bus activity
  }
  ASSERT_EQ(rig.emulator.fifo_samples(), first + 85);
  EXPECT_EQ(rig.emulator.samples_dropped(), 0u);
  FifoRead read;
  driver.ReadFifo(rig.clock, &read);
  EXPECT_TRUE(read.overflow);
  EXPECT_EQ(read.samples.size(), 85u);
}

TEST(GyroDriver, ABrownOutIsBadDataAndAnUnhealthyPartUntilConfiguredAgain) {
  const int64_t brownout_ns = kDriverStartNs + 500000000;
  DriverRig rig(GyroPart::kMpu9250, std::nullopt, {{brownout_ns, 20000000}});
  GyroDriver driver(&rig.bus, GyroPart::kMpu9250);
  driver.Configure(DriverConfig(8000, 250), rig.clock);
  EXPECT_TRUE(driver.Healthy());
  rig.clock.SleepUntilNs(brownout_ns + 1000000);
  FifoRead read;
  driver.ReadFifo(rig.clock, &read);
  EXPECT_TRUE(read.bad_data);  // a count of 0x1FFF bytes: more than the FIFO holds
  EXPECT_TRUE(read.samples.empty());
  EXPECT_FALSE(driver.Healthy());
  rig.clock.SleepUntilNs(brownout_ns + 30000000);  // power back, at the part's reset values
  EXPECT_FALSE(driver.Healthy());
  driver.Configure(DriverConfig(8000, 250), rig.clock);
  EXPECT_TRUE(driver.Healthy());
}

}  // namespace
}  // namespace shutterlab
