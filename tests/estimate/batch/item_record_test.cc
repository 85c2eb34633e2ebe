// A batch item's record: the input stamps, the hash kept for an untouched file, and each reason
// an item is made again.

#include "estimate/batch/item_record.h"

#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <utility>

namespace shutterlab {
namespace {

TEST(ItemRecord, XxhOfKnownContent) {
  test::TempDir dir;
  // XXH3-64 with seed 0 of the empty input and of "a" (xxHash's own test vectors,
  // xsum_sanity_check.c).
  EXPECT_EQ(FileXxh3(test::WriteText(dir, "empty", "")), "2d06800538d394c2");
  EXPECT_EQ(FileXxh3(test::WriteText(dir, "a", "a")), "e6c632b61e964e1f");
}

TEST(ItemRecord, StaleReasons) {
  test::TempDir dir;
  const std::string log = test::WriteText(dir, "f.ulg", "first content");
  const std::string extra = test::WriteText(dir, "g.ulg", "other");
  std::vector<PlannedCommand> plan = {{BatchJob::kAnalyze,
                                       "analyze",
                                       {"analyze", log, "--json"},
                                       "analyze/analyze.json",
                                       "logs/analyze.log"}};
  const nlohmann::json recipe = BatchItemRecipe(plan, "shutterlab 0.1");
  const std::vector<InputFileStamp> stamps = StampInputFiles({log});
  ASSERT_EQ(stamps.size(), 1u);
  EXPECT_EQ(stamps[0].bytes, 13u);
  EXPECT_EQ(stamps[0].xxh3, FileXxh3(log));
  nlohmann::json record = {
      {"status", "done"}, {"recipe", recipe}, {"inputs", InputStampsJson(stamps)}};

  EXPECT_EQ(BatchItemStaleReason(nlohmann::json(), recipe, stamps), "not made yet");
  EXPECT_EQ(BatchItemStaleReason(record, recipe, stamps), "");
  nlohmann::json failed = record;
  failed["status"] = "failed";
  EXPECT_EQ(BatchItemStaleReason(failed, recipe, stamps), "it failed before");
  EXPECT_EQ(BatchItemStaleReason(record, BatchItemRecipe(plan, "shutterlab 0.2"), stamps),
            "the tool changed");
  plan[0].args.push_back("--readout");
  EXPECT_EQ(BatchItemStaleReason(record, BatchItemRecipe(plan, "shutterlab 0.1"), stamps),
            "its options changed");
  EXPECT_EQ(BatchItemStaleReason(record, recipe, StampInputFiles({log, extra})),
            "an input was added: " + extra);
  EXPECT_EQ(BatchItemStaleReason(record, recipe, {}), "an input was removed: " + log);

  // The same size and time keep the recorded hash (a file is not read again); another content
  // at the same size is hashed again when its time moved, and found.
  std::vector<InputFileStamp> faked = stamps;
  faked[0].xxh3 = "0123456789abcdef";
  EXPECT_EQ(StampInputFiles({log}, faked)[0].xxh3, "0123456789abcdef");
  test::WriteText(dir, "f.ulg", "other content");  // 13 bytes too
  std::filesystem::last_write_time(log,
                                   std::filesystem::last_write_time(log) + std::chrono::seconds(5));
  EXPECT_EQ(BatchItemStaleReason(record, recipe, StampInputFiles({log}, stamps)),
            "an input changed: " + log);
  // Touched but unchanged: hashed again, the same: up to date.
  test::WriteText(dir, "f.ulg", "first content");
  std::filesystem::last_write_time(log,
                                   std::filesystem::last_write_time(log) + std::chrono::seconds(9));
  EXPECT_EQ(BatchItemStaleReason(record, recipe, StampInputFiles({log}, stamps)), "");
  EXPECT_EQ(InputStampsFromRecord(record)[0].xxh3, stamps[0].xxh3);
}

}  // namespace
}  // namespace shutterlab
