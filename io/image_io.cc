#include "io/image_io.h"

#include "io/exiv2_setup.h"
#include "sim/check.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <exiv2/exiv2.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
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

namespace {

// Writes image (in-memory type from its depth) as `file_type` to a temporary file beside path (the
// extension kept: OpenImageIO chooses the format by it), lets configure set the spec and finish add
// to the written file, then renames it to path. Nothing is left behind on failure.
void WriteThroughTemp(const std::string& path, const cv::Mat& image, OIIO::TypeDesc file_type,
                      const std::function<void(OIIO::ImageSpec*)>& configure,
                      const std::function<void(const std::string&)>& finish) {
  SHUTTERLAB_CHECK(!image.empty()) << "cannot write an empty image to " << path;
  const OIIO::TypeDesc type = OiioType(image.depth());
  SHUTTERLAB_CHECK(type != OIIO::TypeDesc::UNKNOWN) << "unsupported pixel depth writing " << path;
  const std::filesystem::path target(path);
  const std::filesystem::path temp = target.parent_path() / (".tmp" + std::to_string(::getpid()) +
                                                             "_" + target.filename().string());
  OIIO::ImageSpec spec(image.cols, image.rows, image.channels(), file_type);
  if (configure) configure(&spec);
  const auto remove_temp = [&temp] {
    std::error_code ec;
    std::filesystem::remove(temp, ec);
  };
  {
    auto output = OIIO::ImageOutput::create(temp.string());
    if (!output)
      throw IoError(IoMessage(path, 0, "cannot write image: " + OiioError("unknown format")));
    cv::Mat contiguous = image.isContinuous() ? image : image.clone();
    const bool ok = output->open(temp.string(), spec) &&
                    output->write_image(type, contiguous.data) && output->close();
    if (!ok) {
      const std::string message = OiioError(output->geterror());
      remove_temp();
      throw IoError(IoMessage(path, 0, "cannot write image: " + message));
    }
  }
  try {
    if (finish) finish(temp.string());
  } catch (...) {
    remove_temp();
    throw;
  }
  std::error_code ec;
  std::filesystem::rename(temp, target, ec);
  if (ec) {
    remove_temp();
    throw IoError(IoMessage(path, 0, "cannot write image: rename failed"));
  }
}

bool IsJpegPath(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
  return extension == ".jpg" || extension == ".jpeg";
}

}  // namespace

void WriteImage(const std::string& path, const cv::Mat& image,
                const std::vector<std::string>& channel_names) {
  SHUTTERLAB_CHECK(channel_names.empty() ||
                   static_cast<int>(channel_names.size()) == image.channels())
      << "channel names do not match the channel count writing " << path;
  const std::string extension = std::filesystem::path(path).extension().string();
  WriteThroughTemp(path, image, OiioType(image.depth()),
                   [&](OIIO::ImageSpec* spec) {
                     if (!channel_names.empty()) spec->channelnames = channel_names;
                     if (image.channels() == 4 && channel_names.empty()) spec->alpha_channel = 3;
                     // zlib level 1: photographic textures barely compress further, and level 6
                     // costs ~5x.
                     if (extension == ".png" || extension == ".PNG")
                       spec->attribute("png:compressionLevel", 1);
                     if (IsJpegPath(path)) spec->attribute("Compression", "jpeg:95");
                   },
                   {});
}

namespace {

// The JPEG standard's luminance quantisation table (ITU-T T.81 Annex K, Table K.1), natural order.
constexpr std::array<int, 64> kStandardLuminance = {
    16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
    14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
    18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
    49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};
// Natural position of the k-th coefficient in a DQT segment (zig-zag order).
constexpr std::array<int, 64> kZigZag = {
    0,  1,  8,  16, 9,  2,  3,  10, 17, 24, 32, 25, 18, 11, 4,  5,  12, 19, 26, 33, 40, 48,
    41, 34, 27, 20, 13, 6,  7,  14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23,
    30, 37, 44, 51, 58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63};

// The luminance table (id 0) of a JPEG file, natural order; nullopt when there is none before the
// first scan, or the file is not a well-formed JPEG up to there. Reads marker segments only.
std::optional<std::array<int, 64>> JpegLuminanceTable(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const auto byte = [&in]() -> int {
    const int c = in.get();
    return c == EOF ? -1 : c;
  };
  if (byte() != 0xFF || byte() != 0xD8) return std::nullopt;
  while (in) {
    int marker = byte();
    if (marker != 0xFF) return std::nullopt;
    while (marker == 0xFF) marker = byte();                                   // fill bytes
    if (marker < 0 || marker == 0xDA || marker == 0xD9) return std::nullopt;  // scan or end
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;       // no length
    const int high = byte(), low = byte();
    if (high < 0 || low < 0) return std::nullopt;
    int remaining = (high << 8 | low) - 2;
    if (remaining < 0) return std::nullopt;
    if (marker != 0xDB) {
      in.seekg(remaining, std::ios::cur);
      continue;
    }
    while (remaining > 0) {
      const int pq_tq = byte();
      const bool sixteen_bit = (pq_tq >> 4) != 0;
      std::array<int, 64> table{};
      for (int k = 0; k < 64; ++k) {
        const int first = byte(), second = sixteen_bit ? byte() : 0;
        if (pq_tq < 0 || first < 0 || second < 0) return std::nullopt;
        table[kZigZag[k]] = sixteen_bit ? (first << 8 | second) : first;
      }
      remaining -= 1 + (sixteen_bit ? 128 : 64);
      if ((pq_tq & 0x0F) == 0) return table;
    }
  }
  return std::nullopt;
}

// The IJG quality (1..100) whose luminance table is nearest `table` (libjpeg's jpeg_set_quality
// with baseline tables: scale 5000 / q below 50, 200 - 2 q from 50, entries clamped to 1..255).
int NearestIjgQuality(const std::array<int, 64>& table) {
  int best_quality = 0;
  long best_distance = -1;
  for (int quality = 1; quality <= 100; ++quality) {
    const long scale = quality < 50 ? 5000 / quality : 200 - 2 * quality;
    long distance = 0;
    for (int k = 0; k < 64; ++k) {
      const long entry = std::clamp((kStandardLuminance[k] * scale + 50) / 100, 1L, 255L);
      distance += std::abs(entry - table[k]);
    }
    if (best_distance < 0 || distance < best_distance) {
      best_distance = distance;
      best_quality = quality;
    }
  }
  return best_quality;
}

}  // namespace

ImageFileInfo ReadImageFileInfo(const std::string& path) {
  OIIO::ImageSpec config;
  config.attribute("oiio:reorient", 0);
  auto input = OIIO::ImageInput::open(path, &config);
  if (!input) throw IoError(IoMessage(path, 0, "cannot read image: " + OiioError("unknown error")));
  const OIIO::ImageSpec& spec = input->spec();
  ImageFileInfo info;
  info.format = input->format_name();
  info.width = spec.width;
  info.height = spec.height;
  info.channels = spec.nchannels;
  const OIIO::TypeDesc::BASETYPE base = static_cast<OIIO::TypeDesc::BASETYPE>(spec.format.basetype);
  info.floating = base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT ||
                  base == OIIO::TypeDesc::DOUBLE;
  info.bits_per_channel = static_cast<int>(spec.format.size()) * 8;
  if (!info.floating && info.bits_per_channel > 16) info.bits_per_channel = 16;  // as ReadImage
  if (base == OIIO::TypeDesc::DOUBLE) info.bits_per_channel = 32;
  info.compression = spec.get_string_attribute("Compression");
  input->close();
  if (info.format == "jpeg") {
    info.jpeg_subsampling = spec.get_string_attribute("jpeg:subsampling");
    if (const auto table = JpegLuminanceTable(path)) info.jpeg_quality = NearestIjgQuality(*table);
  }
  return info;
}

namespace {

// Every exiv2 call of this unit runs under this lock, after the shared set-up
// (io/exiv2_setup.h): copying metadata is rare next to reading it, and is kept to one thread
// at a time as a precaution. Reading photos (photo_metadata) needs only the set-up's XMP lock.
std::mutex& Exiv2Lock() {
  static std::mutex lock;
  return lock;
}

// Copies like's EXIF, IPTC and XMP into the file at `temp` and sets `xmp`; notes on `path`.
std::vector<std::string> CopyMetadata(const std::string& path, const std::string& temp,
                                      const std::string& like,
                                      const std::vector<std::pair<std::string, std::string>>& xmp) {
  std::vector<std::string> notes;
  const std::lock_guard<std::mutex> guard(Exiv2Lock());
  internal::InitialiseExiv2();
  try {
    if (Exiv2::ImageFactory::getType(temp) == Exiv2::ImageType::none) {
      notes.push_back(path + ": this format holds no EXIF or XMP: metadata of " + like +
                      " not copied");
      return notes;
    }
    auto target = Exiv2::ImageFactory::open(temp);
    target->readMetadata();
    const auto writes = [&target](Exiv2::MetadataId id) {
      return (target->checkMode(id) & Exiv2::amWrite) != 0;
    };
    if (!like.empty() && Exiv2::ImageFactory::getType(like) != Exiv2::ImageType::none) {
      auto source = Exiv2::ImageFactory::open(like);
      source->readMetadata();
      if (writes(Exiv2::mdExif)) {
        target->setExifData(source->exifData());
      } else if (!source->exifData().empty()) {
        notes.push_back(path + ": this format holds no EXIF: EXIF of " + like + " not copied");
      }
      if (writes(Exiv2::mdIptc)) target->setIptcData(source->iptcData());
      if (writes(Exiv2::mdXmp)) {
        target->setXmpData(source->xmpData());
      } else if (!source->xmpData().empty()) {
        notes.push_back(path + ": this format holds no XMP: XMP of " + like + " not copied");
      }
    }
    if (writes(Exiv2::mdXmp)) {
      for (const auto& [key, value] : xmp) target->xmpData()[key] = value;
    }
    target->writeMetadata();
  } catch (const Exiv2::AnyError& e) {
    throw IoError(IoMessage(path, 0, std::string("cannot copy metadata: ") + e.what()));
  }
  return notes;
}

}  // namespace

std::vector<std::string> WriteImageLike(
    const std::string& path, const cv::Mat& image, const ImageLike& like,
    const std::vector<std::pair<std::string, std::string>>& xmp) {
  const ImageFileInfo& info = like.info;
  OIIO::TypeDesc file_type = OiioType(image.depth());
  if (info.floating && info.bits_per_channel == 16 && image.depth() == CV_32F) {
    file_type = OIIO::TypeDesc::HALF;
  }
  std::vector<std::string> notes;
  WriteThroughTemp(
      path, image, file_type,
      [&](OIIO::ImageSpec* spec) {
        if (IsJpegPath(path)) {
          spec->attribute("Compression", "jpeg:" + std::to_string(info.jpeg_quality.value_or(95)));
          if (!info.jpeg_subsampling.empty()) {
            spec->attribute("jpeg:subsampling", info.jpeg_subsampling);
          }
        } else if (!info.compression.empty() && info.format != "jpeg") {
          spec->attribute("Compression", info.compression);
        }
      },
      [&](const std::string& temp) { notes = CopyMetadata(path, temp, like.path, xmp); });
  return notes;
}

std::vector<std::pair<std::string, std::string>> ReadImageMetadata(const std::string& path) {
  if (!std::filesystem::exists(path)) throw IoError(IoMessage(path, 0, "no such file"));
  std::vector<std::pair<std::string, std::string>> out;
  const std::lock_guard<std::mutex> guard(Exiv2Lock());
  internal::InitialiseExiv2();
  try {
    if (Exiv2::ImageFactory::getType(path) == Exiv2::ImageType::none) return out;
    auto image = Exiv2::ImageFactory::open(path);
    image->readMetadata();
    for (const Exiv2::Exifdatum& d : image->exifData()) out.emplace_back(d.key(), d.toString());
    for (const Exiv2::Iptcdatum& d : image->iptcData()) out.emplace_back(d.key(), d.toString());
    for (const Exiv2::Xmpdatum& d : image->xmpData()) out.emplace_back(d.key(), d.toString());
  } catch (const Exiv2::AnyError& e) {
    throw IoError(IoMessage(path, 0, std::string("cannot read metadata: ") + e.what()));
  }
  return out;
}

}  // namespace shutterlab
