#include "io/image_check.h"

#include "io/codecs.h"

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <vector>

// jpeglib.h needs FILE and size_t declared before it.
#include <jpeglib.h>
// After jpeglib.h: the message codes of its warnings.
#include <jerror.h>

namespace shutterlab {
namespace {

// libjpeg reports through these: a fatal error jumps back to the decode; a warning that means
// the coded data is cut or damaged is kept as the first complaint. Other warnings (an unknown JFIF
// revision, padding before the end marker that some encoders write) leave the pixels whole.
struct JpegErrors {
  jpeg_error_mgr manager;  // first: libjpeg casts the pointer it is given
  std::jmp_buf fatal;
  std::string first;
};

bool MeansDamage(const jpeg_error_mgr& err) {
  switch (err.msg_code) {
    case JWRN_JPEG_EOF:        // Premature end of JPEG file
    case JWRN_HIT_MARKER:      // Corrupt JPEG data: premature end of data segment
    case JWRN_MUST_RESYNC:     // Corrupt JPEG data: found marker instead of RST
    case JWRN_HUFF_BAD_CODE:   // Corrupt JPEG data: bad Huffman code
    case JWRN_ARITH_BAD_CODE:  // Corrupt JPEG data: bad arithmetic code
      return true;
    case JWRN_EXTRANEOUS_DATA:  // N extraneous bytes before marker M: harmless before EOI only
      return err.msg_parm.i[1] != 0xD9;
    default:
      return false;
  }
}

void KeepFirstMessage(j_common_ptr info, int level) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  if (level >= 0 || !errors->first.empty() || !MeansDamage(*info->err)) return;
  char text[JMSG_LENGTH_MAX];
  info->err->format_message(info, text);
  errors->first = text;
}

void JumpOnError(j_common_ptr info) {
  std::longjmp(reinterpret_cast<JpegErrors*>(info->err)->fatal, 1);
}

std::string OiioProblem(const std::string& path);

// A JPEG decoded by libjpeg at 1/8, 1/4 or 1/2 size (the smallest of its DCT scales that keeps
// min_width columns, else whole), its rows into pixels (grey or R, G, B), or read and dropped when
// pixels is null: then the check's quick settings (fast DCT, no fancy upsampling), as every coded
// bit is read either way. False when libjpeg cannot decode it at all (damage past its warnings,
// 12-bit, lossless; CMYK for pixels); errors->first holds its first complaint of damage. No C++
// object with a destructor is made between setjmp and longjmp here.
bool DecodeJpeg(std::FILE* file, int min_width, cv::Mat* pixels, JpegErrors* errors) {
  jpeg_decompress_struct info;
  info.err = jpeg_std_error(&errors->manager);
  errors->manager.emit_message = KeepFirstMessage;
  errors->manager.error_exit = JumpOnError;
  // volatile: set after setjmp and read after a longjmp back to it.
  JSAMPLE* volatile row = nullptr;
  if (setjmp(errors->fatal) != 0) {
    std::free(row);
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_create_decompress(&info);
  jpeg_stdio_src(&info, file);
  jpeg_read_header(&info, TRUE);
  info.scale_num = 1;
  info.scale_denom = 1;
  for (const unsigned denom : {8u, 4u, 2u}) {
    if ((info.image_width + denom - 1) / denom >= static_cast<unsigned>(std::max(1, min_width))) {
      info.scale_denom = denom;
      break;
    }
  }
  if (pixels == nullptr) {
    info.dct_method = JDCT_IFAST;
    info.do_fancy_upsampling = FALSE;
  } else if (info.jpeg_color_space != JCS_GRAYSCALE) {
    if (info.num_components != 3) {
      jpeg_destroy_decompress(&info);
      return false;
    }
    info.out_color_space = JCS_RGB;
  }
  jpeg_start_decompress(&info);
  if (pixels != nullptr) {
    try {  // no libjpeg call in here: a longjmp never crosses it
      pixels->create(static_cast<int>(info.output_height), static_cast<int>(info.output_width),
                     CV_8UC(info.output_components));
    } catch (...) {
      jpeg_destroy_decompress(&info);
      throw;
    }
  } else {
    row = static_cast<JSAMPLE*>(
        std::malloc(static_cast<size_t>(info.output_width) * info.output_components));
    if (row == nullptr) {
      jpeg_destroy_decompress(&info);
      throw std::bad_alloc();
    }
  }
  while (info.output_scanline < info.output_height) {
    JSAMPLE* line =
        pixels != nullptr ? pixels->ptr<JSAMPLE>(static_cast<int>(info.output_scanline)) : row;
    jpeg_read_scanlines(&info, &line, 1);
  }
  jpeg_finish_decompress(&info);
  std::free(row);
  jpeg_destroy_decompress(&info);
  return true;
}

// The decode of every coded bit at 1/8 size, its first complaint of damage; one libjpeg cannot
// decode at all (or a kind it does not decode: 12-bit, lossless) is left to OpenImageIO's verdict.
std::string JpegProblem(std::FILE* file, const std::string& path) {
  JpegErrors errors;
  if (!DecodeJpeg(file, 1, nullptr, &errors)) return OiioProblem(path);
  return errors.first;
}

bool StartsLikeJpeg(std::FILE* file) {
  unsigned char magic[3] = {0, 0, 0};
  const bool jpeg = std::fread(magic, 1, 3, file) == 3 && magic[0] == 0xFF && magic[1] == 0xD8 &&
                    magic[2] == 0xFF;
  std::rewind(file);
  return jpeg;
}

std::string OiioProblem(const std::string& path) {
  codecs::ImageHeader header;
  const std::string error = Codecs().read_header(path, &header);
  if (!error.empty()) return error;
  // A frame too large to hold is not checked (its metadata said so much already).
  if (static_cast<double>(header.width) * header.height * header.channels > 2e9) return "";
  cv::Mat pixels;
  std::string complaint;
  const std::string failure =
      Codecs().read_image(path, codecs::SampleType::kUint8, &pixels, &header, &complaint);
  return failure.empty() ? complaint : failure;
}

}  // namespace

std::string UndecodableImageText(const std::string& problem) {
  return "its image data does not decode (" + problem +
         "): a cut or damaged file; copy it from the card again";
}

std::string ImageDataProblem(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file) return "cannot be opened";
  try {
    if (StartsLikeJpeg(file.get())) return JpegProblem(file.get(), path);
    file.reset();
    return OiioProblem(path);
  } catch (const std::exception&) {
    return "";  // a decoder that could not run (memory) says nothing of the file
  }
}

std::optional<cv::Mat> ReadJpegScaled(const std::string& path, int min_width) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file || !StartsLikeJpeg(file.get())) return std::nullopt;
  JpegErrors errors;
  cv::Mat pixels;
  if (!DecodeJpeg(file.get(), min_width, &pixels, &errors)) return std::nullopt;
  return pixels;
}

}  // namespace shutterlab
