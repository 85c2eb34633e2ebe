#pragma once
// Error tiers:
//  - SHUTTERLAB_CHECK(cond) << "msg": a violated precondition or invariant; throws
//  std::invalid_argument.
//  - IoError: bad input at an IO boundary; the message names the path, line or record, and the
//  problem.
//  - std::optional / status structs for per-item "no answer" during computation.

#include <sstream>
#include <stdexcept>
#include <string>

namespace shutterlab {

// Thrown by readers and writers; what() is one line "PATH:LINE: problem" (":LINE" omitted when
// unknown).
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Builds "path:line: problem" for IoError. line <= 0 leaves the line out.
std::string IoMessage(const std::string& path, long line, const std::string& problem);

// A message without the source location that SHUTTERLAB_CHECK appends for developers
// (" [file.cc:N check failed (condition)]"), for a person: what the CLI prints.
std::string WithoutCheckLocation(const std::string& message);

namespace internal {
// Collects a streamed message and throws std::invalid_argument when destroyed, so that
// SHUTTERLAB_CHECK(x) << "detail" reads like a log statement (colmap's THROW_CHECK).
class CheckFailure {
 public:
  CheckFailure(const char* file, int line, const char* condition);
  CheckFailure(const CheckFailure&) = delete;
  ~CheckFailure() noexcept(false);
  template <typename T>
  CheckFailure& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }

 private:
  std::ostringstream stream_;
  std::string where_;
};
}  // namespace internal

}  // namespace shutterlab

#define SHUTTERLAB_CHECK(condition) \
  if (condition) {                  \
  } else                            \
    ::shutterlab::internal::CheckFailure(__FILE__, __LINE__, #condition)
