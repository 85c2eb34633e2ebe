// import.json's claims read into typed effect values at the edge.
#include "estimate/loop/claims_io.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <string>

namespace shutterlab {
namespace {

TEST(ReadSourceClaims, ReadsTheTestableClaimsTyped) {
  test::TempDir dir;
  const std::string path = dir / "import.json";
  WriteFileAtomically(path, R"({"claims": [
    {"what": "intrinsics", "value": {"fx": 500}, "status": "guess"},
    {"what": "readout_s", "value": 0.033312, "status": "source claim"},
    {"what": "gyro_to_camera", "value": [[0, -1, 0], [-1, 0, 0], [0, 0, -1]]},
    {"what": "direction", "value": "bottom_to_top", "status": "guess"},
    {"what": "time_offset_s", "value": 0.0, "status": "guess"}]})");
  const std::vector<SourceClaim> claims = ReadSourceClaims(path);
  ASSERT_EQ(claims.size(), 4u);  // intrinsics: no effect tests it
  EXPECT_EQ(claims[0].what, "readout_s");
  EXPECT_EQ(claims[0].status, "source claim");
  EXPECT_EQ(claims[0].effect, Effect::kReadoutTime);
  EXPECT_TRUE(claims[0].value == EffectValue(0.033312));
  EXPECT_EQ(claims[1].effect, Effect::kGyroToCamera);
  EXPECT_EQ(claims[1].status, "");
  Eigen::Matrix3d m;
  m << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  EXPECT_TRUE(claims[1].value == EffectValue(m));
  EXPECT_EQ(claims[2].effect, Effect::kReadoutDirection);
  EXPECT_TRUE(claims[2].value == EffectValue(ReadoutDirection::kBottomToTop));
  EXPECT_EQ(claims[3].effect, Effect::kTimeOffset);
  EXPECT_TRUE(claims[3].value == EffectValue(0.0));
}

TEST(ReadSourceClaims, NoFileOrNoClaimsIsNone) {
  test::TempDir dir;
  EXPECT_TRUE(ReadSourceClaims(dir / "import.json").empty());
  WriteFileAtomically(dir / "import.json", R"({"source": "phone"})");
  EXPECT_TRUE(ReadSourceClaims(dir / "import.json").empty());
}

TEST(ReadSourceClaims, ABadClaimIsNamedWithItsValue) {
  test::TempDir dir;
  const std::string path = dir / "import.json";
  WriteFileAtomically(path, R"({"claims": [{"what": "direction", "value": "top_to_bottom"},
    {"what": "readout_s", "value": "fast"}]})");
  try {
    ReadSourceClaims(path);
    ADD_FAILURE() << "no throw";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("claim 2: \"readout_s\" has an unusable value \"fast\""), std::string::npos)
        << what;
  }
  WriteFileAtomically(path, R"({"claims": [{"what": "direction", "value": "left_to_right"}]})");
  EXPECT_THROW(ReadSourceClaims(path), IoError);
  WriteFileAtomically(path, R"({"claims": [{"what": 3}]})");
  EXPECT_THROW(ReadSourceClaims(path), IoError);
  WriteFileAtomically(path, R"({"claims": [)");
  EXPECT_THROW(ReadSourceClaims(path), IoError);
}

}  // namespace
}  // namespace shutterlab
