#include "sim/logs/log_format.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace shutterlab {
namespace {

TEST(LogFormat, NamesRoundTripThroughBothParsers) {
  for (LogFormat f : {LogFormat::kAuto, LogFormat::kGyroCsv, LogFormat::kGcsv, LogFormat::kRaw,
                      LogFormat::kULog, LogFormat::kBlackbox, LogFormat::kDataFlash,
                      LogFormat::kGoproMp4, LogFormat::kGyroDump, LogFormat::kColumns}) {
    EXPECT_EQ(ParseLogFormat(LogFormatName(f)), f) << LogFormatName(f);
    if (f == LogFormat::kAuto || IsPlainGyroFormat(f)) {
      EXPECT_EQ(ParseGyroFormat(LogFormatName(f)), f) << LogFormatName(f);
    } else {
      EXPECT_THROW(ParseGyroFormat(LogFormatName(f)), std::invalid_argument) << LogFormatName(f);
    }
  }
  EXPECT_EQ(ParseLogFormat("CSV"), LogFormat::kGyroCsv);
  EXPECT_EQ(ParseLogFormat("px4"), LogFormat::kULog);
  EXPECT_EQ(ParseLogFormat("bin"), LogFormat::kDataFlash);
  EXPECT_EQ(ParseLogFormat("MP4"), LogFormat::kGoproMp4);
  EXPECT_EQ(ParseLogFormat("dump"), LogFormat::kGyroDump);
}

TEST(LogFormat, UnknownNamesAreNamedWithTheChoices) {
  try {
    ParseLogFormat("jpeg");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("unknown log format 'jpeg' (auto, ulog, dataflash, "
                                          "blackbox, gopro, gyro.csv, gcsv, raw, gyro_dump, "
                                          "columns)",
                                          0),
              0u)
        << e.what();
  }
  try {
    ParseGyroFormat("ulog");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("unknown gyro format 'ulog' (auto, csv, gcsv, raw)", 0),
              0u)
        << e.what();
  }
  RawCountOptions raw;
  raw.range_dps = 300;
  EXPECT_THROW(raw.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
