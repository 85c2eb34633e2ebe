#include "sim/readout_direction.h"

#include <gtest/gtest.h>

namespace shutterlab {
namespace {

TEST(ReadoutDirection, NamesRoundTripAndOtherTextIsNone) {
  for (ReadoutDirection d : {ReadoutDirection::kTopToBottom, ReadoutDirection::kBottomToTop,
                             ReadoutDirection::kLeftToRight, ReadoutDirection::kRightToLeft}) {
    EXPECT_EQ(ParseReadoutDirection(ReadoutDirectionName(d)), d) << ReadoutDirectionName(d);
  }
  EXPECT_STREQ(ReadoutDirectionName(ReadoutDirection::kTopToBottom), "top_to_bottom");
  EXPECT_STREQ(ReadoutDirectionName(ReadoutDirection::kBottomToTop), "bottom_to_top");
  EXPECT_FALSE(ParseReadoutDirection("TopToBottom").has_value());
  EXPECT_FALSE(ParseReadoutDirection("").has_value());
  EXPECT_TRUE(IsRowReadout(ReadoutDirection::kBottomToTop));
  EXPECT_FALSE(IsRowReadout(ReadoutDirection::kLeftToRight));
}

}  // namespace
}  // namespace shutterlab
