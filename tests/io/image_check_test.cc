// io/image_check.h: a photo whose metadata is whole but whose pixels are cut or damaged is found
// by decoding it (a JPEG at 1/8 size through libjpeg, anything else whole through OpenImageIO),
// and by io/image_io.h ReadWholeImage from OpenImageIO's full decode and its warning.

#include "io/image_check.h"

#include "io/codecs.h"
#include "io/image_io.h"
#include "sim/text_file.h"
#include "tests/io/photo_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <random>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

// A JPEG with DJI-like metadata and a noisy 640 x 480 picture (a scan of some kilobytes).
std::string NoisyPhoto() {
  test::FixturePhoto p;
  p.width = 640;
  p.height = 480;
  p.focal_length_35mm = 24;
  p.xmp = test::DjiXmp({{"RelativeAltitude", "+60"}}, false);
  const std::string header_only = test::JpegWithMetadata(p);
  // The fixture's grey scan replaced by a noisy one: the same metadata before the tables.
  cv::Mat noise(p.height, p.width, CV_8UC3);
  cv::randu(noise, 0, 255);
  const std::vector<uchar> encoded = EncodeImage(".jpg", noise);
  const std::string tables = "\xff\xdb";  // DQT: where the encoder's part starts in both
  const std::string noisy(encoded.begin(), encoded.end());
  return header_only.substr(0, header_only.find(tables)) + noisy.substr(noisy.find(tables));
}

// Where the entropy-coded scan starts (after the SOS segment) and ends (before EOI).
std::pair<size_t, size_t> ScanOf(const std::string& jpeg) {
  const size_t sos = jpeg.find("\xff\xda");
  const size_t length =
      static_cast<unsigned char>(jpeg[sos + 2]) << 8 | static_cast<unsigned char>(jpeg[sos + 3]);
  return {sos + 2 + length, jpeg.size() - 2};
}

TEST(ImageDataProblem, AWholePhotoDecodes) {
  test::TempDir dir;
  WriteFileAtomically(dir / "whole.jpg", NoisyPhoto());
  EXPECT_EQ(ImageDataProblem(dir / "whole.jpg"), "");
  // The photo's metadata reads as before: the check is about the pixels.
  EXPECT_EQ(ReadPhotoMetadata(dir / "whole.jpg").width, 640);
}

TEST(ImageDataProblem, APhotoCutInsideItsImageDataIsFound) {
  test::TempDir dir;
  const std::string whole = NoisyPhoto();
  const auto [begin, end] = ScanOf(whole);
  ASSERT_GT(end - begin, 10000u);
  for (const double share : {0.05, 0.5, 0.99}) {
    const std::string path = dir / "cut.jpg";
    WriteFileAtomically(path, whole.substr(0, begin + static_cast<size_t>(share * (end - begin))));
    EXPECT_NE(ImageDataProblem(path).find("Premature end of JPEG file"), std::string::npos)
        << share;
    // The metadata is all still there: only decoding tells.
    EXPECT_EQ(ReadPhotoMetadata(path).width, 640) << share;
  }
  // Cut before the scan: libjpeg refuses it outright.
  WriteFileAtomically(dir / "tables.jpg", whole.substr(0, begin - 20));
  EXPECT_NE(ImageDataProblem(dir / "tables.jpg"), "");
}

TEST(ImageDataProblem, DamagedImageDataIsFound) {
  test::TempDir dir;
  std::string damaged = NoisyPhoto();
  const auto [begin, end] = ScanOf(damaged);
  // A run of 0xFF 0xD0.. bytes in the scan: restart markers where none were declared.
  for (size_t at = begin + (end - begin) / 2; at < begin + (end - begin) / 2 + 40; at += 2) {
    damaged[at] = '\xff';
    damaged[at + 1] = '\xd3';
  }
  WriteFileAtomically(dir / "damaged.jpg", damaged);
  EXPECT_NE(ImageDataProblem(dir / "damaged.jpg"), "");
}

TEST(ImageDataProblem, OtherFormatsAreDecodedWhole) {
  test::TempDir dir;
  cv::Mat noise(120, 160, CV_8UC3);
  cv::randu(noise, 0, 255);
  WriteImage(dir / "whole.png", noise);
  EXPECT_EQ(ImageDataProblem(dir / "whole.png"), "");
  const std::string png = ReadFileToString(dir / "whole.png");
  WriteFileAtomically(dir / "cut.png", png.substr(0, png.size() / 2));
  EXPECT_NE(ImageDataProblem(dir / "cut.png"), "");
  EXPECT_EQ(ImageDataProblem(dir / "missing.jpg"), "cannot be opened");
  WriteFileAtomically(dir / "text.jpg", "cut off");
  EXPECT_NE(ImageDataProblem(dir / "text.jpg"), "");
}

TEST(ReadWholeImage, RefusesWhatTheOneEighthDecodeRefusesAndReadsTheRest) {
  // Two decoders: OpenImageIO's full decode (its warning) against libjpeg's 1/8 one.
  test::TempDir dir;
  const std::string whole = NoisyPhoto();
  WriteFileAtomically(dir / "whole.jpg", whole);
  EXPECT_EQ(ReadWholeImage(dir / "whole.jpg").size(), cv::Size(640, 480));
  const auto [begin, end] = ScanOf(whole);
  std::string damaged = whole;
  for (size_t at = begin + (end - begin) / 2; at < begin + (end - begin) / 2 + 40; at += 2) {
    damaged[at] = '\xff';
    damaged[at + 1] = '\xd3';
  }
  WriteFileAtomically(dir / "damaged.jpg", damaged);
  std::vector<std::string> paths = {dir / "damaged.jpg"};
  for (const double share : {0.05, 0.5, 0.99}) {
    paths.push_back(dir / FormatNumber("cut_%g.jpg", share));
    WriteFileAtomically(paths.back(),
                        whole.substr(0, begin + static_cast<size_t>(share * (end - begin))));
  }
  // libjpeg passes on its first warning only: a harmless one first (an unknown JFIF revision,
  // 3.01) must not hide the cut after it.
  // A JFIF APP0 segment of revision 3.01 after the start of image.
  const std::string app0("\xff\xe0\x00\x10JFIF\x00\x03\x01\x00\x00\x01\x00\x01\x00\x00", 18);
  const std::string revised = whole.substr(0, 2) + app0 + whole.substr(2);
  WriteFileAtomically(dir / "jfif3_whole.jpg", revised);
  EXPECT_EQ(ReadWholeImage(dir / "jfif3_whole.jpg").size(), cv::Size(640, 480));
  paths.push_back(dir / "jfif3_cut.jpg");
  WriteFileAtomically(paths.back(), revised.substr(0, app0.size() + begin + (end - begin) * 3 / 4));
  WriteFileAtomically(dir / "text.jpg", "cut off");
  paths.push_back(dir / "text.jpg");
  for (const std::string& path : paths) {
    const std::string problem = ImageDataProblem(path);
    ASSERT_NE(problem, "") << path;
    try {
      ReadWholeImage(path);
      ADD_FAILURE() << path << " read whole";
    } catch (const UndecodableImage& e) {
      const std::string said = e.what();
      EXPECT_EQ(said.rfind(path + ": its image data does not decode (", 0), 0u) << said;
      EXPECT_NE(said.find("copy it from the card again"), std::string::npos) << said;
      if (path != dir / "text.jpg") {
        EXPECT_NE(said.find("(" + problem + ")"), std::string::npos) << said << " / " << problem;
        // ReadImage still decodes it, grey or smeared where the data was lost.
        EXPECT_EQ(ReadImage(path).size(), cv::Size(640, 480)) << path;
      }
    }
  }
}

TEST(ReadImagePreview, AJpegAtTheSmallestDctScaleThatKeepsTheWidthOtherFilesWhole) {
  test::TempDir dir;
  // A smooth 800 x 600 picture (the scaled decode keeps low frequencies), colour and grey.
  cv::Mat colour(600, 800, CV_8UC3), grey(600, 800, CV_8UC1);
  for (int v = 0; v < colour.rows; ++v) {
    for (int u = 0; u < colour.cols; ++u) {
      colour.at<cv::Vec3b>(v, u) = cv::Vec3b(u * 255 / 799, v * 255 / 599, (u + v) * 255 / 1398);
      grey.at<uchar>(v, u) = static_cast<uchar>((u * 3 + v) * 255 / (799 * 3 + 599));
    }
  }
  WriteImage(dir / "colour.jpg", colour);
  WriteImage(dir / "grey.jpg", grey);
  WriteImage(dir / "colour.png", colour);
  const cv::Mat whole = ReadImage(dir / "colour.jpg");
  for (const auto& [min_width, size] : std::vector<std::pair<int, cv::Size>>{{1, {100, 75}},
                                                                             {100, {100, 75}},
                                                                             {101, {200, 150}},
                                                                             {201, {400, 300}},
                                                                             {401, {800, 600}},
                                                                             {800, {800, 600}},
                                                                             {5000, {800, 600}}}) {
    const cv::Mat preview = ReadImagePreview(dir / "colour.jpg", min_width);
    ASSERT_EQ(preview.size(), size) << min_width;
    ASSERT_EQ(preview.type(), CV_8UC3);
    // The same picture as the whole decode shrunk (R, G, B in the file's order as ReadImage's):
    // within a level or two on a gradient.
    cv::Mat shrunk;
    cv::resize(whole, shrunk, size, 0, 0, cv::INTER_AREA);
    cv::Mat difference;
    cv::absdiff(preview, shrunk, difference);
    const cv::Scalar mean = cv::mean(difference);
    for (int c = 0; c < 3; ++c) EXPECT_LT(mean[c], 2.0) << min_width << " channel " << c;
  }
  // A width that is not a multiple of 8 rounds up, as libjpeg's scaled output does.
  cv::Mat odd;
  cv::resize(colour, odd, cv::Size(803, 601));
  WriteImage(dir / "odd.jpg", odd);
  EXPECT_EQ(ReadImagePreview(dir / "odd.jpg", 100).size(), cv::Size(101, 76));
  EXPECT_EQ(ReadImagePreview(dir / "odd.jpg", -1).size(), cv::Size(101, 76))
      << "below 1 counts as 1";
  const cv::Mat grey_preview = ReadImagePreview(dir / "grey.jpg", 100);
  EXPECT_EQ(grey_preview.size(), cv::Size(100, 75));
  EXPECT_EQ(grey_preview.type(), CV_8UC1);
  // Another format is read whole, exactly.
  const cv::Mat png = ReadImagePreview(dir / "colour.png", 100);
  ASSERT_EQ(png.size(), colour.size());
  EXPECT_EQ(cv::norm(png, colour, cv::NORM_INF), 0.0);
  EXPECT_FALSE(ReadJpegScaled(dir / "colour.png", 100));
  EXPECT_THROW(ReadImagePreview(dir / "missing.jpg", 100), IoError);
}

}  // namespace
}  // namespace shutterlab
