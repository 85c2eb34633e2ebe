#include "sim/record/device_spec.h"

#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/text_file.h"

namespace shutterlab {

DeviceSpec ParseDeviceSpec(const std::string& text) {
  DeviceSpec spec;
  spec.text = text;
  std::string rest = text;
  if (rest.rfind("emulate:", 0) == 0) {
    spec.emulate = true;
    rest = rest.substr(8);
  } else if (rest.rfind("spi:", 0) == 0) {
    rest = rest.substr(4);
  }
  std::vector<std::string_view> fields;
  SplitFields(rest, ',', &fields);
  spec.path = std::string(fields[0]);
  SHUTTERLAB_CHECK(!spec.path.empty())
      << "device '" << text << "' names no " << (spec.emulate ? "trace" : "SPI device");
  for (size_t i = 1; i < fields.size(); ++i) {
    const std::string_view field = fields[i];
    const size_t eq = field.find('=');
    const std::string key(field.substr(0, eq));
    const std::string value(eq == std::string_view::npos ? "" : field.substr(eq + 1));
    const auto number = ParseDouble(value);
    auto need = [&](bool ok) {
      SHUTTERLAB_CHECK(ok) << "device '" << text << "': bad value for " << key << ": '" << value
                           << "'";
    };
    if (key == "part") {
      spec.part = ParseGyroPart(value);
    } else if (key == "rate") {
      need(number && *number > 0);
      spec.rate_hz = *number;
    } else if (key == "range") {
      need(number && *number == static_cast<int>(*number));
      spec.range_dps = static_cast<int>(*number);
    } else if (key == "mode" && !spec.emulate) {
      need(number && (*number == 0 || *number == 3));
      spec.spi_mode = static_cast<int>(*number);
    } else if (key == "ppm" && spec.emulate) {
      need(number.has_value());
      spec.ppm = *number;
    } else {
      throw std::invalid_argument("device '" + text + "': unknown key '" + key +
                                  "' (part, rate, range" +
                                  (spec.emulate ? ", ppm)" : ", mode; ppm is for emulate:)"));
    }
  }
  return spec;
}

OpenedDevice OpenDevice(const DeviceSpec& spec, GyroPart default_part, const Clock* clock,
                        std::shared_ptr<std::atomic<int64_t>> origin) {
  OpenedDevice device;
  device.part = spec.part.value_or(default_part);
  if (!spec.emulate) {
    device.bus = std::make_unique<SpidevTransport>(spec.path, spec.spi_mode);
    return device;
  }
  FlightLog log = ReadFlightLog(spec.path);
  EmulatorOptions options;
  options.part = device.part;
  options.ppm = spec.ppm;
  options.shared_origin = std::move(origin);
  auto emulator = std::make_unique<SensorEmulator>(std::move(log.gyro), clock, options);
  device.emulator = emulator.get();
  device.bus = std::move(emulator);
  return device;
}

}  // namespace shutterlab
