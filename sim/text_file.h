#pragma once
// Whole-file text input and all-or-nothing file output, shared by every reader and writer.

#include <charconv>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

// Reads a whole file; throws IoError naming the path when it cannot.
std::string ReadFileToString(const std::string& path);

// A file's size, modification time and identity (device, inode) when a reading in several passes
// first opened it. A log still being recorded grows between the passes, and one rewritten or
// replaced (even at the same size) holds other bytes: either would give one pass's samples to the
// next. Every later pass, and the end, checks that the file is as it was.
struct LogStamp {
  std::string path;
  uint64_t size_bytes = 0;
  int64_t modified_ns = 0;
  uint64_t device = 0, inode = 0;
  // The file at path now (all zero when it cannot be looked at: opening it then says why).
  static LogStamp Of(const std::string& path);
  // The file an open descriptor reads, whatever path names later; path names it in messages.
  static LogStamp Of(int fd, const std::string& path);
  // Throws IoError, one line naming the file, when it is no longer what the stamp describes.
  void CheckUnchanged() const;
};

// A whole file, read-only, mapped into memory. Mapping avoids the zero-fill and first-touch faults
// of a fresh buffer, which cost more than parsing on large logs (about 11 us per 4 KiB page on our
// machines). What cannot be mapped (a pipe, a FIFO, /dev/stdin) is first copied to a temporary
// file, unlinked as soon as it is made (it never outlives the process), in $TMPDIR (else /tmp),
// and that is mapped: a log on a pipe is then read in passes, in bounded memory, as a file is.
// Throws IoError naming the file (and the temporary folder when the copy fails, as on a full disk).
class MappedFile {
 public:
  // kWhole: every page read in when mapped (a file parsed whole). kStreamed: pages read in as they
  // are touched, and handed back by ReleaseBefore, so that a binary log of any length is read
  // front to back in bounded memory.
  enum class Paging { kWhole, kStreamed };
  explicit MappedFile(const std::string& path, Paging paging = Paging::kWhole);
  // The file an open descriptor reads (a regular file whole; anything else from where it stands,
  // copied first), without opening it again. The descriptor stays the caller's to close (the
  // mapping outlives it); path names the file in messages.
  MappedFile(int fd, const std::string& path, Paging paging);
  // The bytes of a descriptor that cannot be mapped (a pipe) from where it stands, after `head`
  // (bytes already read from it, such as a look at its start), copied to a temporary file and
  // mapped. The descriptor stays the caller's.
  static std::unique_ptr<MappedFile> Copied(std::string_view head, int fd, const std::string& path,
                                            Paging paging);
  // A copy that CopyToTemporaryFile made, mapped through its descriptor (which stays the
  // caller's); path names the input it copied in messages.
  static std::unique_ptr<MappedFile> OfCopy(int copy_fd, const std::string& path, Paging paging);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::string_view text() const { return {data_, size_}; }
  const std::string& path() const { return path_; }
  // Whether the bytes are a copy (a pipe's), not the named file's own.
  bool copied() const { return !stamp_; }
  // Hands the pages before byte `offset` back to the kernel, in whole 2 MiB spans of the file (all
  // of them at its end): they leave the process's resident memory; touching them again reads them
  // again from the file. An offset before the last one starts again from the file's start: a
  // reader's next pass over the file hands its pages back the same way.
  void ReleaseBefore(size_t offset);
  // Maps the pages of bytes [begin, end) into this process before they are read, in one call
  // instead of a page fault every few pages (each fault costs microseconds in a virtual machine).
  // A hint: false, and nothing done, where the kernel cannot (before Linux 5.14).
  bool Populate(size_t begin, size_t end) const;
  // Throws IoError, one line naming the file, when the file mapped has changed since (LogStamp):
  // a log still being recorded, or rewritten, whose pages would give other bytes than a pass
  // before read (or SIGBUS past a new end). Nothing to check for a copy, which nothing else
  // writes.
  void CheckUnchanged() const;

 private:
  MappedFile() = default;
  void Open(int fd, Paging paging);
  void Map(int fd, size_t size, Paging paging);
  // Copies fd's bytes after head into an unlinked temporary file and maps it.
  void Copy(std::string_view head, int fd, Paging paging);
  // Maps the copy that copy_fd reads (empty when it is).
  void MapCopy(int copy_fd, Paging paging);

  std::string path_;
  const char* data_ = nullptr;
  size_t size_ = 0;
  size_t released_ = 0;            // bytes from the start already handed back
  std::optional<LogStamp> stamp_;  // of the named file mapped; none for a copy
};

// `head`, then the bytes of fd from where it stands to its end (none when fd is -1), copied into a
// temporary file in $TMPDIR (else /tmp) that is unlinked as soon as it is made: it lives as long
// as the descriptor returned (the caller's to close), never past the process. Throws IoError
// naming path (and the folder, when the copy fails, as on a full disk).
int CopyToTemporaryFile(std::string_view head, int fd, const std::string& path);

// Asks the kernel for transparent huge pages on the page-aligned part of [data, data + bytes),
// before it is first touched: one fault per 2 MiB instead of per 4 KiB for large sample arrays.
// A hint only; harmless where unsupported.
void AdviseHugePages(const void* data, size_t bytes);

// Writes content to path via a temporary file in the same folder and a rename, so that a reader
// never sees a partial file and a failed write leaves no output. Throws IoError.
void WriteFileAtomically(const std::string& path, std::string_view content);

// A text file read in blocks of whole lines, so that a file of any length is parsed in bounded
// memory (a block, plus the longest line): a regular file mapped (MappedFile kStreamed), a pipe
// read into a buffer. Also over a text in memory (tests, fuzzing: small blocks
// put every line end at a block edge somewhere).
class TextBlocks {
 public:
  // A block the parser finds still in the L2 cache after read() copied it there (flight on a
  // 30-million-line gyro.csv: 1.38 s CPU with 4 MiB blocks, 1.34-1.36 s with 256 KiB, same run).
  static constexpr size_t kBlockBytes = 256 << 10;
  // A file; throws IoError naming the path when it cannot be opened.
  static TextBlocks OfFile(const std::string& path, size_t block_bytes = kBlockBytes);
  // A copy that CopyToTemporaryFile made, mapped through copy_fd (which stays the caller's; the
  // mapping outlives it); path names the input it copied in messages.
  static TextBlocks OfCopy(int copy_fd, const std::string& path);
  // A text in memory, which must outlive the blocks.
  static TextBlocks InMemory(std::string_view text, size_t block_bytes = kBlockBytes);
  ~TextBlocks();
  TextBlocks(TextBlocks&& other) noexcept;
  TextBlocks(const TextBlocks&) = delete;
  TextBlocks& operator=(const TextBlocks&) = delete;
  // The next run of whole lines: up to and including a '\n', or the input's last line when it has
  // none. Empty at the end. Valid until the next call. Throws IoError when a read fails.
  std::string_view Next();
  // Up to `bytes` of the input's start, without handing them out: Next gives them again. Only
  // before the first Next. A pipe is read once, so a look at its start must come from here.
  std::string_view Peek(size_t bytes);
  // The whole input mapped, for a reader that reads it in passes (a binary log): a file's own
  // mapping (not opened again), a pipe's bytes copied to a temporary file (MappedFile::Copied, the
  // bytes looked at by Peek first). Only before the first Next; the blocks are empty after.
  std::unique_ptr<MappedFile> TakeMapped();
  // The share of the input handed out so far, 0..1.
  double Fraction() const;
  // The input's length in bytes; 0 when unknown (a pipe).
  uint64_t size_bytes() const { return size_; }

 private:
  TextBlocks() = default;
  // One read() of up to max_bytes into buffer_ at `at` (again on EINTR): the bytes read, 0 at the
  // end (end_of_file_ set). Throws IoError when it fails.
  size_t Read(size_t at, size_t max_bytes);
  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0;                       // of the file (0 when unknown)
  uint64_t handed_out_ = 0;                 // bytes returned by Next
  std::string_view memory_;                 // the text in memory (or mapped), else empty
  std::unique_ptr<MappedFile> mapped_;      // a regular file, mapped: memory_ is its text
  size_t populated_ = 0;                    // of mapped_, bytes from the start mapped ahead
  std::unique_ptr<char[]> buffer_;          // a pipe's block
  size_t capacity_ = 0;                     // of buffer_
  size_t carry_begin_ = 0, carry_end_ = 0;  // a started last line, kept for the next block
  bool end_of_file_ = false;
};

// A file read in several passes (the still search, a sensor pair's fit, analyze's passes), each
// from its start: a regular file opened again by its path for every pass, which must still be
// the file the first pass read (LogStamp); anything else (a pipe, a FIFO, /dev/stdin, which the
// first read drains) copied once, whole, to a temporary file (CopyToTemporaryFile) that every pass
// reads, so that a log on a pipe is read in the same passes and bounded memory as a file. Copies
// of a ReopenableFile share the copy; a moved-from one is not to be used.
class ReopenableFile {
 public:
  // Throws IoError naming the path when it cannot be opened, or the copy fails.
  explicit ReopenableFile(const std::string& path);
  const std::string& path() const { return stamp_.path; }
  // The input from its start, for one pass; throws IoError (LogStamp::CheckUnchanged) when a
  // regular file is no longer the one first opened.
  TextBlocks Open() const;
  // After the last pass: the file was the same throughout (IoError otherwise).
  void CheckUnchanged() const;

 private:
  struct Copy;
  LogStamp stamp_;
  std::shared_ptr<const Copy> copy_;  // a pipe's bytes; null for a regular file
};

// The lines of a TextBlocks, one at a time, with 1-based line numbers and a trailing '\r'
// stripped, as LineCursor gives them from a whole text.
class LineReader {
 public:
  explicit LineReader(TextBlocks blocks) : blocks_(std::move(blocks)) {}
  // The next line, or nullopt at the end. Valid until the next call.
  std::optional<std::string_view> Next();
  long line_number() const { return line_number_; }
  double Fraction() const { return blocks_.Fraction(); }
  uint64_t size_bytes() const { return blocks_.size_bytes(); }
  // The line Next returned last is the input's last and has no line break: a file that does not
  // read there was cut inside it (copied or recorded while still being written).
  bool unterminated() const { return unterminated_; }

 private:
  TextBlocks blocks_;
  std::string_view block_;
  size_t pos_ = 0;
  long line_number_ = 0;
  bool unterminated_ = false;
};

// Iterates the lines of a text buffer, tracking 1-based line numbers; strips a trailing '\r'.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {}
  // Next line, or nullopt at the end of the buffer.
  std::optional<std::string_view> Next();
  long line_number() const { return line_number_; }
  // As LineReader::unterminated: the line Next returned last ends the text without a line break.
  bool unterminated() const { return unterminated_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  long line_number_ = 0;
  bool unterminated_ = false;
};

// Splits a line on a delimiter, trimming spaces and tabs around each field. Appends to fields
// (cleared first) to let callers reuse the vector across lines.
void SplitFields(std::string_view line, char delimiter, std::vector<std::string_view>* fields);

// Powers of ten exact in a double (10^22 is the largest).
inline constexpr double kExactPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                         1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                         1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

inline bool IsDecimalDigit(char c) { return static_cast<unsigned>(c - '0') < 10; }

// The value of a plain decimal of `count` digits in all, `after_point` of them after the point,
// whose digits read as the integer `mantissa` (wrapped when they are many): true and *value set
// when it is one correctly rounded division of two exact doubles (at most 19 digits, the mantissa
// at most 2^53, at most 22 after the point: Clinger's fast path, as std::from_chars itself takes
// it), false when another way must read it.
inline bool ClingerDecimal(bool negative, uint64_t mantissa, size_t count, size_t after_point,
                           double* value) {
  if (count == 0 || count > 19 || mantissa > (uint64_t{1} << 53) || after_point > 22) return false;
  const double v = static_cast<double>(mantissa) / kExactPow10[after_point];
  // -v by its sign bit, without a branch: a log's signs are as good as random, and a mispredicted
  // branch per number cost more than the division (flight end to end on 30 million lines: 5 %).
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  bits ^= uint64_t{negative} << 63;
  std::memcpy(value, &bits, sizeof(bits));
  return true;
}

// std::from_chars for a double at p, exactly (the same value and end), faster on the plain
// decimals that logs write ("-0.012345"): ClingerDecimal. Anything else (exponents, more digits,
// inf, nan) goes to std::from_chars. nullptr when there is no number.
inline const char* FromCharsDouble(const char* p, const char* end, double* value) {
  const char* q = p;
  const bool negative = q < end && *q == '-';
  q += negative;
  uint64_t mantissa = 0;
  const char* digits = q;
  while (q < end && IsDecimalDigit(*q)) mantissa = mantissa * 10 + (*q++ - '0');
  size_t count = static_cast<size_t>(q - digits);
  size_t after_point = 0;
  if (q < end && *q == '.') {
    const char* fraction = ++q;
    while (q < end && IsDecimalDigit(*q)) mantissa = mantissa * 10 + (*q++ - '0');
    after_point = static_cast<size_t>(q - fraction);
    count += after_point;
  }
  const bool exponent = q < end && (*q == 'e' || *q == 'E');
  if (!exponent && ClingerDecimal(negative, mantissa, count, after_point, value)) return q;
  const auto [next, ec] = std::from_chars(p, end, *value);
  return ec == std::errc() ? next : nullptr;
}

// FromCharsDouble's fast path alone, without comparing a byte position with the buffer's end:
// the caller guarantees a byte that is neither a digit nor '.' (a line end) at or after p inside
// the buffer. Returns the end of a plain decimal ("-0.012345", "12", "3.") read exactly as
// FromCharsDouble reads it; nullptr for anything else (an exponent, '+', more digits, inf, nan, no
// number), which the caller reads another way. What makes a 30-million-line gyro.csv read at
// GB/s: a row's numbers are then a few instructions a digit.
inline const char* PlainDecimalBeforeLineEnd(const char* p, double* value) {
  const bool negative = *p == '-';
  const char* q = p + negative;
  uint64_t mantissa = 0;
  const char* digits = q;
  while (IsDecimalDigit(*q)) mantissa = mantissa * 10 + (*q++ - '0');
  size_t count = static_cast<size_t>(q - digits);
  size_t after_point = 0;
  if (*q == '.') {
    const char* fraction = ++q;
    while (IsDecimalDigit(*q)) mantissa = mantissa * 10 + (*q++ - '0');
    after_point = static_cast<size_t>(q - fraction);
    count += after_point;
  }
  if ((*q | 0x20) == 'e') return nullptr;  // 'e' or 'E'
  return ClingerDecimal(negative, mantissa, count, after_point, value) ? q : nullptr;
}

// Parses a whole field as a finite double (leading '+' allowed). nullopt when the field is not a
// number, has trailing text, or is inf/nan.
std::optional<double> ParseDouble(std::string_view field);
// Parses a whole field as a signed 64-bit integer. nullopt when it is not one.
std::optional<int64_t> ParseInt(std::string_view field);

// Shortest round-trip text of a double (std::to_chars), appended to out.
void AppendDouble(double value, std::string* out);
// Appends t_ns as seconds with nine decimals, exactly (no floating-point rounding).
void AppendSecondsFromNs(int64_t t_ns, std::string* out);

// The text without a leading UTF-8 byte-order mark (what some editors put before a file's first
// line).
inline std::string_view StripBom(std::string_view line) {
  if (line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);
  return line;
}

// Lowercase copy of a string (ASCII).
std::string ToLower(std::string_view s);
// True when name ends in ".jpg" or ".jpeg", in any case.
bool HasJpegExtension(std::string_view name);
// True when name ends in ".png", in any case.
bool HasPngExtension(std::string_view name);

// One number through a printf format ("%.3f"), for tables and messages.
std::string FormatNumber(const char* format, double value);

}  // namespace shutterlab
