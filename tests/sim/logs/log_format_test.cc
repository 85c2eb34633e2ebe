#include "sim/logs/log_format.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace shutterlab {
namespace {

TEST(LogFormat, RawCountRangesAreTheParts) {
  RawCountOptions raw;
  for (int range : {250, 500, 1000, 2000}) {
    raw.range_dps = range;
    EXPECT_NO_THROW(raw.Check()) << range;
  }
  raw.range_dps = 300;
  EXPECT_THROW(raw.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
