#pragma once
// What `record --device` names: a real sensor on a Linux spidev device, or an emulated one
// playing a gyro trace; and what `record --trigger` names.
//
//   /dev/spidev0.0[,part=icm42688p][,rate=8000][,range=250][,mode=0]  (also spi:/dev/spidev0.0,...)
//   emulate:TRACE[,part=mpu9250][,rate=8000][,range=250][,ppm=40]
//
// TRACE is any gyro log the readers take (sim/logs/flight_log_io.h: gyro.csv, .gcsv, raw counts,
// ULog, blackbox, DataFlash); it has no commas in its path.

#include "record/clock.h"
#include "record/gyro_part.h"
#include "record/sensor_emulator.h"
#include "record/spi_transport.h"
#include "record/trigger_source.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace shutterlab {

struct DeviceSpec {
  bool emulate = false;
  std::string path;  // the spidev device, or the trace to play
  std::optional<GyroPart> part;
  std::optional<double> rate_hz;
  std::optional<int> range_dps;
  double ppm = 0.0;  // emulate only
  int spi_mode = 0;  // spidev only: 0 or 3
  std::string text;  // as given
};

// Throws std::invalid_argument naming the spec and the bad key or value.
DeviceSpec ParseDeviceSpec(const std::string& text);

// An opened device: the bus the driver talks to, and the emulator when it is one.
struct OpenedDevice {
  std::unique_ptr<SpiTransport> bus;
  SensorEmulator* emulator = nullptr;  // == bus.get() when emulated
  GyroPart part = GyroPart::kMpu9250;
};

// Opens the spidev device, or reads the trace (ReadFlightLog, any format) and builds the emulator
// on clock, playing on the time line `origin` (EmulatorOptions::shared_origin: pass the same to
// every device of a recording). part is the spec's, else default_part. Throws IoError for an
// unreadable device or trace.
OpenedDevice OpenDevice(const DeviceSpec& spec, GyroPart default_part, const Clock* clock,
                        std::shared_ptr<std::atomic<int64_t>> origin = nullptr);

// What `record --trigger` names: CHIP:LINE (a GPIO line, opened with gpio_bias: up, down, off,
// as-is), emulate:every=2s[,bounce=N][,width=5ms] (pulses every 2 s up to duration_s, which must
// then be given) or emulate:FILE (a trigger file's times on the trace's clock, as analyze
// --triggers reads it). Emulated pulse times count from the emulated sensor's first sample (the
// trace's start), so that they sit where the trace's camera triggers were; with a real sensor
// (emulator null), from the start. Throws std::invalid_argument naming the spec, IoError for an
// unreadable line or file.
std::unique_ptr<TriggerSource> OpenTriggerSpec(const std::string& spec,
                                               const std::string& gpio_bias, Clock* clock,
                                               SensorEmulator* emulator, double duration_s);

}  // namespace shutterlab
