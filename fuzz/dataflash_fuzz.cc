// libFuzzer target: ArduPilot DataFlash bytes (sim/logs/dataflash.h), read both ways: whole
// (ParseDataFlash) and streamed in chunks of 1 to 17 samples with pass-1 limits small enough to be
// exceeded (OpenDataFlash); they must agree in every sample, warning and count (the streamed way
// may add its "memory" warning), or refuse alike.
#include "fuzz/fuzz_util.h"
#include "sim/logs/dataflash.h"

#include <string>
#include <vector>

namespace {

struct Read {
  shutterlab::FlightLog log;
  std::string error;
  bool refused = false;
};

std::vector<std::string> Lines(const shutterlab::FlightLog& log) {
  std::vector<std::string> lines;
  for (const shutterlab::LogWarning& w : log.warnings) {
    if (w.kind != "memory") lines.push_back(w.kind + ": " + w.message);
  }
  return lines;
}

bool SameSamples(const shutterlab::GyroTrace& a, const shutterlab::GyroTrace& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    // Bit for bit: NaN never reaches a trace, so == is exact here.
    if (a[i].t_ns != b[i].t_ns || a[i].omega_rad_s != b[i].omega_rad_s) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  const std::string_view bytes = fuzz::Bytes(data, size);
  Read whole, streamed;
  try {
    whole.log = ParseDataFlash(bytes, "fuzz.bin");
  } catch (const IoError& e) {
    whole.refused = true;
    whole.error = e.what();
  }
  const uint8_t knob = size > 5 ? data[size - 1] : 0;
  try {
    DataFlashStream stream =
        OpenDataFlash(bytes, "fuzz.bin", fuzz::ChunkSamples(knob),
                      internal::CandidateLimits{1 + knob % 5u, 1 + (knob >> 4) % 7u});
    streamed.log = std::move(stream.log);
    streamed.log.gyro = ReadAllSamples(stream.samples.get());
  } catch (const IoError& e) {
    streamed.refused = true;
    streamed.error = e.what();
  }
  const bool same = whole.refused == streamed.refused && whole.error == streamed.error &&
                    whole.log.gyro_source == streamed.log.gyro_source &&
                    whole.log.gyro_sources_available == streamed.log.gyro_sources_available &&
                    whole.log.records_skipped == streamed.log.records_skipped &&
                    whole.log.camera_events.size() == streamed.log.camera_events.size() &&
                    whole.log.utc_fixes.size() == streamed.log.utc_fixes.size() &&
                    Lines(whole.log) == Lines(streamed.log) &&
                    SameSamples(whole.log.gyro, streamed.log.gyro);
  if (!same) __builtin_trap();
  return 0;
}
