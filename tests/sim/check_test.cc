#include "sim/check.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace shutterlab {
namespace {

// A failed check throws its message with the source location appended for developers; a person is
// shown the message alone, also after a caller has put the path in front.
TEST(Check, TheLocationIsForDevelopersAndComesOffForAPerson) {
  try {
    const int samples = 3;
    SHUTTERLAB_CHECK(samples >= 10) << "bias segment holds " << samples << " samples [sic]";
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("bias segment holds 3 samples [sic] [check_test.cc:", 0), 0u) << what;
    EXPECT_NE(what.find(" check failed (samples >= 10)]"), std::string::npos) << what;
    EXPECT_EQ(WithoutCheckLocation(what), "bias segment holds 3 samples [sic]");
    EXPECT_EQ(WithoutCheckLocation("log.csv: " + what),
              "log.csv: bias segment holds 3 samples [sic]");
  }
  EXPECT_EQ(WithoutCheckLocation("a plain message [with brackets]"),
            "a plain message [with brackets]");
  EXPECT_EQ(WithoutCheckLocation(""), "");
}

}  // namespace
}  // namespace shutterlab
