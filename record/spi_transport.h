#pragma once
// The bus a gyro driver talks through: one full-duplex SPI transfer per chip-select assertion. The
// Linux spidev device (a real sensor on a Raspberry Pi) and the register-level emulators
// (record/sensor_emulator.h) both implement it, so the recorder runs the same code on both.
//
// InvenSense SPI framing (MPU-9250 / MPU-6500 and ICM-42688-P alike): the first byte is the
// register address with bit 7 set for a read; the following bytes carry data, the address
// incrementing after each byte (except on the FIFO data register, which streams the FIFO).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab {

class SpiTransport {
 public:
  virtual ~SpiTransport() = default;
  // Sends tx[0..n) while receiving rx[0..n) at speed_hz (the parts allow faster clocks for sensor
  // and FIFO reads than for configuration). Throws IoError when the bus fails.
  virtual void Transfer(const uint8_t* tx, uint8_t* rx, size_t n, uint32_t speed_hz) = 0;
  virtual std::string Name() const = 0;  // for messages: "/dev/spidev0.0", "emulated MPU-9250"
};

// Reads n registers from address on (a burst), into out[0..n).
void ReadRegisters(SpiTransport& bus, uint8_t address, uint8_t* out, size_t n, uint32_t speed_hz);
uint8_t ReadRegister(SpiTransport& bus, uint8_t address, uint32_t speed_hz);
void WriteRegister(SpiTransport& bus, uint8_t address, uint8_t value, uint32_t speed_hz);

// Linux spidev (/dev/spidevB.C), 8 bits per word, SPI mode 0 by default: both parts take modes 0
// and 3, and the Raspberry Pi's second bus (SPI1, the auxiliary "mini SPI") has no mode 3.
class SpidevTransport : public SpiTransport {
 public:
  // Opens the device; throws IoError naming it (missing, no permission: the spi group; a mode the
  // controller lacks).
  explicit SpidevTransport(const std::string& path, int mode = 0);
  ~SpidevTransport() override;
  SpidevTransport(const SpidevTransport&) = delete;
  SpidevTransport& operator=(const SpidevTransport&) = delete;
  void Transfer(const uint8_t* tx, uint8_t* rx, size_t n, uint32_t speed_hz) override;
  std::string Name() const override { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace shutterlab
