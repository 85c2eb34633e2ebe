#include "render/image_io.h"

#include "sim/check.h"

#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <unistd.h>

namespace shutterlab {
namespace {

// OIIO keeps a per-thread error string; read it whole (clearing it) after every failed call.
std::string OiioError(const std::string& fallback) {
  std::string message = OIIO::geterror();
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
  for (char& c : message) {
    if (c == '\n') c = ' ';
  }
  return message.empty() ? fallback : message;
}

int CvDepth(OIIO::TypeDesc::BASETYPE base) {
  switch (base) {
    case OIIO::TypeDesc::UINT8:
      return CV_8U;
    case OIIO::TypeDesc::HALF:
    case OIIO::TypeDesc::FLOAT:
    case OIIO::TypeDesc::DOUBLE:
      return CV_32F;
    default:
      return CV_16U;
  }
}

OIIO::TypeDesc OiioType(int depth) {
  switch (depth) {
    case CV_8U:
      return OIIO::TypeDesc::UINT8;
    case CV_16U:
      return OIIO::TypeDesc::UINT16;
    case CV_32F:
      return OIIO::TypeDesc::FLOAT;
    default:
      return OIIO::TypeDesc::UNKNOWN;
  }
}

// Reads all channels of the first subimage as `depth`.
cv::Mat ReadRaw(const std::string& path, int forced_depth, int* file_channels,
                std::vector<std::string>* channel_names) {
  OIIO::ImageSpec config;
  config.attribute("oiio:reorient", 0);  // no EXIF auto-rotation: rows stay sensor rows
  auto input = OIIO::ImageInput::open(path, &config);
  if (!input) throw IoError(IoMessage(path, 0, "cannot read image: " + OiioError("unknown error")));
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth != 1) {
    throw IoError(IoMessage(path, 0, "not a 2-D image"));
  }
  const int depth = forced_depth >= 0
                        ? forced_depth
                        : CvDepth(static_cast<OIIO::TypeDesc::BASETYPE>(spec.format.basetype));
  cv::Mat image(spec.height, spec.width, CV_MAKETYPE(depth, spec.nchannels));
  if (!input->read_image(0, 0, 0, spec.nchannels, OiioType(depth), image.data)) {
    throw IoError(IoMessage(path, 0, "cannot decode image: " + OiioError(input->geterror())));
  }
  *file_channels = spec.nchannels;
  if (channel_names) *channel_names = spec.channelnames;
  input->close();
  return image;
}

}  // namespace

cv::Mat ReadImage(const std::string& path) {
  int channels = 0;
  cv::Mat raw = ReadRaw(path, -1, &channels, nullptr);
  if (channels == 1 || channels == 3) return raw;
  if (channels == 4) {
    cv::Mat rgb;
    const int from_to[] = {0, 0, 1, 1, 2, 2};
    rgb.create(raw.rows, raw.cols, CV_MAKETYPE(raw.depth(), 3));
    cv::mixChannels(&raw, 1, &rgb, 1, from_to, 3);
    return rgb;
  }
  throw IoError(IoMessage(
      path, 0, "has " + std::to_string(channels) + " channels; expected grey, RGB or RGBA"));
}

cv::Mat ReadFloatImage(const std::string& path, std::vector<std::string>* channel_names) {
  int channels = 0;
  return ReadRaw(path, CV_32F, &channels, channel_names);
}

void WriteImage(const std::string& path, const cv::Mat& image,
                const std::vector<std::string>& channel_names) {
  SHUTTERLAB_CHECK(!image.empty()) << "cannot write an empty image to " << path;
  const OIIO::TypeDesc type = OiioType(image.depth());
  SHUTTERLAB_CHECK(type != OIIO::TypeDesc::UNKNOWN) << "unsupported pixel depth writing " << path;
  SHUTTERLAB_CHECK(channel_names.empty() ||
                   static_cast<int>(channel_names.size()) == image.channels())
      << "channel names do not match the channel count writing " << path;
  const std::filesystem::path target(path);
  // The temporary keeps the extension: OIIO chooses the format by it.
  const std::filesystem::path temp = target.parent_path() / (".tmp" + std::to_string(::getpid()) +
                                                             "_" + target.filename().string());
  OIIO::ImageSpec spec(image.cols, image.rows, image.channels(), type);
  if (!channel_names.empty()) spec.channelnames = channel_names;
  if (image.channels() == 4 && channel_names.empty()) spec.alpha_channel = 3;
  const std::string extension = target.extension().string();
  // zlib level 1: photographic textures barely compress further, and level 6 costs ~5x the time.
  if (extension == ".png" || extension == ".PNG") spec.attribute("png:compressionLevel", 1);
  if (extension == ".jpg" || extension == ".jpeg" || extension == ".JPG")
    spec.attribute("Compression", "jpeg:95");
  {
    auto output = OIIO::ImageOutput::create(temp.string());
    if (!output)
      throw IoError(IoMessage(path, 0, "cannot write image: " + OiioError("unknown format")));
    cv::Mat contiguous = image.isContinuous() ? image : image.clone();
    const bool ok = output->open(temp.string(), spec) &&
                    output->write_image(type, contiguous.data) && output->close();
    if (!ok) {
      const std::string message = OiioError(output->geterror());
      std::error_code ec;
      std::filesystem::remove(temp, ec);
      throw IoError(IoMessage(path, 0, "cannot write image: " + message));
    }
  }
  std::error_code ec;
  std::filesystem::rename(temp, target, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    throw IoError(IoMessage(path, 0, "cannot write image: rename failed"));
  }
}

}  // namespace shutterlab
