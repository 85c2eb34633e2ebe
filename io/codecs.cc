#include "io/codecs.h"

#include "sim/check.h"

#include <dlfcn.h>
#include <filesystem>
#include <stdexcept>

namespace shutterlab {
namespace {

constexpr char kModuleFile[] = "libshutterlab_codecs.so";

const codecs::Functions& LoadCodecs() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe_dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
  std::string tried;
  for (const fs::path& candidate :
       {exe_dir / kModuleFile, exe_dir / ".." / "lib" / "shutterlab" / kModuleFile}) {
    void* handle = ::dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = ::dlerror();
      tried += (tried.empty() ? "" : "; ") + std::string(why ? why : candidate.string());
      continue;
    }
    // The module stays loaded for the life of the process: its codecs hold global state.
    using Entry = const codecs::Functions* (*)();
    const auto entry = reinterpret_cast<Entry>(::dlsym(handle, "shutterlab_codecs"));
    const codecs::Functions* functions = entry ? entry() : nullptr;
    if (!functions || functions->version != codecs::kCodecsVersion)
      throw std::runtime_error(candidate.string() +
                               ": not this build's codecs module (rebuild: cmake --build build)");
    return *functions;
  }
  throw std::runtime_error("cannot load the image and video codecs module (" + tried +
                           "): rebuild (cmake --build build) or reinstall shutterlab");
}

}  // namespace

const codecs::Functions& Codecs() {
  static const codecs::Functions& functions = LoadCodecs();
  return functions;
}

std::vector<uchar> EncodeImage(const std::string& extension, const cv::Mat& bgr) {
  std::vector<uchar> bytes;
  SHUTTERLAB_CHECK(Codecs().encode(extension, bgr, &bytes))
      << "OpenCV cannot encode a " << bgr.cols << " x " << bgr.rows << " image as " << extension;
  return bytes;
}

VideoFrames::VideoFrames(const std::string& path) : video_(Codecs().open_video(path)) {
  if (!video_) throw IoError(IoMessage(path, -1, "OpenCV cannot open the video"));
}

VideoFrames::~VideoFrames() { Codecs().close_video(video_); }

bool VideoFrames::Read(cv::Mat* bgr, double* position_ms) {
  return Codecs().read_video_frame(video_, bgr, position_ms);
}

}  // namespace shutterlab
