#include "record/spi_transport.h"

#include "sim/check.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <linux/spi/spidev.h>
#include <sys/ioctl.h>
#include <unistd.h>

namespace shutterlab {

void ReadRegisters(SpiTransport& bus, uint8_t address, uint8_t* out, size_t n, uint32_t speed_hz) {
  // One transfer: the address byte, then n dummy bytes clocked out while the data comes in.
  thread_local std::vector<uint8_t> tx, rx;
  tx.assign(n + 1, 0);
  rx.resize(n + 1);
  tx[0] = static_cast<uint8_t>(address | 0x80);
  bus.Transfer(tx.data(), rx.data(), n + 1, speed_hz);
  std::memcpy(out, rx.data() + 1, n);
}

uint8_t ReadRegister(SpiTransport& bus, uint8_t address, uint32_t speed_hz) {
  uint8_t value = 0;
  ReadRegisters(bus, address, &value, 1, speed_hz);
  return value;
}

void WriteRegister(SpiTransport& bus, uint8_t address, uint8_t value, uint32_t speed_hz) {
  const uint8_t tx[2] = {static_cast<uint8_t>(address & 0x7F), value};
  uint8_t rx[2];
  bus.Transfer(tx, rx, 2, speed_hz);
}

namespace {
std::string Errno(const std::string& path, const std::string& what) {
  return IoMessage(path, 0, what + ": " + std::strerror(errno));
}
}  // namespace

SpidevTransport::SpidevTransport(const std::string& path, int mode) : path_(path) {
  SHUTTERLAB_CHECK(mode == 0 || mode == 3) << path << ": SPI mode must be 0 or 3, got " << mode;
  fd_ = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) {
    throw IoError(Errno(path,
                        "cannot open the SPI device (is SPI enabled in config.txt, and "
                        "is the user in the spi group?)"));
  }
  uint8_t mode_bits = mode == 3 ? SPI_MODE_3 : SPI_MODE_0;
  uint8_t bits = 8;
  if (::ioctl(fd_, SPI_IOC_WR_MODE, &mode_bits) < 0 ||
      ::ioctl(fd_, SPI_IOC_WR_BITS_PER_WORD, &bits) < 0) {
    const std::string message =
        Errno(path, "cannot set SPI mode " + std::to_string(mode) + ", 8 bits per word");
    ::close(fd_);
    throw IoError(message);
  }
}

SpidevTransport::~SpidevTransport() {
  if (fd_ >= 0) ::close(fd_);
}

void SpidevTransport::Transfer(const uint8_t* tx, uint8_t* rx, size_t n, uint32_t speed_hz) {
  spi_ioc_transfer transfer{};
  transfer.tx_buf = reinterpret_cast<uintptr_t>(tx);
  transfer.rx_buf = reinterpret_cast<uintptr_t>(rx);
  transfer.len = static_cast<uint32_t>(n);
  transfer.speed_hz = speed_hz;
  transfer.bits_per_word = 8;
  if (::ioctl(fd_, SPI_IOC_MESSAGE(1), &transfer) < 0) {
    throw IoError(Errno(path_, "SPI transfer of " + std::to_string(n) + " bytes failed"));
  }
}

}  // namespace shutterlab
