// The InvenSense SPI framing the register helpers put on any bus (the read bit on the address, one
// dummy byte clocked per byte read, the data after the address byte, the clock passed through),
// and a spidev device that cannot be opened refused with its path. No hardware needed.

#include "record/spi_transport.h"

#include "sim/check.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// A bus that records what was sent and answers with a fixed pattern: byte i of a transfer is
// 0xA0 + i.
class RecordingSpiBus : public SpiTransport {
 public:
  struct Sent {
    std::vector<uint8_t> tx;
    uint32_t speed_hz;
  };
  void Transfer(const uint8_t* tx, uint8_t* rx, size_t n, uint32_t speed_hz) override {
    sent.push_back({std::vector<uint8_t>(tx, tx + n), speed_hz});
    for (size_t i = 0; i < n; ++i) rx[i] = static_cast<uint8_t>(0xA0 + i);
  }
  std::string Name() const override { return "recording bus"; }
  std::vector<Sent> sent;
};

TEST(SpiTransport, ABurstReadSetsTheReadBitAndReturnsTheBytesAfterTheAddress) {
  RecordingSpiBus bus;
  uint8_t out[4] = {};
  ReadRegisters(bus, 0x72, out, 4, 20000000);
  ASSERT_EQ(bus.sent.size(), 1u);
  EXPECT_EQ(bus.sent[0].tx, (std::vector<uint8_t>{0xF2, 0, 0, 0, 0}));  // 0x72 | 0x80, 4 dummies
  EXPECT_EQ(bus.sent[0].speed_hz, 20000000u);
  // The byte clocked in with the address is not data: out holds bytes 1..4.
  EXPECT_EQ(out[0], 0xA1);
  EXPECT_EQ(out[3], 0xA4);
  EXPECT_EQ(ReadRegister(bus, 0x75, 1000000), 0xA1);
  EXPECT_EQ(bus.sent[1].tx, (std::vector<uint8_t>{0xF5, 0}));
}

TEST(SpiTransport, AWriteClearsTheReadBitAndSendsTheValue) {
  RecordingSpiBus bus;
  WriteRegister(bus, 0x6B, 0x80, 1000000);
  WriteRegister(bus, 0xEB, 0x01, 1000000);  // an address with bit 7 set is still a write
  ASSERT_EQ(bus.sent.size(), 2u);
  EXPECT_EQ(bus.sent[0].tx, (std::vector<uint8_t>{0x6B, 0x80}));
  EXPECT_EQ(bus.sent[1].tx, (std::vector<uint8_t>{0x6B, 0x01}));
  EXPECT_EQ(bus.sent[0].speed_hz, 1000000u);
}

TEST(SpiTransport, AMissingSpidevIsAnIoErrorNamingIt) {
  const std::string path = "/nonexistent/spidev9.9";
  try {
    SpidevTransport bus(path);
    FAIL() << "opened " << path;
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_THROW(SpidevTransport(path, 1), std::invalid_argument);  // modes 0 and 3 only
}

}  // namespace
}  // namespace shutterlab
