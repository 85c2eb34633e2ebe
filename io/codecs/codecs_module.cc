#include "io/codecs/codecs_module.h"

#include <OpenImageIO/imageio.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <vector>

namespace shutterlab::codecs {
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

SampleType FromOiio(OIIO::TypeDesc::BASETYPE base) {
  switch (base) {
    case OIIO::TypeDesc::UINT8:
      return SampleType::kUint8;
    case OIIO::TypeDesc::UINT16:
      return SampleType::kUint16;
    case OIIO::TypeDesc::HALF:
      return SampleType::kHalf;
    case OIIO::TypeDesc::FLOAT:
      return SampleType::kFloat;
    case OIIO::TypeDesc::DOUBLE:
      return SampleType::kDouble;
    default:
      return SampleType::kOther;
  }
}

OIIO::TypeDesc ToOiio(SampleType type) {
  switch (type) {
    case SampleType::kUint8:
      return OIIO::TypeDesc::UINT8;
    case SampleType::kUint16:
      return OIIO::TypeDesc::UINT16;
    case SampleType::kHalf:
      return OIIO::TypeDesc::HALF;
    case SampleType::kFloat:
      return OIIO::TypeDesc::FLOAT;
    case SampleType::kDouble:
      return OIIO::TypeDesc::DOUBLE;
    default:
      return OIIO::TypeDesc::UNKNOWN;
  }
}

int CvDepth(SampleType type) {
  switch (type) {
    case SampleType::kUint8:
      return CV_8U;
    case SampleType::kUint16:
      return CV_16U;
    case SampleType::kFloat:
      return CV_32F;
    default:
      return -1;
  }
}

// Opens path with EXIF auto-rotation off and fills *header; nullptr and *error when it cannot.
std::unique_ptr<OIIO::ImageInput> OpenImage(const std::string& path, ImageHeader* header,
                                            std::string* error) {
  OIIO::ImageSpec config;
  config.attribute("oiio:reorient", 0);  // rows stay sensor rows
  auto input = OIIO::ImageInput::open(path, &config);
  if (!input) {
    *error = OiioError("unknown error");
    return nullptr;
  }
  const OIIO::ImageSpec& spec = input->spec();
  header->format = input->format_name();
  header->width = spec.width;
  header->height = spec.height;
  header->depth = spec.depth;
  header->channels = spec.nchannels;
  header->sample_type = FromOiio(static_cast<OIIO::TypeDesc::BASETYPE>(spec.format.basetype));
  header->bytes_per_sample = static_cast<int>(spec.format.size());
  header->compression = spec.get_string_attribute("Compression");
  header->jpeg_subsampling = spec.get_string_attribute("jpeg:subsampling");
  header->channel_names = spec.channelnames;
  return input;
}

std::string ReadHeader(const std::string& path, ImageHeader* header) {
  std::string error;
  auto input = OpenImage(path, header, &error);
  if (input) input->close();
  return error;
}

std::string ReadImage(const std::string& path, SampleType as, cv::Mat* image, ImageHeader* header,
                      std::string* complaint) {
  try {
    std::string error;
    auto input = OpenImage(path, header, &error);
    if (!input) return error;
    if (CvDepth(as) < 0) return "cannot read samples as this type";
    image->create(header->height, header->width, CV_MAKETYPE(CvDepth(as), header->channels));
    if (!input->read_image(0, 0, 0, header->channels, ToOiio(as), image->data)) {
      const std::string error = OiioError(input->geterror());
      return error.empty() ? "the image data cannot be decoded" : error;
    }
    *complaint = input->geterror();
    input->close();
    return "";
  } catch (const std::exception& e) {  // memory, from create or the decoder
    return e.what();
  }
}

std::string WriteImage(const std::string& path, const cv::Mat& image,
                       const ImageWriteSettings& settings) {
  try {
    const SampleType in_memory = image.depth() == CV_8U    ? SampleType::kUint8
                                 : image.depth() == CV_16U ? SampleType::kUint16
                                 : image.depth() == CV_32F ? SampleType::kFloat
                                                           : SampleType::kOther;
    if (in_memory == SampleType::kOther || !image.isContinuous()) return "unsupported pixel layout";
    OIIO::ImageSpec spec(image.cols, image.rows, image.channels(), ToOiio(settings.file_type));
    if (!settings.channel_names.empty()) spec.channelnames = settings.channel_names;
    if (settings.alpha_channel >= 0) spec.alpha_channel = settings.alpha_channel;
    if (!settings.compression.empty()) spec.attribute("Compression", settings.compression);
    if (!settings.jpeg_subsampling.empty())
      spec.attribute("jpeg:subsampling", settings.jpeg_subsampling);
    if (settings.png_compression_level >= 0)
      spec.attribute("png:compressionLevel", settings.png_compression_level);
    if (settings.png_filter != 0) spec.attribute("png:filter", settings.png_filter);
    auto output = OIIO::ImageOutput::create(path);
    if (!output) return OiioError("unknown format");
    const bool ok = output->open(path, spec) &&
                    output->write_image(ToOiio(in_memory), image.data) && output->close();
    if (ok) return "";
    const std::string error = OiioError(output->geterror());
    return error.empty() ? "the writer failed" : error;
  } catch (const std::exception& e) {
    return e.what();
  }
}

bool Encode(const std::string& extension, const cv::Mat& bgr, std::vector<uchar>* bytes) {
  try {
    return cv::imencode(extension, bgr, *bytes);
  } catch (const std::exception&) {  // cv::Exception for a format or type OpenCV refuses
    return false;
  }
}

void* OpenVideo(const std::string& path) {
  try {
    auto capture = std::make_unique<cv::VideoCapture>(path);
    return capture->isOpened() ? capture.release() : nullptr;
  } catch (const std::exception&) {
    return nullptr;
  }
}

bool ReadVideoFrame(void* video, cv::Mat* bgr, double* position_ms) {
  try {
    auto* capture = static_cast<cv::VideoCapture*>(video);
    if (!capture->read(*bgr) || bgr->empty()) return false;
    *position_ms = capture->get(cv::CAP_PROP_POS_MSEC);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

void CloseVideo(void* video) { delete static_cast<cv::VideoCapture*>(video); }

}  // namespace
}  // namespace shutterlab::codecs

extern "C" __attribute__((visibility("default"))) const shutterlab::codecs::Functions*
shutterlab_codecs() {
  using namespace shutterlab::codecs;
  static const Functions functions{kCodecsVersion, ReadHeader, ReadImage,      WriteImage,
                                   Encode,         OpenVideo,  ReadVideoFrame, CloseVideo};
  return &functions;
}
