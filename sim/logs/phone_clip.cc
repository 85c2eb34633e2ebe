#include "sim/logs/phone_clip.h"

#include "sim/check.h"
#include "sim/logs/column_csv.h"
#include "sim/text_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <regex>
#include <string_view>

namespace shutterlab {
namespace fs = std::filesystem;
namespace {

// Parses "NAME :value" style fields of gyro_dump.txt: the text after `key` up to the next space or
// comma. nullopt when the key is absent.
std::optional<std::string_view> FieldAfter(std::string_view line, std::string_view key) {
  const size_t at = line.find(key);
  if (at == std::string_view::npos) return std::nullopt;
  size_t begin = at + key.size();
  while (begin < line.size() && (line[begin] == ' ' || line[begin] == ':')) ++begin;
  size_t end = begin;
  while (end < line.size() && line[end] != ' ' && line[end] != ',') ++end;
  return line.substr(begin, end - begin);
}

// gyro.txt: gx,gy,gz,t per line (rad/s, s), no header: the column reader, told so. Sets
// clip->gyro, clip->time_origin_ns and clip->warnings (a last line cut inside is left out, said).
void ReadGyroTxt(const std::string& gyro_path, PhoneClip* clip) {
  ColumnCsvOptions options;
  options.columns = {"4", "1", "2", "3"};
  options.delimiter = ',';
  options.header = HeaderMode::kNo;
  ColumnCsvLog log = ReadColumnCsv(gyro_path, options);
  if (log.trace.size() < 2) throw IoError(IoMessage(gyro_path, -1, "fewer than 2 samples"));
  // Times are ~4.3e6 s on the device clock: subtract whole seconds so that files keep small
  // numbers.
  const int64_t first_t_ns = log.trace.samples().front().t_ns;
  clip->time_origin_ns =
      (first_t_ns >= 0 ? first_t_ns : first_t_ns - 999999999) / 1000000000 * 1000000000;
  std::vector<GyroSample> samples = log.trace.samples();
  for (GyroSample& s : samples) s.t_ns -= clip->time_origin_ns;
  clip->gyro = GyroTrace(std::move(samples));
  clip->warnings = std::move(log.warnings);
  for (LogWarning& warning : clip->warnings)  // on the trace's clock, as the audit's warnings
    if (warning.t_s) *warning.t_s -= clip->time_origin_ns * 1e-9;
}

// framestamp.txt: one SOF time per line, line N = frame N. Sets clip->sof_ns.
void ReadFramestampTxt(const std::string& stamp_path, PhoneClip* clip) {
  const std::string stamp_text = ReadFileToString(stamp_path);
  LineCursor stamps(stamp_text);
  while (auto line = stamps.Next()) {
    if (line->empty()) continue;
    const auto value = ParseDouble(*line);
    if (!value) throw IoError(IoMessage(stamp_path, stamps.line_number(), "not a time in seconds"));
    if (static_cast<long>(clip->sof_ns.size()) + 1 != stamps.line_number())
      throw IoError(
          IoMessage(stamp_path, stamps.line_number(), "blank line: line N must be frame N"));
    clip->sof_ns.push_back(SecondsToNs(*value) - clip->time_origin_ns);
  }
  if (clip->sof_ns.empty()) throw IoError(IoMessage(stamp_path, -1, "no start-of-frame times"));
}

// gyro_dump.txt: "SOF <us>,  frameNum :N exp time <s>". Sets clip->exposure_s and
// clip->dump_sof_max_diff_s (against the SOF times already read).
void ReadGyroDumpTxt(const std::string& dump_path, PhoneClip* clip) {
  const std::string dump_text = ReadFileToString(dump_path);
  LineCursor dump(dump_text);
  while (auto line = dump.Next()) {
    if (line->substr(0, 3) != "SOF") continue;
    const auto sof = FieldAfter(*line, "SOF");
    const auto frame = FieldAfter(*line, "frameNum");
    const auto exposure = FieldAfter(*line, "exp time");
    const auto sof_us = sof ? ParseInt(*sof) : std::nullopt;
    const auto n = frame ? ParseInt(*frame) : std::nullopt;
    const auto exposure_s = exposure ? ParseDouble(*exposure) : std::nullopt;
    if (!sof_us || !n || !exposure_s)
      throw IoError(IoMessage(dump_path, dump.line_number(),
                              "expected 'SOF <us>, frameNum :N exp time <s>'"));
    const int64_t frame_n = n.value_or(0);
    clip->exposure_s[frame_n] = exposure_s.value_or(0.0);
    if (frame_n >= 1 && frame_n <= static_cast<int64_t>(clip->sof_ns.size())) {
      const int64_t sof_ns = sof_us.value_or(0) * 1000 - clip->time_origin_ns;
      const double diff_s = std::abs(sof_ns - clip->sof_ns[frame_n - 1]) * 1e-9;
      clip->dump_sof_max_diff_s = std::max(clip->dump_sof_max_diff_s, diff_s);
    }
  }
}

// frames/RE_frame-N.jpg (any image extension). Sets clip->frame_images.
void ListFrameImages(const fs::path& frames_dir, PhoneClip* clip) {
  const std::regex name_pattern(R"(RE_frame-(\d+)\.(jpg|jpeg|png))", std::regex::icase);
  for (const auto& file : fs::directory_iterator(frames_dir)) {
    std::smatch match;
    const std::string name = file.path().filename().string();
    if (!std::regex_match(name, match, name_pattern)) continue;
    const int64_t n = std::stoll(match[1].str());
    if (n < 1 || n > static_cast<int64_t>(clip->sof_ns.size()))
      throw IoError(IoMessage(file.path().string(), -1,
                              "frame " + std::to_string(n) + " has no time in framestamp.txt (" +
                                  std::to_string(clip->sof_ns.size()) + " lines)"));
    clip->frame_images[n] = file.path().string();
  }
  if (clip->frame_images.empty())
    throw IoError(IoMessage(frames_dir.string(), -1, "no RE_frame-N.jpg images"));
}

}  // namespace

std::string MissingPhoneClipPart(const std::string& folder) {
  for (const char* name : {"gyro.txt", "framestamp.txt", "frames"})
    if (!fs::exists(fs::path(folder) / name)) return name;
  return "";
}

PhoneClip ReadPhoneClip(const std::string& folder) {
  const fs::path root(folder);
  PhoneClip clip;
  ReadGyroTxt((root / "gyro.txt").string(), &clip);
  ReadFramestampTxt((root / "framestamp.txt").string(), &clip);
  const fs::path dump_path = root / "gyro_dump.txt";
  if (fs::exists(dump_path)) ReadGyroDumpTxt(dump_path.string(), &clip);  // optional
  ListFrameImages(root / "frames", &clip);
  return clip;
}

}  // namespace shutterlab
