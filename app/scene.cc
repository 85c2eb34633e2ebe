// `shutterlab scene`: a procedural nadir ground texture (render/ground_texture.h) to render over,
// for users without a nadir photo of their own.

#include "app/command.h"
#include "io/image_io.h"
#include "render/ground_texture.h"

#include <cstdio>
#include <memory>
#include <string>

namespace shutterlab::app {
namespace {

struct SceneCliOptions {
  GroundTextureOptions texture;
  std::string out_path;
};

const CommandRegistration kSceneRegistration(45, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "scene",
      "write a procedural nadir ground texture (fields, roads, roofs, trees) to render over");
  auto o = std::make_shared<SceneCliOptions>();
  cmd->add_option("--out", o->out_path, "output image (PNG, TIFF, JPEG, EXR by extension)")
      ->required();
  cmd->add_option("--width", o->texture.width_px, "width, px")->capture_default_str();
  cmd->add_option("--height", o->texture.height_px, "height, px")->capture_default_str();
  AddQuantityOption(cmd, "--gsd", &o->texture.ground_sample_distance_m, "m", "cm",
                    "ground sample distance, per pixel (altitude / focal length in px)");
  cmd->add_option("--seed", o->texture.seed, "random seed (same seed, same bytes)")
      ->capture_default_str();
  return std::function<void()>([o] {
    o->texture.Check();
    WriteImage(o->out_path, MakeGroundTexture(o->texture));
    std::printf("wrote %s: %dx%d px at %g m/px\n", o->out_path.c_str(), o->texture.width_px,
                o->texture.height_px, o->texture.ground_sample_distance_m);
  });
});

}  // namespace
}  // namespace shutterlab::app
