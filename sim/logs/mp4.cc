#include "sim/logs/mp4.h"

#include "sim/check.h"

#include <algorithm>
#include <array>
#include <functional>
#include <string_view>

namespace shutterlab {
namespace {

constexpr int kMaxDepth =
    16;  // deeper nesting than any real file: a corrupted size loops no further

// Big-endian reads from a bounded buffer; every read is checked, so a bad length is an IoError
// naming the file offset and never an out-of-bounds read.
class Bytes {
 public:
  Bytes(std::string_view data, uint64_t file_offset, const std::string& path)
      : data_(data), file_offset_(file_offset), path_(path) {}

  size_t size() const { return data_.size(); }
  [[noreturn]] void Fail(size_t at, const std::string& problem) const {
    throw IoError(
        IoMessage(path_, -1, "offset " + std::to_string(file_offset_ + at) + ": " + problem));
  }
  void Need(size_t at, size_t bytes, const char* what) const {
    if (at > data_.size() || bytes > data_.size() - at)
      Fail(at, std::string(what) + " truncated (needs " + std::to_string(bytes) + " bytes, " +
                   std::to_string(at > data_.size() ? 0 : data_.size() - at) + " left)");
  }
  uint64_t U(size_t at, int bytes, const char* what) const {
    Need(at, bytes, what);
    uint64_t value = 0;
    for (int i = 0; i < bytes; ++i) value = (value << 8) | static_cast<uint8_t>(data_[at + i]);
    return value;
  }
  uint32_t U32(size_t at, const char* what) const { return static_cast<uint32_t>(U(at, 4, what)); }
  std::string FourCc(size_t at, const char* what) const {
    Need(at, 4, what);
    return std::string(data_.substr(at, 4));
  }
  uint64_t FileOffset(size_t at) const { return file_offset_ + at; }

 private:
  std::string_view data_;
  uint64_t file_offset_;
  const std::string& path_;
};

struct Box {
  std::string type;
  size_t begin = 0;  // body start (after the header)
  size_t end = 0;    // one past the body
};

// Calls visit for each box in [begin, end) of bytes. A box whose size runs past end is an error.
void ForEachBox(const Bytes& bytes, size_t begin, size_t end,
                const std::function<void(const Box&)>& visit) {
  size_t at = begin;
  while (at < end) {
    if (end - at < 8)
      bytes.Fail(at, "box header truncated (" + std::to_string(end - at) + " bytes)");
    uint64_t size = bytes.U32(at, "box size");
    Box box;
    box.type = bytes.FourCc(at + 4, "box type");
    size_t header = 8;
    if (size == 1) {
      size = bytes.U(at + 8, 8, "64-bit box size");
      header = 16;
    } else if (size == 0) {
      size = end - at;  // extends to the end of its parent
    }
    if (size < header || size > end - at)
      bytes.Fail(at, "box '" + box.type + "' size " + std::to_string(size) +
                         " runs past its parent (" + std::to_string(end - at) + " bytes left)");
    box.begin = at + header;
    box.end = at + size;
    visit(box);
    at = box.end;
  }
}

// Reads a full-box's version byte and checks the body holds at least `bytes` after it.
int Version(const Bytes& bytes, const Box& box) {
  return static_cast<int>(bytes.U(box.begin, 1, ("'" + box.type + "' version").c_str()));
}

// Checks that `count` entries of `entry_bytes` each fit in the box from `at`.
void NeedEntries(const Bytes& bytes, const Box& box, size_t at, uint64_t count,
                 size_t entry_bytes) {
  if (at > box.end || count > (box.end - at) / entry_bytes)
    bytes.Fail(at, "'" + box.type + "' declares " + std::to_string(count) + " entries, box holds " +
                       std::to_string(at > box.end ? 0 : (box.end - at) / entry_bytes));
}

struct RawTables {
  std::vector<std::pair<uint32_t, uint32_t>> stts;  // (count, delta)
  std::vector<std::pair<uint32_t, uint32_t>> ctts;  // (count, offset as int32 bits)
  std::vector<std::array<uint32_t, 2>> stsc;        // (first chunk, samples per chunk)
  std::vector<uint32_t> sizes;
  std::vector<uint64_t> chunk_offsets;
  bool has_stsz = false, has_stco = false;
  size_t stbl_at = 0;
};

// A run-length table of (sample count, value) pairs: stts (durations) and ctts (offsets).
std::vector<std::pair<uint32_t, uint32_t>> ReadRuns(const Bytes& bytes, const Box& box,
                                                    uint64_t file_size) {
  const size_t b = box.begin;
  const uint32_t count = bytes.U32(b + 4, (box.type + " entry count").c_str());
  NeedEntries(bytes, box, b + 8, count, 8);
  std::vector<std::pair<uint32_t, uint32_t>> runs;
  uint64_t total = 0;
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t n = bytes.U32(b + 8 + 8 * i, box.type.c_str());
    total += n;
    // A sample takes at least one byte of the file: more samples than bytes is corruption, and
    // checking it bounds the memory the tables may claim.
    if (total > file_size)
      bytes.Fail(b + 8 + 8 * i, box.type + " counts more samples than the file has bytes");
    runs.emplace_back(n, bytes.U32(b + 12 + 8 * i, box.type.c_str()));
  }
  return runs;
}

void ParseStbl(const Bytes& bytes, const Box& stbl, uint64_t file_size, Mp4Track* track,
               RawTables* raw) {
  raw->stbl_at = stbl.begin;
  ForEachBox(bytes, stbl.begin, stbl.end, [&](const Box& box) {
    const size_t b = box.begin;
    if (box.type == "stsd") {
      const uint32_t count = bytes.U32(b + 4, "stsd entry count");
      if (count > 0 && b + 16 <= box.end)
        track->sample_format = bytes.FourCc(b + 12, "stsd format");
    } else if (box.type == "stts") {
      raw->stts = ReadRuns(bytes, box, file_size);
    } else if (box.type == "ctts") {
      raw->ctts =
          ReadRuns(bytes, box, file_size);  // version 1 offsets are signed; read as int32 later
    } else if (box.type == "stsc") {
      const uint32_t count = bytes.U32(b + 4, "stsc entry count");
      NeedEntries(bytes, box, b + 8, count, 12);
      for (uint32_t i = 0; i < count; ++i)
        raw->stsc.push_back(
            {bytes.U32(b + 8 + 12 * i, "stsc"), bytes.U32(b + 12 + 12 * i, "stsc")});
    } else if (box.type == "stsz") {
      raw->has_stsz = true;
      const uint32_t fixed = bytes.U32(b + 4, "stsz sample size");
      const uint32_t count = bytes.U32(b + 8, "stsz sample count");
      if (count > file_size) bytes.Fail(b + 8, "stsz counts more samples than the file has bytes");
      if (fixed != 0) {
        raw->sizes.assign(count, fixed);
      } else {
        NeedEntries(bytes, box, b + 12, count, 4);
        for (uint32_t i = 0; i < count; ++i)
          raw->sizes.push_back(bytes.U32(b + 12 + 4 * i, "stsz"));
      }
    } else if (box.type == "stz2") {
      raw->has_stsz = true;
      const int field_bits = static_cast<int>(bytes.U(b + 7, 1, "stz2 field size"));
      const uint32_t count = bytes.U32(b + 8, "stz2 sample count");
      if (field_bits != 4 && field_bits != 8 && field_bits != 16)
        bytes.Fail(b + 7,
                   "stz2 field size " + std::to_string(field_bits) + " (4, 8 or 16 expected)");
      const uint64_t need = (static_cast<uint64_t>(count) * field_bits + 7) / 8;
      bytes.Need(b + 12, need, "stz2 table");
      if (b + 12 + need > box.end) bytes.Fail(b + 12, "stz2 table runs past its box");
      for (uint32_t i = 0; i < count; ++i) {
        if (field_bits == 4) {
          const uint64_t byte = bytes.U(b + 12 + i / 2, 1, "stz2");
          raw->sizes.push_back(static_cast<uint32_t>(i % 2 == 0 ? byte >> 4 : byte & 0xF));
        } else {
          raw->sizes.push_back(static_cast<uint32_t>(
              bytes.U(b + 12 + i * (field_bits / 8), field_bits / 8, "stz2")));
        }
      }
    } else if (box.type == "stco" || box.type == "co64") {
      raw->has_stco = true;
      const size_t width = box.type == "stco" ? 4 : 8;
      const uint32_t count = bytes.U32(b + 4, "chunk offset count");
      NeedEntries(bytes, box, b + 8, count, width);
      for (uint32_t i = 0; i < count; ++i)
        raw->chunk_offsets.push_back(
            bytes.U(b + 8 + width * i, static_cast<int>(width), "chunk offset"));
    }
  });
}

// Expands the run-length tables into one entry per sample.
void BuildSamples(const Bytes& bytes, const RawTables& raw, Mp4Track* track) {
  const size_t at = raw.stbl_at;
  if (!raw.has_stsz || !raw.has_stco)
    bytes.Fail(at, "track " + std::to_string(track->track_id) +
                       ": sample table lacks stsz/stz2 or stco/co64");
  const size_t n = raw.sizes.size();
  track->sizes = raw.sizes;
  // Times.
  int64_t t = 0;
  for (const auto& [count, delta] : raw.stts) {
    for (uint32_t k = 0; k < count && track->decode_ticks.size() < n; ++k) {
      track->decode_ticks.push_back(t);
      track->durations.push_back(delta);
      t += delta;
    }
  }
  if (track->decode_ticks.size() != n)
    bytes.Fail(at, "track " + std::to_string(track->track_id) + ": stts times " +
                       std::to_string(track->decode_ticks.size()) + " samples, stsz has " +
                       std::to_string(n));
  if (!raw.ctts.empty()) {
    for (const auto& [count, offset] : raw.ctts)
      for (uint32_t k = 0; k < count && track->composition_offsets.size() < n; ++k)
        track->composition_offsets.push_back(static_cast<int32_t>(offset));
    if (track->composition_offsets.size() != n)
      bytes.Fail(at, "track " + std::to_string(track->track_id) + ": ctts covers " +
                         std::to_string(track->composition_offsets.size()) + " of " +
                         std::to_string(n) + " samples");
  }
  // Offsets: chunk c (1-based) holds samples_per_chunk of the last stsc entry with first_chunk <=
  // c.
  size_t sample = 0;
  for (size_t e = 0; e < raw.stsc.size() && sample < n; ++e) {
    const uint64_t first = raw.stsc[e][0];
    const uint64_t last =
        e + 1 < raw.stsc.size() ? raw.stsc[e + 1][0] : raw.chunk_offsets.size() + 1;
    if (first < 1 || last < first) bytes.Fail(at, "stsc first chunks are not increasing");
    for (uint64_t chunk = first; chunk < last && sample < n; ++chunk) {
      if (chunk > raw.chunk_offsets.size())
        bytes.Fail(at, "stsc refers to chunk " + std::to_string(chunk) + " of " +
                           std::to_string(raw.chunk_offsets.size()));
      uint64_t offset = raw.chunk_offsets[chunk - 1];
      for (uint32_t k = 0; k < raw.stsc[e][1] && sample < n; ++k) {
        track->offsets.push_back(offset);
        offset += track->sizes[sample++];
      }
    }
  }
  if (track->offsets.size() != n)
    bytes.Fail(at, "track " + std::to_string(track->track_id) + ": chunks hold " +
                       std::to_string(track->offsets.size()) + " of " + std::to_string(n) +
                       " samples");
}

Mp4Track ParseTrak(const Bytes& bytes, const Box& trak, uint64_t file_size, int depth) {
  Mp4Track track;
  RawTables raw;
  bool have_stbl = false;
  std::function<void(const Box&, int)> visit = [&](const Box& box, int level) {
    if (level > kMaxDepth) bytes.Fail(box.begin, "boxes nested too deep");
    const size_t b = box.begin;
    if (box.type == "tkhd") {
      track.track_id = bytes.U32(b + (Version(bytes, box) == 1 ? 20 : 12), "tkhd track id");
    } else if (box.type == "mdhd") {
      track.timescale = bytes.U32(b + (Version(bytes, box) == 1 ? 20 : 12), "mdhd timescale");
      if (track.timescale == 0) bytes.Fail(b, "mdhd timescale is 0");
    } else if (box.type == "hdlr") {
      track.handler = bytes.FourCc(b + 8, "hdlr handler type");
    } else if (box.type == "elst") {
      const int version = Version(bytes, box);
      const uint32_t count = bytes.U32(b + 4, "elst entry count");
      const size_t entry = version == 1 ? 20 : 12;
      NeedEntries(bytes, box, b + 8, count, entry);
      // The first non-empty edit (media time -1 is an empty edit: a delay, not modelled here).
      for (uint32_t i = 0; i < count; ++i) {
        const size_t at = b + 8 + entry * i + (version == 1 ? 8 : 4);
        const int64_t media_time = version == 1 ? static_cast<int64_t>(bytes.U(at, 8, "elst"))
                                                : static_cast<int32_t>(bytes.U32(at, "elst"));
        if (media_time >= 0) {
          track.edit_media_time = media_time;
          break;
        }
      }
    } else if (box.type == "stbl") {
      have_stbl = true;
      ParseStbl(bytes, box, file_size, &track, &raw);
    } else if (box.type == "mdia" || box.type == "minf" || box.type == "edts") {
      ForEachBox(bytes, box.begin, box.end, [&](const Box& child) { visit(child, level + 1); });
    }
  };
  ForEachBox(bytes, trak.begin, trak.end, [&](const Box& child) { visit(child, depth + 1); });
  if (have_stbl) {
    if (track.timescale == 0)
      bytes.Fail(trak.begin, "track " + std::to_string(track.track_id) + " has no mdhd timescale");
    BuildSamples(bytes, raw, &track);
  }
  return track;
}

}  // namespace

double Mp4Track::DecodeTimeS(size_t i) const {
  return static_cast<double>(decode_ticks.at(i) - edit_media_time) / timescale;
}

double Mp4Track::PresentationTimeS(size_t i) const {
  const int64_t offset = composition_offsets.empty() ? 0 : composition_offsets.at(i);
  return static_cast<double>(decode_ticks.at(i) + offset - edit_media_time) / timescale;
}

std::vector<Mp4Track> ParseMoov(const std::string& moov_body, uint64_t file_offset,
                                uint64_t file_size, const std::string& path) {
  const Bytes bytes(moov_body, file_offset, path);
  std::vector<Mp4Track> tracks;
  ForEachBox(bytes, 0, moov_body.size(), [&](const Box& box) {
    if (box.type == "trak") tracks.push_back(ParseTrak(bytes, box, file_size, 1));
  });
  return tracks;
}

std::vector<Mp4UserBox> ParseUserData(const std::string& moov_body, uint64_t file_offset,
                                      const std::string& path) {
  const Bytes bytes(moov_body, file_offset, path);
  std::vector<Mp4UserBox> boxes;
  ForEachBox(bytes, 0, moov_body.size(), [&](const Box& udta) {
    if (udta.type != "udta") return;
    try {
      ForEachBox(bytes, udta.begin, udta.end, [&](const Box& box) {
        boxes.push_back(
            {box.type, moov_body.substr(box.begin, box.end - box.begin), file_offset + box.begin});
      });
    } catch (const IoError&) {
      // User data is optional metadata, and QuickTime ends its list with a 4-byte 0 that is no
      // box: keep the boxes before whatever does not parse.
    }
  });
  return boxes;
}

const Mp4UserBox* Mp4File::FindUserBox(const std::string& type) const {
  for (const Mp4UserBox& box : user_boxes_) {
    if (box.type == type) return &box;
  }
  return nullptr;
}

Mp4File::Mp4File(const std::string& path) : path_(path), file_(path, std::ios::binary) {
  if (!file_) throw IoError(IoMessage(path, -1, "cannot open"));
  file_.seekg(0, std::ios::end);
  file_size_ = static_cast<uint64_t>(file_.tellg());
  // Walk the top-level boxes by their headers only: 'mdat' may be gigabytes.
  uint64_t at = 0;
  bool found = false;
  while (at < file_size_ && !found) {
    char header[16];
    const uint64_t left = file_size_ - at;
    if (left < 8)
      throw IoError(IoMessage(path, -1,
                              "offset " + std::to_string(at) + ": box header truncated (" +
                                  std::to_string(left) + " bytes)"));
    file_.seekg(static_cast<std::streamoff>(at));
    file_.read(header, static_cast<std::streamsize>(std::min<uint64_t>(16, left)));
    const Bytes head(std::string_view(header, std::min<uint64_t>(16, left)), at, path_);
    uint64_t size = head.U32(0, "box size");
    const std::string type = head.FourCc(4, "box type");
    uint64_t header_size = 8;
    if (size == 1) {
      size = head.U(8, 8, "64-bit box size");
      header_size = 16;
    } else if (size == 0) {
      size = left;
    }
    if (size < header_size || size > left)
      throw IoError(IoMessage(path, -1,
                              "offset " + std::to_string(at) + ": box '" + type + "' size " +
                                  std::to_string(size) + " runs past the end of the file (" +
                                  std::to_string(left) + " bytes left; truncated?)"));
    if (type == "moov") {
      std::string body(size - header_size, '\0');
      file_.seekg(static_cast<std::streamoff>(at + header_size));
      file_.read(body.data(), static_cast<std::streamsize>(body.size()));
      if (!file_)
        throw IoError(IoMessage(path, -1, "offset " + std::to_string(at) + ": cannot read 'moov'"));
      tracks_ = ParseMoov(body, at + header_size, file_size_, path_);
      user_boxes_ = ParseUserData(body, at + header_size, path_);
      found = true;
    }
    at += size;
  }
  if (!found)
    throw IoError(
        IoMessage(path, -1, "no 'moov' box: not an MP4 file, or truncated before its index"));
}

const Mp4Track* Mp4File::FindTrack(const std::string& handler,
                                   const std::string& sample_format) const {
  for (const Mp4Track& track : tracks_)
    if (track.handler == handler && (sample_format.empty() || track.sample_format == sample_format))
      return &track;
  return nullptr;
}

bool LooksLikeMp4(std::string_view first_bytes) {
  if (first_bytes.size() < 8) return false;
  const std::string_view type = first_bytes.substr(4, 4);
  return type == "ftyp" || type == "moov" || type == "mdat" || type == "wide" || type == "free";
}

std::string Mp4File::ReadSample(const Mp4Track& track, size_t index) {
  const uint64_t offset = track.offsets.at(index);
  const uint32_t size = track.sizes.at(index);
  if (offset > file_size_ || size > file_size_ - offset)
    throw IoError(IoMessage(path_, -1,
                            "offset " + std::to_string(offset) + ": sample " +
                                std::to_string(index) + " of track " +
                                std::to_string(track.track_id) + " (" + std::to_string(size) +
                                " bytes) lies past the end of the file (truncated?)"));
  std::string bytes(size, '\0');
  file_.clear();
  file_.seekg(static_cast<std::streamoff>(offset));
  file_.read(bytes.data(), size);
  if (!file_)
    throw IoError(
        IoMessage(path_, -1, "offset " + std::to_string(offset) + ": cannot read sample"));
  return bytes;
}

}  // namespace shutterlab
