#include "sim/logs/blackbox.h"

#include "sim/check.h"
#include "sim/logs/blackbox_codec.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <utility>

// The per-field helpers must inline into the frame loop for speed; GCC declines on its own.
#if defined(__GNUC__)
#define SHUTTERLAB_BLACKBOX_INLINE inline __attribute__((always_inline))
#else
#define SHUTTERLAB_BLACKBOX_INLINE inline
#endif

namespace shutterlab {
namespace {

using blackbox::ByteReader;

constexpr std::string_view kLogStartMarker =
    "H Product:Blackbox flight data recorder by Nicholas Sherlock\n";
// The firmware never writes a frame longer than this; a longer one is corrupt
// (blackbox-tools FLIGHT_LOG_MAX_FRAME_LENGTH).
constexpr size_t kMaxFrameBytes = 256;
// Header lines longer than this are garbage (the firmware's lines are well under 1 KiB).
constexpr size_t kMaxHeaderLineBytes = 1024;
// More fields than any firmware logs; bounds the per-frame arrays.
constexpr size_t kMaxFields = 256;
// A main frame whose time or iteration jumps further than this past the last accepted one is
// taken as corrupt (blackbox-tools MAXIMUM_TIME_JUMP_BETWEEN_FRAMES / _ITERATION_JUMP_).
constexpr int64_t kMaxTimeJumpUs = 10 * 1000000;
constexpr uint32_t kMaxIterationJump = 500 * 10;
constexpr uint32_t kNoIteration = std::numeric_limits<uint32_t>::max();
// Op code of a field with the increment predictor: it consumes no bytes.
constexpr uint8_t kIncrementOp = 255;
constexpr int kEventLogEnd = 255;  // firmware FLIGHT_LOG_EVENT_LOG_END
// Larger I intervals (never written by a firmware) are handled without the skip table.
constexpr int64_t kMaxTabulatedIInterval = 1 << 16;
// Bytes read between two hand-backs of the pages behind (MappedFile::ReleaseBefore): what a
// streamed file keeps resident.
constexpr size_t kReleaseEveryBytes = size_t{4} << 20;

// A blackbox file's bytes for as long as a stream reads them: a file mapped page by page
// (MappedFile::Paging::kStreamed; a pipe's bytes copied to a temporary file first), or a caller's
// buffer (owned or borrowed). The file is read front to back several times (the search for the
// logs, pass 1, pass 2); each reading hands its pages back behind it (ReleaseBefore starts again
// from the file's start for the next).
class BlackboxBytes {
 public:
  static std::unique_ptr<BlackboxBytes> OfMapped(std::unique_ptr<MappedFile> mapped) {
    auto bytes = std::make_unique<BlackboxBytes>(mapped->path());
    bytes->view_ = mapped->text();
    bytes->mapped_ = std::move(mapped);
    return bytes;
  }
  // Before another reading front to back: a file must still be what was mapped.
  void StartReading() { CheckUnchanged(); }
  static std::unique_ptr<BlackboxBytes> Owning(std::string content, const std::string& path) {
    auto bytes = std::make_unique<BlackboxBytes>(path);
    bytes->owned_ = std::move(content);
    bytes->view_ = bytes->owned_;
    return bytes;
  }
  static std::unique_ptr<BlackboxBytes> Borrowing(std::string_view content,
                                                  const std::string& path) {
    auto bytes = std::make_unique<BlackboxBytes>(path);
    bytes->view_ = content;
    return bytes;
  }
  explicit BlackboxBytes(std::string path) : path_(std::move(path)) {}

  std::string_view view() const { return view_; }
  const uint8_t* data() const { return reinterpret_cast<const uint8_t*>(view_.data()); }
  const std::string& path() const { return path_; }
  void ReleaseBefore(size_t offset) {
    if (mapped_) mapped_->ReleaseBefore(offset);
  }
  // A mapped file must still be what was mapped: one that grew (still being recorded), was
  // rewritten, or shrank (a page past its new end would kill the process with SIGBUS) is refused
  // in one line.
  void CheckUnchanged() const {
    if (mapped_) mapped_->CheckUnchanged();
  }

 private:
  std::string path_;
  std::unique_ptr<MappedFile> mapped_;
  std::string owned_;
  std::string_view view_;
};

// The six frame kinds; 'H' is the GPS home frame once the header is over.
int FrameKind(int marker) {
  switch (marker) {
    case 'I':
      return 0;
    case 'P':
      return 1;
    case 'G':
      return 2;
    case 'H':
      return 3;
    case 'S':
      return 4;
    case 'E':
      return 5;
    default:
      return -1;
  }
}
constexpr int kKindI = 0, kKindP = 1, kKindG = 2, kKindH = 3, kKindS = 4, kKindE = 5;
constexpr int kDefinedKinds = 5;  // I P G H S have field definitions; E does not

// One decoding step: a single field or a group of fields sharing one tagged encoding.
struct Op {
  uint8_t encoding;
  uint8_t count;
  uint16_t first;
};

struct FrameDef {
  std::vector<std::string> names;
  std::vector<int> is_signed;
  std::vector<int> predictor;
  std::vector<int> encoding;
  bool has_names = false, has_predictor = false, has_encoding = false;
  bool usable = false;  // complete and compiled
  std::vector<Op> ops;
  size_t count() const { return names.size(); }
};

struct LogHeader {
  std::array<FrameDef, kDefinedKinds> defs;
  int data_version = 0;  // blackbox-tools' default when the line is absent
  int64_t i_interval = 32;
  int64_t p_num = 1;
  int64_t p_denom = 1;
  std::optional<std::string> firmware_type;
  std::string firmware_revision;
  std::string craft_name;
  std::optional<uint32_t> gyro_scale_bits;
  int64_t minthrottle = 1150;
  int64_t motor_output_low = 1150;
  int64_t vbatref = 4095;
  int idx_iteration = -1, idx_time = -1, idx_motor0 = -1;
  std::array<int, 3> idx_gyro{-1, -1, -1};
  std::array<int, 2> idx_home{-1, -1};
  bool has_gyro_unfilt = false;
  size_t data_begin = 0;  // first byte of the first data frame (== end when there is none)
};

// Lenient integer parse (atoi-like: leading spaces, sign, digits; 0 when none), as the reference
// reader parses header values. Saturates instead of overflowing.
int64_t ParseLeadingInt(std::string_view s) {
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  bool negative = false;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) negative = s[i++] == '-';
  int64_t value = 0;
  for (; i < s.size() && s[i] >= '0' && s[i] <= '9'; ++i) {
    if (value < (int64_t{1} << 40)) value = value * 10 + (s[i] - '0');
  }
  return negative ? -value : value;
}

std::vector<int> ParseIntList(std::string_view s) {
  std::vector<int> out;
  size_t start = 0;
  while (start <= s.size() && out.size() <= kMaxFields) {
    size_t comma = s.find(',', start);
    if (comma == std::string_view::npos) comma = s.size();
    out.push_back(static_cast<int>(ParseLeadingInt(s.substr(start, comma - start))));
    start = comma + 1;
  }
  return out;
}

std::vector<std::string> ParseNameList(std::string_view s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= s.size() && out.size() <= kMaxFields) {
    size_t comma = s.find(',', start);
    if (comma == std::string_view::npos) comma = s.size();
    out.emplace_back(s.substr(start, comma - start));
    start = comma + 1;
  }
  return out;
}

bool StartsWith(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && s.compare(0, prefix.size(), prefix) == 0;
}
bool EndsWith(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void ApplyHeaderLine(std::string_view name, std::string_view value, LogHeader* h) {
  if (StartsWith(name, "Field ") && name.size() > 7) {
    const int kind = FrameKind(static_cast<unsigned char>(name[6]));
    if (kind < 0 || kind >= kDefinedKinds) return;
    FrameDef& def = h->defs[kind];
    if (EndsWith(name, " name")) {
      def.names = ParseNameList(value);
      def.has_names = true;
      if (kind == kKindI) {  // P frames share the I frames' names and signedness
        h->defs[kKindP].names = def.names;
        h->defs[kKindP].has_names = true;
      }
    } else if (EndsWith(name, " signed")) {
      def.is_signed = ParseIntList(value);
      if (kind == kKindI) h->defs[kKindP].is_signed = def.is_signed;
    } else if (EndsWith(name, " predictor")) {
      def.predictor = ParseIntList(value);
      def.has_predictor = true;
    } else if (EndsWith(name, " encoding")) {
      def.encoding = ParseIntList(value);
      def.has_encoding = true;
    }
  } else if (name == "I interval") {
    h->i_interval = std::max<int64_t>(1, ParseLeadingInt(value));
  } else if (name == "P interval") {
    // "1/16" (num/denom) in older firmware; Betaflight 4 writes just the denominator ("16"),
    // read as 1/16 as blackbox-log-viewer does (flightlog_parser.js, "P interval" handler).
    const size_t slash = value.find('/');
    if (slash != std::string_view::npos) {
      h->p_num = ParseLeadingInt(value.substr(0, slash));
      h->p_denom = ParseLeadingInt(value.substr(slash + 1));
    } else {
      h->p_num = 1;
      h->p_denom = ParseLeadingInt(value);
    }
  } else if (name == "Data version") {
    h->data_version = static_cast<int>(ParseLeadingInt(value));
  } else if (name == "Firmware type") {
    h->firmware_type = std::string(value);
  } else if (name == "Firmware revision") {
    h->firmware_revision = std::string(value);
  } else if (name == "Craft name") {
    h->craft_name = std::string(value);
  } else if (name == "minthrottle") {
    h->minthrottle = ParseLeadingInt(value);
    h->motor_output_low = h->minthrottle;  // the newer motorOutput line overrides it
  } else if (name == "motorOutput") {
    h->motor_output_low = ParseLeadingInt(value);
  } else if (name == "vbatref") {
    h->vbatref = ParseLeadingInt(value);
  } else if (name == "gyro_scale" || name == "gyro.scale") {
    // The IEEE-754 bits of a float, in hex ("0x3f800000" = 1.0).
    std::string text(value);
    char* end = nullptr;
    const unsigned long bits = std::strtoul(text.c_str(), &end, 16);
    if (end != text.c_str()) h->gyro_scale_bits = static_cast<uint32_t>(bits);
  }
}

// Parses the header lines from `begin` up to the first data frame marker.
LogHeader ParseHeader(const uint8_t* data, size_t begin, size_t end) {
  LogHeader h;
  size_t pos = begin;
  while (pos < end) {
    const uint8_t c = data[pos];
    if (c == 'H') {
      if (pos + 1 < end && data[pos + 1] == ' ') {
        const size_t line_begin = pos + 2;
        const size_t limit = std::min(end, line_begin + kMaxHeaderLineBytes);
        size_t newline = line_begin;
        while (newline < limit && data[newline] != '\n' && data[newline] != 0) ++newline;
        if (newline < limit && data[newline] == '\n') {
          std::string_view line(reinterpret_cast<const char*>(data) + line_begin,
                                newline - line_begin);
          if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
          const size_t colon = line.find(':');
          if (colon != std::string_view::npos)
            ApplyHeaderLine(line.substr(0, colon), line.substr(colon + 1), &h);
          pos = newline + 1;
        } else {
          pos = newline;  // a broken line: resume at the byte that ended it
          if (pos == line_begin) ++pos;
        }
      } else {
        pos += 1;
      }
    } else if (FrameKind(c) >= 0) {
      break;  // the first data frame (never 'H' here: in the header 'H' starts a header line)
    } else {
      ++pos;  // garbage before the first frame is skipped, as the reference reader does
    }
  }
  h.data_begin = pos;
  return h;
}

bool KnownPredictor(int p) { return p >= 0 && p <= 11; }
bool KnownEncoding(int e) {
  switch (e) {
    case blackbox::kSignedVb:
    case blackbox::kUnsignedVb:
    case blackbox::kNeg14Bit:
    case blackbox::kTag8_8Svb:
    case blackbox::kTag2_3S32:
    case blackbox::kTag8_4S16:
    case blackbox::kNull:
    case blackbox::kTag2_3SVariable:
      return true;
    default:
      return false;
  }
}

// Checks a frame definition and compiles it to ops. Returns an empty string when usable, else the
// problem. `kind` selects the rules (main frames may not use the home-coordinate predictors).
std::string CompileFrameDef(int kind, const LogHeader& h, FrameDef* def) {
  const char kMarkers[] = "IPGHS";
  const std::string frame = std::string("'") + kMarkers[kind] + "' frame definition";
  const size_t n = def->count();
  if (n == 0) return frame + " has no fields";
  if (n > kMaxFields) return frame + " has more than " + std::to_string(kMaxFields) + " fields";
  if (def->predictor.size() != n || def->encoding.size() != n) {
    return frame + " has " + std::to_string(n) + " names but " +
           std::to_string(def->predictor.size()) + " predictors and " +
           std::to_string(def->encoding.size()) + " encodings";
  }
  def->is_signed.resize(n, 0);
  if (kind == kKindG) {
    // Home coordinates come in lat/lon pairs with the same predictor id; the second of a pair
    // predicts from the second home field (blackbox-tools flightLogParse does the same rewrite).
    for (size_t i = 1; i < n; ++i) {
      if (def->predictor[i - 1] == blackbox::kPredictHomeCoord &&
          def->predictor[i] == blackbox::kPredictHomeCoord) {
        def->predictor[i] = blackbox::kPredictHomeCoord1;
      }
    }
  }
  // Every field's predictor, the fields inside an encoded group too (a group's later field
  // predicted from motor[0] with no motor[0] field read before the ring buffer).
  for (size_t i = 0; i < n; ++i) {
    const int pred = def->predictor[i];
    if (pred != blackbox::kPredictHomeCoord1 && !KnownPredictor(pred)) {
      return frame + ": unsupported predictor " + std::to_string(pred) + " for field " +
             def->names[i];
    }
    if (pred == blackbox::kPredictMotor0 &&
        (h.idx_motor0 < 0 || h.idx_motor0 >= static_cast<int>(i) || kind == kKindG ||
         kind == kKindH || kind == kKindS)) {
      return frame + ": field " + def->names[i] +
             " is predicted from motor[0], which is not decoded before it";
    }
  }
  def->ops.clear();
  for (size_t i = 0; i < n;) {
    const int pred = def->predictor[i];
    const int enc = def->encoding[i];
    if (pred == blackbox::kPredictIncrement) {
      def->ops.push_back({kIncrementOp, 1, static_cast<uint16_t>(i)});
      ++i;
      continue;
    }
    if (!KnownEncoding(enc)) {
      return frame + ": unsupported encoding " + std::to_string(enc) + " for field " +
             def->names[i];
    }
    size_t count = 1;
    if (enc == blackbox::kTag8_4S16) count = 4;
    if (enc == blackbox::kTag2_3S32 || enc == blackbox::kTag2_3SVariable) count = 3;
    if (enc == blackbox::kTag8_8Svb) {
      while (count < 8 && i + count < n && def->encoding[i + count] == blackbox::kTag8_8Svb)
        ++count;
    }
    if (i + count > n) {
      return frame + ": encoding " + std::to_string(enc) + " of field " + def->names[i] +
             " needs " + std::to_string(count) + " fields but only " + std::to_string(n - i) +
             " remain";
    }
    for (size_t j = 1; j < count; ++j) {
      if (def->predictor[i + j] == blackbox::kPredictIncrement) {
        return frame + ": field " + def->names[i + j] +
               " uses the increment predictor inside an encoded group";
      }
    }
    def->ops.push_back(
        {static_cast<uint8_t>(enc), static_cast<uint8_t>(count), static_cast<uint16_t>(i)});
    i += count;
  }
  def->usable = true;
  return "";
}

// rad/s per gyroADC count. blackbox-tools parser.c (parseHeaderLine, "gyro_scale"): Baseflight
// writes a scale in rad/µs per count; every other firmware (Cleanflight, Betaflight, INAV all
// write "Firmware type:Cleanflight") writes deg/s per count, which the tool converts with
// `gyroScale * (M_PI / 180.0) * 0.000001`, and flightlogGyroToRadiansPerSecond then multiplies by
// 1e6. So: Baseflight rad/s = raw * scale * 1e6; otherwise rad/s = raw * scale * pi / 180.
// Betaflight >= 3 writes scale 1.0 (0x3f800000): gyroADC is in deg/s.
double GyroRadPerSecondPerLsb(const LogHeader& h, std::vector<LogWarning>* warnings) {
  float scale = 1.0f;
  if (h.gyro_scale_bits) {
    std::memcpy(&scale, &*h.gyro_scale_bits, sizeof(scale));
  }
  if (!h.gyro_scale_bits || !std::isfinite(scale) || scale <= 0.0f) {
    warnings->push_back(
        {"unit", "header has no usable gyro_scale; gyroADC taken as deg/s (Betaflight >= 3)"});
    scale = 1.0f;
  }
  const bool baseflight = h.firmware_type && *h.firmware_type != "Cleanflight";
  return baseflight ? static_cast<double>(scale) * 1e6 : static_cast<double>(scale) * kRadPerDeg;
}

// Identifies the fields the reader uses (blackbox-tools identifyMainFields).
void IdentifyFields(LogHeader* h) {
  const FrameDef& main = h->defs[kKindI];
  for (size_t i = 0; i < main.count(); ++i) {
    const std::string& name = main.names[i];
    const int index = static_cast<int>(i);
    if (name == "loopIteration")
      h->idx_iteration = index;
    else if (name == "time")
      h->idx_time = index;
    else if (name == "motor[0]")
      h->idx_motor0 = index;
    else if (StartsWith(name, "gyroUnfilt["))
      h->has_gyro_unfilt = true;
    for (int axis = 0; axis < 3; ++axis) {
      const std::string suffix = "[" + std::to_string(axis) + "]";
      if (name == "gyroADC" + suffix || name == "gyroData" + suffix) h->idx_gyro[axis] = index;
    }
  }
  const FrameDef& home = h->defs[kKindH];
  for (size_t i = 0; i < home.count(); ++i) {
    if (home.names[i] == "GPS_home[0]") h->idx_home[0] = static_cast<int>(i);
    if (home.names[i] == "GPS_home[1]") h->idx_home[1] = static_cast<int>(i);
  }
}

// Everything one log yields but its samples.
struct DecodedLog {
  BlackboxLogInfo info;
  int64_t first_t_ns = 0, last_t_ns = 0;  // of the first and last accepted main frame
  std::vector<LogWarning> warnings;
  size_t corrupt_frames = 0;
  size_t rejected_main_frames = 0;
  size_t unknown_events = 0;
  size_t logging_resumes = 0;
  std::string gyro_field;
  bool has_gyro_unfilt = false;
};

// The frame decoder of one log: header state, the three-frame main history, and the loop over
// the data that mirrors blackbox-tools' flightLogParse (a frame is accepted when the byte after it
// starts another frame or ends the log; otherwise it is corrupt and the search for the next frame
// restarts one byte after its start). The loop pauses once a chunk of samples is full and resumes
// where it stopped, so that the samples of a log of any length are handed on in bounded memory.
class LogDecoder {
 public:
  // bytes: the file, whose pages the decoder hands back behind itself.
  LogDecoder(BlackboxBytes* bytes, size_t end, LogHeader header, double rad_per_lsb)
      : bytes_(bytes), data_(bytes->data()), h_(std::move(header)), rad_per_lsb_(rad_per_lsb) {
    at_.pos = h_.data_begin;
    at_.end = end;
    const size_t n = h_.defs[kKindI].count();
    // The skip count after iteration k depends only on k mod the I interval: tabulate it once
    // (the direct count costs two 64-bit divisions per skipped iteration on every P frame).
    if (h_.i_interval <= kMaxTabulatedIInterval) {
      skip_table_.resize(static_cast<size_t>(h_.i_interval));
      for (int64_t k = 0; k < h_.i_interval; ++k) {
        skip_table_[k] = CountSkippedIterationsAfter(static_cast<uint32_t>(k));
      }
    }
    ring_.assign(3 * n, 0);
    n_main_ = n;
    for (int kind = kKindG; kind <= kKindS; ++kind)
      scratch_[kind].assign(h_.defs[kind].count() + 8, 0);
    home_.assign(h_.defs[kKindH].count() + 1, 0);
  }

  // Decodes on, counting into *out, until the log ends (true) or, when samples is given, it holds
  // max_samples (false: call again for more). Accepted main frames are appended to *samples.
  bool Run(DecodedLog* out, std::vector<GyroSample>* samples, size_t max_samples) {
    samples_ = samples;
    Cursor c = at_;  // in registers while the loop runs
    while (true) {
      if (samples && samples->size() >= max_samples) {
        at_ = c;
        return false;
      }
      if (c.pos >= release_at_) {
        // Pages behind the position are done with (a corrupt frame moves back at most
        // kMaxFrameBytes: such a page is read again, never wrongly).
        bytes_->ReleaseBefore(c.pos > kMaxFrameBytes ? c.pos - kMaxFrameBytes : 0);
        release_at_ = c.pos + kReleaseEveryBytes;
      }
      const int command = c.pos < c.end ? data_[c.pos++] : -1;
      if (c.have_last) {
        const size_t frame_size = (command < 0 ? c.pos : c.pos - 1) - c.frame_start;
        const bool next_starts_frame = command >= 0 && FrameKind(command) >= 0;
        const bool looks_complete = next_starts_frame || (command < 0 && !c.premature_eof);
        if (frame_size <= kMaxFrameBytes && looks_complete) {
          Complete(c.last_kind, out);
        } else {
          // Corrupt: resynchronise on the next plausible frame start after this frame's marker.
          // Frame starts only move forward, so the loop ends.
          ++out->corrupt_frames;
          main_valid_ = false;
          c.pos = c.frame_start + 1;
          c.have_last = false;
          c.premature_eof = false;
          continue;
        }
        c.have_last = false;
      }
      if (command < 0) break;
      c.frame_start = c.pos - 1;
      const int kind = FrameKind(command);
      if (kind >= 0 && (kind == kKindE || h_.defs[kind].usable)) {
        // A frame may not be longer than kMaxFrameBytes: reading stops there (and the frame is
        // corrupt), so one attempt costs at most that many bytes however garbled the input.
        ByteReader r{data_, c.pos, std::min(c.end, c.frame_start + kMaxFrameBytes), false};
        Parse(kind, &r);
        c.pos = r.pos;
        c.premature_eof = r.eof;
        if (kind == kKindE && event_valid_ && event_ == kEventLogEnd) c.end = c.pos;
        c.have_last = true;
        c.last_kind = kind;
      } else {
        main_valid_ = false;  // a byte that starts no known frame: the main stream lost sync
      }
    }
    at_ = c;
    return true;
  }

  // The byte the decoder has reached.
  size_t position() const { return at_.pos; }

 private:
  // Where the loop over the bytes stands between two calls of Run.
  struct Cursor {
    size_t pos = 0;
    size_t end = 0;  // a LOG_END event moves it to just after itself
    bool have_last = false;
    int last_kind = -1;
    size_t frame_start = 0;
    bool premature_eof = false;
  };

  int64_t* Slot(int index) { return index < 0 ? nullptr : ring_.data() + index * n_main_; }

  bool ShouldHaveFrame(uint32_t iteration) const {
    return static_cast<int64_t>((iteration % h_.i_interval + h_.p_num - 1) % h_.p_denom) < h_.p_num;
  }

  // Iterations the logging rate left out after iteration `last` (the increment predictor's step;
  // blackbox-tools countIntentionallySkippedFrames); bounded by the I interval, within which every
  // schedule logs at least one iteration.
  uint32_t CountSkippedIterationsAfter(uint32_t last) const {
    uint32_t count = 0;
    for (uint32_t i = last + 1; !ShouldHaveFrame(i) && count < h_.i_interval; ++i) ++count;
    return count;
  }
  uint32_t CountSkippedIterations() const {
    if (last_iteration_ == kNoIteration) return 0;
    if (!skip_table_.empty()) return skip_table_[last_iteration_ % skip_table_.size()];
    return CountSkippedIterationsAfter(last_iteration_);
  }

  SHUTTERLAB_BLACKBOX_INLINE int64_t Predict(int predictor, int64_t value, int field,
                                             const int64_t* current, const int64_t* prev,
                                             const int64_t* prev2) const {
    switch (predictor) {
      case blackbox::kPredictZero:
        return value;
      case blackbox::kPredictPrevious:
        return prev ? value + prev[field] : value;
      case blackbox::kPredictStraightLine:
        return prev ? value + 2 * prev[field] - prev2[field] : value;
      case blackbox::kPredictAverage2:
        return prev ? value + (prev[field] + prev2[field]) / 2 : value;
      case blackbox::kPredictMinThrottle:
        return value + h_.minthrottle;
      case blackbox::kPredictMotor0:
        return value + current[h_.idx_motor0];
      case blackbox::kPredict1500:
        return value + 1500;
      case blackbox::kPredictVbatRef:
        return value + h_.vbatref;
      case blackbox::kPredictMinMotor:
        return value + h_.motor_output_low;
      case blackbox::kPredictHomeCoord:
        return h_.idx_home[0] >= 0 ? value + home_[h_.idx_home[0]] : value;
      case blackbox::kPredictHomeCoord1:
        return h_.idx_home[1] >= 0 ? value + home_[h_.idx_home[1]] : value;
      case blackbox::kPredictLastMainFrameTime: {
        const int64_t* last = prev_ >= 0 ? ring_.data() + prev_ * n_main_ : nullptr;
        return last ? value + last[h_.idx_time] : value;
      }
      default:
        return value;  // unreachable: CompileFrameDef rejects unknown predictors
    }
  }

  // Decodes one frame's fields into `frame` (blackbox-tools parseFrame).
  void DecodeFields(const FrameDef& def, ByteReader* r, int64_t* frame, const int64_t* prev,
                    const int64_t* prev2, uint32_t skipped) {
    int32_t values[8];
    for (const Op& op : def.ops) {
      const int i = op.first;
      int64_t value;
      switch (op.encoding) {
        case kIncrementOp:
          frame[i] = static_cast<int64_t>(skipped) + 1 + (prev ? prev[i] : 0);
          continue;
        case blackbox::kSignedVb:
          value = r->ReadSignedVb();
          break;
        case blackbox::kUnsignedVb:
          value = r->ReadUnsignedVb();
          break;
        case blackbox::kNeg14Bit:
          value = r->ReadNeg14Bit();
          break;
        case blackbox::kNull:
          value = 0;
          break;
        case blackbox::kTag8_8Svb:
          r->ReadTag8_8Svb(values, op.count);
          ApplyGroup(def, op, values, frame, prev, prev2);
          continue;
        case blackbox::kTag2_3S32:
          r->ReadTag2_3S32(values);
          ApplyGroup(def, op, values, frame, prev, prev2);
          continue;
        case blackbox::kTag2_3SVariable:
          r->ReadTag2_3SVariable(values);
          ApplyGroup(def, op, values, frame, prev, prev2);
          continue;
        case blackbox::kTag8_4S16:
          if (h_.data_version < 2) {
            r->ReadTag8_4S16V1(values);
          } else {
            r->ReadTag8_4S16V2(values);
          }
          ApplyGroup(def, op, values, frame, prev, prev2);
          continue;
        default:
          value = 0;
          break;  // unreachable: CompileFrameDef rejects unknown encodings
      }
      value = Predict(def.predictor[i], value, i, frame, prev, prev2);
      // Single fields are 32 bits wide in the firmware: wrap as it does.
      frame[i] = def.is_signed[i] ? static_cast<int64_t>(static_cast<int32_t>(value))
                                  : static_cast<int64_t>(static_cast<uint32_t>(value));
    }
  }

  SHUTTERLAB_BLACKBOX_INLINE void ApplyGroup(const FrameDef& def, const Op& op,
                                             const int32_t* values, int64_t* frame,
                                             const int64_t* prev, const int64_t* prev2) {
    for (int j = 0; j < op.count; ++j) {
      const int i = op.first + j;
      frame[i] = Predict(def.predictor[i], values[j], i, frame, prev, prev2);
    }
  }

  void Parse(int kind, ByteReader* r) {
    switch (kind) {
      case kKindI:
        DecodeFields(h_.defs[kKindI], r, Slot(cur_), Slot(prev_), Slot(prev_), 0);
        break;
      case kKindP:
        skipped_ = CountSkippedIterations();
        DecodeFields(h_.defs[kKindP], r, Slot(cur_), Slot(prev_), Slot(prev2_), skipped_);
        break;
      case kKindG:
      case kKindH:
      case kKindS:
        DecodeFields(h_.defs[kind], r, scratch_[kind].data(), nullptr, nullptr, 0);
        break;
      case kKindE:
        ParseEvent(r);
        break;
    }
  }

  // Event frames (firmware FlightLogEvent). Returns through event_ / resume_*; unknown types make
  // the frame invalid, as in blackbox-tools.
  void ParseEvent(ByteReader* r) {
    event_ = r->ReadByte();
    event_valid_ = true;
    switch (event_) {
      case 0:  // SYNC_BEEP: time
        r->ReadUnsignedVb();
        break;
      case 10:  // AUTOTUNE_CYCLE_START (legacy)
        for (int k = 0; k < 5; ++k) r->ReadByte();
        break;
      case 11:  // AUTOTUNE_CYCLE_RESULT (legacy)
        for (int k = 0; k < 4; ++k) r->ReadByte();
        break;
      case 12:  // AUTOTUNE_TARGETS (legacy): s16, s8, s8, s16, s16
        for (int k = 0; k < 8; ++k) r->ReadByte();
        break;
      case 13: {  // INFLIGHT_ADJUSTMENT: function, then a float or a signed VB
        const uint8_t function = r->ReadByte();
        if (function > 127) {
          for (int k = 0; k < 4; ++k) r->ReadByte();
        } else {
          r->ReadSignedVb();
        }
        break;
      }
      case 14:  // LOGGING_RESUME: iteration, time
        resume_iteration_ = r->ReadUnsignedVb();
        resume_time_us_ = static_cast<int64_t>(r->ReadUnsignedVb()) + rollover_us_;
        break;
      case 15:  // DISARM: reason
        r->ReadUnsignedVb();
        break;
      case 20:  // GTUNE_CYCLE_RESULT (legacy): axis, gyroAVG, newP
        r->ReadByte();
        r->ReadSignedVb();
        r->ReadByte();
        r->ReadByte();
        break;
      case 30:  // FLIGHTMODE: new flags, last flags
        r->ReadUnsignedVb();
        r->ReadUnsignedVb();
        break;
      case kEventLogEnd: {  // LOG_END: "End of log\0" ends this log's data
        static constexpr char kEndMessage[] = "End of log";  // 10 chars + the NUL = 11 bytes
        if (r->end - r->pos >= sizeof(kEndMessage) &&
            std::memcmp(r->data + r->pos, kEndMessage, sizeof(kEndMessage)) == 0) {
          r->pos += sizeof(kEndMessage);  // Run() ends the log's data here
        } else {
          event_valid_ = false;  // bytes that merely looked like an event
        }
        break;
      }
      default:
        event_valid_ = false;
        break;
    }
  }

  // blackbox-tools flightLogDetectAndApplyTimestampRollover: the firmware's µs clock is 32 bits.
  int64_t ApplyRollover(int64_t t_us) {
    if (last_time_us_ != -1) {
      const uint32_t now = static_cast<uint32_t>(t_us);
      const uint32_t last = static_cast<uint32_t>(last_time_us_);
      if (now < last && static_cast<uint32_t>(now - last) < static_cast<uint32_t>(kMaxTimeJumpUs)) {
        rollover_us_ += int64_t{1} << 32;
      }
    }
    return static_cast<int64_t>(static_cast<uint32_t>(t_us)) + rollover_us_;
  }

  bool PlausibleAfterLast(const int64_t* frame) const {
    const uint32_t iteration = static_cast<uint32_t>(frame[h_.idx_iteration]);
    const int64_t t_us = frame[h_.idx_time];
    return iteration >= last_iteration_ && iteration < last_iteration_ + kMaxIterationJump &&
           t_us >= last_time_us_ && t_us < last_time_us_ + kMaxTimeJumpUs;
  }

  void AcceptMain(const int64_t* frame, DecodedLog* out) {
    last_iteration_ = static_cast<uint32_t>(frame[h_.idx_iteration]);
    last_time_us_ = frame[h_.idx_time];
    const int64_t t_ns = last_time_us_ * 1000;
    if (out->info.main_frames++ == 0) out->first_t_ns = t_ns;
    out->last_t_ns = t_ns;
    if (!samples_) return;
    GyroSample sample;
    sample.t_ns = t_ns;
    sample.omega_rad_s = Eigen::Vector3d(static_cast<double>(frame[h_.idx_gyro[0]]),
                                         static_cast<double>(frame[h_.idx_gyro[1]]),
                                         static_cast<double>(frame[h_.idx_gyro[2]])) *
                         rad_per_lsb_;
    samples_->push_back(sample);
  }

  void Complete(int kind, DecodedLog* out) {
    switch (kind) {
      case kKindI: {
        int64_t* frame = Slot(cur_);
        frame[h_.idx_time] = ApplyRollover(frame[h_.idx_time]);
        main_valid_ = last_iteration_ == kNoIteration || PlausibleAfterLast(frame);
        if (!main_valid_) {
          prev_ = prev2_ = -1;
          ++out->rejected_main_frames;
          return;
        }
        AcceptMain(frame, out);
        ++out->info.i_frames;
        prev_ = prev2_ = cur_;
        cur_ = (cur_ + 1) % 3;
        return;
      }
      case kKindP: {
        int64_t* frame = Slot(cur_);
        frame[h_.idx_time] = ApplyRollover(frame[h_.idx_time]);
        if (main_valid_ && !PlausibleAfterLast(frame)) {
          main_valid_ = false;
          prev_ = prev2_ = -1;
        }
        if (!main_valid_) {  // a P frame cannot resynchronise the stream: wait for an I frame
          ++out->rejected_main_frames;
          return;
        }
        AcceptMain(frame, out);
        prev2_ = prev_;
        prev_ = cur_;
        cur_ = (cur_ + 1) % 3;
        return;
      }
      case kKindH:
        std::copy(scratch_[kKindH].begin(), scratch_[kKindH].begin() + h_.defs[kKindH].count(),
                  home_.begin());
        return;
      case kKindE:
        if (!event_valid_) {
          ++out->unknown_events;
          return;
        }
        if (event_ == 14) {
          // Logging paused and resumed: accept the jump in iteration and time. A resume that goes
          // back in time is corrupt data (the firmware's clock only runs forward); taking it would
          // let later frames go back in time too.
          if (resume_time_us_ < last_time_us_) {
            ++out->unknown_events;
            return;
          }
          last_iteration_ = resume_iteration_;
          last_time_us_ = resume_time_us_;
          ++out->logging_resumes;
        } else if (event_ == kEventLogEnd) {
          out->info.ended_cleanly = true;
        }
        return;
      default:
        return;  // G and S frames carry nothing the gyro trace needs
    }
  }

  BlackboxBytes* bytes_;
  const uint8_t* data_;
  const LogHeader h_;
  double rad_per_lsb_;
  Cursor at_;
  size_t release_at_ = 0;
  std::vector<GyroSample>* samples_ = nullptr;  // where accepted main frames go; none: counted
  size_t n_main_ = 0;
  std::vector<int64_t> ring_;
  int cur_ = 0, prev_ = -1, prev2_ = -1;
  std::array<std::vector<int64_t>, kDefinedKinds> scratch_;
  std::vector<int64_t> home_;
  std::vector<uint32_t> skip_table_;
  bool main_valid_ = false;
  uint32_t last_iteration_ = kNoIteration;
  int64_t last_time_us_ = -1;
  int64_t rollover_us_ = 0;
  uint32_t skipped_ = 0;
  int event_ = -1;
  bool event_valid_ = false;
  uint32_t resume_iteration_ = 0;
  int64_t resume_time_us_ = 0;
};

// A log's header, checked and compiled, ready for LogDecoder.
struct PreparedLog {
  DecodedLog out;  // info, the header's warnings, the gyro fields
  LogHeader header;
  double rad_per_lsb = 0.0;
};

// Reads the header of the log in [begin, end). Throws IoError (naming the path and the log) when
// it does not define what the gyro trace needs.
PreparedLog PrepareLog(const uint8_t* data, size_t begin, size_t end, int index,
                       const std::string& path) {
  PreparedLog prepared;
  DecodedLog& out = prepared.out;
  out.info.index = index;
  out.info.begin_byte = begin;
  out.info.size_bytes = end - begin;
  const std::string where =
      "log " + std::to_string(index) + " (byte " + std::to_string(begin) + ")";
  auto fail = [&](const std::string& problem) {
    throw IoError(IoMessage(path, 0, where + ": " + problem));
  };

  LogHeader& h = prepared.header;
  h = ParseHeader(data, begin, end);
  out.info.firmware = h.firmware_revision;
  out.info.craft_name = h.craft_name;
  if (!h.defs[kKindI].has_names)
    fail("header has no 'H Field I name' line (truncated or not a blackbox log)");
  IdentifyFields(&h);
  if (h.idx_iteration < 0 || h.idx_time < 0)
    fail("main frames have no loopIteration or time field");
  for (int axis = 0; axis < 3; ++axis) {
    if (h.idx_gyro[axis] < 0)
      fail("main frames have no gyroADC[" + std::to_string(axis) + "] field");
  }
  if (h.p_num < 1 || h.p_denom < 1 || h.p_num > h.p_denom) {
    fail("bad 'P interval' " + std::to_string(h.p_num) + "/" + std::to_string(h.p_denom));
  }
  std::string problem = CompileFrameDef(kKindI, h, &h.defs[kKindI]);
  if (!problem.empty()) fail(problem);
  FrameDef& p = h.defs[kKindP];
  if (p.has_predictor || p.has_encoding) {
    problem = CompileFrameDef(kKindP, h, &p);
    if (!problem.empty()) fail(problem);
  }
  for (int kind = kKindG; kind <= kKindS; ++kind) {
    FrameDef& def = h.defs[kind];
    if (!def.has_names && !def.has_predictor && !def.has_encoding) continue;
    problem = CompileFrameDef(kind, h, &def);
    // Only the gyro matters here: a broken GPS or slow definition makes those frames unreadable,
    // and the resynchronisation skips them.
    if (!problem.empty())
      out.warnings.push_back({"format", where + ": " + problem + "; those frames are skipped"});
  }
  prepared.rad_per_lsb = GyroRadPerSecondPerLsb(h, &out.warnings);
  out.gyro_field =
      h.defs[kKindI].names[h.idx_gyro[0]].substr(0, h.defs[kKindI].names[h.idx_gyro[0]].find('['));
  out.has_gyro_unfilt = h.has_gyro_unfilt;
  return prepared;
}

// Decodes the log in [begin, end) of bytes, counting its frames; with_rate also gives its median
// rate (from every sample's time, held while it decodes: for ListBlackboxLogs). Throws IoError as
// PrepareLog does.
DecodedLog DecodeLog(BlackboxBytes* bytes, size_t begin, size_t end, int index,
                     const std::string& path, bool with_rate) {
  PreparedLog prepared = PrepareLog(bytes->data(), begin, end, index, path);
  DecodedLog out = std::move(prepared.out);
  LogDecoder decoder(bytes, end, std::move(prepared.header), prepared.rad_per_lsb);
  std::vector<GyroSample> samples;
  decoder.Run(&out, with_rate ? &samples : nullptr, std::numeric_limits<size_t>::max());

  out.info.skipped_frames = out.corrupt_frames + out.rejected_main_frames;
  if (out.info.main_frames >= 2) {
    out.info.duration_s = (out.last_t_ns - out.first_t_ns) * 1e-9;
    if (with_rate) {
      std::vector<int64_t> dt(samples.size() - 1);
      for (size_t k = 0; k + 1 < samples.size(); ++k) dt[k] = samples[k + 1].t_ns - samples[k].t_ns;
      const int64_t median_dt = UpperMedian(std::move(dt));
      if (median_dt > 0) out.info.rate_hz = 1e9 / static_cast<double>(median_dt);
    }
  }
  return out;
}

// Start offsets of the logs in a file (blackbox-tools flightLogCreate: every start marker),
// searched a block at a time so that the pages behind go back as the search moves on.
std::vector<size_t> FindLogStarts(BlackboxBytes* bytes) {
  const std::string_view all = bytes->view();
  std::vector<size_t> starts;
  const std::boyer_moore_horspool_searcher searcher(kLogStartMarker.begin(), kLogStartMarker.end());
  size_t from = 0;  // where the search goes on (past the last marker found)
  for (size_t block = 0; block < all.size(); block += kReleaseEveryBytes) {
    // A marker that starts in this block may end in the next.
    const auto block_end =
        all.begin() + std::min(all.size(), block + kReleaseEveryBytes + kLogStartMarker.size() - 1);
    auto it = all.begin() + std::max(from, block);
    while ((it = std::search(it, block_end, searcher)) != block_end) {
      starts.push_back(static_cast<size_t>(it - all.begin()));
      it += kLogStartMarker.size();
      from = static_cast<size_t>(it - all.begin());
    }
    bytes->ReleaseBefore(block);
  }
  return starts;
}

struct DecodedFile {
  std::vector<DecodedLog> logs;  // problem set where a log could not be decoded
  size_t leading_garbage_bytes = 0;
};

DecodedFile DecodeAllLogs(BlackboxBytes* bytes, const std::vector<size_t>& starts,
                          const std::string& path, bool with_rate) {
  if (starts.empty()) {
    throw IoError(IoMessage(
        path, 0, "not a blackbox log: no 'H Product:Blackbox flight data recorder' header"));
  }
  bytes->StartReading();
  DecodedFile file;
  file.leading_garbage_bytes = starts.front();
  for (size_t k = 0; k < starts.size(); ++k) {
    const size_t end = k + 1 < starts.size() ? starts[k + 1] : bytes->view().size();
    try {
      file.logs.push_back(DecodeLog(bytes, starts[k], end, static_cast<int>(k), path, with_rate));
    } catch (const IoError& e) {
      DecodedLog failed;
      failed.info.index = static_cast<int>(k);
      failed.info.begin_byte = starts[k];
      failed.info.size_bytes = end - starts[k];
      failed.info.problem = e.what();
      file.logs.push_back(std::move(failed));
    }
  }
  return file;
}

std::string FormatSeconds(double t_s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f s", t_s);
  return text;
}

std::string Plural(size_t n, const std::string& word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

// ---- CSV export (blackbox_decode: "loopIteration, time (us), ..., gyroADC[0], ...") ----

std::string_view TrimQuotesAndSpaces(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '"'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '"')) s.remove_suffix(1);
  return s;
}

// Splits "name (unit)" into name and unit (unit empty when absent).
std::pair<std::string_view, std::string_view> SplitUnit(std::string_view column) {
  column = TrimQuotesAndSpaces(column);
  const size_t open = column.find(" (");
  if (open == std::string_view::npos || column.back() != ')') return {column, {}};
  return {column.substr(0, open), column.substr(open + 2, column.size() - open - 3)};
}

struct CsvColumns {
  int time = -1;
  double time_to_ns = 1000.0;  // µs unless the header says otherwise
  std::array<int, 3> gyro{-1, -1, -1};
  double gyro_to_rad_s = kRadPerDeg;
  bool gyro_unit_stated = false;
  bool has_loop_iteration = false;
};

std::optional<CsvColumns> ParseCsvHeader(std::string_view line, std::string* problem) {
  std::vector<std::string_view> fields;
  SplitFields(line, ',', &fields);
  CsvColumns c;
  std::string_view gyro_unit;
  for (size_t i = 0; i < fields.size(); ++i) {
    const auto [name, unit] = SplitUnit(fields[i]);
    if (name == "loopIteration") c.has_loop_iteration = true;
    if (name == "time" && c.time < 0) {
      c.time = static_cast<int>(i);
      if (unit == "us" || unit.empty())
        c.time_to_ns = 1000.0;
      else if (unit == "ms")
        c.time_to_ns = 1e6;
      else if (unit == "s")
        c.time_to_ns = 1e9;
      else {
        *problem = "unknown time unit '" + std::string(unit) + "'";
        return std::nullopt;
      }
    }
    for (int axis = 0; axis < 3; ++axis) {
      if (name == "gyroADC[" + std::to_string(axis) + "]" && c.gyro[axis] < 0) {
        c.gyro[axis] = static_cast<int>(i);
        if (axis == 0) gyro_unit = unit;
      }
    }
  }
  if (c.time < 0 || c.gyro[0] < 0 || c.gyro[1] < 0 || c.gyro[2] < 0) {
    *problem = "CSV header has no time or gyroADC[0..2] column";
    return std::nullopt;
  }
  if (gyro_unit == "rad/s") {
    c.gyro_to_rad_s = 1.0;
    c.gyro_unit_stated = true;
  } else if (gyro_unit == "deg/s") {
    c.gyro_unit_stated = true;
  } else if (!gyro_unit.empty() && gyro_unit != "raw") {
    *problem = "unknown gyroADC unit '" + std::string(gyro_unit) + "'";
    return std::nullopt;
  }
  return c;
}

bool LooksLikeCsvHeader(std::string_view first_line) {
  return first_line.find("loopIteration") != std::string_view::npos &&
         first_line.find("time") != std::string_view::npos &&
         first_line.find("gyroADC[0]") != std::string_view::npos;
}

std::string_view FirstLine(std::string_view bytes) {
  size_t start = 0;
  if (bytes.size() >= 3 && bytes.substr(0, 3) == "\xEF\xBB\xBF") start = 3;  // UTF-8 BOM
  const size_t newline = bytes.find('\n', start);
  return bytes.substr(start,
                      newline == std::string_view::npos ? std::string_view::npos : newline - start);
}

// The sample of one data row of blackbox_decode's CSV (line n), split into *fields.
GyroSample BlackboxCsvRow(std::string_view line, const CsvColumns& columns, const std::string& path,
                          long n, std::vector<std::string_view>* fields) {
  SplitFields(line, ',', fields);
  const int needed =
      std::max({columns.time, columns.gyro[0], columns.gyro[1], columns.gyro[2]}) + 1;
  if (static_cast<int>(fields->size()) < needed) {
    throw IoError(IoMessage(path, n,
                            "expected at least " + std::to_string(needed) + " fields, found " +
                                std::to_string(fields->size())));
  }
  const std::optional<double> t = ParseDouble((*fields)[columns.time]);
  if (!t) {
    throw IoError(
        IoMessage(path, n, "time '" + std::string((*fields)[columns.time]) + "' is not a number"));
  }
  GyroSample sample;
  const double t_ns = *t * columns.time_to_ns;
  if (!(std::abs(t_ns) < 9.2e18)) throw IoError(IoMessage(path, n, "time out of range"));
  sample.t_ns = std::llround(t_ns);
  for (int axis = 0; axis < 3; ++axis) {
    const std::optional<double> v = ParseDouble((*fields)[columns.gyro[axis]]);
    if (!v) {
      throw IoError(IoMessage(path, n,
                              "gyroADC[" + std::to_string(axis) + "] '" +
                                  std::string((*fields)[columns.gyro[axis]]) +
                                  "' is not a number"));
    }
    sample.omega_rad_s[axis] = *v * columns.gyro_to_rad_s;
  }
  return sample;
}

// The samples of blackbox_decode's CSV, parsed a chunk of rows at a time.
class BlackboxCsvSource : public FillingSource {
 public:
  // cursor: past the header line of bytes' text.
  BlackboxCsvSource(std::unique_ptr<BlackboxBytes> bytes, LineCursor cursor, CsvColumns columns,
                    size_t chunk_samples)
      : FillingSource(chunk_samples),
        bytes_(std::move(bytes)),
        cursor_(cursor),
        columns_(columns) {}
  double Fraction() const override {
    if (ended_ || bytes_->view().empty()) return 1.0;
    return static_cast<double>(read_bytes_) / bytes_->view().size();
  }

 protected:
  void Fill(std::vector<GyroSample>* chunk) override {
    if (ended_) return;
    bytes_->CheckUnchanged();
    const std::string& path = bytes_->path();
    ReserveChunk(chunk, bytes_->view().size() - read_bytes_);
    while (chunk->size() < chunk_samples()) {
      const std::optional<std::string_view> line = cursor_.Next();
      if (!line) {
        ended_ = true;
        if (!last_t_ns_) throw IoError(IoMessage(path, cursor_.line_number(), "no data rows"));
        return;
      }
      read_bytes_ = static_cast<size_t>(line->data() + line->size() - bytes_->view().data());
      if (read_bytes_ >= released_ + kReleaseEveryBytes) {
        bytes_->ReleaseBefore(read_bytes_);
        released_ = read_bytes_;
      }
      if (line->find_first_not_of(" \t") == std::string_view::npos) continue;
      try {
        const GyroSample sample =
            BlackboxCsvRow(*line, columns_, path, cursor_.line_number(), &fields_);
        if (last_t_ns_ && sample.t_ns < *last_t_ns_)
          throw IoError(IoMessage(path, cursor_.line_number(), "time goes backwards"));
        chunk->push_back(sample);
        last_t_ns_ = sample.t_ns;
      } catch (const IoError&) {
        if (!cursor_.unterminated()) throw;  // only the last line may be cut
        LeaveOutCutLastLine(cursor_.line_number(), last_t_ns_);
      }
    }
  }

 private:
  std::unique_ptr<BlackboxBytes> bytes_;
  LineCursor cursor_;
  CsvColumns columns_;
  std::vector<std::string_view> fields_;
  std::optional<int64_t> last_t_ns_;  // of the last row taken
  size_t read_bytes_ = 0;             // up to the end of the last line read
  size_t released_ = 0;
  bool ended_ = false;
};

// A CSV export: its header now, its rows as they are taken.
BlackboxStream OpenCsv(std::unique_ptr<BlackboxBytes> bytes, size_t chunk_samples) {
  const std::string& path = bytes->path();
  bytes->StartReading();
  LineCursor cursor(bytes->view());
  std::optional<std::string_view> line = cursor.Next();
  if (!line) throw IoError(IoMessage(path, 1, "empty file"));
  std::string problem;
  const std::optional<CsvColumns> columns = ParseCsvHeader(StripBom(*line), &problem);
  if (!columns) throw IoError(IoMessage(path, 1, problem));

  BlackboxStream stream;
  FlightLog& log = stream.log;
  log.format = "betaflight_csv";
  log.gyro_source = "gyroADC";
  log.gyro_sources_available = {"gyroADC"};
  if (!columns->gyro_unit_stated) {
    log.warnings.push_back({"unit",
                            "gyroADC has no unit in the CSV header; taken as deg/s (Betaflight >= "
                            "3 logs gyro_scale 1.0)"});
  }
  stream.samples =
      std::make_unique<BlackboxCsvSource>(std::move(bytes), cursor, *columns, chunk_samples);
  return stream;
}

// Pass 2 over a native file: the chosen log decoded again, its samples handed on a chunk at a time.
class BlackboxFrameSource : public FillingSource {
 public:
  // log: the chosen log as pass 1 decoded it.
  BlackboxFrameSource(std::unique_ptr<BlackboxBytes> bytes, const DecodedLog& log,
                      size_t chunk_samples)
      : FillingSource(chunk_samples),
        bytes_(std::move(bytes)),
        index_(log.info.index),
        begin_(log.info.begin_byte),
        end_(log.info.begin_byte + log.info.size_bytes),
        main_frames_(log.info.main_frames) {}
  // The share of the chosen log's bytes decoded.
  double Fraction() const override {
    if (ended_) return 1.0;  // a LOG_END event may end it before its last byte
    if (!decoder_) return 0.0;
    return end_ > begin_ ? static_cast<double>(std::min(decoder_->position(), end_) - begin_) /
                               static_cast<double>(end_ - begin_)
                         : 1.0;
  }

 protected:
  void Fill(std::vector<GyroSample>* chunk) override {
    if (ended_) return;
    if (!decoder_) {
      bytes_->StartReading();
      PreparedLog prepared = PrepareLog(bytes_->data(), begin_, end_, index_, bytes_->path());
      decoder_ = std::make_unique<LogDecoder>(bytes_.get(), end_, std::move(prepared.header),
                                              prepared.rad_per_lsb);
    }
    bytes_->CheckUnchanged();
    ReserveChunk(chunk, end_ - std::min(decoder_->position(), end_));
    ended_ = decoder_->Run(&counts_, chunk, chunk_samples());
    if (ended_ && counts_.info.main_frames != main_frames_) {
      // Only bytes that changed since pass 1 decode differently.
      throw IoError(
          IoMessage(bytes_->path(), 0,
                    "changed while it was read (log " + std::to_string(index_) + " held " +
                        Plural(main_frames_, "main frame") + ", then " +
                        std::to_string(counts_.info.main_frames) +
                        "): is it still being recorded? Read a copy, or the finished log"));
    }
  }

 private:
  std::unique_ptr<BlackboxBytes> bytes_;
  int index_;
  size_t begin_, end_;
  size_t main_frames_;  // what pass 1 found
  std::unique_ptr<LogDecoder> decoder_;
  DecodedLog counts_;  // pass 2's own counts
  bool ended_ = false;
};

// Which log of the file to read: log_index, or -1 for the one with the most main frames (the
// first of equals). Throws IoError when it is out of range or cannot be read.
int ChooseLog(const DecodedFile& file, int log_index, const std::string& path) {
  const int count = static_cast<int>(file.logs.size());
  int chosen = log_index;
  if (log_index < -1 || log_index >= count) {
    throw IoError(IoMessage(path, 0,
                            "log index " + std::to_string(log_index) +
                                " out of range: the file holds " + Plural(count, "log") + " (0.." +
                                std::to_string(count - 1) + ")"));
  }
  if (chosen < 0) {
    size_t best = 0;
    for (const DecodedLog& log : file.logs) {
      if (log.info.problem.empty() && log.info.main_frames > best) {
        best = log.info.main_frames;
        chosen = log.info.index;
      }
    }
    if (chosen < 0) {
      // Nothing decodable: report the first log's problem (or that it is empty).
      const DecodedLog& first = file.logs.front();
      if (!first.info.problem.empty()) throw IoError(first.info.problem);
      throw IoError(IoMessage(path, 0, "no log in the file holds a main frame"));
    }
  }
  const DecodedLog& log = file.logs[chosen];
  if (!log.info.problem.empty()) throw IoError(log.info.problem);
  if (log.info.main_frames == 0)
    throw IoError(IoMessage(path, 0, "log " + std::to_string(chosen) + " holds no main frame"));
  return chosen;
}

// All of the chosen log but its samples: the sources, records_skipped and what was lost.
FlightLog DescribeLog(DecodedFile& file, int chosen, int log_index) {
  const int count = static_cast<int>(file.logs.size());
  DecodedLog& log = file.logs[chosen];
  const std::string where = "log " + std::to_string(chosen);
  FlightLog out;
  out.format = "betaflight";
  out.gyro_source = log.gyro_field;
  out.gyro_sources_available = {log.gyro_field};
  if (log.has_gyro_unfilt) out.gyro_sources_available.push_back("gyroUnfilt");
  out.records_skipped = log.corrupt_frames + log.rejected_main_frames;
  out.warnings = std::move(log.warnings);
  if (count > 1) {
    std::string others;
    for (const DecodedLog& other : file.logs) {
      if (other.info.index == chosen) continue;
      others += (others.empty() ? "" : ", ") + std::to_string(other.info.index) + " (" +
                Plural(other.info.main_frames, "frame") + ", " +
                FormatSeconds(other.info.duration_s) + ")";
    }
    out.warnings.push_back({"unused_source",
                            "the file holds " + Plural(count, "log") + "; read " + where +
                                (log_index < 0 ? " (the longest)" : "") + " with " +
                                Plural(log.info.main_frames, "main frame") + "; others: " + others,
                            std::nullopt, count - 1});
  }
  if (file.leading_garbage_bytes > 0) {
    out.warnings.push_back(
        {"corrupt", Plural(file.leading_garbage_bytes, "byte") + " before the first log ignored"});
  }
  if (log.corrupt_frames > 0) {
    out.warnings.push_back({"corrupt",
                            where + ": " + Plural(log.corrupt_frames, "corrupt frame") + " skipped",
                            std::nullopt, log.corrupt_frames});
  }
  if (log.rejected_main_frames > 0) {
    out.warnings.push_back({"corrupt",
                            where + ": " + Plural(log.rejected_main_frames, "main frame") +
                                " dropped while resynchronising after corrupt data",
                            std::nullopt, log.rejected_main_frames});
  }
  if (log.unknown_events > 0) {
    out.warnings.push_back(
        {"format",
         where + ": " + Plural(log.unknown_events, "unrecognised event frame") + " ignored",
         std::nullopt, log.unknown_events});
  }
  if (log.logging_resumes > 0) {
    out.warnings.push_back({"gap",
                            where + ": logging paused and resumed " +
                                Plural(log.logging_resumes, "time") + " (gaps in the trace)",
                            std::nullopt, log.logging_resumes});
  }
  if (!log.info.ended_cleanly) {
    out.warnings.push_back(
        {"truncated",
         where + ": no LOG_END event (the recording was cut off or the file truncated)",
         std::optional<double>(log.last_t_ns * 1e-9)});
  }
  return out;
}

// A native file: pass 1 decodes every log, counting, to choose one and say what it lost; its
// samples come from pass 2 (BlackboxFrameSource). starts: FindLogStarts's.
BlackboxStream OpenNative(std::unique_ptr<BlackboxBytes> bytes, const std::vector<size_t>& starts,
                          int log_index, size_t chunk_samples,
                          size_t* leading_garbage_bytes = nullptr) {
  DecodedFile file = DecodeAllLogs(bytes.get(), starts, bytes->path(), false);
  if (leading_garbage_bytes) *leading_garbage_bytes = file.leading_garbage_bytes;
  const int chosen = ChooseLog(file, log_index, bytes->path());
  BlackboxStream stream;
  stream.log = DescribeLog(file, chosen, log_index);
  stream.samples =
      std::make_unique<BlackboxFrameSource>(std::move(bytes), file.logs[chosen], chunk_samples);
  return stream;
}

// A native file or a CSV export (a file with no start marker whose first line is the export's).
BlackboxStream OpenAny(std::unique_ptr<BlackboxBytes> bytes, int log_index, size_t chunk_samples) {
  const std::vector<size_t> starts = FindLogStarts(bytes.get());
  if (starts.empty() && LooksLikeCsvHeader(FirstLine(bytes->view()))) {
    if (log_index > 0) {
      throw IoError(IoMessage(bytes->path(), 0,
                              "log index " + std::to_string(log_index) +
                                  " out of range: a CSV export holds 1 log (0)"));
    }
    return OpenCsv(std::move(bytes), chunk_samples);
  }
  return OpenNative(std::move(bytes), starts, log_index, chunk_samples);
}

FlightLog ReadWhole(BlackboxStream stream) {
  FlightLog log = std::move(stream.log);
  log.gyro = ReadAllSamples(stream.samples.get());
  for (LogWarning& warning : stream.samples->Warnings()) log.warnings.push_back(std::move(warning));
  return log;
}

std::vector<BlackboxLogInfo> ListLogs(std::unique_ptr<BlackboxBytes> bytes) {
  const std::vector<size_t> starts = FindLogStarts(bytes.get());
  if (starts.empty() && LooksLikeCsvHeader(FirstLine(bytes->view()))) {
    BlackboxLogInfo info;
    info.size_bytes = bytes->view().size();
    const FlightLog log = ReadWhole(OpenCsv(std::move(bytes), FillingSource::kDefaultChunkSamples));
    info.main_frames = log.gyro.size();
    info.duration_s = log.gyro.DurationS();
    info.rate_hz = log.gyro.sampling().RateHz();
    return {info};
  }
  DecodedFile file = DecodeAllLogs(bytes.get(), starts, bytes->path(), true);
  std::vector<BlackboxLogInfo> infos;
  infos.reserve(file.logs.size());
  for (DecodedLog& log : file.logs) infos.push_back(std::move(log.info));
  return infos;
}

}  // namespace

bool LooksLikeBlackbox(std::string_view first_bytes) {
  if (first_bytes.find(kLogStartMarker.substr(0, kLogStartMarker.size() - 1)) !=
      std::string_view::npos)
    return true;
  return LooksLikeCsvHeader(FirstLine(first_bytes));
}

BlackboxStream OpenBlackbox(const std::string& path, int log_index, size_t chunk_samples) {
  return OpenBlackbox(std::make_unique<MappedFile>(path, MappedFile::Paging::kStreamed), log_index,
                      chunk_samples);
}

BlackboxStream OpenBlackbox(std::unique_ptr<MappedFile> file, int log_index, size_t chunk_samples) {
  return OpenAny(BlackboxBytes::OfMapped(std::move(file)), log_index, chunk_samples);
}

BlackboxStream OpenBlackboxBytes(std::string bytes, const std::string& path, int log_index,
                                 size_t chunk_samples) {
  return OpenAny(BlackboxBytes::Owning(std::move(bytes), path), log_index, chunk_samples);
}

BlackboxStream OpenBlackboxBuffer(std::string_view bytes, const std::string& path, int log_index,
                                  size_t chunk_samples) {
  return OpenAny(BlackboxBytes::Borrowing(bytes, path), log_index, chunk_samples);
}

FlightLog DecodeBlackbox(std::string_view bytes, const std::string& path, int log_index,
                         BlackboxDecodeStats* stats) {
  auto borrowed = BlackboxBytes::Borrowing(bytes, path);
  const std::vector<size_t> starts = FindLogStarts(borrowed.get());
  size_t leading_garbage_bytes = 0;
  BlackboxStream stream = OpenNative(std::move(borrowed), starts, log_index,
                                     FillingSource::kDefaultChunkSamples, &leading_garbage_bytes);
  if (stats) stats->bytes_decoded = bytes.size() - leading_garbage_bytes;
  return ReadWhole(std::move(stream));
}

std::vector<BlackboxLogInfo> ListBlackboxLogsInBuffer(std::string_view bytes,
                                                      const std::string& path) {
  return ListLogs(BlackboxBytes::Borrowing(bytes, path));
}

std::vector<BlackboxLogInfo> ListBlackboxLogs(const std::string& path) {
  return ListLogs(
      BlackboxBytes::OfMapped(std::make_unique<MappedFile>(path, MappedFile::Paging::kStreamed)));
}

FlightLog ReadBlackbox(const std::string& path, int log_index) {
  return ReadWhole(OpenBlackbox(path, log_index));
}

}  // namespace shutterlab
