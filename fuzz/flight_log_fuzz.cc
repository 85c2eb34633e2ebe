// libFuzzer target: any file handed to a command that takes a log (sim/logs/flight_log_io.h
// ReadFlightLog): format detection, then gyro.csv, Gyroflow .gcsv, raw counts, a gyro dump, the
// blackbox CSV export or a binary log, then the trace audit. A blackbox log (streamed from the
// file's mapping) must also equal the same bytes read from memory in chunks of 1 to 17 samples;
// a difference traps.
#include "fuzz/fuzz_util.h"
#include "sim/logs/blackbox.h"
#include "sim/logs/flight_log_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static shutterlab::fuzz::InputFile file("log");
  const std::string& path = file.Write(data, size);
  const shutterlab::fuzz::Outcome from_file =
      shutterlab::fuzz::ReadOutcome([&] { return shutterlab::ReadFlightLog(path); });
  const std::string_view bytes = shutterlab::fuzz::Bytes(data, size);
  bool blackbox = false;
  shutterlab::fuzz::Expect([&] {
    blackbox = shutterlab::DetectFlightLogFormat(bytes.substr(0, 16 * 1024), path) ==
               shutterlab::LogFormat::kBlackbox;
  });
  if (!blackbox) return 0;
  const size_t chunk = size > 0 ? shutterlab::fuzz::ChunkSamples(data[size - 1]) : 1;
  const shutterlab::fuzz::Outcome from_memory = shutterlab::fuzz::ReadOutcome([&] {
    shutterlab::BlackboxStream stream = shutterlab::OpenBlackboxBuffer(bytes, path, -1, chunk);
    shutterlab::FlightLog log = shutterlab::fuzz::TakeAll(&stream.log, stream.samples.get());
    for (shutterlab::LogWarning& w : shutterlab::AuditTrace(log.gyro))
      log.warnings.push_back(std::move(w));
    return log;
  });
  if (from_file != from_memory) __builtin_trap();
  return 0;
}
