#include "sim/text_file.h"

#include "sim/check.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <random>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <utility>

namespace shutterlab {

std::string ReadFileToString(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(IoMessage(path, 0, std::string("cannot open: ") + std::strerror(errno)));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw IoError(IoMessage(path, 0, "cannot read (not a regular file?)"));
  std::string content(static_cast<size_t>(size), '\0');
  in.seekg(0, std::ios::beg);
  if (size > 0 && !in.read(content.data(), size)) throw IoError(IoMessage(path, 0, "read failed"));
  return content;
}

namespace {

LogStamp StampOf(const struct stat& info, const std::string& path) {
  LogStamp stamp;
  stamp.path = path;
  stamp.size_bytes = static_cast<uint64_t>(info.st_size);
  stamp.modified_ns = static_cast<int64_t>(info.st_mtim.tv_sec) * 1000000000 + info.st_mtim.tv_nsec;
  stamp.device = static_cast<uint64_t>(info.st_dev);
  stamp.inode = static_cast<uint64_t>(info.st_ino);
  return stamp;
}

// Where temporary copies go: $TMPDIR, else /tmp.
std::string TemporaryFolder() {
  const char* folder = std::getenv("TMPDIR");
  return folder && *folder ? folder : "/tmp";
}

// Writes all of [data, data + size) to fd; false (errno set) when a write fails.
bool WriteAll(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// Closes a descriptor when it goes out of scope.
struct Descriptor {
  int fd;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

LogStamp LogStamp::Of(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    LogStamp none;
    none.path = path;
    return none;
  }
  return StampOf(info, path);
}

LogStamp LogStamp::Of(int fd, const std::string& path) {
  struct stat info {};
  if (::fstat(fd, &info) != 0)
    throw IoError(IoMessage(path, 0, std::string("cannot read: ") + std::strerror(errno)));
  return StampOf(info, path);
}

void LogStamp::CheckUnchanged() const {
  const LogStamp now = Of(path);
  if (now.size_bytes == size_bytes && now.modified_ns == modified_ns && now.device == device &&
      now.inode == inode)
    return;
  const std::string what =
      now.size_bytes == size_bytes
          ? "rewritten, still " + std::to_string(size_bytes) + " bytes"
          : std::to_string(size_bytes) + " bytes, now " + std::to_string(now.size_bytes);
  throw IoError(IoMessage(path, 0,
                          "changed while it was read in passes (" + what +
                              "): is it still being recorded? Analyse a copy, or the finished "
                              "log"));
}

MappedFile::MappedFile(const std::string& path, Paging paging) : path_(path) {
  const Descriptor file{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (file.fd < 0)
    throw IoError(IoMessage(path, 0, std::string("cannot open: ") + std::strerror(errno)));
  Open(file.fd, paging);
}

MappedFile::MappedFile(int fd, const std::string& path, Paging paging) : path_(path) {
  Open(fd, paging);
}

void MappedFile::Open(int fd, Paging paging) {
  struct stat info {};
  if (::fstat(fd, &info) != 0)
    throw IoError(IoMessage(path_, 0, std::string("cannot read: ") + std::strerror(errno)));
  if (S_ISREG(info.st_mode) && info.st_size > 0) {
    Map(fd, static_cast<size_t>(info.st_size), paging);
    if (!data_)
      throw IoError(IoMessage(path_, 0, std::string("cannot map: ") + std::strerror(errno)));
    stamp_ = StampOf(info, path_);
    return;
  }
  // Not a file to map (a pipe; an empty regular file, or one such as /proc's that says it is).
  Copy({}, fd, paging);
}

std::unique_ptr<MappedFile> MappedFile::Copied(std::string_view head, int fd,
                                               const std::string& path, Paging paging) {
  std::unique_ptr<MappedFile> copied(new MappedFile());
  copied->path_ = path;
  copied->Copy(head, fd, paging);
  return copied;
}

void MappedFile::Map(int fd, size_t size, Paging paging) {
  const int populate = paging == Paging::kWhole ? MAP_POPULATE : 0;
  void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | populate, fd, 0);
  if (p == MAP_FAILED) return;
  data_ = static_cast<const char*>(p);
  size_ = size;
}

int CopyToTemporaryFile(std::string_view head, int fd, const std::string& path) {
  const std::string folder = TemporaryFolder();
  std::string name = folder + "/shutterlab-XXXXXX";
  Descriptor copy{::mkostemp(name.data(), O_CLOEXEC)};
  const auto failed = [&](const std::string& reason) {
    return IoError(IoMessage(path, 0,
                             "cannot copy it to a temporary file in " + folder + ": " + reason +
                                 " (TMPDIR names another folder)"));
  };
  if (copy.fd < 0) throw failed(std::strerror(errno));
  // Unlinked at once: the file lives as long as its descriptor and mapping, never past the process.
  ::unlink(name.c_str());
  if (!WriteAll(copy.fd, head.data(), head.size())) throw failed(std::strerror(errno));
  if (fd >= 0) {
    // 1 MiB a read: a pipe hands out at most its buffer (64 KiB) a read, a file more.
    constexpr size_t kCopyBytes = 1 << 20;
    std::unique_ptr<char[]> buffer(new char[kCopyBytes]);
    while (true) {
      const ssize_t n = ::read(fd, buffer.get(), kCopyBytes);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0)
        throw IoError(IoMessage(path, 0, std::string("read failed: ") + std::strerror(errno)));
      if (n == 0) break;
      if (!WriteAll(copy.fd, buffer.get(), static_cast<size_t>(n)))
        throw failed(std::strerror(errno));
    }
  }
  return std::exchange(copy.fd, -1);
}

void MappedFile::Copy(std::string_view head, int fd, Paging paging) {
  const Descriptor copy{CopyToTemporaryFile(head, fd, path_)};
  MapCopy(copy.fd, paging);
}

std::unique_ptr<MappedFile> MappedFile::OfCopy(int copy_fd, const std::string& path,
                                               Paging paging) {
  std::unique_ptr<MappedFile> copied(new MappedFile());
  copied->path_ = path;
  copied->MapCopy(copy_fd, paging);
  return copied;
}

void MappedFile::MapCopy(int copy_fd, Paging paging) {
  const auto failed = [&](const std::string& reason) {
    return IoError(
        IoMessage(path_, 0, "cannot map its copy in " + TemporaryFolder() + ": " + reason));
  };
  struct stat info {};
  if (::fstat(copy_fd, &info) != 0) throw failed(std::strerror(errno));
  if (info.st_size == 0) {
    data_ = "";
    return;
  }
  Map(copy_fd, static_cast<size_t>(info.st_size), paging);
  if (!data_) throw failed(std::strerror(errno));
}

MappedFile::~MappedFile() {
  if (size_ > 0) ::munmap(const_cast<char*>(data_), size_);
}

void MappedFile::ReleaseBefore(size_t offset) {
  if (size_ == 0) return;
  // Whole 2 MiB spans of the file (its end aside): the kernel may map a file's page cache in huge
  // pages, and handing back part of one splits it, with a TLB flush. Handing back each 256 KiB
  // block of a gyro.csv cost `flight` 11 % of its CPU time on a 6.18 kernel (perf: madvise 5.6 %,
  // pmdp_huge_clear_flush 5.3 %); whole spans split nothing, in an eighth of the calls.
  constexpr size_t kReleaseBytes = 2 << 20;
  const size_t end = offset >= size_ ? size_ : offset / kReleaseBytes * kReleaseBytes;
  // Behind what was handed back: a new pass from the start (a reader's second pass), whose pages
  // are resident again; hand them back as it goes, as in the first.
  if (end < released_) released_ = 0;
  if (end <= released_) return;
  // MADV_DONTNEED on a private read-only file mapping drops the pages from this process; the
  // page cache keeps them, so a later touch costs a minor fault, not a read from disk.
  ::madvise(const_cast<char*>(data_) + released_, end - released_, MADV_DONTNEED);
  released_ = end;
}

bool MappedFile::Populate(size_t begin, size_t end) const {
#ifdef MADV_POPULATE_READ
  const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  begin = begin / page * page;
  end = std::min(end, size_);
  return end <= begin ||
         ::madvise(const_cast<char*>(data_) + begin, end - begin, MADV_POPULATE_READ) == 0;
#else
  (void)begin;
  (void)end;
  return false;
#endif
}

void MappedFile::CheckUnchanged() const {
  if (stamp_) stamp_->CheckUnchanged();
}

void AdviseHugePages(const void* data, size_t bytes) {
#ifdef MADV_HUGEPAGE
  constexpr uintptr_t kHugePage = 2u << 20;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(kHugePage - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

void WriteFileAtomically(const std::string& path, std::string_view content) {
  // A unique temporary name beside the target: rename() is atomic only within one file system.
  std::random_device entropy;
  const std::string tmp =
      path + ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(entropy() % 1000000);
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw IoError(IoMessage(path, 0, std::string("cannot write: ") + std::strerror(errno)));
  const bool written = std::fwrite(content.data(), 1, content.size(), f) == content.size();
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed || std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    std::remove(tmp.c_str());
    throw IoError(IoMessage(path, 0, "write failed: " + reason));
  }
}

TextBlocks TextBlocks::OfFile(const std::string& path, size_t block_bytes) {
  TextBlocks blocks;
  blocks.path_ = path;
  blocks.capacity_ = std::max<size_t>(block_bytes, 1);
  blocks.fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (blocks.fd_ < 0)
    throw IoError(IoMessage(path, 0, std::string("cannot open: ") + std::strerror(errno)));
  struct stat info {};
  const bool regular = ::fstat(blocks.fd_, &info) == 0 && S_ISREG(info.st_mode);
  if (regular && info.st_size > 0) {
    // A regular file is mapped (through the descriptor just opened) and its blocks handed out in
    // place, each block's pages handed back when the next is taken: bounded memory without
    // read()'s copy into a buffer (11 % of `flight` on a 30-million-line gyro.csv). What it holds
    // when opened is read; a file that grows meanwhile is read as it was (its last line cut there
    // is said, as any cut line is).
    blocks.mapped_ = std::make_unique<MappedFile>(blocks.fd_, path, MappedFile::Paging::kStreamed);
    ::close(blocks.fd_);
    blocks.fd_ = -1;
    blocks.memory_ = blocks.mapped_->text();
    blocks.size_ = blocks.memory_.size();
    return blocks;
  }
  if (regular) {
    blocks.size_ = static_cast<uint64_t>(info.st_size);
    // A block no larger than the file needs (with room to see its end in the same read), so that
    // a small log does not allocate and fault in a whole block; a file that grows meanwhile is
    // still read whole, in more reads.
    constexpr uint64_t kSmallestBlock = 4 << 10;
    blocks.capacity_ = static_cast<size_t>(
        std::min<uint64_t>(blocks.capacity_, std::max(blocks.size_ + 1, kSmallestBlock)));
  }
  blocks.buffer_.reset(new char[blocks.capacity_]);
  return blocks;
}

TextBlocks TextBlocks::OfCopy(int copy_fd, const std::string& path) {
  TextBlocks blocks;
  blocks.path_ = path;
  blocks.capacity_ = kBlockBytes;
  blocks.mapped_ = MappedFile::OfCopy(copy_fd, path, MappedFile::Paging::kStreamed);
  blocks.memory_ = blocks.mapped_->text();
  blocks.size_ = blocks.memory_.size();
  return blocks;
}

struct ReopenableFile::Copy {
  explicit Copy(int fd) : file{fd} {}
  Copy(const Copy&) = delete;
  Copy& operator=(const Copy&) = delete;
  const Descriptor file;  // closed with the last ReopenableFile that shares it
};

ReopenableFile::ReopenableFile(const std::string& path) {
  const Descriptor file{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  struct stat info {};
  if (file.fd < 0 || ::fstat(file.fd, &info) != 0)
    throw IoError(IoMessage(path, 0, std::string("cannot open: ") + std::strerror(errno)));
  stamp_ = StampOf(info, path);
  if (!S_ISREG(info.st_mode))
    copy_ = std::make_shared<const Copy>(CopyToTemporaryFile({}, file.fd, path));
}

TextBlocks ReopenableFile::Open() const {
  if (copy_) return TextBlocks::OfCopy(copy_->file.fd, stamp_.path);
  stamp_.CheckUnchanged();
  return TextBlocks::OfFile(stamp_.path);
}

void ReopenableFile::CheckUnchanged() const {
  if (!copy_) stamp_.CheckUnchanged();
}

TextBlocks TextBlocks::InMemory(std::string_view text, size_t block_bytes) {
  TextBlocks blocks;
  blocks.size_ = text.size();
  blocks.memory_ = text;
  blocks.capacity_ = std::max<size_t>(block_bytes, 1);
  return blocks;
}

TextBlocks::TextBlocks(TextBlocks&& other) noexcept
    : path_(std::move(other.path_)),
      fd_(std::exchange(other.fd_, -1)),
      size_(other.size_),
      handed_out_(other.handed_out_),
      memory_(other.memory_),
      mapped_(std::move(other.mapped_)),
      populated_(other.populated_),
      buffer_(std::move(other.buffer_)),
      capacity_(other.capacity_),
      carry_begin_(other.carry_begin_),
      carry_end_(other.carry_end_),
      end_of_file_(other.end_of_file_) {}

TextBlocks::~TextBlocks() {
  if (fd_ >= 0) ::close(fd_);
}

size_t TextBlocks::Read(size_t at, size_t max_bytes) {
  while (true) {
    const ssize_t n = ::read(fd_, buffer_.get() + at, max_bytes);
    if (n > 0) return static_cast<size_t>(n);
    if (n == 0) {
      end_of_file_ = true;
      return 0;
    }
    if (errno != EINTR)
      throw IoError(IoMessage(path_, 0, std::string("read failed: ") + std::strerror(errno)));
  }
}

std::string_view TextBlocks::Next() {
  if (fd_ < 0) {  // in memory: cut at the last line end within a block (or the next one after)
    const size_t begin = handed_out_;
    if (mapped_) mapped_->ReleaseBefore(begin);
    if (begin >= memory_.size()) return {};
    size_t end = std::min(memory_.size(), begin + capacity_);
    if (end < memory_.size()) {
      const size_t last = memory_.rfind('\n', end - 1);
      if (last != std::string_view::npos && last >= begin) {
        end = last + 1;
      } else {
        const size_t next = memory_.find('\n', end);
        end = next == std::string_view::npos ? memory_.size() : next + 1;
      }
    }
    handed_out_ = end;
    // The pages up to a 2 MiB span past this block mapped ahead, a span at a time.
    constexpr size_t kPopulateBytes = 2 << 20;
    if (mapped_ && end + kPopulateBytes > populated_) {
      const size_t to = (end + 2 * kPopulateBytes - 1) / kPopulateBytes * kPopulateBytes;
      mapped_->Populate(populated_, to);
      populated_ = to;
    }
    return memory_.substr(begin, end - begin);
  }
  // The started line of the last block first, then as much of the file as fits.
  size_t filled = carry_end_ - carry_begin_;
  std::memmove(buffer_.get(), buffer_.get() + carry_begin_, filled);
  carry_begin_ = carry_end_ = 0;
  size_t searched = 0;
  while (true) {
    while (!end_of_file_ && filled < capacity_) filled += Read(filled, capacity_ - filled);
    const void* last =
        filled > searched ? ::memrchr(buffer_.get() + searched, '\n', filled - searched) : nullptr;
    if (last != nullptr || end_of_file_) {
      const size_t end = last ? static_cast<const char*>(last) - buffer_.get() + 1 : filled;
      carry_begin_ = end;
      carry_end_ = filled;
      handed_out_ += end;
      return {buffer_.get(), end};
    }
    // One line longer than the block: a larger block.
    searched = filled;
    std::unique_ptr<char[]> larger(new char[capacity_ * 2]);
    std::memcpy(larger.get(), buffer_.get(), filled);
    buffer_ = std::move(larger);
    capacity_ *= 2;
  }
}

std::string_view TextBlocks::Peek(size_t bytes) {
  SHUTTERLAB_CHECK(handed_out_ == 0) << "TextBlocks::Peek after Next";
  if (fd_ < 0) return memory_.substr(0, bytes);
  bytes = std::min(bytes, capacity_);
  // The carried bytes are the next block's start. No more than asked: the rest comes in Next's
  // reads, without touching the whole block now.
  while (!end_of_file_ && carry_end_ < bytes) carry_end_ += Read(carry_end_, bytes - carry_end_);
  return {buffer_.get(), std::min(bytes, carry_end_)};
}

std::unique_ptr<MappedFile> TextBlocks::TakeMapped() {
  SHUTTERLAB_CHECK(handed_out_ == 0) << "TextBlocks::TakeMapped after Next";
  std::unique_ptr<MappedFile> mapped = std::move(mapped_);
  if (!mapped) {
    // A pipe: what Peek read first, then the rest; or a text in memory.
    const std::string_view head =
        fd_ >= 0 ? std::string_view(buffer_.get() + carry_begin_, carry_end_ - carry_begin_)
                 : memory_;
    mapped = MappedFile::Copied(head, fd_, path_, MappedFile::Paging::kStreamed);
  }
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  memory_ = {};
  size_ = 0;
  carry_begin_ = carry_end_ = 0;
  end_of_file_ = true;
  return mapped;
}

double TextBlocks::Fraction() const {
  return size_ > 0 ? std::min(1.0, static_cast<double>(handed_out_) / size_) : 1.0;
}

std::optional<std::string_view> LineReader::Next() {
  if (pos_ >= block_.size()) {
    block_ = blocks_.Next();
    pos_ = 0;
    if (block_.empty()) return std::nullopt;
  }
  size_t end = block_.find('\n', pos_);
  // A block holds whole lines, but for the input's last when it has no line break.
  unterminated_ = end == std::string_view::npos;
  if (unterminated_) end = block_.size();
  std::string_view line = block_.substr(pos_, end - pos_);
  pos_ = end + 1;
  ++line_number_;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

std::optional<std::string_view> LineCursor::Next() {
  if (pos_ >= text_.size()) return std::nullopt;
  size_t end = text_.find('\n', pos_);
  unterminated_ = end == std::string_view::npos;
  if (unterminated_) end = text_.size();
  std::string_view line = text_.substr(pos_, end - pos_);
  pos_ = end + 1;
  ++line_number_;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

void SplitFields(std::string_view line, char delimiter, std::vector<std::string_view>* fields) {
  fields->clear();
  size_t start = 0;
  while (true) {
    size_t end = line.find(delimiter, start);
    std::string_view field =
        line.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
    while (!field.empty() && (field.front() == ' ' || field.front() == '\t'))
      field.remove_prefix(1);
    while (!field.empty() && (field.back() == ' ' || field.back() == '\t')) field.remove_suffix(1);
    fields->push_back(field);
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
}

std::optional<double> ParseDouble(std::string_view field) {
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return std::nullopt;
  double value = 0.0;
  const char* end = field.data() + field.size();
  if (FromCharsDouble(field.data(), end, &value) != end || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::optional<int64_t> ParseInt(std::string_view field) {
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return std::nullopt;
  int64_t value = 0;
  const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec != std::errc() || ptr != field.data() + field.size()) return std::nullopt;
  return value;
}

void AppendDouble(double value, std::string* out) {
  char buffer[32];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out->append(buffer, ec == std::errc() ? ptr - buffer : 0);
}

void AppendSecondsFromNs(int64_t t_ns, std::string* out) {
  // By hand rather than snprintf: gyro.csv writes one a sample, and with snprintf the one-off cost
  // of correct --photos on a 120 s log at 1 kHz was 0.25 s against 0.22 s (bench/photos_bench.cc).
  char buffer[32];
  char* p = buffer;
  if (t_ns < 0) *p++ = '-';
  const uint64_t magnitude = t_ns < 0 ? 0 - static_cast<uint64_t>(t_ns) : t_ns;
  p = std::to_chars(p, buffer + 21, magnitude / 1000000000ULL).ptr;
  *p++ = '.';
  uint64_t fraction_ns = magnitude % 1000000000ULL;
  for (int digit = 8; digit >= 0; --digit, fraction_ns /= 10) p[digit] = '0' + fraction_ns % 10;
  out->append(buffer, p + 9 - buffer);
}

std::string ToLower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

namespace {

// True when name ends in `end` (lowercase), in any case.
bool EndsInAnyCase(std::string_view name, std::string_view end) {
  return name.size() >= end.size() && ToLower(name.substr(name.size() - end.size())) == end;
}

}  // namespace

bool HasJpegExtension(std::string_view name) {
  return EndsInAnyCase(name, ".jpg") || EndsInAnyCase(name, ".jpeg");
}

bool HasPngExtension(std::string_view name) { return EndsInAnyCase(name, ".png"); }

std::string FormatNumber(const char* format, double value) {
  // Most results fit the stack buffer; a longer format (a sentence around the number) is sized
  // and written again rather than cut.
  char buffer[64];
  const int length = std::snprintf(buffer, sizeof(buffer), format, value);
  if (length < 0) return {};
  if (static_cast<size_t>(length) < sizeof(buffer)) return std::string(buffer, length);
  std::string out(static_cast<size_t>(length) + 1, '\0');
  std::snprintf(out.data(), out.size(), format, value);
  out.resize(static_cast<size_t>(length));
  return out;
}

}  // namespace shutterlab
