// libFuzzer target: a delimited gyro log read by its columns (sim/logs/column_csv.h). The first
// input byte picks the column choice, delimiter and units; the rest is the file's text.
#include "sim/logs/column_csv.h"

#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace shutterlab;
  if (size == 0) return 0;
  const uint8_t pick = data[0];
  ColumnCsvOptions options;
  options.columns = (pick & 1) ? std::vector<std::string>{"4", "1", "2", "3"}
                               : std::vector<std::string>{"t", "gx", "gy", "gz"};
  constexpr char kDelimiters[] = {'\0', ',', ';', '\t', ' '};
  options.delimiter = kDelimiters[(pick >> 1) % 5];
  options.time_unit = (pick & 0x10) ? TimeUnit::kMicroseconds : TimeUnit::kSeconds;
  options.rate_unit = (pick & 0x20) ? RateUnit::kDegPerSecond : RateUnit::kRadPerSecond;
  fuzz::Expect([&] { ParseColumnCsv(fuzz::Bytes(data + 1, size - 1), "fuzz.csv", options); });
  return 0;
}
