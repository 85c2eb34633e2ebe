#include "sim/check.h"

namespace shutterlab {

std::string IoMessage(const std::string& path, long line, const std::string& problem) {
  std::string message = path;
  if (line > 0) message += ":" + std::to_string(line);
  return message + ": " + problem;
}

std::string WithoutCheckLocation(const std::string& message) {
  const size_t open = message.rfind(" [");
  if (open == std::string::npos || message.back() != ']' ||
      message.find(" check failed (", open) == std::string::npos) {
    return message;
  }
  return message.substr(0, open);
}

namespace internal {

CheckFailure::CheckFailure(const char* file, int line, const char* condition) {
  std::string f(file);
  const size_t slash = f.find_last_of('/');
  where_ = (slash == std::string::npos ? f : f.substr(slash + 1)) + ":" + std::to_string(line) +
           " check failed (" + condition + ")";
}

CheckFailure::~CheckFailure() noexcept(false) {
  const std::string detail = stream_.str();
  // The detail alone is what a user needs; the source location is appended for developers.
  throw std::invalid_argument(detail.empty() ? where_ : detail + " [" + where_ + "]");
}

}  // namespace internal
}  // namespace shutterlab
