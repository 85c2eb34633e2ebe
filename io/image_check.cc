#include "io/image_check.h"

#include <OpenImageIO/imageio.h>

#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

// jpeglib.h needs FILE and size_t declared before it.
#include <jpeglib.h>

namespace shutterlab {
namespace {

// libjpeg reports through these: a fatal error jumps back to the decode, a warning (a corrupt or
// cut stream that libjpeg would fill in grey) is kept as the first complaint.
struct JpegErrors {
  jpeg_error_mgr manager;  // first: libjpeg casts the pointer it is given
  std::jmp_buf fatal;
  std::string first;
};

void KeepFirstMessage(j_common_ptr info, int level) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  if (level >= 0 || !errors->first.empty()) return;  // trace messages, or a later warning
  char text[JMSG_LENGTH_MAX];
  info->err->format_message(info, text);
  errors->first = text;
}

void JumpOnError(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  if (errors->first.empty()) {
    char text[JMSG_LENGTH_MAX];
    info->err->format_message(info, text);
    errors->first = text;
  }
  std::longjmp(errors->fatal, 1);
}

// The JPEG decode itself. No C++ object with a destructor lives between setjmp and longjmp here.
std::string JpegProblem(std::FILE* file) {
  jpeg_decompress_struct info;
  JpegErrors errors;
  info.err = jpeg_std_error(&errors.manager);
  errors.manager.emit_message = KeepFirstMessage;
  errors.manager.error_exit = JumpOnError;
  // volatile: set after setjmp and read after a longjmp back to it.
  JSAMPLE* volatile row = nullptr;
  if (setjmp(errors.fatal) != 0) {
    std::free(row);
    jpeg_destroy_decompress(&info);
    return errors.first;
  }
  jpeg_create_decompress(&info);
  jpeg_stdio_src(&info, file);
  jpeg_read_header(&info, TRUE);
  info.scale_num = 1;
  info.scale_denom = 8;
  info.dct_method = JDCT_IFAST;
  info.do_fancy_upsampling = FALSE;
  jpeg_start_decompress(&info);
  row = static_cast<JSAMPLE*>(
      std::malloc(static_cast<size_t>(info.output_width) * info.output_components));
  while (info.output_scanline < info.output_height) {
    JSAMPLE* line = row;
    jpeg_read_scanlines(&info, &line, 1);
  }
  jpeg_finish_decompress(&info);
  std::free(row);
  jpeg_destroy_decompress(&info);
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
  auto input = OIIO::ImageInput::open(path);
  if (!input) return OIIO::geterror();
  const OIIO::ImageSpec& spec = input->spec();
  std::vector<unsigned char> pixels(static_cast<size_t>(spec.width) * spec.height *
                                    spec.nchannels);
  const bool read = input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8,
                                      pixels.data());
  const std::string error = input->geterror();
  if (!error.empty()) return error;
  return read ? "" : "the image data cannot be decoded";
}

}  // namespace

std::string ImageDataProblem(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return "cannot be opened";
  std::string problem;
  if (StartsLikeJpeg(file)) {
    problem = JpegProblem(file);
    std::fclose(file);
  } else {
    std::fclose(file);
    problem = OiioProblem(path);
  }
  return problem;
}

}  // namespace shutterlab
