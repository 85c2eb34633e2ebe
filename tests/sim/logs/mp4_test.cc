#include "sim/logs/mp4.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <fstream>
#include <random>

namespace shutterlab {
namespace {

// Big-endian box builders for hand-made files.
std::string U32(uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
          static_cast<char>(v)};
}
std::string BoxOf(const std::string& type, const std::string& body) {
  return U32(static_cast<uint32_t>(8 + body.size())) + type + body;
}
std::string FullBox(const std::string& type, const std::string& body) {
  return BoxOf(type, U32(0) + body);
}

// A file with one 'meta'/'gpmd' track of five samples: sizes 3, 5, 7, 2, 4 bytes in two chunks
// (3 samples, then 2), durations 10, 10, 10 (stts run) and 25, 40, timescale 100.
std::string TinyMp4(uint32_t mdat_at, std::vector<uint32_t>* offsets) {
  const std::vector<uint32_t> sizes{3, 5, 7, 2, 4};
  const uint32_t chunk1 = mdat_at + 8, chunk2 = chunk1 + 3 + 5 + 7 + 100;  // a gap between chunks
  *offsets = {chunk1, chunk1 + 3, chunk1 + 8, chunk2, chunk2 + 2};
  std::string stsz = U32(0) + U32(5);
  for (uint32_t s : sizes) stsz += U32(s);
  const std::string stbl = BoxOf(
      "stbl", FullBox("stsd", U32(1) + U32(16) + "gpmd" + U32(0) + U32(1)) +
                  FullBox("stts", U32(3) + U32(3) + U32(10) + U32(1) + U32(25) + U32(1) + U32(40)) +
                  FullBox("stsc", U32(2) + U32(1) + U32(3) + U32(1) + U32(2) + U32(2) + U32(1)) +
                  FullBox("stsz", stsz) + FullBox("stco", U32(2) + U32(chunk1) + U32(chunk2)));
  const std::string mdia = BoxOf(
      "mdia", FullBox("mdhd", U32(0) + U32(0) + U32(100) + U32(95)) +
                  FullBox("hdlr", U32(0) + "meta" + std::string(12, '\0')) + BoxOf("minf", stbl));
  const std::string trak =
      BoxOf("trak", FullBox("tkhd", U32(0) + U32(0) + U32(7) + std::string(60, '\0')) + mdia);
  std::string mdat_body(3 + 5 + 7 + 100 + 2 + 4, 'x');
  return BoxOf("ftyp", "isom" + U32(0)) + BoxOf("mdat", mdat_body) + BoxOf("moov", trak);
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(Mp4, HandBuiltSampleTableKnownAnswer) {
  test::TempDir dir;
  std::vector<uint32_t> offsets;
  const std::string bytes = TinyMp4(16, &offsets);  // ftyp is 16 bytes
  WriteBytes(dir / "tiny.mp4", bytes);
  Mp4File mp4(dir / "tiny.mp4");
  ASSERT_EQ(mp4.tracks().size(), 1u);
  const Mp4Track* track = mp4.FindTrack("meta", "gpmd");
  ASSERT_NE(track, nullptr);
  EXPECT_EQ(track->track_id, 7u);
  EXPECT_EQ(track->timescale, 100u);
  ASSERT_EQ(track->size(), 5u);
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(track->offsets[i], offsets[i]) << i;
  EXPECT_EQ(track->decode_ticks, (std::vector<int64_t>{0, 10, 20, 30, 55}));
  EXPECT_DOUBLE_EQ(track->DecodeTimeS(4), 0.55);
  EXPECT_EQ(mp4.ReadSample(*track, 2), std::string(7, 'x'));
  EXPECT_EQ(mp4.FindTrack("vide", ""), nullptr);
}

// User data: the boxes of moov/udta, in order; a QuickTime list's closing 4-byte 0 (no box) ends
// it without an error.
TEST(Mp4, HandBuiltUserDataBoxes) {
  test::TempDir dir;
  std::vector<uint32_t> offsets;
  std::string bytes = TinyMp4(16, &offsets);
  const std::string udta = BoxOf("udta", BoxOf("FIRM", "HD5.02") + BoxOf("GPMF", "abcd") + U32(0));
  // Grow moov (the last box) by the udta.
  const size_t moov_at = bytes.size() - (bytes.size() - bytes.rfind("moov") + 4);
  const uint32_t moov_size = static_cast<uint32_t>(bytes.size() - moov_at + udta.size());
  bytes.replace(moov_at, 4, U32(moov_size));
  bytes += udta;
  WriteBytes(dir / "udta.mp4", bytes);
  Mp4File mp4(dir / "udta.mp4");
  ASSERT_EQ(mp4.tracks().size(), 1u);
  const Mp4UserBox* gpmf = mp4.FindUserBox("GPMF");
  ASSERT_NE(gpmf, nullptr);
  EXPECT_EQ(gpmf->body, "abcd");
  EXPECT_EQ(bytes.substr(gpmf->file_offset, 4), "abcd");
  ASSERT_NE(mp4.FindUserBox("FIRM"), nullptr);
  EXPECT_EQ(mp4.FindUserBox("FIRM")->body, "HD5.02");
  EXPECT_EQ(mp4.FindUserBox("MUID"), nullptr);
}

TEST(Mp4, HandBuiltEveryTruncationAndByteFlipIsAnErrorOrATable) {
  std::vector<uint32_t> offsets;
  const std::string bytes = TinyMp4(16, &offsets);
  const size_t moov_at = bytes.find("moov") - 4;
  const std::string body = bytes.substr(moov_at + 8);
  // Every truncation of the moov body, and every byte of it set to 0x00, 0xFF and 0x80.
  for (size_t cut = 0; cut < body.size(); ++cut) {
    try {
      ParseMoov(body.substr(0, cut), moov_at + 8, bytes.size(), "tiny.mp4");
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("tiny.mp4: offset "), std::string::npos) << e.what();
    }
  }
  for (size_t i = 0; i < body.size(); ++i) {
    for (char value : {'\0', '\xff', '\x80'}) {
      std::string flipped = body;
      flipped[i] = value;
      try {
        for (const Mp4Track& track : ParseMoov(flipped, moov_at + 8, bytes.size(), "tiny.mp4"))
          EXPECT_EQ(track.offsets.size(), track.sizes.size());
      } catch (const IoError&) {
      }
    }
  }
}

TEST(Mp4, KarmaTracks) {
  SHUTTERLAB_NEED_REAL_DATA();
  Mp4File mp4(test::KarmaClipPath());
  EXPECT_EQ(mp4.file_size(), 4134647u);
  ASSERT_EQ(mp4.tracks().size(), 5u);
  const Mp4Track* gpmd = mp4.FindTrack("meta", "gpmd");
  ASSERT_NE(gpmd, nullptr);
  EXPECT_EQ(gpmd->timescale, 1000u);
  ASSERT_EQ(gpmd->size(), 13u);  // 13 one-second payloads of 1001 ticks
  for (size_t k = 0; k < 13; ++k) {
    EXPECT_EQ(gpmd->durations[k], 1001u);
    EXPECT_EQ(gpmd->decode_ticks[k], static_cast<int64_t>(1001 * k));
  }
  EXPECT_EQ(gpmd->sizes.front(), 7768u);
  EXPECT_EQ(gpmd->sizes.back(), 3052u);
  EXPECT_EQ(gpmd->offsets.front(), 323381u);
  EXPECT_EQ(mp4.ReadSample(*gpmd, 0).substr(0, 4), "DEVC");
  const Mp4Track* video = mp4.FindTrack("vide", "avc1");
  ASSERT_NE(video, nullptr);
  EXPECT_EQ(video->timescale, 90000u);
  ASSERT_EQ(video->size(), 362u);  // 362 frames at 90000/3003 = 29.97 fps
  EXPECT_TRUE(video->composition_offsets.empty());
  EXPECT_EQ(video->edit_media_time, 0);
  EXPECT_DOUBLE_EQ(video->PresentationTimeS(361), 361 * 3003 / 90000.0);
  // The 'fdsc' metadata track is not the gpmd one.
  EXPECT_NE(mp4.FindTrack("meta", "fdsc"), nullptr);
}

TEST(Mp4, KarmaTruncatedCopiesGiveAnErrorNamingTheOffset) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(test::KarmaClipPath());
  test::TempDir dir;
  // The index ('moov') is at the end: any cut loses it, or cuts a box header.
  for (size_t cut : {size_t{0}, size_t{5}, size_t{20}, size_t{1000}, size_t{4115984},
                     size_t{4115992 + 100}, bytes.size() - 1}) {
    WriteBytes(dir / "cut.mp4", bytes.substr(0, cut));
    try {
      Mp4File mp4(dir / "cut.mp4");
      ADD_FAILURE() << "cut at " << cut << " was accepted";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("cut.mp4"), std::string::npos) << e.what();
    }
  }
}

TEST(Mp4, KarmaMoovByteFlipsNeverCrash) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(test::KarmaClipPath());
  const size_t moov_at = 4115984;
  const std::string body = bytes.substr(moov_at + 8);
  std::mt19937 rng(6);
  std::uniform_int_distribution<size_t> where(0, body.size() - 1);
  std::uniform_int_distribution<int> value(0, 255);
  int errors = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::string flipped = body;
    for (int k = 0; k < 3; ++k) flipped[where(rng)] = static_cast<char>(value(rng));
    try {
      for (const Mp4Track& track : ParseMoov(flipped, moov_at + 8, bytes.size(), "karma.mp4"))
        ASSERT_EQ(track.offsets.size(), track.size());
    } catch (const IoError&) {
      ++errors;
    }
  }
  EXPECT_GT(errors, 0);  // some flips hit a size or count
}

}  // namespace
}  // namespace shutterlab
