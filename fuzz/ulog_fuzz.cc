// libFuzzer target: PX4 ULog bytes, read both ways: whole (sim/logs/ulog.h ParseULog) and streamed
// (internal::OpenULogBytes: pass 1, then pass 2 in chunks of 1 to 17 samples, from the input's
// size), with the default candidate limits or, for every other size, limits so small that the
// fallback (a topic instance's times held whole) runs. Both must give the same log, but for the
// fallback's one "memory" warning, or the same error; anything else traps.
#include "fuzz/fuzz_util.h"
#include "sim/logs/ulog.h"

#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using namespace shutterlab;

template <typename T>
bool SameBits(const std::optional<T>& a, const std::optional<T>& b) {
  return a.has_value() == b.has_value() && (!a || std::memcmp(&*a, &*b, sizeof(T)) == 0);
}

bool SameLog(const FlightLog& a, const FlightLog& b) {
  if (a.format != b.format || a.gyro_source != b.gyro_source ||
      a.gyro_sources_available != b.gyro_sources_available ||
      a.records_skipped != b.records_skipped || a.altitude_source != b.altitude_source ||
      !SameBits(a.altitude_above_ground_m, b.altitude_above_ground_m) ||
      a.warnings.size() != b.warnings.size() || a.camera_events.size() != b.camera_events.size() ||
      a.utc_fixes.size() != b.utc_fixes.size() || a.gyro.size() != b.gyro.size())
    return false;
  for (size_t i = 0; i < a.warnings.size(); ++i) {
    const LogWarning &x = a.warnings[i], &y = b.warnings[i];
    if (x.kind != y.kind || x.message != y.message || !SameBits(x.t_s, y.t_s) || x.count != y.count)
      return false;
  }
  for (size_t i = 0; i < a.camera_events.size(); ++i) {
    const CameraEvent &x = a.camera_events[i], &y = b.camera_events[i];
    if (x.t_ns != y.t_ns || x.sequence != y.sequence || x.kind != y.kind) return false;
  }
  for (size_t i = 0; i < a.utc_fixes.size(); ++i) {
    if (a.utc_fixes[i].t_ns != b.utc_fixes[i].t_ns ||
        a.utc_fixes[i].utc_ns != b.utc_fixes[i].utc_ns)
      return false;
  }
  for (size_t i = 0; i < a.gyro.size(); ++i) {
    if (a.gyro[i].t_ns != b.gyro[i].t_ns ||
        std::memcmp(a.gyro[i].omega_rad_s.data(), b.gyro[i].omega_rad_s.data(),
                    3 * sizeof(double)) != 0)
      return false;
  }
  return true;
}

// The stream read chunk by chunk into a log, without the fallback's warning; or the error.
std::optional<FlightLog> ReadStreamed(std::string_view bytes, size_t chunk_samples,
                                      const internal::CandidateLimits& limits, std::string* error) {
  try {
    ULogStream stream =
        internal::OpenULogBytes(std::string(bytes), "fuzz.ulg", chunk_samples, limits);
    std::vector<GyroSample> samples;
    for (GyroChunk chunk = stream.gyro->Next(); !chunk.empty(); chunk = stream.gyro->Next()) {
      if (chunk.size > chunk_samples) __builtin_trap();
      samples.insert(samples.end(), chunk.begin(), chunk.end());
    }
    FlightLog log = std::move(stream.log);
    log.gyro = GyroTrace(std::move(samples));
    for (size_t i = 0; i < log.warnings.size(); ++i) {
      if (log.warnings[i].kind == "memory") {
        log.warnings.erase(log.warnings.begin() + static_cast<long>(i));
        break;
      }
    }
    return log;
  } catch (const IoError& e) {
    *error = e.what();
  } catch (const std::invalid_argument& e) {
    *error = e.what();
  }
  return std::nullopt;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes = fuzz::Bytes(data, size);
  std::optional<FlightLog> whole;
  std::string whole_error;
  try {
    whole = ParseULog(bytes, "fuzz.ulg");
  } catch (const IoError& e) {
    whole_error = e.what();
  } catch (const std::invalid_argument& e) {
    whole_error = e.what();
  }
  // One streamed read per input, its limits chosen by the input's size as the chunk is (34
  // combinations): a third read per input made each execution half as fast again, for the same
  // coverage over a campaign.
  const size_t chunk = fuzz::ChunkSamples(static_cast<uint8_t>(size));
  const internal::CandidateLimits limits =
      (size / 17) % 2 == 0 ? internal::CandidateLimits{} : internal::CandidateLimits{2, 2};
  std::string error;
  const std::optional<FlightLog> streamed = ReadStreamed(bytes, chunk, limits, &error);
  if (streamed.has_value() != whole.has_value()) __builtin_trap();
  if (streamed ? !SameLog(*streamed, *whole) : error != whole_error) __builtin_trap();
  return 0;
}
