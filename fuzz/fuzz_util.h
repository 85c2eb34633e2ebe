#pragma once
// What every fuzz target shares: the one expected way for a reader to refuse bytes is IoError or
// std::invalid_argument (a clear one-line error). Anything else (a crash, a sanitizer report, an
// uncaught exception of another type, a hang) is a bug that libFuzzer reports.

#include "sim/check.h"
#include "sim/gyro_source.h"
#include "sim/logs/flight_log.h"
#include "sim/trace_audit.h"

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unistd.h>

namespace shutterlab::fuzz {

inline std::string_view Bytes(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Runs read(); swallows the errors a reader is allowed to throw.
template <typename Read>
void Expect(const Read& read) {
  try {
    read();
  } catch (const IoError&) {
  } catch (const std::invalid_argument&) {
  }
}

// Samples per chunk for a streaming reader, from an input byte: 1 to 17, so that chunk edges fall
// everywhere in a small input (and no run allocates a full-size chunk).
inline size_t ChunkSamples(uint8_t byte) { return 1 + byte % 17; }

// Takes every chunk of a source through the trace audit, as the commands do.
inline void AuditEveryChunk(GyroSource* source, const TraceAuditOptions& options = {}) {
  TraceAuditor auditor(options);
  for (GyroChunk chunk = source->Next(); !chunk.empty(); chunk = source->Next())
    auditor.Add(chunk.data, chunk.size);
  auditor.Finish();
  auditor.Sampling();
}

// Every sample and warning of a source after the log's own, as ReadFlightLog gives them.
inline FlightLog TakeAll(FlightLog* log, GyroSource* source) {
  FlightLog out = std::move(*log);
  out.gyro = ReadAllSamples(source);
  for (LogWarning& warning : source->Warnings()) out.warnings.push_back(std::move(warning));
  return out;
}

// What a reading gave, to compare two ways of reading the same bytes: its error, or its log
// (samples and warning times bit for bit, sources, records_skipped, warnings).
struct Outcome {
  std::string error;
  std::string log;
  bool operator!=(const Outcome& other) const { return error != other.error || log != other.log; }
};

template <typename T>
void AppendBits(const T& value, std::string* out) {
  out->append(reinterpret_cast<const char*>(&value), sizeof(value));
}

// Runs read() (which returns a FlightLog) and describes what it gave.
template <typename Read>
Outcome ReadOutcome(const Read& read) {
  Outcome out;
  try {
    const FlightLog log = read();
    out.log = log.format + "|" + log.gyro_source + "|" + std::to_string(log.records_skipped) + "|";
    for (const std::string& source : log.gyro_sources_available) out.log += source + ",";
    for (const LogWarning& w : log.warnings) {
      out.log += "|" + w.kind + ":" + w.message;
      AppendBits(w.t_s.value_or(-1.0), &out.log);
      AppendBits(w.count.value_or(~size_t{0}), &out.log);
    }
    for (const GyroSample& sample : log.gyro.samples()) {
      AppendBits(sample.t_ns, &out.log);
      for (int axis = 0; axis < 3; ++axis) AppendBits(sample.omega_rad_s[axis], &out.log);
    }
  } catch (const IoError& e) {
    out.error = e.what();
  } catch (const std::invalid_argument& e) {
    out.error = std::string("invalid argument: ") + e.what();
  }
  return out;
}

// For the readers that take a path: the bytes in a file of this process, rewritten per input.
class InputFile {
 public:
  explicit InputFile(const std::string& leaf)
      : path_((access("/dev/shm", W_OK) == 0 ? std::string("/dev/shm/") : std::string("/tmp/")) +
              "shutterlab_fuzz_" + std::to_string(getpid()) + "_" + leaf) {}
  ~InputFile() { std::remove(path_.c_str()); }
  const std::string& Write(const uint8_t* data, size_t size) {
    FILE* f = std::fopen(path_.c_str(), "wb");
    if (f) {
      if (size) std::fwrite(data, 1, size, f);
      std::fclose(f);
    }
    return path_;
  }

 private:
  std::string path_;
};

}  // namespace shutterlab::fuzz
