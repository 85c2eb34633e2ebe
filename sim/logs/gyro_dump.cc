#include "sim/logs/gyro_dump.h"

#include "sim/check.h"
#include "sim/logs/raw_csv.h"  // ParseTimeInUnitNs

#include <array>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

// The first non-blank line of text (without a '\r').
std::string_view FirstLine(std::string_view text) {
  LineCursor lines(StripBom(text));
  while (auto line = lines.Next()) {
    if (line->find_first_not_of(" \t") != std::string_view::npos) return *line;
  }
  return {};
}

// The words of a line, split on runs of spaces and tabs.
void SplitWords(std::string_view line, std::vector<std::string_view>* words) {
  words->clear();
  size_t start = line.find_first_not_of(" \t");
  while (start != std::string_view::npos) {
    const size_t end = line.find_first_of(" \t", start);
    words->push_back(line.substr(start, end == std::string_view::npos ? end : end - start));
    start = line.find_first_not_of(" \t", end);
  }
}

bool StartsWith(std::string_view text, std::string_view prefix) {
  return text.substr(0, prefix.size()) == prefix;
}

class GyroDumpSource : public FillingSource {
 public:
  GyroDumpSource(TextBlocks blocks, const std::string& path, size_t chunk_samples)
      : FillingSource(chunk_samples), lines_(std::move(blocks)), path_(path) {}

  double Fraction() const override { return lines_.Fraction(); }

 private:
  void Fill(std::vector<GyroSample>* chunk) override {
    ReserveChunk(chunk, lines_.size_bytes());
    while (chunk->size() < chunk_samples()) {
      const auto line = lines_.Next();
      if (!line) {
        Finish();
        break;
      }
      SplitWords(lines_.line_number() == 1 ? StripBom(*line) : *line, &words_);
      if (words_.empty() || words_[0] == "SOF") continue;
      std::optional<GyroSample> sample;
      try {
        sample = ReadLine(lines_.line_number());
      } catch (const IoError&) {
        if (!lines_.unterminated()) throw;
        LeaveOutCutLastLine(lines_.line_number());
        continue;
      }
      if (sample) chunk->push_back(*sample);
    }
    if (chunk->empty() && !last_t_ns())
      throw IoError(IoMessage(path_, 0, "no gyro lines ('frameid:N gyro:K x .. y .. z .. ts ..')"));
  }

  // The sample of line n (split into words_), or none when it repeats the sample before.
  std::optional<GyroSample> ReadLine(long n) {
    constexpr std::array<std::string_view, 4> kKeys = {"x", "y", "z", "ts"};
    if (words_.size() != 10 || !StartsWith(words_[0], "frameid:") ||
        !StartsWith(words_[1], "gyro:") || words_[2] != kKeys[0] || words_[4] != kKeys[1] ||
        words_[6] != kKeys[2] || words_[8] != kKeys[3]) {
      throw IoError(IoMessage(path_, n, "expected 'frameid:N gyro:K x X y Y z Z ts T(us)'"));
    }
    GyroSample s;
    for (int axis = 0; axis < 3; ++axis) {
      const std::string_view field = words_[3 + 2 * axis];
      const auto value = ParseDouble(field);
      if (!value) {
        throw IoError(IoMessage(
            path_, n, std::string(kKeys[axis]) + " is not a number: '" + std::string(field) + "'"));
      }
      s.omega_rad_s[axis] = *value;
    }
    const auto t_ns = ParseTimeInUnitNs(words_[9], TimeUnit::kMicroseconds);
    if (!t_ns) {
      throw IoError(IoMessage(
          path_, n, "ts is not a finite time in us in range: '" + std::string(words_[9]) + "'"));
    }
    s.t_ns = *t_ns;
    if (last_ && last_->t_ns == s.t_ns && last_->omega_rad_s == s.omega_rad_s) {
      if (repeated_++ == 0) first_repeat_ = {n, s.t_ns};
      return std::nullopt;
    }
    TakeTimeInOrder(path_, n, s.t_ns, words_[9]);
    last_ = s;
    return s;
  }

  // At the end: what was left out as repeats.
  void Finish() {
    if (finished_) return;
    finished_ = true;
    if (repeated_ == 0) return;
    LogWarning w;
    w.kind = "repeated_sample";
    w.message = std::to_string(repeated_) +
                " sample(s) repeated at the start of the next frame's batch (same time and rates "
                "as the line before) left out, first at line " +
                std::to_string(first_repeat_.first);
    w.t_s = first_repeat_.second * 1e-9;
    w.count = repeated_;
    AddWarning(std::move(w));
  }

  LineReader lines_;
  std::string path_;
  std::vector<std::string_view> words_;
  std::optional<GyroSample> last_;
  size_t repeated_ = 0;
  std::pair<long, int64_t> first_repeat_{0, 0};  // line, time
  bool finished_ = false;
};

}  // namespace

bool LooksLikeGyroDump(std::string_view first_bytes) {
  const std::string_view line = FirstLine(first_bytes);
  std::vector<std::string_view> words;
  SplitWords(line, &words);
  return !words.empty() && (StartsWith(words[0], "frameid:") || words[0] == "SOF");
}

std::unique_ptr<GyroSource> OpenGyroDump(TextBlocks blocks, const std::string& path,
                                         size_t chunk_samples) {
  return std::make_unique<GyroDumpSource>(std::move(blocks), path, chunk_samples);
}

}  // namespace shutterlab
