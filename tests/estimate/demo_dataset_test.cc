// The demo's closing-the-loop dataset (estimate/demo_dataset.h RenderAndValidate).

#include "estimate/demo_dataset.h"

#include "model/effects.h"
#include "tests/estimate/loop/validate_fixtures.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace shutterlab {
namespace {

// The demo's helper: a small dataset with a 4 ms offset, validated, outputs written.
TEST(DemoDataset, RenderAndValidateFindsTheInjectedOffset) {
  test::TempDir dir;
  InjectedDemoOptions options;
  options.scene_path = test::GroundScenePath(2);
  options.out_dir = dir / "demo";
  options.frames = 4;
  options.width = 320;
  options.height = 240;
  const ValidationResult result = RenderAndValidate(options);
  ASSERT_FALSE(result.loop.effects.empty()) << test::LoopSummary(result);
  EXPECT_EQ(Spec(result.loop.effects.front().effect).name, "time_offset")
      << test::LoopSummary(result);
  EXPECT_NEAR(result.loop.model.rig.time_offset_s, 0.004, 0.3e-3) << test::LoopSummary(result);
  for (const char* file : {"report.json", "plots/validate.html", "dataset/truth.json"}) {
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "demo" / file)) << file;
  }
}

}  // namespace
}  // namespace shutterlab
