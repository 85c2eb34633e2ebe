#pragma once
// Camera trigger edges from a GPIO line through libgpiod 1.6 (the v1 API, Debian bookworm):
// both edges are requested as line events; the kernel stamps each in its interrupt handler. Since
// Linux 5.7 those stamps are CLOCK_MONOTONIC, the recorder's clock; an older kernel's
// CLOCK_REALTIME stamps are recognised (far from the monotonic time) and moved onto it.

#include "record/trigger_source.h"

#include <memory>
#include <string>

namespace shutterlab {

// Opens `line` (an offset) of `chip` ("gpiochip0", "/dev/gpiochip0" or "0") as an input with
// both edges, with the internal bias pull-up/down/off where the kernel offers it ("up", "down",
// "off", "as-is"). Throws IoError naming the chip and line.
std::unique_ptr<TriggerSource> OpenGpioTrigger(const std::string& chip, unsigned line,
                                               const std::string& bias = "as-is");

}  // namespace shutterlab
