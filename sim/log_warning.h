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
  // too_few_samples, unused_source (the contract's words), or corrupt, format, unit, assumption.
  std::string kind;
  std::string message;        // one line, with counts and times
  std::optional<double> t_s;  // trace time of the first occurrence, s on the log's clock
  std::optional<size_t> count;
};

// "kind: message", as printed on stderr.
inline std::string WarningLine(const LogWarning& warning) {
  return warning.kind + ": " + warning.message;
}

}  // namespace shutterlab
