#pragma once
// The sample tables of an MP4 / QuickTime file (ISO/IEC 14496-12): enough to find a track by its
// handler and sample format (a GoPro 'meta' track with a 'gpmd' sample entry, the 'vide' track),
// time its samples and read their bytes. Plain byte parsing, no dependency.
//
// Every length and count is checked against the bytes that hold it: a truncated or corrupted file
// throws IoError("PATH: offset N: problem"), never reads out of bounds and never loops forever
// (each box advances by at least its 8-byte header; nesting is depth-limited).

#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

struct Mp4Track {
  uint32_t track_id = 0;        // tkhd
  std::string handler;          // hdlr handler type: "vide", "soun", "meta", "tmcd", ...
  std::string sample_format;    // first stsd sample entry: "avc1", "mp4a", "gpmd", ...
  uint32_t timescale = 0;       // mdhd ticks per second
  int64_t edit_media_time = 0;  // elst: media time (ticks) shown at movie time 0; 0 without elst
  // One entry per sample, in decode order.
  std::vector<uint64_t> offsets;      // file offset of the sample's bytes (stco/co64 + stsc + stsz)
  std::vector<uint32_t> sizes;        // bytes (stsz/stz2)
  std::vector<int64_t> decode_ticks;  // decode time, ticks from the track start (stts)
  std::vector<uint32_t> durations;    // ticks (stts)
  std::vector<int32_t> composition_offsets;  // ctts; empty when the track has none

  size_t size() const { return sizes.size(); }
  // Presentation time of sample i on the movie timeline, seconds: (decode + composition offset
  // - edit media time) / timescale.
  double PresentationTimeS(size_t i) const;
  // Decode time of sample i on the movie timeline, seconds.
  double DecodeTimeS(size_t i) const;
};

// A box of the movie's user data ('moov/udta'), e.g. GoPro's 'GPMF' global settings.
struct Mp4UserBox {
  std::string type;          // FourCC
  std::string body;          // the bytes after its header
  uint64_t file_offset = 0;  // of body[0], for messages
};

// An open MP4 file: its track tables, read once from 'moov', and random access to sample bytes.
class Mp4File {
 public:
  // Reads the box structure and every track's sample table. Throws IoError naming the path and the
  // file offset of the problem (no 'moov', a box running past its parent, inconsistent tables).
  explicit Mp4File(const std::string& path);

  const std::string& path() const { return path_; }
  uint64_t file_size() const { return file_size_; }
  const std::vector<Mp4Track>& tracks() const { return tracks_; }
  // The first 'moov/udta' box of this type; nullptr when the file has none.
  const Mp4UserBox* FindUserBox(const std::string& type) const;
  // The first track with this handler and (when non-empty) sample format; nullptr if none.
  const Mp4Track* FindTrack(const std::string& handler, const std::string& sample_format) const;
  // Bytes of one sample; throws IoError when they lie outside the file.
  std::string ReadSample(const Mp4Track& track, size_t index);

 private:
  std::string path_;
  std::ifstream file_;
  uint64_t file_size_ = 0;
  std::vector<Mp4Track> tracks_;
  std::vector<Mp4UserBox> user_boxes_;
};

// An MP4 / QuickTime file by its first box: 'ftyp' (or a bare 'moov', 'mdat', 'wide', 'free') in
// bytes 4..8 of the file.
bool LooksLikeMp4(std::string_view first_bytes);

// The boxes of a 'moov' body's 'udta' (every udta, in order); file_offset as for ParseMoov.
std::vector<Mp4UserBox> ParseUserData(const std::string& moov_body, uint64_t file_offset,
                                      const std::string& path);

// Parses a 'moov' box body (the bytes after its header) into tracks. file_offset is the file
// offset of moov_body[0], for error messages; file_size bounds the sample offsets. Exposed for
// tests on hand-built boxes.
std::vector<Mp4Track> ParseMoov(const std::string& moov_body, uint64_t file_offset,
                                uint64_t file_size, const std::string& path);

}  // namespace shutterlab
