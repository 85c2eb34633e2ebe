#pragma once
// The gyro driver: configures an MPU-9250 / MPU-6500 or an ICM-42688-P for FIFO reading of the
// gyro alone, and reads the FIFO, over any SpiTransport (a Linux spidev device or an emulator).

#include "record/clock.h"
#include "record/gyro_part.h"
#include "record/spi_transport.h"

#include <array>
#include <cstdint>
#include <vector>

namespace shutterlab {

// One read of the FIFO.
struct FifoRead {
  // Clock times just before and just after the FIFO count was read: the count was latched
  // between them, so every sample read was produced before t_after_ns and the next one after
  // t_before_ns (record/fifo_clock.h).
  int64_t t_before_ns = 0, t_after_ns = 0;
  std::vector<std::array<int16_t, 3>> samples;  // counts, sensor axes, oldest first
  // The FIFO was full (overflow interrupt, or the count at capacity): samples produced after these
  // may have been lost; the FIFO has been flushed.
  bool overflow = false;
  // The count or a packet was not what the configuration gives (a bus error, a reset part): the
  // rest of the FIFO was flushed.
  bool bad_data = false;
};

class GyroDriver {
 public:
  // bus: not owned, outlives the driver.
  GyroDriver(SpiTransport* bus, GyroPart part);

  const PartInfo& info() const { return info_; }

  // Resets the part, checks WHO_AM_I, sets rate and range, the FIFO to gyro x, y, z only with new
  // data dropped when full, and starts it. Waits on clock for the reset. Throws IoError
  // "BUS: WHO_AM_I is 0x12, expected 0x71 (MPU-9250)..." for another part or none, and
  // std::invalid_argument for a setting the part lacks.
  PartSetting Configure(const SensorConfig& config, Clock& clock);
  // Configure in two halves, for a caller that must not wait (the reader recovering one part
  // while it keeps reading another): BeginReset, then FinishConfigure once ResetWaitNs passed.
  void BeginReset();
  int64_t ResetWaitNs() const;
  PartSetting FinishConfigure(const SensorConfig& config, Clock& clock);

  // Reads the FIFO status, count and data into *out (its sample vector reused). Throws IoError
  // when the bus fails.
  void ReadFifo(Clock& clock, FifoRead* out);

  // Empties the FIFO (after an overflow or bad data).
  void FlushFifo();

  // WHO_AM_I and the gyro configuration read back as Configure left them: false when the part was
  // reset (a brown-out) or the bus answers something else.
  bool Healthy();

 private:
  bool Icm() const { return info_.part == GyroPart::kIcm42688p; }
  void ParsePackets(size_t bytes, FifoRead* out);

  SpiTransport* bus_;
  const PartInfo& info_;
  PartSetting setting_;
  std::vector<uint8_t> fifo_bytes_;
};

}  // namespace shutterlab
