#include "io/image_io.h"

#include "io/photo_metadata.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/io/io_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <png.h>
#include <string>
#include <utility>
#include <vector>
#include <zlib.h>

namespace shutterlab {
namespace {

TEST(ImageIo, LosslessFormatsRoundTripExactly) {
  test::TempDir dir;
  for (const char* extension : {".png", ".tif"}) {
    for (int type : {CV_8UC1, CV_8UC3, CV_16UC1, CV_16UC3}) {
      const cv::Mat image = test::SmoothTexture(cv::Size(37, 23), type, 9, 0.5);
      const std::string path = dir / ("image_" + std::to_string(type) + extension);
      WriteImage(path, image);
      const cv::Mat back = ReadImage(path);
      ASSERT_EQ(back.type(), type) << path;
      EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0.0) << path;
    }
  }
}

// A mask is packed one bit a pixel (unpacked and counted alike), written so and read back, by
// libpng's own unpacking through OpenImageIO, as 0 where it was 0 and 255 wherever it was not:
// every width from 1 to 19 (the last byte of a row padded with 0), values that share no bit with
// each other.
TEST(ImageIo, MaskIsOneBitAPixelAndReadsBackAs0And255) {
  test::TempDir dir;
  cv::RNG rng(7);
  const uint8_t values[] = {0, 1, 2, 4, 8, 16, 32, 64, 128, 255, 0, 0};
  for (int width = 1; width <= 19; ++width) {
    cv::Mat mask(5, width, CV_8UC1);
    for (int y = 0; y < mask.rows; ++y) {
      for (int x = 0; x < mask.cols; ++x) mask.at<uint8_t>(y, x) = values[rng.uniform(0, 12)];
    }
    const PackedMask packed = PackMask(mask);
    EXPECT_EQ(cv::countNonZero(UnpackMask(packed) != ((mask != 0) & 255)), 0) << width;
    EXPECT_EQ(CountSetPixels(packed), static_cast<size_t>(cv::countNonZero(mask))) << width;
    const int padding = 8 * packed.bits.cols - width;
    EXPECT_EQ(cv::countNonZero(packed.bits.col(packed.bits.cols - 1) & ((1 << padding) - 1)), 0)
        << "the bits past a row of " << width;
    const std::string path = dir / ("mask_" + std::to_string(width) + ".png");
    WriteMask(path, packed);
    const std::string bytes = ReadFileToString(path);
    ASSERT_GT(bytes.size(), 25u);
    EXPECT_EQ(bytes[24], 1) << "the IHDR's bit depth of " << path;
    const cv::Mat back = ReadImage(path);
    ASSERT_EQ(back.type(), CV_8UC1) << path;
    EXPECT_EQ(cv::countNonZero(back != ((mask != 0) & 255)), 0) << path;
    EXPECT_EQ(cv::countNonZero((back != 0) & (back != 255)), 0) << path;
  }
}

// COLMAP, the masks' first reader (--ImageReader.mask_path), honours a one-bit mask: with the left
// half masked its feature extractor keeps fewer features of a noise image, and exactly as many as
// with the same mask written in 8 bits.
TEST(ImageIo, ColmapHonoursAOneBitMask) {
  if (std::system("colmap help >/dev/null 2>&1") != 0) {
    if (test::RealDataRequired()) FAIL() << "colmap is not installed (scripts/test.sh installs it)";
    GTEST_SKIP() << "colmap is not installed (apt-get install colmap)";
  }
  test::TempDir dir;
  cv::Mat image(240, 320, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(255));
  std::filesystem::create_directories(dir / "images");
  WriteImage(dir / "images/noise.png", image);
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(255));
  mask.colRange(0, 160).setTo(0);
  std::filesystem::create_directories(dir / "one_bit");
  std::filesystem::create_directories(dir / "eight_bit");
  WriteMask(dir / "one_bit/noise.png.png", PackMask(mask));
  WriteImage(dir / "eight_bit/noise.png.png", mask);
  const auto features = [&](const std::string& name, const std::string& masks) {
    const std::string log = dir / (name + ".log");
    const std::string command =
        "QT_QPA_PLATFORM=offscreen GLOG_log_dir='" + dir.path().string() +
        "' colmap feature_extractor --database_path '" + (dir / (name + ".db")) +
        "' --image_path '" + (dir / "images") + "' " +
        (masks.empty() ? "" : "--ImageReader.mask_path '" + (dir / masks) + "' ") +
        "--SiftExtraction.use_gpu 0 --SiftExtraction.num_threads 1 >'" + log + "' 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << ReadFileToString(log);
    const std::string text = ReadFileToString(log);
    const size_t at = text.find("Features:");
    return at == std::string::npos ? -1 : std::atoi(text.c_str() + at + 9);
  };
  const int all = features("all", ""), one_bit = features("one_bit", "one_bit"),
            eight_bit = features("eight_bit", "eight_bit");
  EXPECT_GT(all, 100);
  EXPECT_GT(one_bit, 0);
  EXPECT_LT(one_bit, 0.7 * all) << "half the image masked";
  EXPECT_EQ(one_bit, eight_bit);
}

TEST(ImageIo, ChannelOrderIsTheFilesRgb) {
  // A pure red pixel written as channel 0 comes back as channel 0 (no BGR swap anywhere).
  test::TempDir dir;
  cv::Mat image(2, 2, CV_8UC3, cv::Scalar(255, 0, 0));
  WriteImage(dir / "red.png", image);
  const cv::Mat back = ReadImage(dir / "red.png");
  EXPECT_EQ(back.at<cv::Vec3b>(1, 1), cv::Vec3b(255, 0, 0));
}

TEST(ImageIo, JpegRoundTripsClosely) {
  test::TempDir dir;
  const cv::Mat image = test::SmoothTexture(cv::Size(64, 48), CV_8UC3, 9, 3.0);
  WriteImage(dir / "image.jpg", image);
  const cv::Mat back = ReadImage(dir / "image.jpg");
  ASSERT_EQ(back.type(), CV_8UC3);
  // Quality 95 on a smooth texture: a few levels at most.
  EXPECT_LT(cv::norm(back, image, cv::NORM_L1) / image.total() / 3, 3.0);
}

TEST(ImageIo, ExrKeepsFloatsAndChannelNames) {
  test::TempDir dir;
  cv::Mat field(5, 7, CV_32FC2);
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 7; ++u)
      field.at<cv::Vec2f>(v, u) = cv::Vec2f(0.1f * u - 1e-3f * v, -3.25f * v + 1e-7f);
  }
  field.at<cv::Vec2f>(2, 3) = cv::Vec2f(NAN, NAN);
  WriteImage(dir / "disp.exr", field, {"dx", "dy"});
  std::vector<std::string> names;
  const cv::Mat back = ReadFloatImage(dir / "disp.exr", &names);
  ASSERT_EQ(back.type(), CV_32FC2);
  EXPECT_EQ(names, (std::vector<std::string>{"dx", "dy"}));
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 7; ++u) {
      const cv::Vec2f a = field.at<cv::Vec2f>(v, u), b = back.at<cv::Vec2f>(v, u);
      if (v == 2 && u == 3) {
        EXPECT_TRUE(std::isnan(b[0]) && std::isnan(b[1]));
      } else {
        EXPECT_EQ(a, b);  // float32 stays float32 bit for bit
      }
    }
  }
}

// The value of key in metadata, "" when absent.
std::string MetadataValue(const std::vector<std::pair<std::string, std::string>>& metadata,
                          const std::string& key) {
  for (const auto& [k, v] : metadata) {
    if (k == key) return v;
  }
  return "";
}

TEST(ImageIo, JpegQualityIsReadFromTheQuantisationTables) {
  test::TempDir dir;
  const cv::Mat image = test::SmoothTexture(cv::Size(64, 48), CV_8UC3, 9, 3.0);
  WriteImage(dir / "default.jpg", image);
  EXPECT_EQ(ReadImageFileInfo(dir / "default.jpg").jpeg_quality, 95);
  for (const int quality : {30, 75, 92}) {
    ImageLike like;
    like.info.format = "jpeg";
    like.info.jpeg_quality = quality;
    like.info.jpeg_subsampling = "4:4:4";
    const std::string path = dir / ("q" + std::to_string(quality) + ".jpg");
    WriteImageLike(path, image, like);
    const ImageFileInfo info = ReadImageFileInfo(path);
    EXPECT_EQ(info.format, "jpeg");
    EXPECT_EQ(info.jpeg_quality, quality);
    EXPECT_EQ(info.jpeg_subsampling, "4:4:4");
  }
  WriteImage(dir / "lossless.png", image);
  EXPECT_FALSE(ReadImageFileInfo(dir / "lossless.png").jpeg_quality) << "a PNG has none";
}

TEST(ImageIo, WritingLikeKeepsTheBitDepth) {
  test::TempDir dir;
  struct Case {
    const char* name;
    int type;
    bool half;
  };
  for (const Case& c : {Case{"a.png", CV_8UC3, false}, Case{"b.png", CV_16UC1, false},
                        Case{"c.tif", CV_16UC3, false}, Case{"d.tif", CV_8UC1, false},
                        Case{"e.exr", CV_32FC3, true}, Case{"f.exr", CV_32FC3, false}}) {
    const cv::Mat image = test::SmoothTexture(cv::Size(33, 21), c.type, 4, 1.0);
    ImageLike like;
    like.info.floating = CV_MAT_DEPTH(c.type) == CV_32F;
    like.info.bits_per_channel = c.half ? 16 : static_cast<int>(CV_ELEM_SIZE1(c.type)) * 8;
    const std::string path = dir / c.name;
    WriteImageLike(path, image, like);
    const ImageFileInfo info = ReadImageFileInfo(path);
    EXPECT_EQ(info.bits_per_channel, like.info.bits_per_channel) << c.name;
    EXPECT_EQ(info.floating, like.info.floating) << c.name;
    const cv::Mat back = ReadImage(path);
    EXPECT_EQ(back.type(), c.type) << c.name;
    // Lossless, but half floats keep 11 significant bits.
    EXPECT_LE(cv::norm(back, image, cv::NORM_INF), c.half ? 1e-3 : 0.0) << c.name;
  }
}

// A PNG's image data (its IDAT chunks' zlib stream): the header's FLEVEL (the top two bits of
// FLG) says which class of level wrote it (RFC 1950: 0 fastest, i.e. level 1; 2 the default, 6),
// and each row of the inflated data starts with its filter's type (PNG_FILTER_VALUE_*).
struct PngData {
  int level_class = -1;
  std::vector<int> row_filters;
};
PngData ReadPngData(const std::string& path, int row_bytes, int rows) {
  const std::string bytes = ReadFileToString(path);
  std::string stream;
  for (size_t at = 8; at + 12 <= bytes.size();) {  // after the signature: length, type, data, CRC
    const auto byte = [&](size_t k) {
      return static_cast<uint32_t>(static_cast<uint8_t>(bytes[k]));
    };
    const uint32_t length = byte(at) << 24 | byte(at + 1) << 16 | byte(at + 2) << 8 | byte(at + 3);
    if (bytes.compare(at + 4, 4, "IDAT") == 0) stream += bytes.substr(at + 8, length);
    at += 12 + static_cast<size_t>(length);
  }
  PngData out;
  if (stream.size() < 2) return out;
  out.level_class = static_cast<uint8_t>(stream[1]) >> 6;
  std::string raw(static_cast<size_t>(row_bytes + 1) * rows, '\0');
  uLongf size = raw.size();
  if (uncompress(reinterpret_cast<Bytef*>(raw.data()), &size,
                 reinterpret_cast<const Bytef*>(stream.data()), stream.size()) != Z_OK) {
    return out;
  }
  for (int v = 0; v < rows; ++v)
    out.row_filters.push_back(static_cast<uint8_t>(raw[v * (row_bytes + 1)]));
  return out;
}

// A PNG is written at zlib level 1, whether new (WriteImage) or like another (a corrected video
// frame), colour with PAETH on every row and a mask unfiltered: the same pixels at a fraction of
// the default's time.
TEST(ImageIo, PngsAreWrittenAtTheFastestZlibLevelWithOneFilter) {
  test::TempDir dir;
  const cv::Mat image = test::SmoothTexture(cv::Size(64, 48), CV_8UC3, 4, 1.0);
  WriteImage(dir / "new.png", image);
  ImageLike like{dir / "new.png", ReadImageFileInfo(dir / "new.png")};
  WriteImageLike(dir / "like.png", image, like);
  cv::Mat mask(48, 64, CV_8UC1, cv::Scalar(255));
  mask(cv::Rect(0, 0, 10, 48)).setTo(0);
  WriteImage(dir / "mask.png", mask);
  for (const char* name : {"new.png", "like.png", "mask.png"}) {
    const bool grey = std::string(name) == "mask.png";
    const PngData data = ReadPngData(dir / name, grey ? 64 : 64 * 3, 48);
    EXPECT_EQ(data.level_class, 0) << name;
    ASSERT_EQ(data.row_filters.size(), 48u) << name;
    // Row 0 has no row above: libpng may take it unfiltered.
    for (int v = 1; v < 48; ++v) {
      EXPECT_EQ(data.row_filters[v], grey ? PNG_FILTER_VALUE_NONE : PNG_FILTER_VALUE_PAETH)
          << name << " row " << v;
    }
  }
  EXPECT_EQ(cv::norm(ReadImage(dir / "like.png"), image, cv::NORM_INF), 0.0);
}

TEST(ImageIo, MetadataIsCopiedWhereTheFormatHoldsIt) {
  test::TempDir dir;
  const cv::Mat image = test::SmoothTexture(cv::Size(40, 30), CV_8UC3, 2, 1.0);
  ImageLike plain;
  plain.info.format = "jpeg";
  EXPECT_TRUE(WriteImageLike(dir / "source.jpg", image, plain,
                             {{"Xmp.shutterlab.Test", "abc"}, {"Xmp.dc.source", "unit test"}})
                  .empty());
  ImageLike like{dir / "source.jpg", ReadImageFileInfo(dir / "source.jpg")};
  for (const char* name : {"copy.jpg", "copy.png", "copy.tif"}) {
    EXPECT_TRUE(
        WriteImageLike(dir / name, image, like, {{"Xmp.shutterlab.Reference", "row0"}}).empty())
        << name;
    const auto metadata = ReadImageMetadata(dir / name);
    EXPECT_EQ(MetadataValue(metadata, "Xmp.shutterlab.Test"), "abc") << name;
    EXPECT_EQ(MetadataValue(metadata, "Xmp.dc.source"), "unit test") << name;
    EXPECT_EQ(MetadataValue(metadata, "Xmp.shutterlab.Reference"), "row0") << name;
  }
  cv::Mat floats;
  image.convertTo(floats, CV_32FC3, 1.0 / 255);
  const std::vector<std::string> notes = WriteImageLike(dir / "copy.exr", floats, like);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("holds no EXIF or XMP"), std::string::npos) << notes[0];
  EXPECT_EQ(ReadImage(dir / "copy.exr").type(), CV_32FC3) << "the pixels are written all the same";
}

// exiv2 is set up once a process, in one place (io/exiv2_setup.h), whichever of reading a photo
// and writing shutterlab's XMP keys comes first: in a fresh process (the death test runs the binary
// again) a photo read first must leave the keys writable. (The set-up's XMP lock has no getter.)
TEST(ImageIo, XmpKeysAreWrittenAfterAPhotoWasReadFirst) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const auto read_then_write = [] {
    const test::TempDir dir;  // removed before the child exits
    const cv::Mat image = test::SmoothTexture(cv::Size(40, 30), CV_8UC3, 2, 1.0);
    const std::string photo = dir / "photo.jpg", out = dir / "out.jpg";
    WriteImage(photo, image);
    ReadPhotoMetadata(photo);
    const ImageLike like{photo, ReadImageFileInfo(photo)};
    const std::vector<std::pair<std::string, std::string>> xmp = {
        {"Xmp.shutterlab.Reference", "row0"}};
    const bool written = WriteImageLike(out, image, like, xmp).empty();
    return written && MetadataValue(ReadImageMetadata(out), "Xmp.shutterlab.Reference") == "row0";
  };
  EXPECT_EXIT(std::exit(read_then_write() ? 0 : 1), ::testing::ExitedWithCode(0), "");
}

TEST(ImageIo, RealDronePhotoKeepsItsExifAndDjiXmp) {
  SHUTTERLAB_REAL_DATA(photo, "incoming/dji_fc8482_clusterodm/test-photo-1.jpg");
  test::TempDir dir;
  const ImageLike like{photo, ReadImageFileInfo(photo)};
  // Re-compressed to 118 KB for 9 MP (its PROVENANCE.md): every luminance entry is 255, what IJG
  // quality 1 gives.
  EXPECT_EQ(like.info.jpeg_quality, 1);
  const cv::Mat image = ReadImage(photo);
  EXPECT_TRUE(WriteImageLike(dir / "corrected.jpg", image, like).empty());
  const auto original = ReadImageMetadata(photo), copied = ReadImageMetadata(dir / "corrected.jpg");
  for (const char* key : {"Exif.Image.Make", "Exif.Image.Model", "Exif.Photo.DateTimeOriginal",
                          "Exif.GPSInfo.GPSLatitude", "Xmp.drone-dji.RelativeAltitude",
                          "Xmp.drone-dji.GimbalPitchDegree", "Xmp.drone-dji.FlightYSpeed"}) {
    ASSERT_NE(MetadataValue(original, key), "") << key;
    EXPECT_EQ(MetadataValue(copied, key), MetadataValue(original, key)) << key;
  }
  EXPECT_EQ(ReadImageFileInfo(dir / "corrected.jpg").jpeg_quality, like.info.jpeg_quality);
}

TEST(ImageIo, BadFilesThrowIoErrorNamingThePath) {
  test::TempDir dir;
  WriteFileAtomically(dir / "garbage.png", "this is not a png");
  for (const std::string& path : {dir / "missing.png", dir / "garbage.png"}) {
    try {
      ReadImage(path);
      ADD_FAILURE() << "read " << path;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  // Writing into a missing folder fails cleanly and leaves nothing behind.
  EXPECT_THROW(WriteImage(dir / "no/such/folder/out.png", cv::Mat(2, 2, CV_8UC1, cv::Scalar(1))),
               IoError);
  EXPECT_THROW(WriteImage(dir / "out.unknownext", cv::Mat(2, 2, CV_8UC1, cv::Scalar(1))), IoError);
  size_t files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path()))
    ++files;
  EXPECT_EQ(files, 1u) << "only garbage.png may remain";
}

}  // namespace
}  // namespace shutterlab
