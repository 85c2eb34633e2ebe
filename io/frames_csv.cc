#include "io/frames_csv.h"

#include "sim/check.h"
#include "sim/gyro_trace.h"
#include "sim/text_file.h"

#include <cmath>
#include <cstdio>
#include <set>

namespace shutterlab {
namespace {

std::vector<FrameEntry> ReadFrames(const std::string& path, bool with_images) {
  const std::string text = ReadFileToString(path);
  LineCursor lines(text);
  std::vector<std::string_view> fields;
  std::optional<std::string_view> header = lines.Next();
  while (header && header->find_first_not_of(" \t") == std::string_view::npos)
    header = lines.Next();
  if (!header) throw IoError(IoMessage(path, 0, "empty file, expected a header line"));
  SplitFields(*header, ',', &fields);
  const size_t needed = with_images ? 4 : 2;
  const char* expected = with_images ? "frame,t_first_row,ref,image" : "frame,t_first_row";
  const char* names[4] = {"frame", "t_first_row", "ref", "image"};
  bool header_ok = fields.size() >= needed;
  for (size_t i = 0; header_ok && i < needed; ++i) header_ok = ToLower(fields[i]) == names[i];
  if (!header_ok) {
    throw IoError(IoMessage(path, lines.line_number(),
                            "header is '" + std::string(*header) + "', expected " + expected));
  }
  std::vector<FrameEntry> frames;
  std::set<int64_t> ids;
  while (std::optional<std::string_view> line = lines.Next()) {
    if (line->find_first_not_of(" \t") == std::string_view::npos) continue;
    SplitFields(*line, ',', &fields);
    const long n = lines.line_number();
    if (fields.size() < needed) {
      throw IoError(IoMessage(path, n,
                              "expected " + std::to_string(needed) + " columns " + expected +
                                  ", found " + std::to_string(fields.size())));
    }
    const std::optional<int64_t> id = ParseInt(fields[0]);
    if (!id || *id < 0)
      throw IoError(IoMessage(
          path, n, "frame '" + std::string(fields[0]) + "' is not a non-negative integer"));
    if (!ids.insert(*id).second)
      throw IoError(IoMessage(path, n, "frame " + std::to_string(*id) + " appears twice"));
    const std::optional<double> t = ParseDouble(fields[1]);
    if (!t || std::abs(*t) > 9e9) {
      throw IoError(IoMessage(
          path, n, "t_first_row '" + std::string(fields[1]) + "' is not a time in seconds"));
    }
    FrameEntry entry;
    entry.frame = *id;
    entry.t_first_row_ns = SecondsToNs(*t);
    if (with_images) {
      entry.ref = std::string(fields[2]);
      entry.image = std::string(fields[3]);
      if (entry.image.empty()) throw IoError(IoMessage(path, n, "image is empty"));
    }
    frames.push_back(std::move(entry));
  }
  if (frames.empty()) throw IoError(IoMessage(path, 0, "no frames"));
  return frames;
}

}  // namespace

std::vector<FrameEntry> ReadFrameTimes(const std::string& path) { return ReadFrames(path, false); }

std::vector<FrameEntry> ReadFramesCsv(const std::string& path) { return ReadFrames(path, true); }

void WriteFramesCsv(const std::string& path, const std::vector<FrameEntry>& frames) {
  std::string out = "frame,t_first_row,ref,image\n";
  for (const FrameEntry& f : frames) {
    SHUTTERLAB_CHECK(f.ref.find_first_of(",\n") == std::string::npos &&
                     f.image.find_first_of(",\n") == std::string::npos)
        << "image paths must not contain commas or newlines";
    out += std::to_string(f.frame);
    out += ',';
    AppendSecondsFromNs(f.t_first_row_ns, &out);
    out += ',' + f.ref + ',' + f.image + '\n';
  }
  WriteFileAtomically(path, out);
}

void WriteFrameTimes(const std::string& path, const std::vector<int64_t>& times_ns) {
  std::string out = "frame,t_first_row\n";
  for (size_t i = 0; i < times_ns.size(); ++i) {
    out += std::to_string(i) + ",";
    AppendSecondsFromNs(times_ns[i], &out);
    out += '\n';
  }
  WriteFileAtomically(path, out);
}

std::string FrameName(int64_t frame) {
  char name[32];
  std::snprintf(name, sizeof(name), "%04lld", static_cast<long long>(frame));
  return name;
}

}  // namespace shutterlab
