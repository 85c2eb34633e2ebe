#include "record/device_spec.h"

#include "record/gpio_trigger.h"
#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/trigger_file.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <cmath>

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
      spec.rate_hz = ParseQuantity(value, "Hz", "device '" + text + "': rate=", "Hz");
      need(spec.rate_hz > 0);
    } else if (key == "range") {
      const double range_dps =
          ParseQuantity(value, "deg/s", "device '" + text + "': range=", "deg/s");
      need(range_dps > 0 && range_dps <= 1e6 && range_dps == std::round(range_dps));
      spec.range_dps = static_cast<int>(range_dps);
    } else if (key == "mode" && !spec.emulate) {
      need(number && (*number == 0 || *number == 3));
      spec.spi_mode = static_cast<int>(*number);
    } else if (key == "ppm" && spec.emulate) {
      need(number.has_value());  // the key names the unit
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

std::unique_ptr<TriggerSource> OpenTriggerSpec(const std::string& spec,
                                               const std::string& gpio_bias, Clock* clock,
                                               SensorEmulator* emulator, double duration_s) {
  if (spec.rfind("emulate:", 0) != 0) {
    const size_t colon = spec.rfind(':');
    SHUTTERLAB_CHECK(colon != std::string::npos && colon > 0)
        << "--trigger takes CHIP:LINE (e.g. gpiochip0:17) or emulate:..., got '" << spec << "'";
    const auto line = ParseInt(spec.substr(colon + 1));
    SHUTTERLAB_CHECK(line && *line >= 0) << "--trigger: bad line number in '" << spec << "'";
    return OpenGpioTrigger(spec.substr(0, colon), static_cast<unsigned>(*line), gpio_bias);
  }
  std::vector<std::string_view> fields;
  const std::string rest = spec.substr(8);
  SplitFields(rest, ',', &fields);
  std::vector<int64_t> pulses;
  int64_t width_ns = 5000000;
  int bounce = 0;
  for (const std::string_view field : fields) {
    const std::string text(field);
    if (text.rfind("every=", 0) == 0) {
      SHUTTERLAB_CHECK(duration_s > 0) << "--trigger emulate:every= needs --duration";
      pulses = PulsesEvery(ParseQuantity(text.substr(6), "s", "--trigger emulate:every=", "s"),
                           duration_s);
    } else if (text.rfind("bounce=", 0) == 0) {
      const auto n = ParseInt(text.substr(7));
      SHUTTERLAB_CHECK(n && *n >= 0 && *n < 100) << "--trigger: bad bounce in '" << spec << "'";
      bounce = static_cast<int>(*n);
    } else if (text.rfind("width=", 0) == 0) {
      width_ns = SecondsToNs(ParseQuantity(text.substr(6), "s", "--trigger emulate:width=", "ms"));
    } else {
      const TriggerFile file = ReadTriggerFile(text);
      SHUTTERLAB_CHECK(file.clock == TriggerClock::kLog)
          << "--trigger emulate:" << text << ": the times must be on the trace's clock (they are "
          << TriggerClockName(file.clock) << ")";
      for (const TriggerEvent& event : file.events) pulses.push_back(event.t_ns);
    }
  }
  // Pulse times count from the emulated sensor's first sample (the trace's start), so that they
  // sit where the trace's camera triggers were; with a real sensor, from the start.
  const int64_t start_ns = clock->NowNs();
  std::function<std::optional<int64_t>()> origin = [emulator,
                                                    start_ns]() -> std::optional<int64_t> {
    if (!emulator) return start_ns;
    return emulator->PlayOriginNs();
  };
  return std::make_unique<EmulatedTriggerLine>(std::move(pulses), width_ns, bounce, origin, clock);
}

}  // namespace shutterlab
