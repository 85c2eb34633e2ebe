// libFuzzer target: a COLMAP text model (io/colmap_model.h ReadColmapTextModel). The input is
// cameras.txt, images.txt and points3D.txt separated by NUL bytes (a missing part: an empty file).
#include "fuzz/fuzz_util.h"
#include "io/colmap_model.h"

#include <cstdio>
#include <string>
#include <string_view>
#include <sys/stat.h>
#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // A folder of its own, as InputFile names its files (left behind: a few bytes in /dev/shm).
  static const std::string dir = [] {
    const std::string path =
        (access("/dev/shm", W_OK) == 0 ? std::string("/dev/shm/") : std::string("/tmp/")) +
        "shutterlab_fuzz_" + std::to_string(getpid()) + "_colmap_model";
    mkdir(path.c_str(), 0700);
    return path;
  }();
  std::string_view rest = shutterlab::fuzz::Bytes(data, size);
  for (const char* name : {"/cameras.txt", "/images.txt", "/points3D.txt"}) {
    const size_t end = rest.find('\0');
    const std::string_view part = rest.substr(0, end);
    rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 1);
    FILE* f = std::fopen((dir + name).c_str(), "wb");
    if (!f) return 0;
    if (!part.empty()) std::fwrite(part.data(), 1, part.size(), f);
    std::fclose(f);
  }
  shutterlab::fuzz::Expect([&] { shutterlab::ReadColmapTextModel(dir); });
  return 0;
}
