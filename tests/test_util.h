#pragma once
// Helpers shared by the test suites: rotation matchers, temporary folders, running the CLI.

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "sim/so3.h"

namespace shutterlab::test {

inline void ExpectRotationNear(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b,
                               double tol_rad) {
  EXPECT_LE(AngularDistance(a, b), tol_rad)
      << "a = " << a.coeffs().transpose() << "  b = " << b.coeffs().transpose();
}

// A fresh folder under the build tree's temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "_" + info->name() : "tmp";
    path_ = std::filesystem::temp_directory_path() / ("shutterlab_" + name + "_" +
                                                      std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string operator/(const std::string& leaf) const { return (path_ / leaf).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

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

// Appends a plain value's bytes in host (little-endian on our targets) order: the binary log
// formats (ULog, DataFlash) that the reader tests write byte by byte.
template <typename T>
void PutLittleEndian(std::string* out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  out->append(raw, sizeof(T));
}

inline std::string SourcePath(const std::string& relative) {
  return std::string(SHUTTERLAB_SOURCE_DIR) + "/" + relative;
}

}  // namespace shutterlab::test
