#include "record/record_output.h"

#include "sim/check.h"
#include "sim/logs/gcsv.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fcntl.h>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <sys/stat.h>
#include <unistd.h>

namespace shutterlab {
namespace {

std::string ErrnoText() { return std::strerror(errno); }

// "DIR/.NAME.SUFFIX-XXXXXX" created with mkstemp; the fd returned, the path in *path.
int MakeTempBeside(const std::string& final_path, const std::string& suffix, std::string* path) {
  const std::filesystem::path target(final_path);
  const std::filesystem::path dir = target.has_parent_path() ? target.parent_path() : ".";
  std::string pattern =
      (dir / ("." + target.filename().string() + "." + suffix + "-XXXXXX")).string();
  const int fd = ::mkstemp(pattern.data());
  if (fd < 0)
    throw IoError(IoMessage(final_path, 0, "cannot create a file beside it: " + ErrnoText()));
  *path = pattern;
  return fd;
}

void WriteAll(int fd, const char* data, size_t n, const std::string& name) {
  while (n > 0) {
    const ssize_t written = ::write(fd, data, n);
    if (written < 0) {
      if (errno == EINTR) continue;
      throw IoError(IoMessage(name, 0, "write failed: " + ErrnoText()));
    }
    data += written;
    n -= static_cast<size_t>(written);
  }
}

// Copies from_fd from byte `from` to its end onto the end of to_fd, in the kernel where it can.
void CopyRows(int from_fd, off_t from, int to_fd, const std::string& name) {
  if (::lseek(from_fd, from, SEEK_SET) < 0)
    throw IoError(IoMessage(name, 0, "seek failed: " + ErrnoText()));
  while (true) {
    const ssize_t n = ::copy_file_range(from_fd, nullptr, to_fd, nullptr, size_t{1} << 30, 0);
    if (n == 0) return;
    if (n > 0) continue;
    if (errno == EINTR) continue;
    if (errno != EXDEV && errno != ENOSYS && errno != EINVAL && errno != EOPNOTSUPP) {
      throw IoError(IoMessage(name, 0, "copy failed: " + ErrnoText()));
    }
    break;  // fall back to read and write
  }
  std::vector<char> buffer(size_t{1} << 20);
  while (true) {
    const ssize_t n = ::read(from_fd, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw IoError(IoMessage(name, 0, "read failed: " + ErrnoText()));
    if (n == 0) return;
    WriteAll(to_fd, buffer.data(), static_cast<size_t>(n), name);
  }
}

// Writes path whole or not at all: fill(fd) writes a temporary file beside it, which is synced and
// renamed into place; on any failure it is removed and the error passed on.
void WriteWhole(const std::string& path, const std::function<void(int)>& fill) {
  std::string temp_path;
  const int out_fd = MakeTempBeside(path, "tmp", &temp_path);
  try {
    fill(out_fd);
    if (::fchmod(out_fd, 0644) < 0 || ::fsync(out_fd) < 0) {
      throw IoError(IoMessage(path, 0, "cannot sync: " + ErrnoText()));
    }
  } catch (...) {
    ::close(out_fd);
    std::remove(temp_path.c_str());
    throw;
  }
  ::close(out_fd);  // once: closing it again could close a descriptor another thread just opened
  if (::rename(temp_path.c_str(), path.c_str()) < 0) {
    const std::string why = ErrnoText();
    std::remove(temp_path.c_str());
    throw IoError(IoMessage(path, 0, "cannot rename into place: " + why));
  }
}

std::string Vector3Text(const Eigen::Vector3d& v) {
  std::string text;
  for (int axis = 0; axis < 3; ++axis) {
    if (axis) text += ';';
    AppendDouble(v[axis], &text);
  }
  return text;
}

std::string Number(double value) { return FormatNumber("%.9g", value); }

}  // namespace

RowFile::RowFile(const std::string& final_path, const std::string& partial_header,
                 double sync_interval_s)
    : final_path_(final_path),
      partial_path_(final_path + ".partial"),
      sync_interval_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(sync_interval_s))) {
  // Read and write: Finish copies the rows from it. The header is written and synced in an
  // unnamed file that is then linked into place, so that a kill or power cut never leaves the
  // partial file without its header; where the file system has no unnamed files (vfat), the file
  // is made under its name and written at once.
  const std::filesystem::path dir = std::filesystem::path(final_path_).has_parent_path()
                                        ? std::filesystem::path(final_path_).parent_path()
                                        : std::filesystem::path(".");
  fd_ = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0644);
  const bool unnamed = fd_ >= 0;
  if (!unnamed) fd_ = ::open(partial_path_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  const auto refuse_existing = [&] {
    throw IoError(
        IoMessage(partial_path_, 0,
                  "exists: a recording before this one was cut (killed, power lost or the disk "
                  "full); it is kept as it is: read it (shutterlab analyze " +
                      partial_path_ + ") or move it away, then record again"));
  };
  if (fd_ < 0 && errno == EEXIST) refuse_existing();
  if (fd_ < 0) throw IoError(IoMessage(final_path_, 0, "cannot create: " + ErrnoText()));
  try {
    WriteAll(fd_, partial_header.data(), partial_header.size(), partial_path_);
    if (::fdatasync(fd_) < 0)
      throw IoError(IoMessage(partial_path_, 0, "cannot sync: " + ErrnoText()));
    if (unnamed) {
      const std::string fd_path = "/proc/self/fd/" + std::to_string(fd_);
      if (::linkat(AT_FDCWD, fd_path.c_str(), AT_FDCWD, partial_path_.c_str(), AT_SYMLINK_FOLLOW) <
          0) {
        if (errno == EEXIST) refuse_existing();
        throw IoError(IoMessage(partial_path_, 0, "cannot create: " + ErrnoText()));
      }
      // The name itself on disk: a power cut right after must not lose the file.
      const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
      if (dir_fd >= 0) {
        ::fsync(dir_fd);
        ::close(dir_fd);
      }
    }
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    if (!unnamed) std::remove(partial_path_.c_str());
    throw;
  }
  header_bytes_ = partial_header.size();
  size_bytes_ = static_cast<off_t>(header_bytes_);
  synced_bytes_ = size_bytes_;
  last_sync_ = std::chrono::steady_clock::now();
}

RowFile::~RowFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!finished_ && !has_rows()) std::remove(partial_path_.c_str());
}

void RowFile::Append(const std::string& text) {
  try {
    WriteAll(fd_, text.data(), text.size(), partial_path_);
  } catch (const IoError&) {
    // A full disk (or a file size limit) mid-block: back to the last whole row, so that the file
    // kept holds whole rows only.
    if (::ftruncate(fd_, size_bytes_) == 0) ::lseek(fd_, size_bytes_, SEEK_SET);
    throw;
  }
  size_bytes_ += static_cast<off_t>(text.size());
  const auto now = std::chrono::steady_clock::now();
  if (now - last_sync_ >= sync_interval_) {
    if (::fdatasync(fd_) < 0)
      throw IoError(IoMessage(partial_path_, 0, "cannot sync: " + ErrnoText()));
    last_sync_ = now;
    synced_bytes_ = size_bytes_;
  }
}

void RowFile::Finish(const std::string& header) {
  WriteWhole(final_path_, [&](int out_fd) {
    WriteAll(out_fd, header.data(), header.size(), final_path_);
    CopyRows(fd_, static_cast<off_t>(header_bytes_), out_fd, final_path_);
  });
  finished_ = true;
  std::remove(partial_path_.c_str());
}

void RowFile::WriteAlso(const std::string& path, AlsoFormat format, double rad_s_per_count,
                        const Eigen::Matrix3d& orientation) const {
  WriteWhole(path, [&](int out_fd) {
    std::string out =
        format == AlsoFormat::kGyroCsv ? "t,gx,gy,gz\n" : "t,gx_counts,gy_counts,gz_counts\n";
    // The rows as written: "t_ns,c0,c1,c2\n", read back in blocks (a line may straddle two).
    std::vector<char> block(size_t{1} << 20);
    std::string carry;
    for (off_t at = static_cast<off_t>(header_bytes_); at < size_bytes_;) {
      const ssize_t n = ::pread(fd_, block.data(), block.size(), at);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw IoError(IoMessage(partial_path_, 0, "read failed: " + ErrnoText()));
      at += n;
      carry.append(block.data(), static_cast<size_t>(n));
      size_t begin = 0;
      for (size_t end; (end = carry.find('\n', begin)) != std::string::npos; begin = end + 1) {
        int64_t fields[4];
        const char* p = carry.data() + begin;
        for (int64_t& field : fields) p = std::from_chars(p, carry.data() + end, field).ptr + 1;
        AppendSecondsFromNs(fields[0], &out);
        const Eigen::Vector3d counts(fields[1], fields[2], fields[3]);
        const Eigen::Vector3d values = format == AlsoFormat::kGyroCsv
                                           ? Eigen::Vector3d(orientation * counts * rad_s_per_count)
                                           : counts;
        for (int axis = 0; axis < 3; ++axis) {
          out += ',';
          if (format == AlsoFormat::kGyroCsv)
            AppendDouble(values[axis], &out);
          else
            out += std::to_string(fields[axis + 1]);
        }
        out += '\n';
      }
      carry.erase(0, begin);
      if (out.size() > block.size()) {
        WriteAll(out_fd, out.data(), out.size(), path);
        out.clear();
      }
    }
    WriteAll(out_fd, out.data(), out.size(), path);
  });
}

AlsoFormat ParseAlsoFormat(const std::string& name) {
  if (name == "gyro.csv") return AlsoFormat::kGyroCsv;
  if (name == "raw") return AlsoFormat::kRawCounts;
  throw std::invalid_argument("--also: '" + name + "' is not a format (gyro.csv, raw)");
}

std::string AlsoPath(const std::string& gcsv_path, AlsoFormat format) {
  const std::string stem =
      gcsv_path.size() > 5 && gcsv_path.compare(gcsv_path.size() - 5, 5, ".gcsv") == 0
          ? gcsv_path.substr(0, gcsv_path.size() - 5)
          : gcsv_path;
  return stem + (format == AlsoFormat::kGyroCsv ? ".gyro.csv" : ".raw.csv");
}

void AppendRecordedRow(const RecordedSample& sample, int64_t t0_ns, std::string* out) {
  char buffer[64];
  char* p = buffer;
  char* end = buffer + sizeof(buffer);
  p = std::to_chars(p, end, sample.t_ns - t0_ns).ptr;
  for (int axis = 0; axis < 3; ++axis) {
    *p++ = ',';
    p = std::to_chars(p, end, sample.counts[axis]).ptr;
  }
  *p++ = '\n';
  out->append(buffer, p);
}

namespace {

// The header of sensor `index`: with its summary when `finished`, else what the start knows and
// the line that says what a kill or a power cut loses.
std::string GcsvHeaderOf(const RecordSummary& summary, int index, const RecorderOptions& options,
                         bool finished) {
  const SensorSummary& s = summary.sensors.at(index);
  const PartInfo& part = GetPartInfo(s.setting.part);
  GcsvWriteOptions gcsv;
  gcsv.id = "shutterlab record";
  gcsv.orientation = options.orientation;
  gcsv.time_unit = TimeUnit::kNanoseconds;
  gcsv.gscale = kPi / 180.0 / s.setting.lsb_per_dps;  // rad/s per count
  auto& h = gcsv.extra_header;
  if (!options.note.empty()) h.emplace_back("note", options.note);
  h.emplace_back("vendor", "shutterlab");
  h.emplace_back("fwversion", "shutterlab record 0.1");
  h.emplace_back("timestamp", std::to_string(static_cast<long long>(std::time(nullptr))));
  h.emplace_back("part", part.name);
  h.emplace_back("who_am_i", HexByte(part.who_am_i));
  h.emplace_back("device", s.device);
  h.emplace_back("sensor",
                 std::to_string(index + 1) + " of " + std::to_string(summary.sensors.size()));
  h.emplace_back("odr_hz", Number(s.setting.odr_hz));
  h.emplace_back("range_dps", std::to_string(s.setting.range_dps));
  h.emplace_back("lsb_per_dps", Number(s.setting.lsb_per_dps));
  h.emplace_back("filter", s.setting.Describe());
  h.emplace_back("filter_delay_ms", Number(s.setting.filter_delay_s * 1e3));
  h.emplace_back("clock",
                 "CLOCK_MONOTONIC; t = clock - t0_clock_ns - filter_delay (the motion's time)");
  h.emplace_back("t0_clock_ns", std::to_string(summary.t0_clock_ns));
  if (!finished) {
    h.emplace_back(
        "recording",
        "unfinished: the recorder stopped before its summary (killed, power lost or the "
        "disk full); "
        "a kill loses the reads of about the last " +
            FormatNumber("%.0f", options.writer_interval_s * 1e3) +
            " ms, a power cut those of the last " +
            FormatNumber("%.0f", (options.sync_interval_s + options.writer_interval_s) * 1e3) +
            " ms");
    return GcsvHeaderText(gcsv);
  }
  h.emplace_back("samples", std::to_string(s.samples));
  h.emplace_back("rate_hz", Number(s.rate_hz));
  h.emplace_back("drift_ppm", FormatNumber("%.3f", s.drift_ppm));
  h.emplace_back("timestamp_rms_us", FormatNumber("%.3f", s.timestamp_rms_us));
  h.emplace_back("gaps", std::to_string(s.gaps));
  h.emplace_back("samples_lost", std::to_string(s.lost));
  h.emplace_back("ring_high_water",
                 std::to_string(s.ring_high_water) + " of " + std::to_string(s.ring_capacity));
  h.emplace_back("max_read_interval_ms", FormatNumber("%.3f", s.max_read_interval_s * 1e3));
  h.emplace_back("max_writer_stall_ms", FormatNumber("%.3f", summary.max_writer_stall_s * 1e3));
  h.emplace_back("still_s", Number(s.still_span_s));
  h.emplace_back("still_bias_rad_s", Vector3Text(s.still_bias_rad_s));
  h.emplace_back("still_std_rad_s", Vector3Text(s.still_std_rad_s));
  for (const RecordGap& gap : summary.gaps) {
    if (gap.sensor != index) continue;
    h.emplace_back("gap",
                   FormatNumber("%.9f", gap.t_s) + "," + std::to_string(gap.lost) + "," + gap.kind);
  }
  return GcsvHeaderText(gcsv);
}

}  // namespace

std::string RecordedGcsvHeader(const RecordSummary& summary, int index,
                               const RecorderOptions& options) {
  return GcsvHeaderOf(summary, index, options, true);
}

std::string RecordingGcsvHeader(const RecordSummary& start, int index,
                                const RecorderOptions& options) {
  return GcsvHeaderOf(start, index, options, false);
}

void WriteTriggersFile(const std::string& path, const RecordSummary& summary,
                       const RecorderOptions& options) {
  std::string text =
      "# shutterlab record: camera triggers; t in s on the clock of the .gcsv rows\n";
  text += "# source: " + (options.trigger ? options.trigger->Name() : std::string("none")) + "\n";
  text += "# edges: " + std::string(TriggerPolarityName(options.polarity)) + ", debounce " +
          Number(options.debounce_s) + " s; " + std::to_string(summary.trigger_edges) +
          " edge(s) seen, " + std::to_string(summary.trigger_bounces) + " bounce(s) ignored, " +
          std::to_string(summary.trigger_other_polarity) + " of the other direction\n";
  text += "# t0_clock_ns: " + std::to_string(summary.t0_clock_ns) + "\n";
  text += "image,t\n";
  for (size_t i = 0; i < summary.trigger_t_s.size(); ++i) {
    text += FormatNumber("IMG_%04.0f,", static_cast<double>(i + 1));
    text += FormatNumber("%.9f", summary.trigger_t_s[i]) + "\n";
  }
  WriteFileAtomically(path, text);
}

}  // namespace shutterlab
