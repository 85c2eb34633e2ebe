// The register-level emulators driven over SPI as the datasheets describe, in virtual time:
// WHO_AM_I and reset values, samples at the configured rate on the part's own clock after the
// gyro's start-up, FIFO bytes in register order and big-endian, the range's counts saturating at
// int16, a full FIFO dropping new samples (stop mode) or old bytes (stream mode) and flagging it,
// the ICM's packet headers and count formats, the trace played sample-and-hold and repeated (two
// parts on one play origin alike), a brown-out, and SPI clocks above the part's refused.

#include "record/sensor_emulator.h"

#include "record/gyro_part.h"
#include "record/spi_transport.h"
#include "sim/check.h"
#include "sim/units.h"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kEmuStartNs = 1000000000;     // the virtual clock's start
constexpr uint32_t kEmuSpiHz = 1000000;         // every part takes 1 MHz
constexpr int64_t kEmuMpuStartupNs = 35000000;  // MPU-9250 gyro start-up (datasheet, table 1)
constexpr int64_t kEmuIcmStartupNs = 30000000;  // ICM-42688-P gyro start-up from sleep

// A trace of `n` samples every interval_ns whose rates are omega(j) for sample j.
GyroTrace EmuTrace(size_t n, int64_t interval_ns,
                   const std::function<Eigen::Vector3d(size_t)>& omega) {
  std::vector<GyroSample> samples;
  for (size_t j = 0; j < n; ++j)
    samples.push_back({static_cast<int64_t>(j) * interval_ns, omega(j)});
  return GyroTrace(std::move(samples));
}

GyroTrace EmuConstantTrace(const Eigen::Vector3d& omega) {
  return EmuTrace(1000, 1000000, [&](size_t) { return omega; });
}

// Counts of a rate at lsb_per_dps, computed from the datasheet's definition (not the code's).
int EmuExpectedCount(double omega_rad_s, double lsb_per_dps) {
  return static_cast<int>(std::lround(omega_rad_s * 180.0 / kPi * lsb_per_dps));
}

void EmuWrite(SensorEmulator& part, uint8_t address, uint8_t value) {
  WriteRegister(part, address, value, kEmuSpiHz);
}
uint8_t EmuRead(SensorEmulator& part, uint8_t address) {
  return ReadRegister(part, address, kEmuSpiHz);
}
size_t EmuMpuFifoCount(SensorEmulator& part) {
  uint8_t bytes[2];
  ReadRegisters(part, mpu::kFifoCountH, bytes, 2, kEmuSpiHz);
  return static_cast<size_t>((bytes[0] & 0x1F) << 8 | bytes[1]);
}
std::vector<uint8_t> EmuReadFifoBytes(SensorEmulator& part, uint8_t data_register, size_t n) {
  std::vector<uint8_t> bytes(n);
  ReadRegisters(part, data_register, bytes.data(), n, kEmuSpiHz);
  return bytes;
}
int16_t EmuBigEndian(const uint8_t* p) { return static_cast<int16_t>(p[0] << 8 | p[1]); }

// The MPU's FIFO collecting gyro x, y, z, new data dropped when full (stop) or old data
// overwritten (stream); DLPF_CFG 0 keeps the reset rate, 8 kHz, and 1 gives 1 kHz.
void EmuStartMpuFifo(SensorEmulator& part, bool stop_when_full, uint8_t dlpf_cfg = 0) {
  EmuWrite(part, mpu::kConfig,
           static_cast<uint8_t>((stop_when_full ? mpu::kConfigFifoModeStop : 0) | dlpf_cfg));
  EmuWrite(part, mpu::kFifoEn, mpu::kFifoGyroXyz);
  EmuWrite(part, mpu::kUserCtrl, mpu::kUserCtrlFifoEn);
}

EmulatorOptions EmuOptions(GyroPart part, double ppm = 0.0) {
  EmulatorOptions options;
  options.part = part;
  options.ppm = ppm;
  options.keep_truth = true;
  return options;
}

TEST(SensorEmulator, AnswersWhoAmIAndResetsToTheRegisterMapsValues) {
  VirtualClock clock(kEmuStartNs);
  const GyroTrace trace = EmuConstantTrace(Eigen::Vector3d::Zero());
  for (GyroPart p : {GyroPart::kMpu9250, GyroPart::kMpu6500, GyroPart::kIcm42688p}) {
    SensorEmulator part(trace, &clock, EmuOptions(p));
    EXPECT_EQ(EmuRead(part, 0x75), GetPartInfo(p).who_am_i) << GetPartInfo(p).name;
    EmuWrite(part, 0x75, 0x00);  // read-only
    EXPECT_EQ(EmuRead(part, 0x75), GetPartInfo(p).who_am_i) << GetPartInfo(p).name;
  }
  EmulatorOptions other = EmuOptions(GyroPart::kMpu9250);
  other.who_am_i = 0x12;
  SensorEmulator impostor(trace, &clock, other);
  EXPECT_EQ(EmuRead(impostor, mpu::kWhoAmI), 0x12);

  SensorEmulator mpu_part(trace, &clock, EmuOptions(GyroPart::kMpu9250));
  EmuWrite(mpu_part, mpu::kSmplrtDiv, 7);
  EmuWrite(mpu_part, mpu::kGyroConfig, 0x18);
  EXPECT_EQ(EmuRead(mpu_part, mpu::kSmplrtDiv), 7);
  EmuWrite(mpu_part, mpu::kPwrMgmt1, mpu::kPwrMgmt1Reset);
  EXPECT_EQ(EmuRead(mpu_part, mpu::kSmplrtDiv), 0);
  EXPECT_EQ(EmuRead(mpu_part, mpu::kGyroConfig), 0);
  EXPECT_EQ(EmuRead(mpu_part, mpu::kPwrMgmt1), 0x01);  // awake, auto clock

  SensorEmulator icm_part(trace, &clock, EmuOptions(GyroPart::kIcm42688p));
  EmuWrite(icm_part, icm::kGyroConfig0, 0x23);
  EmuWrite(icm_part, icm::kPwrMgmt0, icm::kGyroModeLowNoise);
  EmuWrite(icm_part, icm::kDeviceConfig, 0x01);           // soft reset
  EXPECT_EQ(EmuRead(icm_part, icm::kGyroConfig0), 0x06);  // +-2000 deg/s, 1 kHz
  EXPECT_EQ(EmuRead(icm_part, icm::kIntfConfig0), icm::kIntfConfig0Default);
  EXPECT_EQ(EmuRead(icm_part, icm::kPwrMgmt0), 0);  // gyro off
}

TEST(SensorEmulator, SamplesAtTheConfiguredRateOnThePartsClockAfterStartUp) {
  VirtualClock clock(kEmuStartNs);
  // +1000 ppm: the 1 kHz part's period is 1 ms / 1.001 = 999001 ns, so 40 ms after its first
  // sample it has produced 41 samples, not the 40 a true 1 kHz part would have.
  SensorEmulator part(EmuConstantTrace(Eigen::Vector3d::Zero()), &clock,
                      EmuOptions(GyroPart::kMpu9250, 1000.0));
  EmuWrite(part, mpu::kPwrMgmt1, mpu::kPwrMgmt1Sleep);
  EmuStartMpuFifo(part, /*stop_when_full=*/true, /*dlpf_cfg=*/1);  // 1 kHz
  const int64_t wake_ns = kEmuStartNs + 10000000;
  clock.SleepUntilNs(wake_ns);
  EmuWrite(part, mpu::kPwrMgmt1, 0x01);  // wake: the gyro starts up
  const int64_t first_ns = wake_ns + kEmuMpuStartupNs;
  clock.SleepUntilNs(first_ns - 1);
  EXPECT_EQ(EmuMpuFifoCount(part), 0u);
  EXPECT_FALSE(part.PlayOriginNs().has_value());
  clock.SleepUntilNs(first_ns + 40000000 - 1);
  EXPECT_EQ(EmuMpuFifoCount(part), 41u * 6);
  ASSERT_EQ(part.fifo_samples(), 41u);
  EXPECT_EQ(part.FifoSampleTimeNs(0), first_ns);
  EXPECT_EQ(part.FifoSampleTimeNs(40), first_ns + 39960040);  // round(40 ms / 1.001)
  EXPECT_EQ(part.PlayOriginNs(), first_ns);
}

TEST(SensorEmulator, FifoHoldsTheRangesCountsBigEndianInRegisterOrder) {
  VirtualClock clock(kEmuStartNs);
  const Eigen::Vector3d omega(0.5, -1.0, 1.5);  // rad/s
  SensorEmulator part(EmuConstantTrace(omega), &clock, EmuOptions(GyroPart::kMpu9250));
  EmuWrite(part, mpu::kGyroConfig, 3 << 3);  // +-2000 deg/s: 16.4 LSB per deg/s
  EmuStartMpuFifo(part, true);
  EmuWrite(part, mpu::kFifoEn, 0x80 | mpu::kFifoGyroXyz);  // temperature too: it comes first
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs + 2 * 125000);  // 3 samples at 8 kHz
  ASSERT_EQ(EmuMpuFifoCount(part), 3u * 8);
  const std::vector<uint8_t> bytes = EmuReadFifoBytes(part, mpu::kFifoRw, 24);
  for (int s = 0; s < 3; ++s) {
    const uint8_t* p = bytes.data() + 8 * s;
    EXPECT_EQ(EmuBigEndian(p), 0) << "temperature, sample " << s;
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_EQ(EmuBigEndian(p + 2 + 2 * axis), EmuExpectedCount(omega[axis], 16.4))
          << "sample " << s << " axis " << axis;
    }
  }
  EXPECT_EQ(EmuMpuFifoCount(part), 0u);  // read out
  // The output registers hold the newest sample.
  uint8_t out[6];
  ReadRegisters(part, mpu::kGyroXoutH, out, 6, kEmuSpiHz);
  EXPECT_EQ(EmuBigEndian(out + 2), EmuExpectedCount(omega[1], 16.4));
}

TEST(SensorEmulator, RatesBeyondTheRangeSaturateAtTheInt16Register) {
  VirtualClock clock(kEmuStartNs);
  const Eigen::Vector3d omega(10.0, -10.0, 4.0);  // 573 deg/s: beyond +-250 deg/s; 229: within
  SensorEmulator part(EmuConstantTrace(omega), &clock, EmuOptions(GyroPart::kMpu9250));
  EmuStartMpuFifo(part, true);
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs);
  ASSERT_EQ(EmuMpuFifoCount(part), 6u);
  const std::vector<uint8_t> bytes = EmuReadFifoBytes(part, mpu::kFifoRw, 6);
  EXPECT_EQ(EmuBigEndian(&bytes[0]), 32767);
  EXPECT_EQ(EmuBigEndian(&bytes[2]), -32768);
  EXPECT_EQ(EmuBigEndian(&bytes[4]), EmuExpectedCount(4.0, 131.0));
}

// A ramp at 8 kHz: every sample's counts differ, so the samples a full FIFO keeps show.
GyroTrace EmuRampTrace() {
  return EmuTrace(8000, 125000,
                  [](size_t j) { return Eigen::Vector3d(0.001 * j, -0.002 * j, 0.1); });
}

TEST(SensorEmulator, AFullFifoInStopModeKeepsTheOldestAndFlagsTheOverflowOnce) {
  VirtualClock clock(kEmuStartNs);
  SensorEmulator part(EmuRampTrace(), &clock, EmuOptions(GyroPart::kMpu9250));
  EmuStartMpuFifo(part, /*stop_when_full=*/true);
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs + 99 * 125000);  // 100 samples
  EXPECT_EQ(EmuMpuFifoCount(part), 85u * 6);  // 512 bytes hold 85 samples; the 86th is dropped
  EXPECT_EQ(part.fifo_samples(), 100u);
  EXPECT_EQ(part.samples_dropped(), 15u);
  EXPECT_EQ(EmuRead(part, mpu::kIntStatus), mpu::kFifoOverflowBit);
  EXPECT_EQ(EmuRead(part, mpu::kIntStatus), 0);  // cleared by reading it
  const std::vector<uint8_t> bytes = EmuReadFifoBytes(part, mpu::kFifoRw, 85 * 6);
  for (size_t s = 0; s < 85; ++s) {
    for (int axis = 0; axis < 3; ++axis) {
      ASSERT_EQ(EmuBigEndian(&bytes[6 * s + 2 * axis]), part.FifoSampleCounts(s)[axis])
          << "sample " << s;
    }
  }
}

TEST(SensorEmulator, AFullFifoInStreamModeOverwritesTheOldestBytes) {
  VirtualClock clock(kEmuStartNs);
  SensorEmulator part(EmuRampTrace(), &clock, EmuOptions(GyroPart::kMpu9250));
  EmuStartMpuFifo(part, /*stop_when_full=*/false);
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs + 99 * 125000);
  // 600 bytes into 512: the newest 512 are the last 2 bytes of sample 14 and samples 15..99.
  ASSERT_EQ(EmuMpuFifoCount(part), 512u);
  EXPECT_EQ(EmuRead(part, mpu::kIntStatus), mpu::kFifoOverflowBit);
  const std::vector<uint8_t> bytes = EmuReadFifoBytes(part, mpu::kFifoRw, 512);
  EXPECT_EQ(EmuBigEndian(&bytes[0]), part.FifoSampleCounts(14)[2]);
  for (size_t s = 15; s < 100; ++s) {
    for (int axis = 0; axis < 3; ++axis) {
      ASSERT_EQ(EmuBigEndian(&bytes[2 + 6 * (s - 15) + 2 * axis]), part.FifoSampleCounts(s)[axis])
          << "sample " << s;
    }
  }
}

TEST(SensorEmulator, FifoResetEmptiesTheFifoAndClearsItself) {
  VirtualClock clock(kEmuStartNs);
  SensorEmulator part(EmuRampTrace(), &clock, EmuOptions(GyroPart::kMpu9250));
  EmuStartMpuFifo(part, true);
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs + 9 * 125000);
  ASSERT_EQ(EmuMpuFifoCount(part), 60u);
  EmuWrite(part, mpu::kUserCtrl, mpu::kUserCtrlFifoEn | mpu::kUserCtrlFifoRst);
  EXPECT_EQ(EmuMpuFifoCount(part), 0u);
  EXPECT_EQ(EmuRead(part, mpu::kUserCtrl), mpu::kUserCtrlFifoEn);  // FIFO_RST self-clearing
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs + 10 * 125000);
  EXPECT_EQ(EmuMpuFifoCount(part), 6u);  // and the FIFO goes on collecting
}

TEST(SensorEmulator, IcmPacketsCarryAHeaderAndTheCountInBytesOrRecords) {
  VirtualClock clock(kEmuStartNs);
  const Eigen::Vector3d omega(-0.25, 0.75, 2.0);
  SensorEmulator part(EmuConstantTrace(omega), &clock, EmuOptions(GyroPart::kIcm42688p));
  EmuWrite(part, icm::kGyroConfig0, 3 << 5 | 6);  // +-250 deg/s, 1 kHz
  EmuWrite(part, icm::kFifoConfig1, icm::kFifoGyroTemp);
  EmuWrite(part, icm::kFifoConfig, icm::kFifoModeStopOnFull);
  EmuWrite(part, icm::kPwrMgmt0, icm::kGyroModeLowNoise);
  clock.SleepUntilNs(kEmuStartNs + kEmuIcmStartupNs - 1);
  EXPECT_EQ(EmuRead(part, icm::kFifoCountH + 1), 0);             // still starting up
  clock.SleepUntilNs(kEmuStartNs + kEmuIcmStartupNs + 2000000);  // 3 samples at 1 kHz
  uint8_t count[2];
  ReadRegisters(part, icm::kFifoCountH, count, 2, kEmuSpiHz);
  EXPECT_EQ(count[0] << 8 | count[1], 3 * 8);             // bytes, big-endian (reset default)
  EmuWrite(part, icm::kIntfConfig0, 0x40 | 0x20 | 0x10);  // records, big-endian
  ReadRegisters(part, icm::kFifoCountH, count, 2, kEmuSpiHz);
  EXPECT_EQ(count[0] << 8 | count[1], 3);
  EmuWrite(part, icm::kIntfConfig0, 0x40 | 0x10);  // records, count little-endian
  ReadRegisters(part, icm::kFifoCountH, count, 2, kEmuSpiHz);
  EXPECT_EQ(count[1] << 8 | count[0], 3);
  EmuWrite(part, icm::kIntfConfig0, icm::kIntfConfig0Default);
  const std::vector<uint8_t> bytes = EmuReadFifoBytes(part, icm::kFifoData, 3 * 8 + 1);
  for (int s = 0; s < 3; ++s) {
    const uint8_t* p = bytes.data() + 8 * s;
    EXPECT_EQ(p[0], icm::kHeaderGyro) << "header, sample " << s;  // gyro, no accel, not empty
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_EQ(EmuBigEndian(p + 1 + 2 * axis), EmuExpectedCount(omega[axis], 131.0));
    }
  }
  EXPECT_EQ(bytes[24], icm::kHeaderEmpty);  // read past the end: the empty header
  EmuWrite(part, icm::kSignalPathReset, icm::kFifoFlushBit);
  clock.SleepUntilNs(kEmuStartNs + kEmuIcmStartupNs + 3000000);  // one more sample
  ReadRegisters(part, icm::kFifoCountH, count, 2, kEmuSpiHz);
  EXPECT_EQ(count[0] << 8 | count[1], 8);
}

// Trace sample j of a 100 Hz, five-sample trace: x = (j + 1) * 0.02 rad/s (150 counts apart).
Eigen::Vector3d EmuStepRate(size_t j) { return Eigen::Vector3d(0.02 * (j + 1), 0.0, 0.0); }

// The x rate a 1 kHz part plays i ms after its play origin: on the line between the two trace
// samples about it, the last held until the trace repeats (every 50 ms: its 40 ms span plus an
// interval).
double EmuPlayedX(int64_t i_ms) {
  const int64_t m = i_ms % 50;
  if (m >= 40) return EmuStepRate(4)[0];
  const size_t j = static_cast<size_t>(m / 10);
  const double fraction = (m % 10) / 10.0;
  return EmuStepRate(j)[0] + fraction * (EmuStepRate(j + 1)[0] - EmuStepRate(j)[0]);
}

TEST(SensorEmulator, PlaysTheTraceFromTheFirstFifoSampleBetweenItsSamplesAndRepeatsIt) {
  VirtualClock clock(kEmuStartNs);
  EmulatorOptions options = EmuOptions(GyroPart::kMpu9250);
  options.filter = false;  // the trace's samples as they are
  SensorEmulator part(EmuTrace(5, 10000000, EmuStepRate), &clock, options);
  EmuStartMpuFifo(part, true, /*dlpf_cfg=*/1);  // 1 kHz
  clock.SleepUntilNs(kEmuStartNs + 200000000);
  EmuMpuFifoCount(part);  // the part produces its samples when the bus is next used
  ASSERT_GE(part.fifo_samples(), 120u);
  for (size_t i = 0; i < 120; ++i) {
    ASSERT_EQ(part.FifoSampleCounts(i)[0],
              EmuExpectedCount(EmuPlayedX(static_cast<int64_t>(i)), 131.0))
        << "FIFO sample " << i;
  }
}

TEST(SensorEmulator, PartsOnASharedOriginPlayOneTimeLine) {
  VirtualClock clock(kEmuStartNs);
  const GyroTrace trace = EmuTrace(5, 10000000, EmuStepRate);
  EmulatorOptions options = EmuOptions(GyroPart::kMpu9250);
  options.shared_origin = std::make_shared<std::atomic<int64_t>>(INT64_MIN);
  options.filter = false;  // the trace's samples as they are
  SensorEmulator first(trace, &clock, options), second(trace, &clock, options);
  EmuStartMpuFifo(first, true, /*dlpf_cfg=*/1);  // 1 kHz
  clock.SleepUntilNs(kEmuStartNs + 60000000);
  EmuStartMpuFifo(second, true, /*dlpf_cfg=*/1);  // about 60 ms after the first began playing
  clock.SleepUntilNs(kEmuStartNs + 100000000);
  EmuMpuFifoCount(first);
  EmuMpuFifoCount(second);
  ASSERT_TRUE(first.PlayOriginNs().has_value());
  EXPECT_EQ(second.PlayOriginNs(), first.PlayOriginNs());
  // The second part's samples play what the first's did at the same time, not the trace's start
  // (which a part on its own time line would play first).
  ASSERT_GT(second.fifo_samples(), 10u);
  const int64_t offset_ms = (second.FifoSampleTimeNs(0) - *first.PlayOriginNs()) / 1000000;
  EXPECT_GT(offset_ms % 50, 5) << offset_ms;  // not where the trace starts
  for (size_t i = 0; i < second.fifo_samples(); ++i) {
    EXPECT_EQ(second.FifoSampleCounts(i)[0],
              EmuExpectedCount(EmuPlayedX(offset_ms + static_cast<int64_t>(i)), 131.0))
        << "sample " << i;
  }
}

// An MPU-9250 playing `omega` at a filter setting (CONFIG's DLPF_CFG, GYRO_CONFIG's FCHOICE_B;
// SMPLRT_DIV 0, +-250 deg/s) for duration_ns of samples: each FIFO sample's time after the first
// and its x rate (rad/s), from the emulator's truth.
struct EmuPlayed {
  std::vector<double> t_s, x_rad_s;
  int64_t delay_ns = 0;  // the emulator's FilterDelayNs
};
EmuPlayed EmuPlayThroughMpuFilter(const GyroTrace& trace, uint8_t dlpf_cfg, uint8_t fchoice_b,
                                  int64_t duration_ns) {
  VirtualClock clock(kEmuStartNs);
  SensorEmulator part(trace, &clock, EmuOptions(GyroPart::kMpu9250));
  EmuWrite(part, mpu::kGyroConfig, fchoice_b);
  EmuStartMpuFifo(part, /*stop_when_full=*/true, dlpf_cfg);
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs + duration_ns);
  EmuMpuFifoCount(part);  // the part produces its samples when the bus is next used
  EmuPlayed played;
  played.delay_ns = part.FilterDelayNs();
  for (size_t i = 0; i < part.fifo_samples(); ++i) {
    played.t_s.push_back((part.FifoSampleTimeNs(i) - part.FifoSampleTimeNs(0)) * 1e-9);
    played.x_rad_s.push_back(part.FifoSampleCounts(i)[0] / 131.0 * kPi / 180.0);
  }
  return played;
}

// Each of the MPU's filter settings against its register map's table (typed here again, not
// read from the code): a ramp comes through the table's delay late (within 2 % or 10 us), and a
// sine at the table's bandwidth keeps 1/sqrt(2) of its amplitude (within 3 %).
TEST(SensorEmulator,
     TheFilterDelaysASlowMotionByTheDatasheetsDelayAndHalvesThePowerAtItsBandwidth) {
  struct Setting {
    uint8_t dlpf_cfg, fchoice_b;
    double bandwidth_hz, delay_ms;
  };
  constexpr double kSlope = 1.0;  // rad/s per s
  // 1.5 s at 128 kHz: the part plays the nearest sample, within 3.9 us of its time.
  const GyroTrace ramp = EmuTrace(
      192000, 7812, [&](size_t j) { return Eigen::Vector3d(kSlope * j * 7812e-9, 0.0, 0.0); });
  for (const Setting& c :
       {Setting{0, 0, 250, 0.97}, Setting{1, 0, 184, 2.9}, Setting{2, 0, 92, 3.9},
        Setting{3, 0, 41, 5.9}, Setting{4, 0, 20, 9.9}, Setting{5, 0, 10, 17.85},
        Setting{6, 0, 5, 33.48}, Setting{7, 0, 3600, 0.17}, Setting{0, 1, 8800, 0.064},
        Setting{0, 2, 3600, 0.11}}) {
    const std::string name =
        "DLPF_CFG " + std::to_string(c.dlpf_cfg) + ", FCHOICE_B " + std::to_string(c.fchoice_b);
    // The ramp: from 0.5 s on (the slowest filter settled), rate = slope (t - delay).
    const EmuPlayed slow = EmuPlayThroughMpuFilter(ramp, c.dlpf_cfg, c.fchoice_b, 1400000000);
    double delay_sum_s = 0;
    size_t n = 0;
    for (size_t i = 0; i < slow.t_s.size(); ++i) {
      if (slow.t_s[i] < 0.5) continue;
      delay_sum_s += slow.t_s[i] - slow.x_rad_s[i] / kSlope;
      ++n;
    }
    ASSERT_GT(n, 400u) << name;
    const double delay_ms = delay_sum_s / n * 1e3;
    EXPECT_NEAR(delay_ms, c.delay_ms, std::max(0.02 * c.delay_ms, 0.01)) << name;
    EXPECT_NEAR(slow.delay_ns * 1e-6, c.delay_ms, 1e-6) << name;
    // The sine at the bandwidth, 1 rad/s, played from a trace ten times finer than the filter
    // runs; its amplitude out by least squares on sin and cos over the last 0.2 s.
    const double f = c.bandwidth_hz;
    const double trace_interval_s = 1.0 / (10 * std::max(8000.0, 4 * f));
    const auto n_trace = static_cast<size_t>(0.5 / trace_interval_s);
    const GyroTrace sine = EmuTrace(n_trace, std::llround(trace_interval_s * 1e9), [&](size_t j) {
      return Eigen::Vector3d(std::sin(2 * kPi * f * j * trace_interval_s), 0.0, 0.0);
    });
    const EmuPlayed fast = EmuPlayThroughMpuFilter(sine, c.dlpf_cfg, c.fchoice_b, 450000000);
    Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
    Eigen::Vector2d projected = Eigen::Vector2d::Zero();
    for (size_t i = 0; i < fast.t_s.size(); ++i) {
      if (fast.t_s[i] < 0.25) continue;
      const Eigen::Vector2d basis(std::sin(2 * kPi * f * fast.t_s[i]),
                                  std::cos(2 * kPi * f * fast.t_s[i]));
      normal += basis * basis.transpose();
      projected += basis * fast.x_rad_s[i];
    }
    const double gain = normal.ldlt().solve(projected).norm();
    EXPECT_NEAR(gain, 1 / std::sqrt(2.0), 0.03 / std::sqrt(2.0)) << name;
  }
}

// The accelerometer of a part that only turns: +1 g up. Level and still, the MPU (+-2 g: 16384
// counts per g) reads +1 g on z in its output registers and its FIFO; after a quarter turn about
// x (pi/2 rad/s for 1 s), up is the sensor's +y. The ICM at +-16 g (2048 counts per g), mounted
// with up along its -x, reads -1 g on x.
TEST(SensorEmulator, TheAccelerometerFeelsGravityTurnedByThePlayedRates) {
  VirtualClock clock(kEmuStartNs);
  const GyroTrace quarter_turn = EmuTrace(3000, 1000000, [](size_t j) {
    return Eigen::Vector3d(j >= 500 && j < 1500 ? kPi / 2 : 0.0, 0.0, 0.0);
  });
  SensorEmulator mpu(quarter_turn, &clock, EmuOptions(GyroPart::kMpu9250));
  EmuWrite(mpu, mpu::kGyroConfig, 3 << 3);                    // +-2000 deg/s: pi/2 rad/s fits
  EmuWrite(mpu, mpu::kConfig, mpu::kConfigFifoModeStop | 1);  // 1 kHz; a full FIFO keeps its first
  EmuWrite(mpu, mpu::kFifoEn, 0x08 | mpu::kFifoGyroXyz);
  EmuWrite(mpu, mpu::kUserCtrl, mpu::kUserCtrlFifoEn);
  const auto accel_registers = [&] {
    uint8_t bytes[6];
    ReadRegisters(mpu, mpu::kAccelXoutH, bytes, 6, kEmuSpiHz);
    return Eigen::Vector3d(EmuBigEndian(bytes), EmuBigEndian(bytes + 2), EmuBigEndian(bytes + 4));
  };
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs + 100000000);  // still, 0.1 s in
  EXPECT_LT((accel_registers() - Eigen::Vector3d(0, 0, 16384)).norm(), 1.0) << accel_registers();
  // The FIFO: accel x, y, z then gyro x, y, z per sample.
  const std::vector<uint8_t> bytes = EmuReadFifoBytes(mpu, mpu::kFifoRw, 12);
  EXPECT_EQ(EmuBigEndian(&bytes[4]), 16384);
  EXPECT_EQ(EmuBigEndian(&bytes[0]), 0);
  clock.SleepUntilNs(kEmuStartNs + kEmuMpuStartupNs + 2000000000);  // the turn done
  const Eigen::Vector3d turned = accel_registers();
  EXPECT_NEAR(turned.y(), 16384, 16384 * 0.005) << turned.transpose();
  EXPECT_NEAR(turned.z(), 0, 16384 * 0.01) << turned.transpose();
  EXPECT_NEAR(turned.x(), 0, 1.0) << turned.transpose();

  EmulatorOptions options = EmuOptions(GyroPart::kIcm42688p);
  options.up_in_sensor = -Eigen::Vector3d::UnitX();
  SensorEmulator icm(EmuConstantTrace(Eigen::Vector3d::Zero()), &clock, options);
  EmuWrite(icm, icm::kFifoConfig1, icm::kFifoGyroTemp);
  EmuWrite(icm, icm::kFifoConfig, icm::kFifoModeStopOnFull);
  EmuWrite(icm, icm::kPwrMgmt0, icm::kGyroModeLowNoise);
  clock.SleepUntilNs(clock.NowNs() + kEmuIcmStartupNs + 10000000);
  uint8_t icm_bytes[6];
  ReadRegisters(icm, icm::kAccelDataX1, icm_bytes, 6, kEmuSpiHz);
  EXPECT_EQ(EmuBigEndian(icm_bytes), -2048);  // ACCEL_FS_SEL 0 (reset): +-16 g
  EXPECT_EQ(EmuBigEndian(icm_bytes + 2), 0);
  EXPECT_EQ(EmuBigEndian(icm_bytes + 4), 0);
}

TEST(SensorEmulator, ABrownOutAnswers0xFFThenComesBackAtResetValues) {
  VirtualClock clock(kEmuStartNs);
  EmulatorOptions options = EmuOptions(GyroPart::kMpu9250);
  options.brownouts = {{kEmuStartNs + 50000000, 10000000}};
  SensorEmulator part(EmuRampTrace(), &clock, options);
  EmuWrite(part, mpu::kSmplrtDiv, 4);
  EmuStartMpuFifo(part, true);
  clock.SleepUntilNs(kEmuStartNs + 45000000);
  EXPECT_GT(EmuMpuFifoCount(part), 0u);
  clock.SleepUntilNs(kEmuStartNs + 55000000);
  EXPECT_EQ(EmuRead(part, mpu::kWhoAmI), 0xFF);
  EXPECT_EQ(EmuRead(part, mpu::kSmplrtDiv), 0xFF);
  clock.SleepUntilNs(kEmuStartNs + 60000000);  // power back
  EXPECT_EQ(EmuRead(part, mpu::kWhoAmI), 0x71);
  EXPECT_EQ(EmuRead(part, mpu::kSmplrtDiv), 0);
  EXPECT_EQ(EmuRead(part, mpu::kFifoEn), 0);
  EXPECT_EQ(EmuMpuFifoCount(part), 0u);
}

TEST(SensorEmulator, RefusesAnSpiClockAboveThePartsAndAnImpossibleClockError) {
  VirtualClock clock(kEmuStartNs);
  const GyroTrace trace = EmuConstantTrace(Eigen::Vector3d::Zero());
  SensorEmulator mpu_part(trace, &clock, EmuOptions(GyroPart::kMpu9250));
  uint8_t value = 0;
  EXPECT_NO_THROW(ReadRegisters(mpu_part, mpu::kWhoAmI, &value, 1, 20000000));
  EXPECT_THROW(ReadRegisters(mpu_part, mpu::kWhoAmI, &value, 1, 20000001), IoError);
  SensorEmulator icm_part(trace, &clock, EmuOptions(GyroPart::kIcm42688p));
  EXPECT_NO_THROW(ReadRegisters(icm_part, icm::kWhoAmI, &value, 1, 24000000));
  EXPECT_THROW(ReadRegisters(icm_part, icm::kWhoAmI, &value, 1, 25000000), IoError);
  for (double ppm : {10000.0, -20000.0, std::nan("")}) {
    EXPECT_THROW((void)SensorEmulator(trace, &clock, EmuOptions(GyroPart::kMpu9250, ppm)),
                 std::invalid_argument)
        << ppm;
  }
}

}  // namespace
}  // namespace shutterlab
