#pragma once
// A gyro trace handed on in chunks, in time order, so that a log of any length is analysed in
// bounded memory: the readers of text logs parse a block at a time (sim/logs/gyro_io.h
// OpenGyroCsv, ...), and a trace already in memory is handed on in slices (TraceSource).

#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

// Samples [data, data + size), valid until the source's next call.
struct GyroChunk {
  const GyroSample* data = nullptr;
  size_t size = 0;
  bool empty() const { return size == 0; }
  const GyroSample* begin() const { return data; }
  const GyroSample* end() const { return data + size; }
};

// Told the share (0..1) of a log's bytes that a reader's opening pass has read, as it goes: a
// flight-controller log's pass 1, before its samples can be taken (tens of seconds on 10^8
// samples), whose progress a terminal shows before the samples' own (GyroSource::Fraction).
using OpeningProgress = std::function<void(double)>;
// An opening pass reports every this many messages: a call per few hundred KiB.
inline constexpr size_t kOpeningProgressMessages = 4096;

class GyroSource {
 public:
  virtual ~GyroSource() = default;
  // The next samples, in non-decreasing time with finite rates (a reader refuses anything else
  // with an IoError naming the file and line); an empty chunk at the end.
  virtual GyroChunk Next() = 0;
  // The share of the input read so far, 0..1 (for progress).
  virtual double Fraction() const = 0;
  // What reading lost (a text log cut inside its last line: sim/log_warning.h
  // CutLastLineWarning), complete once Next has returned the empty chunk.
  virtual std::vector<LogWarning> Warnings() const { return {}; }
  // The next chunk into *out (its content replaced); false at the end. A source that fills a
  // buffer of its own hands it over instead of copying (FillingSource).
  virtual bool NextInto(std::vector<GyroSample>* out) {
    const GyroChunk chunk = Next();
    out->assign(chunk.begin(), chunk.end());
    return !chunk.empty();
  }
};

// A source that fills chunks of its own (the text readers): Fill is all it writes.
class FillingSource : public GyroSource {
 public:
  // Samples per chunk by default: 512 KiB, which stay in L2 while the analysis takes them. Tests
  // and fuzz targets choose a few, which puts chunk edges everywhere in a small input.
  static constexpr size_t kDefaultChunkSamples = 1 << 14;
  explicit FillingSource(size_t chunk_samples = kDefaultChunkSamples)
      : chunk_samples_(std::max<size_t>(chunk_samples, 1)) {}
  GyroChunk Next() final {
    chunk_.clear();
    Fill(&chunk_);
    return {chunk_.data(), chunk_.size()};
  }
  bool NextInto(std::vector<GyroSample>* out) final {
    out->clear();
    Fill(out);
    return !out->empty();
  }
  std::vector<LogWarning> Warnings() const final { return warnings_; }

 protected:
  // Appends the next samples, at most chunk_samples(), to *chunk (empty on entry); none at the end.
  virtual void Fill(std::vector<GyroSample>* chunk) = 0;
  size_t chunk_samples() const { return chunk_samples_; }
  // Room in *chunk for a chunk, but no more than an input of input_bytes can fill (a row of four
  // numbers takes at least 8 bytes; 0: unknown): a small file does not allocate a 2 MiB chunk.
  void ReserveChunk(std::vector<GyroSample>* chunk, uint64_t input_bytes) const {
    const uint64_t rows = input_bytes > 0 ? input_bytes / 8 + 1 : chunk_samples_;
    chunk->reserve(static_cast<size_t>(std::min<uint64_t>(chunk_samples_, rows)));
  }
  // The input's last line (line_number) has no line break and does not read: left out, and said
  // (Warnings). last_t_ns: the time of the sample before it, when there is one.
  void LeaveOutCutLastLine(long line_number, std::optional<int64_t> last_t_ns) {
    warnings_.push_back(CutLastLineWarning(
        line_number, last_t_ns ? std::optional<double>(*last_t_ns * 1e-9) : std::nullopt));
  }
  void LeaveOutCutLastLine(long line_number) { LeaveOutCutLastLine(line_number, last_t_ns_); }
  // Another thing the reader left out or doubted (Warnings).
  void AddWarning(LogWarning warning) { warnings_.push_back(std::move(warning)); }
  // Takes the time of the sample on line line_number of path, refusing one earlier than the
  // sample before it (equal times are kept: a log may stamp two samples alike). time_as_written:
  // its time field as the file holds it, for the message.
  void TakeTimeInOrder(const std::string& path, long line_number, int64_t t_ns,
                       std::string_view time_as_written);
  // The time of the last sample taken, none before the first.
  const std::optional<int64_t>& last_t_ns() const { return last_t_ns_; }

 private:
  std::optional<int64_t> last_t_ns_;
  size_t chunk_samples_;
  std::vector<GyroSample> chunk_;
  std::vector<LogWarning> warnings_;
};

// A trace held in memory, in slices of chunk_samples.
class TraceSource : public GyroSource {
 public:
  explicit TraceSource(GyroTrace trace, size_t chunk_samples = 1 << 16)
      : trace_(std::move(trace)), chunk_(std::max<size_t>(chunk_samples, 1)) {}
  GyroChunk Next() override {
    const size_t n = std::min(chunk_, trace_.size() - next_);
    GyroChunk chunk{trace_.samples().data() + next_, n};
    next_ += n;
    return chunk;
  }
  double Fraction() const override {
    return trace_.empty() ? 1.0 : static_cast<double>(next_) / trace_.size();
  }

 private:
  GyroTrace trace_;
  size_t chunk_;
  size_t next_ = 0;
};

// Every sample of a source, as a trace (validated as GyroTrace validates).
GyroTrace ReadAllSamples(GyroSource* source);
// The same for a caller that keeps no warnings (the readers that return a bare trace): what the
// source lost (a cut last line) is an IoError naming path there, never dropped silently.
GyroTrace ReadAllSamples(GyroSource* source, const std::string& path);

// The source read one chunk ahead on a thread of its own, so that reading (parsing text) and the
// analysis of the chunk before run on two cores. Chunks are copied into a few buffers of its own;
// an exception of the source is thrown from Next in the caller's thread, in order.
std::unique_ptr<GyroSource> ReadAhead(std::unique_ptr<GyroSource> source);

}  // namespace shutterlab
