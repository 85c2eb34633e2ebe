#include "record/sensor_emulator.h"

#include "sim/check.h"
#include "sim/logs/raw_csv.h"
#include "sim/units.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace shutterlab {

void EmulatorOptions::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(ppm) && std::abs(ppm) < 10000.0)
      << "ppm must be within +-10000, got " << ppm;
  SHUTTERLAB_CHECK(up_in_sensor.allFinite() && up_in_sensor.norm() > 0)
      << "up_in_sensor must be a direction";
}

SensorEmulator::SensorEmulator(GyroTrace trace, const Clock* clock, EmulatorOptions options)
    : trace_(std::move(trace)), clock_(clock), options_(options), info_(GetPartInfo(options.part)) {
  options_.Check();
  play_origin_ns_ = options_.shared_origin ? options_.shared_origin
                                           : std::make_shared<std::atomic<int64_t>>(INT64_MIN);
  SHUTTERLAB_CHECK(!trace_.empty()) << "the emulator needs a trace with samples";
  SHUTTERLAB_CHECK(clock_ != nullptr) << "the emulator needs a clock";
  // The level frame's z is up: the sensor's axes in it turn up_in_sensor onto z.
  attitude_ = Eigen::Quaterniond::FromTwoVectors(options_.up_in_sensor.normalized(),
                                                 Eigen::Vector3d::UnitZ())
                  .toRotationMatrix();
  Reset();
}

std::string SensorEmulator::Name() const { return std::string("emulated ") + info_.name; }

std::optional<int64_t> SensorEmulator::PlayOriginNs() const {
  const int64_t origin = play_origin_ns_->load();
  if (origin == INT64_MIN) return std::nullopt;
  return origin;
}

bool SensorEmulator::GyroOn() const {
  if (info_.part == GyroPart::kIcm42688p) return (regs_[icm::kPwrMgmt0] & 0x0C) == 0x0C;
  return (regs_[mpu::kPwrMgmt1] & mpu::kPwrMgmt1Sleep) == 0 && (regs_[mpu::kPwrMgmt2] & 7) != 7;
}

bool SensorEmulator::FifoCollects() const {
  if (info_.part == GyroPart::kIcm42688p) {
    return (regs_[icm::kFifoConfig] & 0xC0) != 0 && (regs_[icm::kFifoConfig1] & 0x03) != 0;
  }
  return (regs_[mpu::kUserCtrl] & mpu::kUserCtrlFifoEn) != 0 && (regs_[mpu::kFifoEn] & 0xF8) != 0;
}

double SensorEmulator::RateHz() const {
  if (info_.part == GyroPart::kIcm42688p) return IcmRateHz(regs_[icm::kGyroConfig0] & 0x0F);
  return MpuRateHz(regs_[mpu::kSmplrtDiv], regs_[mpu::kConfig] & 7, regs_[mpu::kGyroConfig] & 3);
}

double SensorEmulator::LsbPerDps() const {
  if (info_.part == GyroPart::kIcm42688p) {
    return RawSensitivityLsbPerDps(static_cast<int>(IcmRangeDps(regs_[icm::kGyroConfig0] >> 5)));
  }
  return RawSensitivityLsbPerDps(250 << ((regs_[mpu::kGyroConfig] >> 3) & 3));
}

int SensorEmulator::PacketBytes() const {
  if (info_.part == GyroPart::kIcm42688p) {
    const bool accel = regs_[icm::kFifoConfig1] & 0x01, gyro = regs_[icm::kFifoConfig1] & 0x02;
    return accel && gyro ? 16 : 8;  // packet 2, or packet 1 (accel or gyro, with temperature)
  }
  const uint8_t en = regs_[mpu::kFifoEn];
  return ((en & 0x80) ? 2 : 0) + ((en & 0x40) ? 2 : 0) + ((en & 0x20) ? 2 : 0) +
         ((en & 0x10) ? 2 : 0) + ((en & 0x08) ? 6 : 0);
}

void SensorEmulator::Reset() {
  running_ = false;
  regs_.fill(0);
  fifo_.clear();
  int_status_ = 0;
  if (info_.part == GyroPart::kIcm42688p) {
    regs_[icm::kGyroConfig0] = 0x06;  // +-2000 deg/s, 1 kHz
    regs_[icm::kIntfConfig0] = icm::kIntfConfig0Default;
  } else {
    regs_[mpu::kPwrMgmt1] = 0x01;  // awake, auto clock (register map: reset value 0x01)
  }
  Retime(clock_->NowNs());
}

// The rate or the power changed: the sample train restarts from now (after the start-up time
// when the gyro was just switched on).
void SensorEmulator::Retime(int64_t now_ns) {
  const bool was_running = running_;
  running_ = GyroOn() && RateHz() > 0;
  if (!running_) return;
  period_ns_ = 1e9 / RateHz() / (1.0 + options_.ppm * 1e-6);
  anchor_k_ = next_k_;
  anchor_ns_ = was_running ? now_ns : now_ns + info_.gyro_startup_ns;
  if (!was_running) filter_primed_ = false;
  ConfigureFilter();
}

void SensorEmulator::ConfigureFilter() {
  // A first-order filter y += a (x - y) stepped at the internal rate, a chosen so that its gain
  // at the bandwidth is exactly 1/sqrt(2) (with b = 1 - a and w the bandwidth in radians a step:
  // b^2 - 2 (2 - cos w) b + 1 = 0); a slow motion comes through it b / a steps late, and the pure
  // delay before it makes up the rest of the table's delay.
  if (!options_.filter) {
    filter_steps_ = 1;
    filter_gain_ = 1.0;
    filter_pure_delay_ns_ = 0;
    return;
  }
  const GyroFilter filter = CurrentFilter();
  filter_steps_ = std::max(1, static_cast<int>(std::lround(filter.internal_rate_hz / RateHz())));
  const double step_s = 1.0 / filter.internal_rate_hz;
  const double c = 2.0 - std::cos(2 * kPi * filter.bandwidth_hz * step_s);
  filter_gain_ = 1.0 - (c - std::sqrt(c * c - 1.0));
  const double first_order_delay_s = (1.0 - filter_gain_) / filter_gain_ * step_s;
  filter_pure_delay_ns_ = std::llround(std::max(filter.delay_s - first_order_delay_s, 0.0) * 1e9);
}

GyroFilter SensorEmulator::CurrentFilter() const {
  if (info_.part == GyroPart::kIcm42688p) return IcmGyroFilter(RateHz());
  return MpuGyroFilter(regs_[mpu::kConfig] & 7, regs_[mpu::kGyroConfig] & 3);
}

Eigen::Vector3d SensorEmulator::PlayedRate(int64_t t_ns, size_t* cursor) const {
  const auto& samples = trace_.samples();
  int64_t trace_t_ns = trace_.t_begin_ns();
  const auto origin = PlayOriginNs();
  if (origin) {
    // One loop of the trace lasts its span plus one interval, so that it repeats evenly.
    const int64_t loop_ns = trace_.t_end_ns() - trace_.t_begin_ns() +
                            std::max<int64_t>(trace_.sampling().median_interval_ns, 1);
    const int64_t offset_ns = std::max<int64_t>(t_ns - *origin, 0) % loop_ns;
    trace_t_ns += offset_ns;
    if (*cursor < samples.size() && samples[*cursor].t_ns > trace_t_ns) {
      *cursor = 0;  // the trace started again
    }
    while (*cursor + 1 < samples.size() && samples[*cursor + 1].t_ns <= trace_t_ns) {
      ++*cursor;  // the last sample at or before the time
    }
  }
  if (!origin) return samples[0].omega_rad_s;
  if (*cursor + 1 >= samples.size()) return samples[*cursor].omega_rad_s;
  // Between two samples: on the line between them, so that a delay that is no whole number of
  // the trace's intervals is played as it is (the nearest sample would round it to one: 0.44 ms
  // of the 2.9 ms of DLPF_CFG 1 on a 1 kHz trace).
  const GyroSample& before = samples[*cursor];
  const GyroSample& after = samples[*cursor + 1];
  const double fraction =
      static_cast<double>(trace_t_ns - before.t_ns) / static_cast<double>(after.t_ns - before.t_ns);
  return before.omega_rad_s + fraction * (after.omega_rad_s - before.omega_rad_s);
}

// The filter runs at its internal rate: the steps since the last output sample, each on the rate
// felt a pure delay earlier.
std::array<int16_t, 3> SensorEmulator::FilteredCounts(int64_t t_ns) {
  for (int step = filter_steps_ - 1; step >= 0; --step) {
    const int64_t step_ns =
        t_ns - static_cast<int64_t>(std::llround(step * period_ns_ / filter_steps_));
    const Eigen::Vector3d felt = PlayedRate(step_ns - filter_pure_delay_ns_, &trace_cursor_);
    if (!filter_primed_) {
      filter_state_ = felt;  // a part that starts up settles on the motion of its first sample
      filter_primed_ = true;
    } else {
      filter_state_ += filter_gain_ * (felt - filter_state_);
    }
  }
  std::array<int16_t, 3> counts;
  const double lsb = LsbPerDps();
  bool saturated = false;
  for (int axis = 0; axis < 3; ++axis) {
    counts[axis] = RateToCount(filter_state_[axis], lsb, &saturated);
  }
  return counts;
}

void SensorEmulator::TurnAttitude(int64_t t_ns) {
  const auto origin = PlayOriginNs();
  if (!origin || t_ns < *origin) return;  // level, as up_in_sensor says, until the play starts
  if (attitude_t_ns_ == INT64_MIN) attitude_t_ns_ = *origin;
  if (t_ns <= attitude_t_ns_) return;
  // The rate at the middle of the step, turned about the sensor's own axes (right-multiplied).
  const double step_s = (t_ns - attitude_t_ns_) * 1e-9;
  const Eigen::Vector3d omega =
      PlayedRate(attitude_t_ns_ + (t_ns - attitude_t_ns_) / 2, &attitude_cursor_);
  const double angle = omega.norm() * step_s;
  if (angle > 0) attitude_ = attitude_ * Eigen::AngleAxisd(angle, omega.normalized());
  attitude_t_ns_ = t_ns;
}

std::array<int16_t, 3> SensorEmulator::AccelCounts() const {
  const bool icm_part = info_.part == GyroPart::kIcm42688p;
  const uint8_t fs_code = icm_part ? regs_[icm::kAccelConfig0] >> 5 : regs_[mpu::kAccelConfig] >> 3;
  const double lsb_per_g = AccelLsbPerG(info_.part, fs_code);
  // +1 g along up, in the sensor's axes.
  const Eigen::Vector3d felt_g = attitude_.transpose() * Eigen::Vector3d::UnitZ();
  std::array<int16_t, 3> counts;
  for (int axis = 0; axis < 3; ++axis) {
    counts[axis] = static_cast<int16_t>(
        std::clamp(std::lround(felt_g[axis] * lsb_per_g), long{INT16_MIN}, long{INT16_MAX}));
  }
  return counts;
}

int64_t SensorEmulator::FilterDelayNs() const {
  if (!options_.filter) return 0;
  return static_cast<int64_t>(std::llround(CurrentFilter().delay_s * 1e9));
}

void SensorEmulator::PushPacket(const std::array<int16_t, 3>& counts) {
  std::array<uint8_t, 16> packet{};
  int n = 0;
  auto put16 = [&](int16_t v, bool big_endian) {
    const uint16_t u = static_cast<uint16_t>(v);
    packet[n++] = static_cast<uint8_t>(big_endian ? u >> 8 : u & 0xFF);
    packet[n++] = static_cast<uint8_t>(big_endian ? u & 0xFF : u >> 8);
  };
  if (info_.part == GyroPart::kIcm42688p) {
    const bool big = regs_[icm::kIntfConfig0] & 0x10;
    const bool accel = regs_[icm::kFifoConfig1] & 0x01, gyro = regs_[icm::kFifoConfig1] & 0x02;
    packet[n++] =
        static_cast<uint8_t>((accel ? icm::kHeaderAccel : 0) | (gyro ? icm::kHeaderGyro : 0));
    if (accel)
      for (int i = 0; i < 3; ++i) put16(accel_output_[i], big);
    if (gyro)
      for (int i = 0; i < 3; ++i) put16(counts[i], big);
    packet[n++] = 0;            // temperature
    if (accel && gyro) n += 2;  // timestamp
  } else {
    const uint8_t en = regs_[mpu::kFifoEn];  // register order: accel, temperature, gyro x, y, z
    if (en & 0x08)
      for (int i = 0; i < 3; ++i) put16(accel_output_[i], true);
    if (en & 0x80) put16(0, true);
    for (int axis = 0; axis < 3; ++axis) {
      if (en & (0x40 >> axis)) put16(counts[axis], true);
    }
  }
  const size_t capacity = static_cast<size_t>(info_.fifo_bytes);
  const bool drop_new = info_.part == GyroPart::kIcm42688p
                            ? (regs_[icm::kFifoConfig] & 0x80) != 0
                            : (regs_[mpu::kConfig] & mpu::kConfigFifoModeStop) != 0;
  if (fifo_.size() + n > capacity) {
    int_status_ |= info_.part == GyroPart::kIcm42688p ? icm::kFifoFullBit : mpu::kFifoOverflowBit;
    ++samples_dropped_;
    if (drop_new) return;
    while (fifo_.size() + n > capacity) fifo_.pop_front();  // the oldest bytes make room
  }
  fifo_.insert(fifo_.end(), packet.begin(), packet.begin() + n);
}

void SensorEmulator::Produce(int64_t t_ns) {
  const bool collect = FifoCollects();
  if (collect && !PlayOriginNs()) {
    int64_t unset = INT64_MIN;  // another part on the same time line may have set it meanwhile
    play_origin_ns_->compare_exchange_strong(unset, t_ns);
  }
  output_ = FilteredCounts(t_ns);
  TurnAttitude(t_ns);
  accel_output_ = AccelCounts();
  if (!collect) return;
  if (options_.keep_truth) {
    fifo_times_ns_.push_back(t_ns);
    fifo_counts_.push_back(output_);
  }
  PushPacket(output_);
}

void SensorEmulator::Advance(int64_t now_ns) {
  if (!running_) return;
  while (true) {
    const int64_t t_ns =
        anchor_ns_ + static_cast<int64_t>(std::llround((next_k_ - anchor_k_) * period_ns_));
    if (t_ns > now_ns) return;
    Produce(t_ns);
    ++next_k_;
  }
}

uint8_t SensorEmulator::FifoCountByte(bool high) const {
  if (info_.part == GyroPart::kIcm42688p) {
    const uint8_t intf = regs_[icm::kIntfConfig0];
    const size_t count = (intf & 0x40) ? fifo_.size() / PacketBytes() : fifo_.size();
    const bool big = intf & 0x20;
    return static_cast<uint8_t>((high == big) ? (count >> 8) & 0xFF : count & 0xFF);
  }
  return static_cast<uint8_t>(high ? (fifo_.size() >> 8) & 0x1F : fifo_.size() & 0xFF);
}

namespace {

// Byte `offset` (0..5) of output registers x, y, z, each 16 bits high byte first.
uint8_t OutputByte(const std::array<int16_t, 3>& output, int offset) {
  const uint16_t u = static_cast<uint16_t>(output[offset / 2]);
  return static_cast<uint8_t>(offset % 2 == 0 ? u >> 8 : u & 0xFF);
}

}  // namespace

uint8_t SensorEmulator::ReadByte(uint8_t address) {
  const bool icm_part = info_.part == GyroPart::kIcm42688p;
  if (address == info_.who_am_i_reg) return options_.who_am_i.value_or(info_.who_am_i);
  const uint8_t status_reg = icm_part ? icm::kIntStatus : mpu::kIntStatus;
  const uint8_t count_h = icm_part ? icm::kFifoCountH : mpu::kFifoCountH;
  const uint8_t data_reg = icm_part ? icm::kFifoData : mpu::kFifoRw;
  const uint8_t gyro_h = icm_part ? icm::kGyroDataX1 : mpu::kGyroXoutH;
  if (address == status_reg) {
    const uint8_t status = int_status_;
    int_status_ = 0;
    return status;
  }
  if (address == count_h) return FifoCountByte(true);
  if (address == count_h + 1) return FifoCountByte(false);
  if (address == data_reg) {
    if (fifo_.empty()) return icm_part ? icm::kHeaderEmpty : 0;
    const uint8_t byte = fifo_.front();
    fifo_.pop_front();
    return byte;
  }
  const uint8_t accel_h = icm_part ? icm::kAccelDataX1 : mpu::kAccelXoutH;
  if (address >= gyro_h && address < gyro_h + 6) return OutputByte(output_, address - gyro_h);
  if (address >= accel_h && address < accel_h + 6) {
    return OutputByte(accel_output_, address - accel_h);
  }
  return regs_[address & 0x7F];
}

void SensorEmulator::WriteByte(uint8_t address, uint8_t value) {
  const int64_t now_ns = clock_->NowNs();
  if (address == info_.who_am_i_reg) return;  // read-only
  if (info_.part == GyroPart::kIcm42688p) {
    if (address == icm::kBankSel) {
      regs_[address] = value & 7;
      return;
    }
    if ((regs_[icm::kBankSel] & 7) != 0) return;  // other banks: accepted, not emulated
    if (address == icm::kDeviceConfig && (value & 1)) return Reset();
    if (address == icm::kSignalPathReset) {
      if (value & icm::kFifoFlushBit) fifo_.clear();
      return;
    }
  } else {
    if (address == mpu::kPwrMgmt1 && (value & mpu::kPwrMgmt1Reset)) return Reset();
    if (address == mpu::kUserCtrl) {
      if (value & mpu::kUserCtrlFifoRst) fifo_.clear();
      value &= static_cast<uint8_t>(~(mpu::kUserCtrlFifoRst | 0x0B));  // self-clearing resets
    }
  }
  const bool was_on = GyroOn();
  const double was_rate = RateHz();
  regs_[address & 0x7F] = value;
  if (GyroOn() != was_on || RateHz() != was_rate) {
    if (was_on && !GyroOn()) running_ = false;
    Retime(now_ns);
  } else if (running_) {
    ConfigureFilter();  // DLPF_CFG may have changed at the same rate
  }
}

void SensorEmulator::Transfer(const uint8_t* tx, uint8_t* rx, size_t n, uint32_t speed_hz) {
  SHUTTERLAB_CHECK(n >= 1) << "an SPI transfer carries at least the address byte";
  const uint32_t max_hz = info_.spi_data_hz;
  if (speed_hz > max_hz) {
    throw IoError(Name() + ": SPI clock " + std::to_string(speed_hz) + " Hz is above the part's " +
                  std::to_string(max_hz) + " Hz");
  }
  const int64_t now_ns = clock_->NowNs();
  for (const auto& [start_ns, length_ns] : options_.brownouts) {
    if (now_ns >= start_ns && now_ns < start_ns + length_ns) {
      Advance(start_ns);  // what the part produced before it lost power
      browned_out_ = true;
      running_ = false;
      std::fill(rx, rx + n, 0xFF);
      return;
    }
  }
  if (browned_out_) {
    browned_out_ = false;
    Reset();  // power is back: reset values, the gyro starting up again
  }
  Advance(now_ns);
  rx[0] = 0;
  const bool read = tx[0] & 0x80;
  uint8_t address = tx[0] & 0x7F;
  const uint8_t data_reg = info_.part == GyroPart::kIcm42688p ? icm::kFifoData : mpu::kFifoRw;
  for (size_t i = 1; i < n; ++i) {
    if (read) {
      rx[i] = ReadByte(address);
    } else {
      rx[i] = 0;
      WriteByte(address, tx[i]);
    }
    if (address != data_reg) address = static_cast<uint8_t>((address + 1) & 0x7F);
  }
  for (const auto& [start_ns, length_ns] : options_.garbled_reads) {
    if (now_ns >= start_ns && now_ns < start_ns + length_ns) {
      std::uniform_int_distribution<int> byte(0, 255);
      for (size_t i = 1; i < n; ++i) rx[i] = static_cast<uint8_t>(byte(noise_));
    }
  }
}

}  // namespace shutterlab
