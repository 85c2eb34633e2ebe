#include "record/gpio_trigger.h"

#include "sim/check.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <gpiod.h>

namespace shutterlab {
namespace {

int64_t Now(clockid_t id) {
  timespec ts{};
  ::clock_gettime(id, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

class GpioTrigger : public TriggerSource {
 public:
  GpioTrigger(const std::string& chip_name, unsigned offset, const std::string& bias)
      : name_(chip_name + ":" + std::to_string(offset)) {
    chip_ = ::gpiod_chip_open_lookup(chip_name.c_str());
    if (!chip_) Fail("cannot open the GPIO chip");
    line_ = ::gpiod_chip_get_line(chip_, offset);
    if (!line_) Fail("no such line");
    int flags = 0;
    if (bias == "up") {
      flags = GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_UP;
    } else if (bias == "down") {
      flags = GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_DOWN;
    } else if (bias == "off") {
      flags = GPIOD_LINE_REQUEST_FLAG_BIAS_DISABLE;
    } else if (bias != "as-is") {
      throw std::invalid_argument("GPIO bias must be up, down, off or as-is, got '" + bias + "'");
    }
    if (::gpiod_line_request_both_edges_events_flags(line_, "shutterlab record", flags) < 0) {
      Fail("cannot request edge events (line in use?)");
    }
  }
  ~GpioTrigger() override {
    if (line_) ::gpiod_line_release(line_);
    if (chip_) ::gpiod_chip_close(chip_);
  }

  void WaitEdges(int64_t deadline_ns, std::vector<TriggerEdge>* edges) override {
    const int64_t wait_ns = std::max<int64_t>(deadline_ns - Now(CLOCK_MONOTONIC), 0);
    timespec timeout{static_cast<time_t>(wait_ns / 1000000000),
                     static_cast<long>(wait_ns % 1000000000)};
    const int ready = ::gpiod_line_event_wait(line_, &timeout);
    if (ready < 0) Fail("waiting for an edge failed");
    if (ready == 0) return;
    gpiod_line_event events[16];
    const int n = ::gpiod_line_event_read_multiple(line_, events, 16);
    if (n < 0) Fail("reading edge events failed");
    for (int i = 0; i < n; ++i) {
      int64_t t_ns = static_cast<int64_t>(events[i].ts.tv_sec) * 1000000000 + events[i].ts.tv_nsec;
      // A kernel before 5.7 stamps CLOCK_REALTIME: move such a stamp onto the monotonic clock.
      const int64_t mono = Now(CLOCK_MONOTONIC), real = Now(CLOCK_REALTIME);
      if (std::llabs(t_ns - real) < std::llabs(t_ns - mono)) t_ns -= real - mono;
      edges->push_back({t_ns, events[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE});
    }
  }

  std::string Name() const override { return name_; }

 private:
  [[noreturn]] void Fail(const std::string& what) {
    throw IoError(name_ + ": " + what + ": " + std::strerror(errno));
  }

  std::string name_;
  gpiod_chip* chip_ = nullptr;
  gpiod_line* line_ = nullptr;
};

}  // namespace

std::unique_ptr<TriggerSource> OpenGpioTrigger(const std::string& chip, unsigned line,
                                               const std::string& bias) {
  return std::make_unique<GpioTrigger>(chip, line, bias);
}

}  // namespace shutterlab
