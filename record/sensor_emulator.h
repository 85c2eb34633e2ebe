#pragma once
// Register-level emulators of the MPU-9250 / MPU-6500 and the ICM-42688-P behind the same SPI
// transport as the real part, so the recorder's driver, FIFO handling and timestamping run
// unchanged without hardware (`record --device emulate:TRACE`, and the tests).
//
// What is emulated: WHO_AM_I; reset (MPU PWR_MGMT_1 H_RESET, ICM DEVICE_CONFIG soft reset) to the
// datasheets' reset values; power (MPU SLEEP and PWR_MGMT_2, ICM PWR_MGMT0 GYRO_MODE) with the
// gyro's start-up time; the sample rate (MPU SMPLRT_DIV, DLPF_CFG, FCHOICE_B; ICM GYRO_ODR), the
// range (GYRO_FS_SEL), the FIFO (MPU FIFO_EN, USER_CTRL FIFO_EN / FIFO_RST, CONFIG FIFO_MODE, 512
// bytes in register order temperature then gyro x, y, z; ICM FIFO_CONFIG mode, FIFO_CONFIG1,
// SIGNAL_PATH_RESET flush, 2 KiB of packets 1 or 2 with their header byte), the FIFO count
// (MPU 13 bits; ICM bytes or records, either endianness) and the FIFO data register, the
// overflow interrupt (MPU INT_STATUS FIFO_OFLOW_INT, ICM FIFO_FULL_INT, cleared on read) and the
// gyro output registers; the gyro's low-pass filter (GyroFilter at the registers' setting), as a
// first-order filter at its bandwidth run at its internal rate, after a pure delay that makes the
// whole delay of a slow motion the table's; the accelerometer (range MPU ACCEL_FS_SEL, ICM
// ACCEL_FS_SEL; output registers and FIFO) as a sensor that only turns feels it: gravity's
// reaction, +1 g up, turned into the sensor's axes by the played rates integrated from the play
// origin (EmulatorOptions::up_in_sensor there). Not emulated: the accelerometer's own filter and
// any linear acceleration, the temperature (zeros), the I2C master, self-test, other banks.
//
// Time: the part has its own oscillator, `ppm` off the nominal rate (positive: fast), so sample k
// is produced at clock time first + round(k * period / (1 + ppm 1e-6)). Samples are produced
// lazily, on each SPI transfer, up to the clock's now.
//
// Playback: the trace's first sample is played by the first sample that enters the FIFO (the
// play origin); the motion felt at a later clock time t is the trace at trace start +
// (t - origin), on the line between its two samples there (held before the first and after the
// last), and the filter runs on it. The trace repeats when the recording outlasts it. Rates are
// quantised to the range's counts and
// saturate at the int16 register, as the part does.

#include "record/clock.h"
#include "record/gyro_part.h"
#include "record/spi_transport.h"
#include "sim/gyro_trace.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

struct EmulatorOptions {
  GyroPart part = GyroPart::kMpu9250;
  double ppm = 0.0;  // the part's clock error, parts per million (positive: runs fast)
  // Answer WHO_AM_I with this instead of the part's value (another part, a dead bus).
  std::optional<uint8_t> who_am_i;
  // Brown-outs, for tests: from each start (clock ns) for its length the bus answers 0xFF to
  // everything (a loose wire, a dead part), and the part comes back from its reset values.
  std::vector<std::pair<int64_t, int64_t>> brownouts;
  // Noise on the data line back from the part (a long wire, interference), for tests: from each
  // start (clock ns) for its length every byte a read returns is random (seeded), while what is
  // sent still reaches the part and the part runs on. A FIFO count read then is mostly one the FIFO
  // cannot hold (bad data); one that could be is read as data, which an MPU's packets, having no
  // header, cannot show.
  std::vector<std::pair<int64_t, int64_t>> garbled_reads;
  // Emulated parts that share this play origin play their traces on one time line: the first
  // to start its FIFO sets it (two sensors on one camera feel the same motion at the same time,
  // however far apart they were configured). Null: the part's own.
  std::shared_ptr<std::atomic<int64_t>> shared_origin;
  // Keep every FIFO sample's time and counts (FifoSampleTimeNs): the truth tests compare with.
  bool keep_truth = false;
  // False: the trace's rates reach the output unfiltered and undelayed (tests of the playback).
  bool filter = true;
  // Up (against gravity) in the sensor's axes at the play origin: the accelerometer reads +1 g
  // along it while the part is still. Normalised; (0, 0, 1): lying level, z up.
  Eigen::Vector3d up_in_sensor = Eigen::Vector3d::UnitZ();
  // Throws std::invalid_argument naming the first bad field (|ppm| < 10000).
  void Check() const;
};

class SensorEmulator : public SpiTransport {
 public:
  // trace: rad/s about the sensor's axes; clock: the recorder's (not owned, outlives this).
  SensorEmulator(GyroTrace trace, const Clock* clock, EmulatorOptions options);

  void Transfer(const uint8_t* tx, uint8_t* rx, size_t n, uint32_t speed_hz) override;
  std::string Name() const override;

  // Truth for tests and for an emulated trigger line. The clock time of the play origin (the first
  // sample into the FIFO), once there is one; safe to call from any thread.
  std::optional<int64_t> PlayOriginNs() const;
  // With keep_truth: the clock time at which FIFO sample i (0 = the play origin) was produced, and
  // its counts; i < fifo_samples().
  int64_t FifoSampleTimeNs(size_t i) const { return fifo_times_ns_.at(i); }
  const std::array<int16_t, 3>& FifoSampleCounts(size_t i) const { return fifo_counts_.at(i); }
  size_t fifo_samples() const { return fifo_times_ns_.size(); }
  size_t samples_dropped() const { return samples_dropped_; }  // lost to a full FIFO
  // The filter's delay at the current setting (0 without the filter): a sample produced at t shows
  // the motion of about t minus this (a recorder that takes it off stamps the motion's time).
  int64_t FilterDelayNs() const;

 private:
  void Reset();
  void Advance(int64_t now_ns);  // produces every sample up to now
  void Produce(int64_t t_ns);    // one sample
  // The trace's rate felt at clock time t; cursor: where the last call for this use ended (the
  // filter's and the attitude's times differ by a delay, so each keeps its own).
  Eigen::Vector3d PlayedRate(int64_t t_ns, size_t* cursor) const;
  void TurnAttitude(int64_t t_ns);                      // integrates the rates up to t
  std::array<int16_t, 3> AccelCounts() const;           // what the accelerometer reads now
  std::array<int16_t, 3> FilteredCounts(int64_t t_ns);  // the filter's output at t, in counts
  void Retime(int64_t now_ns);                          // the rate or power changed
  void ConfigureFilter();  // the filter's gain, steps and pure delay at the registers' setting
  bool GyroOn() const;
  bool FifoCollects() const;
  double RateHz() const;
  GyroFilter CurrentFilter() const;
  double LsbPerDps() const;
  int PacketBytes() const;
  void PushPacket(const std::array<int16_t, 3>& counts);
  uint8_t ReadByte(uint8_t address);
  void WriteByte(uint8_t address, uint8_t value);
  uint8_t FifoCountByte(bool high) const;

  GyroTrace trace_;
  const Clock* clock_;
  EmulatorOptions options_;
  const PartInfo& info_;
  std::array<uint8_t, 128> regs_{};
  std::deque<uint8_t> fifo_;
  uint8_t int_status_ = 0;
  std::array<int16_t, 3> output_{};        // the gyro output registers
  std::array<int16_t, 3> accel_output_{};  // the accelerometer output registers
  // Sample timing: samples are produced at anchor_ns_ + round((k - anchor_k_) * period_ns_).
  bool running_ = false;
  int64_t anchor_ns_ = 0, anchor_k_ = 0, next_k_ = 0;
  double period_ns_ = 0.0;
  size_t trace_cursor_ = 0;
  // The attitude: the sensor's axes in a level frame (z up), from the play origin on; the time it
  // holds, and its own trace cursor.
  Eigen::Matrix3d attitude_ = Eigen::Matrix3d::Identity();
  int64_t attitude_t_ns_ = INT64_MIN;
  size_t attitude_cursor_ = 0;
  // The filter: its state (rad/s), whether it holds one yet, its gain per internal step, the
  // internal steps per output sample and the pure delay before it.
  Eigen::Vector3d filter_state_ = Eigen::Vector3d::Zero();
  bool filter_primed_ = false;
  double filter_gain_ = 1.0;
  int filter_steps_ = 1;
  int64_t filter_pure_delay_ns_ = 0;
  std::shared_ptr<std::atomic<int64_t>> play_origin_ns_;  // INT64_MIN until the FIFO starts
  std::vector<int64_t> fifo_times_ns_;
  std::vector<std::array<int16_t, 3>> fifo_counts_;
  size_t samples_dropped_ = 0;
  bool browned_out_ = false;
  std::mt19937 noise_{1};  // the bytes of a garbled read (EmulatorOptions::garbled_reads)
};

}  // namespace shutterlab
