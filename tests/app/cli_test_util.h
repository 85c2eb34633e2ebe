#pragma once
// Running the shutterlab executable from the command-line tests.

#include <cstdio>
#include <string>
#include <sys/wait.h>

namespace shutterlab::test {

struct CommandResult {
  int exit_code;
  std::string output;  // stdout and stderr together
};

// Runs the shutterlab executable with the given argument string (shell syntax).
inline CommandResult RunShutterlab(const std::string& args) {
  const std::string command = std::string(SHUTTERLAB_BINARY) + " " + args + " 2>&1";
  CommandResult result{-1, ""};
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) result.output.append(buffer, n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

}  // namespace shutterlab::test
