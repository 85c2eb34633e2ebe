#pragma once
// Fixtures shared by the render tests and the tests above them: the model's rigs and traces
// (tests/model/model_fixtures.h), the io tests' textures (tests/io/io_fixtures.h) and the ground
// scene.

#include "io/image_io.h"
#include "render/ground_texture.h"
#include "tests/io/io_fixtures.h"
#include "tests/model/model_fixtures.h"

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <unistd.h>

namespace shutterlab::test {

// The project's own nadir scene (render/ground_texture.h), 2560x1440 at 4 cm per pixel (about a
// 1280-wide mapping camera's at 50 m), written as a PNG under the temp folder for the tests that
// take a scene file: once per process and seed (a file from another process or an older build is
// never reused), and removed when the process ends.
inline std::string GroundScenePath(uint64_t seed = 1) {
  struct Written {
    std::map<uint64_t, std::string> paths;
    ~Written() {
      std::error_code ec;
      for (const auto& [seed, path] : paths) std::filesystem::remove(path, ec);
    }
  };
  static Written written;
  auto it = written.paths.find(seed);
  if (it != written.paths.end()) return it->second;
  GroundTextureOptions options;
  options.width_px = 2560;
  options.height_px = 1440;
  options.ground_sample_distance_m = 0.04;
  options.seed = seed;
  const std::string path =
      (std::filesystem::temp_directory_path() /
       ("shutterlab_ground_" + std::to_string(::getpid()) + "_" + std::to_string(seed) + ".png"))
          .string();
  WriteImage(path, MakeGroundTexture(options));
  return written.paths[seed] = path;
}

}  // namespace shutterlab::test
