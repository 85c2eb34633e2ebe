// io/codecs.h: OpenImageIO and OpenCV's video reader and encoders (0.37 s of start-up, with the
// hundreds of libraries they bring) are loaded by the command that reads or writes an image file,
// at that moment, and by no other (a page's pictures are PNGs through libpng). The dynamic loader's
// own log (LD_DEBUG=libs) says what a process loaded.

#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

TEST(Startup, ACommandThatTouchesNoImageLoadsNoCodec) {
  const test::CommandResult version = test::RunShutterlab("--version", "", "LD_DEBUG=libs");
  ASSERT_EQ(version.exit_code, 0) << version.output;
  ASSERT_NE(version.err.find("libstdc++"), std::string::npos) << "LD_DEBUG printed nothing";
  EXPECT_EQ(version.err.find("libOpenImageIO"), std::string::npos);
  EXPECT_EQ(version.err.find("libopencv_videoio"), std::string::npos);
  EXPECT_EQ(version.err.find("libopencv_imgcodecs"), std::string::npos);
  EXPECT_EQ(version.err.find("libshutterlab_codecs"), std::string::npos);

  // A flight's page holds pictures (PNG through libpng) and still needs no codec.
  test::TempDir dir;
  ASSERT_EQ(test::RunShutterlab("synth flight --rate 500Hz --duration 20s --t0 1s --format ulog "
                                "--trigger-every 2s --altitude 50m --out " +
                                dir / "flight.ulg")
                .exit_code,
            0);
  const test::CommandResult analyze = test::RunShutterlab(
      "analyze " + dir / "flight.ulg" + " --out " + dir / "analyze", "", "LD_DEBUG=libs");
  ASSERT_EQ(analyze.exit_code, 0) << analyze.out;
  EXPECT_NE(ReadFileToString(dir / "analyze/report.html").find("data:image/png;base64,"),
            std::string::npos);
  EXPECT_EQ(analyze.err.find("libOpenImageIO"), std::string::npos);
  EXPECT_EQ(analyze.err.find("libshutterlab_codecs"), std::string::npos);

  const test::CommandResult scene = test::RunShutterlab(
      "scene --out " + dir / "ground.png" + " --width 64 --height 48", "", "LD_DEBUG=libs");
  ASSERT_EQ(scene.exit_code, 0) << scene.output;
  EXPECT_NE(scene.err.find("libshutterlab_codecs.so"), std::string::npos);
  EXPECT_NE(scene.err.find("libOpenImageIO"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "ground.png"));
}

TEST(Startup, WithoutItsCodecsModuleAnImageCommandSaysSoAndWritesNothing) {
  // The executable alone in a folder, as a broken installation would leave it.
  test::TempDir dir;
  const std::string binary = dir / "shutterlab";
  std::filesystem::copy_file(SHUTTERLAB_BINARY, binary);
  EXPECT_EQ(std::system((binary + " --version > /dev/null").c_str()), 0);

  const std::string command = binary + " scene --out " + dir / "ground.png" +
                              " --width 64 --height 48 2> " + dir / "err.txt";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string err = ReadFileToString(dir / "err.txt");
  EXPECT_EQ(test::LineCount(err), 1u) << err;
  EXPECT_NE(err.find("cannot load the image and video codecs module"), std::string::npos) << err;
  EXPECT_NE(err.find(dir.path().string() + "/libshutterlab_codecs.so"), std::string::npos) << err;
  EXPECT_NE(err.find("rebuild"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(dir / "ground.png"));
}

}  // namespace
}  // namespace shutterlab
