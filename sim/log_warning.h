#pragma once
// One thing a reader could not read or trust (docs/FORMATS.md "Warnings"): a kind, one line for a
// person, and where they apply the trace time of the first occurrence and a count.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct LogWarning {
  // truncated, partial_batch, gap, time_backwards, duplicate_time, rate_change, saturated,
  // too_few_samples, unused_source (the contract's words), or corrupt, format, unit, assumption,
  // repeated_sample, memory.
  std::string kind;
  std::string message;  // one line, with counts and times
  // The trace time of the first occurrence (s on the log's clock) and the count, where they apply.
  // Defaulted, so that {kind, message} says neither does (no -Wmissing-field-initializers).
  std::optional<double> t_s = std::nullopt;
  std::optional<size_t> count = std::nullopt;
};

// A text file's last line had no line break and did not read: the file was cut inside it (copied
// or recorded while still being written). The line is left out and said, never an error; what
// came before it is read. t_s: the time of the last line read, when known.
inline LogWarning CutLastLineWarning(long line_number, std::optional<double> t_s = std::nullopt) {
  return {
      "truncated",
      "line " + std::to_string(line_number) + ": the file ends inside it (no line break): left out",
      t_s, 1};
}

// "kind: message", as printed on stderr.
inline std::string WarningLine(const LogWarning& warning) {
  return warning.kind + ": " + warning.message;
}

}  // namespace shutterlab
