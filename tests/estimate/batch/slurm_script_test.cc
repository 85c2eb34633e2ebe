// The Slurm scripts of a batch: the array lists, one array per memory class, the merge after them.

#include "estimate/batch/slurm_script.h"

#include "estimate/batch/batch_plan.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

TEST(SlurmScript, ArrayIndices) {
  EXPECT_EQ(SlurmArrayIndices({0, 1, 2, 3, 7, 9, 10, 11}), "0-3,7,9-11");
  EXPECT_EQ(SlurmArrayIndices({5}), "5");
  EXPECT_EQ(SlurmArrayIndices({0, 2, 4}), "0,2,4");
}

TEST(SlurmScript, OneArrayPerMemoryClassAndTheMergeAfterThem) {
  test::TempDir dir;
  const std::string small_log = test::WriteText(dir, "small.ulg", std::string(1000, 'x'));
  std::filesystem::create_directories(dir.path() / "ds");
  const std::string big_frame = test::WriteText(dir, "ds/frame.png", std::string(20'000'000, 'x'));
  BatchManifest manifest;
  for (int i = 0; i < 5; ++i) {
    BatchItem item;
    item.id = "item" + std::to_string(i);
    item.readout_s = item.altitude_m = NAN;
    if (i == 1 || i == 3) {
      item.dataset = dir / "ds";
      item.jobs = {BatchJob::kValidate};
    } else {
      item.log = small_log;
      item.jobs = {BatchJob::kAnalyze};
    }
    manifest.items.push_back(item);
  }
  SlurmBatchOptions options;
  options.executable = "/opt/shutter lab/shutterlab";  // a space: quoted for bash
  options.manifest_path = "/data/it's.toml";           // a quote: closed and escaped
  options.out_dir = "/shared/out";
  const SlurmBatchScripts scripts = MakeSlurmBatchScripts(manifest, options);
  ASSERT_EQ(scripts.arrays.size(), 2u);
  EXPECT_EQ(scripts.tasks, 5u);
  // The logs: 200 MiB + 2 B per byte of 1 kB -> the 256 MiB class; the dataset: 200 MiB + 32 x
  // 20 MB = 810 MiB -> 1024 MiB.
  EXPECT_EQ(scripts.arrays[0].name, "batch_256M.sbatch");
  EXPECT_EQ(scripts.arrays[0].items, (std::vector<size_t>{0, 2, 4}));
  EXPECT_NE(scripts.arrays[0].script.find("#SBATCH --array=0,2,4\n"), std::string::npos);
  EXPECT_NE(scripts.arrays[0].script.find("#SBATCH --mem=256M\n"), std::string::npos);
  EXPECT_EQ(scripts.arrays[1].name, "batch_1024M.sbatch");
  EXPECT_NE(scripts.arrays[1].script.find("#SBATCH --array=1,3\n"), std::string::npos);
  EXPECT_NE(scripts.arrays[1].script.find("#SBATCH --mem=1024M\n"), std::string::npos);
  EXPECT_GE(scripts.arrays[1].memory_bytes, EstimateBatchItemMemoryBytes(manifest.items[1]));
  // 3 x (2 min + 1 min per 200 MB) rounded up to a minute: 7 min for 20 MB.
  EXPECT_NE(scripts.arrays[1].script.find("#SBATCH --time=0-00:07:00\n"), std::string::npos);
  EXPECT_NE(scripts.arrays[0].script.find(
                "exec '/opt/shutter lab/shutterlab' batch '/data/it'\\''s.toml' --out "
                "'/shared/out' --item-index \"$SLURM_ARRAY_TASK_ID\"\n"),
            std::string::npos)
      << scripts.arrays[0].script;
  EXPECT_NE(scripts.arrays[0].script.find("#SBATCH --requeue\n"), std::string::npos);
  EXPECT_NE(scripts.merge_script.find("--summary-only\n"), std::string::npos);
  // One class: the plain name.
  manifest.items.resize(1);
  EXPECT_EQ(MakeSlurmBatchScripts(manifest, options).arrays.front().name, "batch.sbatch");
}

}  // namespace
}  // namespace shutterlab
