#pragma once
// Helpers shared by the test suites: rotation matchers, temporary folders, running the CLI.

#include "sim/log_warning.h"
#include "sim/so3.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace shutterlab::test {

// True when a and b are the same double bit for bit (a readers' twins must agree exactly, NaN
// payloads and the sign of zero included).
inline bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(a)) == 0; }

// Where a copy of a log cut at `fraction` of its bytes ends: off a record boundary, as a cut at
// random almost always is (a cut there cannot be told from the end of a log). Odd, so never on a
// two-byte boundary, and moved past any DataFlash record start (0xA3 0x95); the other formats'
// cuts of the shared logs fall inside a record.
inline size_t CutInsideARecord(const std::string& bytes, double fraction) {
  size_t size = static_cast<size_t>(fraction * bytes.size()) | 1;
  while (bytes.compare(size, 2, "\xA3\x95") == 0) size += 2;
  return size;
}

inline void ExpectRotationNear(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b,
                               double tol_rad) {
  EXPECT_LE(AngularDistance(a, b), tol_rad)
      << "a = " << a.coeffs().transpose() << "  b = " << b.coeffs().transpose();
}

// n sample times at 1 kHz as the paper's logger writes them: +-20 % jitter, one time in 200
// repeated, one interval in 500 a 50 ms pause (the logger writing); from 1 s on, ns.
inline std::vector<int64_t> IrregularTimes(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int64_t> jitter(-200000, 200000);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<int64_t> t(n);
  int64_t base = 1000000000;
  for (size_t i = 0; i < n; ++i) {
    const double r = u(rng);
    if (r < 0.002) base += 50000000;       // 50 ms logging gap
    int64_t step = 1000000 + jitter(rng);  // 1 kHz +- 20 %
    if (r > 0.995) step = 0;               // duplicate timestamp
    base += step;
    t[i] = base;
  }
  return t;
}

// True when any warning's "kind: message" line contains text.
inline bool AnyWarningContains(const std::vector<LogWarning>& warnings, const std::string& text) {
  return std::any_of(warnings.begin(), warnings.end(), [&](const LogWarning& w) {
    return WarningLine(w).find(text) != std::string::npos;
  });
}
// The same for anything that carries a warning list (a FlightLog, a clip).
template <typename WithWarnings>
bool AnyWarningContains(const WithWarnings& holder, const std::string& text) {
  return AnyWarningContains(holder.warnings, text);
}

// Every warning's line, one a line, for failure messages.
inline std::string JoinedWarnings(const std::vector<LogWarning>& warnings) {
  std::string all;
  for (const LogWarning& w : warnings) all += WarningLine(w) + "\n";
  return all;
}

// A fresh folder under the build tree's temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "_" + info->name() : "tmp";
    path_ = std::filesystem::temp_directory_path() /
            ("shutterlab_" + name + "_" + std::to_string(std::random_device{}()));
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

// Appends a plain value's bytes in host (little-endian on our targets) order: the binary log
// formats (ULog, DataFlash) that the reader tests write byte by byte.
template <typename T>
void PutLittleEndian(std::string* out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  out->append(raw, sizeof(T));
}

// True in an AddressSanitizer build (gcc defines __SANITIZE_ADDRESS__, clang has the feature),
// where the heaviest cases shrink or are skipped: they run 3 to 10 times slower there.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAsan = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAsan = true;
#else
inline constexpr bool kAsan = false;
#endif
#else
inline constexpr bool kAsan = false;
#endif

// Writes text to dir/name and returns the path.
inline std::string WriteText(const TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir / name;
  std::ofstream(path) << text;
  return path;
}

inline std::string SourcePath(const std::string& relative) {
  return std::string(SHUTTERLAB_SOURCE_DIR) + "/" + relative;
}

// The real recorded data (logs, photos, clips) is not ours and is not in the repository: it lives
// in the shared data folder beside the checkout, ../shared/data, or wherever SHUTTERLAB_DATA_DIR
// points. RealDataPath gives a file or folder there.
inline std::string RealDataDir() {
  const char* dir = std::getenv("SHUTTERLAB_DATA_DIR");
  if (dir != nullptr && *dir != '\0') return dir;
  return std::string(SHUTTERLAB_SOURCE_DIR) + "/../shared/data";
}
inline std::string RealDataPath(const std::string& relative) {
  return RealDataDir() + "/" + relative;
}
// The GoPro HERO5 clip (karma.mp4) that the MP4, GPMF and import tests read.
inline std::string KarmaClipPath() { return RealDataPath("rs/gopro_karma/karma.mp4"); }

// Under CI (CI=true) missing real data, or a missing outside tool a test runs (colmap,
// python3-yaml: scripts/test.sh installs them), is a failure; elsewhere the test is skipped.
inline bool RealDataRequired() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::string(ci) == "true";
}

}  // namespace shutterlab::test

// Declares `const std::string var` = the real-data path `relative`; when it does not exist, the
// test stops here: skipped with a one-line reason, or failed under CI=true.
#define SHUTTERLAB_REAL_DATA(var, relative)                                                  \
  const std::string var = ::shutterlab::test::RealDataPath(relative);                        \
  if (!std::filesystem::exists(var)) {                                                       \
    if (::shutterlab::test::RealDataRequired()) {                                            \
      FAIL() << "real data " << var << " is missing (CI=true needs the shared data folder)"; \
    }                                                                                        \
    GTEST_SKIP()                                                                             \
        << "real data " << var                                                               \
        << " is absent (set SHUTTERLAB_DATA_DIR or put ../shared/data beside the checkout)"; \
  }

// The same for a test that reads several real files: stops unless the real-data folder is there.
#define SHUTTERLAB_NEED_REAL_DATA() SHUTTERLAB_REAL_DATA(real_data_dir_, "")

namespace shutterlab::test {}  // namespace shutterlab::test
