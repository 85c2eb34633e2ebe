#include "record/gyro_driver.h"

#include "sim/check.h"
#include "sim/text_file.h"

namespace shutterlab {
namespace {

// What a WHO_AM_I answer suggests, for the error message.
std::string WhoAmIHint(uint8_t value) {
  if (value == 0x00 || value == 0xFF) return ": no part answers (wiring, chip select, SPI mode?)";
  for (GyroPart part : {GyroPart::kMpu9250, GyroPart::kMpu6500, GyroPart::kIcm42688p}) {
    const PartInfo& info = GetPartInfo(part);
    if (value == info.who_am_i)
      return std::string(": that is an ") + info.name + " (part=" + info.key + ")";
  }
  return ": not a part the recorder knows";
}

uint16_t BigEndian16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

}  // namespace

GyroDriver::GyroDriver(SpiTransport* bus, GyroPart part) : bus_(bus), info_(GetPartInfo(part)) {
  SHUTTERLAB_CHECK(bus_ != nullptr) << "the driver needs a bus";
}

PartSetting GyroDriver::Configure(const SensorConfig& config, Clock& clock) {
  BeginReset();
  clock.SleepUntilNs(clock.NowNs() + ResetWaitNs());
  return FinishConfigure(config, clock);
}

void GyroDriver::BeginReset() {
  const uint32_t hz = info_.spi_config_hz;
  if (Icm()) {
    WriteRegister(*bus_, icm::kBankSel, 0, hz);
    WriteRegister(*bus_, icm::kDeviceConfig, 0x01, hz);  // soft reset
  } else {
    WriteRegister(*bus_, mpu::kPwrMgmt1, mpu::kPwrMgmt1Reset, hz);
  }
}

// ICM-42688-P: 1 ms after a soft reset; MPU-9250: 100 ms, as InvenSense's drivers wait.
int64_t GyroDriver::ResetWaitNs() const { return Icm() ? 2000000 : 100000000; }

PartSetting GyroDriver::FinishConfigure(const SensorConfig& config, Clock& clock) {
  setting_ = ResolvePartSetting(info_.part, config);
  const uint32_t hz = info_.spi_config_hz;
  const uint8_t who = ReadRegister(*bus_, info_.who_am_i_reg, hz);
  if (who != info_.who_am_i) {
    throw IoError(bus_->Name() + ": WHO_AM_I is " + HexByte(who) + ", expected " +
                  HexByte(info_.who_am_i) + " (" + info_.name + ")" + WhoAmIHint(who));
  }
  if (Icm()) {
    WriteRegister(*bus_, icm::kIntfConfig0, icm::kIntfConfig0Default, hz);
    WriteRegister(*bus_, icm::kGyroConfig0,
                  static_cast<uint8_t>(setting_.icm_fs_code << 5 | setting_.icm_odr_code), hz);
    WriteRegister(*bus_, icm::kFifoConfig1, icm::kFifoGyroTemp, hz);
    WriteRegister(*bus_, icm::kFifoConfig, icm::kFifoModeStopOnFull, hz);
    WriteRegister(*bus_, icm::kPwrMgmt0, icm::kGyroModeLowNoise, hz);
    clock.SleepUntilNs(clock.NowNs() + 200000);  // no register access for 200 us after power-up
  } else {
    WriteRegister(*bus_, mpu::kUserCtrl, mpu::kUserCtrlI2cIfDis, hz);  // SPI only
    WriteRegister(*bus_, mpu::kPwrMgmt1, 0x01, hz);                    // awake, PLL clock
    WriteRegister(*bus_, mpu::kPwrMgmt2, 0x00, hz);
    WriteRegister(*bus_, mpu::kSmplrtDiv, setting_.smplrt_div, hz);
    WriteRegister(*bus_, mpu::kConfig, mpu::kConfigFifoModeStop | setting_.dlpf_cfg, hz);
    WriteRegister(*bus_, mpu::kGyroConfig,
                  static_cast<uint8_t>(setting_.fs_sel << 3 | setting_.fchoice_b), hz);
    WriteRegister(*bus_, mpu::kFifoEn, mpu::kFifoGyroXyz, hz);
    WriteRegister(*bus_, mpu::kIntEnable, mpu::kFifoOverflowBit, hz);
    WriteRegister(*bus_, mpu::kUserCtrl, mpu::kUserCtrlI2cIfDis | mpu::kUserCtrlFifoRst, hz);
    WriteRegister(*bus_, mpu::kUserCtrl, mpu::kUserCtrlI2cIfDis | mpu::kUserCtrlFifoEn, hz);
  }
  if (!Healthy()) {
    throw IoError(bus_->Name() + ": the " + info_.name +
                  " did not keep its configuration (read back differs)");
  }
  FlushFifo();
  ReadRegister(*bus_, Icm() ? icm::kIntStatus : mpu::kIntStatus, info_.spi_data_hz);  // clear
  return setting_;
}

bool GyroDriver::Healthy() {
  const uint32_t hz = info_.spi_config_hz;
  if (ReadRegister(*bus_, info_.who_am_i_reg, hz) != info_.who_am_i) return false;
  if (Icm()) {
    return ReadRegister(*bus_, icm::kGyroConfig0, hz) ==
               (setting_.icm_fs_code << 5 | setting_.icm_odr_code) &&
           (ReadRegister(*bus_, icm::kPwrMgmt0, hz) & 0x0C) == icm::kGyroModeLowNoise &&
           ReadRegister(*bus_, icm::kFifoConfig1, hz) == icm::kFifoGyroTemp;
  }
  return ReadRegister(*bus_, mpu::kGyroConfig, hz) == (setting_.fs_sel << 3 | setting_.fchoice_b) &&
         ReadRegister(*bus_, mpu::kFifoEn, hz) == mpu::kFifoGyroXyz &&
         (ReadRegister(*bus_, mpu::kUserCtrl, hz) & mpu::kUserCtrlFifoEn) != 0;
}

void GyroDriver::FlushFifo() {
  const uint32_t hz = info_.spi_config_hz;
  if (Icm()) {
    WriteRegister(*bus_, icm::kSignalPathReset, icm::kFifoFlushBit, hz);
  } else {
    WriteRegister(*bus_, mpu::kUserCtrl,
                  mpu::kUserCtrlI2cIfDis | mpu::kUserCtrlFifoEn | mpu::kUserCtrlFifoRst, hz);
  }
}

void GyroDriver::ParsePackets(size_t bytes, FifoRead* out) {
  const size_t packet = static_cast<size_t>(info_.packet_bytes);
  for (size_t at = 0; at + packet <= bytes; at += packet) {
    const uint8_t* p = fifo_bytes_.data() + at;
    if (Icm()) {
      // Packet 1: header (gyro bit set, "empty" bit clear), gyro x, y, z big-endian, temperature.
      if ((p[0] & icm::kHeaderEmpty) || !(p[0] & icm::kHeaderGyro) || (p[0] & icm::kHeaderAccel)) {
        out->bad_data = true;
        return;
      }
      ++p;
    }
    std::array<int16_t, 3> counts;
    for (int axis = 0; axis < 3; ++axis)
      counts[axis] = static_cast<int16_t>(BigEndian16(p + 2 * axis));
    out->samples.push_back(counts);
  }
}

void GyroDriver::ReadFifo(Clock& clock, FifoRead* out) {
  out->samples.clear();
  out->overflow = out->bad_data = false;
  const uint32_t hz = info_.spi_data_hz;
  const uint8_t status = ReadRegister(*bus_, Icm() ? icm::kIntStatus : mpu::kIntStatus, hz);
  uint8_t count_bytes[2];
  out->t_before_ns = clock.NowNs();
  ReadRegisters(*bus_, Icm() ? icm::kFifoCountH : mpu::kFifoCountH, count_bytes, 2, hz);
  out->t_after_ns = clock.NowNs();
  const size_t count = Icm() ? BigEndian16(count_bytes)
                             : static_cast<size_t>((count_bytes[0] & 0x1F) << 8 | count_bytes[1]);
  const size_t packet = static_cast<size_t>(info_.packet_bytes);
  const size_t capacity = static_cast<size_t>(info_.fifo_bytes);
  out->overflow = (status & (Icm() ? icm::kFifoFullBit : mpu::kFifoOverflowBit)) != 0 ||
                  count + packet > capacity;
  if (count > capacity || (count % packet != 0 && !out->overflow)) {
    out->bad_data = true;  // a count the FIFO cannot hold, or a torn sample
    FlushFifo();
    return;
  }
  const size_t whole = count - count % packet;
  fifo_bytes_.resize(whole);
  if (whole > 0) {
    ReadRegisters(*bus_, Icm() ? icm::kFifoData : mpu::kFifoRw, fifo_bytes_.data(), whole, hz);
  }
  ParsePackets(whole, out);
  if (out->overflow || out->bad_data) FlushFifo();
}

}  // namespace shutterlab
