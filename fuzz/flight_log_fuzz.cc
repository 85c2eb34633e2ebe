// libFuzzer target: any file handed to a command that takes a log (sim/logs/flight_log_io.h
// ReadFlightLog): format detection, then gyro.csv, Gyroflow .gcsv, raw counts, a gyro dump, the
// blackbox CSV export or a binary log, then the trace audit.
#include "sim/logs/flight_log_io.h"

#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static shutterlab::fuzz::InputFile file("log");
  const std::string& path = file.Write(data, size);
  shutterlab::fuzz::Expect([&] { shutterlab::ReadFlightLog(path); });
  return 0;
}
