#include "io/image_check.h"

#include "io/codecs.h"

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <memory>
#include <regex>
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

// The warnings that mean the coded data is cut or damaged; JWRN_EXTRANEOUS_DATA only before a
// marker other than the end of the image (some encoders pad before it).
constexpr int kDamageWarnings[] = {
    JWRN_JPEG_EOF,         // Premature end of JPEG file
    JWRN_HIT_MARKER,       // Corrupt JPEG data: premature end of data segment
    JWRN_MUST_RESYNC,      // Corrupt JPEG data: found marker 0x.. instead of RST.
    JWRN_HUFF_BAD_CODE,    // Corrupt JPEG data: bad Huffman code
    JWRN_ARITH_BAD_CODE,   // Corrupt JPEG data: bad arithmetic code
    JWRN_EXTRANEOUS_DATA,  // Corrupt JPEG data: N extraneous bytes before marker 0x..
};
constexpr unsigned kEndOfImageMarker = 0xD9;

bool MeansDamage(int code, unsigned marker) {
  if (code == JWRN_EXTRANEOUS_DATA) return marker != kEndOfImageMarker;
  return std::find(std::begin(kDamageWarnings), std::end(kDamageWarnings), code) !=
         std::end(kDamageWarnings);
}

void KeepFirstMessage(j_common_ptr info, int level) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  const jpeg_error_mgr& err = *info->err;
  if (level >= 0 || !errors->first.empty() ||
      !MeansDamage(err.msg_code, static_cast<unsigned>(err.msg_parm.i[1]))) {
    return;
  }
  char text[JMSG_LENGTH_MAX];
  info->err->format_message(info, text);
  errors->first = text;
}

void JumpOnError(j_common_ptr info) {
  std::longjmp(reinterpret_cast<JpegErrors*>(info->err)->fatal, 1);
}

std::string OiioProblem(const std::string& path);

// The JPEG decode itself. No C++ object with a destructor is made between setjmp and longjmp
// here. A fatal error (a file libjpeg cannot decode at all, or a kind it does not decode: 12-bit,
// lossless) is left to OpenImageIO's verdict.
std::string JpegProblem(std::FILE* file, const std::string& path) {
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
    return OiioProblem(path);
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
  while (row != nullptr && info.output_scanline < info.output_height) {
    JSAMPLE* line = row;
    jpeg_read_scanlines(&info, &line, 1);
  }
  if (row != nullptr) jpeg_finish_decompress(&info);
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

// Whether `text` is libjpeg's message `format` (e.g. "Corrupt JPEG data: %u extraneous bytes
// before marker 0x%02x"): its literal parts as they are, each printf conversion as the number it
// prints. *marker gets the number printed by a "0x%02x" (the marker of the warnings that name one).
bool MatchesMessage(const std::string& text, const std::string& format, unsigned* marker) {
  static const std::regex conversion("%[0-9]*[dux]");
  static const std::regex special(R"([.^$|()\[\]{}*+?\\])");
  std::string pattern;
  auto literal_start = format.cbegin();
  for (std::sregex_iterator it(format.begin(), format.end(), conversion), end; it != end; ++it) {
    const std::string literal(literal_start, format.cbegin() + it->position());
    pattern += std::regex_replace(literal, special, R"(\$&)");
    pattern += it->str().back() == 'x' ? "([0-9a-fA-F]+)" : "-?[0-9]+";
    literal_start = format.cbegin() + it->position() + it->length();
  }
  pattern += std::regex_replace(std::string(literal_start, format.cend()), special, R"(\$&)");
  std::smatch match;
  if (!std::regex_match(text, match, std::regex(pattern))) return false;
  if (match.size() > 1) *marker = static_cast<unsigned>(std::stoul(match[1].str(), nullptr, 16));
  return true;
}

}  // namespace

std::string JpegDamageIn(const std::string& decoder_warning) {
  // OpenImageIO's wording around libjpeg's message: "JPEG error: MESSAGE (\"PATH\")".
  const std::string prefix = "JPEG error: ";
  const size_t start = decoder_warning.find(prefix);
  if (start == std::string::npos) return "";
  std::string message = decoder_warning.substr(start + prefix.size());
  const size_t path = message.rfind(" (\"");
  if (path != std::string::npos) message.resize(path);
  jpeg_error_mgr table;
  jpeg_std_error(&table);
  for (const int code : kDamageWarnings) {
    unsigned marker = 0;
    if (MatchesMessage(message, table.jpeg_message_table[code], &marker)) {
      return MeansDamage(code, marker) ? message : "";
    }
  }
  return "";
}

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

}  // namespace shutterlab
