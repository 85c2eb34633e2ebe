#include "sim/text_file.h"

#include "sim/check.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <unistd.h>
#include <vector>

namespace shutterlab {
namespace {

// FromCharsDouble is std::from_chars, faster on plain decimals: the same bits and the same end for
// every kind of number a log may hold, and for text that is no number.
TEST(FromCharsDouble, IsStdFromCharsOnEveryKindOfNumber) {
  std::mt19937_64 rng(15);
  std::vector<std::string> texts = {"0",
                                    "-0",
                                    "-0.0",
                                    ".5",
                                    "-.5",
                                    "5.",
                                    ".",
                                    "-",
                                    "",
                                    "1e5",
                                    "1.5e-3",
                                    "1.5e",
                                    "inf",
                                    "nan",
                                    "+1",
                                    "abc",
                                    "0.1",
                                    "0.3",
                                    "1,2",
                                    "-1.5 ",
                                    "9007199254740993",
                                    "9007199254740992.5",
                                    "1234567890123456789",
                                    "12345678901234567890",
                                    "0.00000000000000000000001",
                                    "0.0000000000000000000000001"};
  char buffer[64];
  for (int i = 0; i < 20000; ++i) {
    // Shortest round-trip decimals (up to 17 digits), fixed decimals as loggers write them, and
    // integers of every length.
    const double x = std::ldexp(static_cast<double>(rng() >> 11), -static_cast<int>(rng() % 80)) *
                     ((rng() & 1) ? -1 : 1);
    std::to_chars_result r = std::to_chars(buffer, buffer + sizeof(buffer), x);
    texts.emplace_back(buffer, r.ptr);
    r = std::to_chars(buffer, buffer + sizeof(buffer), x, std::chars_format::fixed,
                      static_cast<int>(rng() % 12));
    texts.emplace_back(buffer, r.ptr);
    texts.push_back(std::to_string(rng() >> (rng() % 64)));
  }
  size_t plain = 0;
  for (const std::string& text : texts) {
    const char* end = text.data() + text.size();
    double expected = -7.0, got = -7.0;
    const auto [expected_end, ec] = std::from_chars(text.data(), end, expected);
    const char* got_end = FromCharsDouble(text.data(), end, &got);
    // The fast path alone, before a line end: the same number, or none (left to the caller).
    const std::string line = text + "\n";
    double fast = -7.0;
    const char* fast_end = PlainDecimalBeforeLineEnd(line.data(), &fast);
    if (ec != std::errc()) {
      EXPECT_EQ(got_end, nullptr) << "'" << text << "'";
      EXPECT_EQ(fast_end, nullptr) << "'" << text << "'";
      continue;
    }
    ASSERT_EQ(got_end, expected_end) << "'" << text << "'";
    EXPECT_TRUE(test::SameBits(got, expected)) << "'" << text << "': " << got << " vs " << expected;
    if (fast_end) {
      ++plain;
      ASSERT_EQ(fast_end - line.data(), expected_end - text.data()) << "'" << text << "'";
      EXPECT_TRUE(test::SameBits(fast, expected))
          << "'" << text << "': " << fast << " vs " << expected;
    } else {
      // Only what is not a plain decimal of at most 19 digits is left to the caller.
      const bool exponent = text.find_first_of("eE") != std::string::npos;
      size_t digits = 0;
      for (char c : text) digits += c >= '0' && c <= '9';
      EXPECT_TRUE(exponent || digits > 15 || text.find_first_of("+in") != std::string::npos)
          << "'" << text << "' should take the fast path";
    }
  }
  EXPECT_GT(plain, texts.size() / 3);  // the loggers' fixed decimals among them
}

// The lines of a text read in blocks of any size are the lines LineCursor gives of it whole, with
// the same numbers: long lines, CR LF, empty lines, a last line without its end.
TEST(LineReader, BlocksOfAnySizeGiveTheLinesOfTheWholeText) {
  std::mt19937_64 rng(15);
  test::TempDir dir;
  const std::string path = dir / "text.txt";
  for (int trial = 0; trial < 200; ++trial) {
    std::string text;
    const int lines = static_cast<int>(rng() % 40);
    for (int l = 0; l < lines; ++l) {
      text.append(rng() % 4 == 0 ? rng() % 300 : rng() % 12, static_cast<char>('a' + l % 26));
      text += rng() % 5 == 0 ? "\r\n" : "\n";
    }
    if (rng() % 2) text += "last";
    std::vector<std::pair<long, std::string>> expected;
    LineCursor cursor(text);
    while (auto line = cursor.Next()) expected.emplace_back(cursor.line_number(), *line);
    const size_t block = 1 + rng() % 64;
    WriteFileAtomically(path, text);
    for (bool from_file : {false, true}) {
      LineReader reader(from_file ? TextBlocks::OfFile(path, block)
                                  : TextBlocks::InMemory(text, block));
      std::vector<std::pair<long, std::string>> got;
      while (auto line = reader.Next()) got.emplace_back(reader.line_number(), *line);
      EXPECT_EQ(got, expected) << "trial " << trial << ", block " << block
                               << (from_file ? ", file" : ", memory");
      EXPECT_DOUBLE_EQ(reader.Fraction(), 1.0);
    }
  }
}

TEST(TextBlocks, EveryBlockEndsAtALineEndAndAMissingFileIsAnIoError) {
  const std::string text = "a,b\nccc\n\ndddd";
  TextBlocks blocks = TextBlocks::InMemory(text, 2);
  std::string joined;
  for (std::string_view block = blocks.Next(); !block.empty(); block = blocks.Next()) {
    EXPECT_TRUE(block.back() == '\n' || joined.size() + block.size() == text.size()) << block;
    joined += block;
  }
  EXPECT_EQ(joined, text);
  EXPECT_THROW(TextBlocks::OfFile("/nonexistent/gyro.csv"), IoError);
}

TEST(TextBlocks, AFileOfAnySizeIsReadWholeWithTheDefaultBlock) {
  // The default block is sized to the file (at least 4 KiB): files just under, at and over that,
  // and one line longer than the block, come back whole.
  test::TempDir dir;
  const std::string path = dir / "text.txt";
  for (size_t size :
       {size_t{0}, size_t{1}, size_t{4095}, size_t{4096}, size_t{4097}, size_t{100000}}) {
    std::string text;
    for (size_t i = 0; text.size() < size; ++i) text += i % 50 == 49 ? '\n' : 'a';
    text.resize(size);
    for (const std::string& content : {text, std::string(9000, 'b') + "\n" + text}) {
      WriteFileAtomically(path, content);
      TextBlocks blocks = TextBlocks::OfFile(path);
      EXPECT_EQ(blocks.size_bytes(), content.size());
      std::string joined;
      for (std::string_view block = blocks.Next(); !block.empty(); block = blocks.Next())
        joined += block;
      EXPECT_EQ(joined, content) << "size " << content.size();
    }
  }
}

TEST(TextBlocks, APeekAtTheStartIsHandedOutAgain) {
  // In memory, from a file with blocks smaller and larger than the look, and an empty file.
  test::TempDir dir;
  const std::string path = dir / "text.txt";
  std::string text;
  for (int i = 0; text.size() < 50000; ++i) text += std::to_string(i * 7919) + ",x\n";
  for (const std::string& content : {text, std::string("ab"), std::string()}) {
    WriteFileAtomically(path, content);
    for (size_t block : {size_t{8}, size_t{4096}, TextBlocks::kBlockBytes}) {
      TextBlocks from_file = TextBlocks::OfFile(path, block);
      TextBlocks in_memory = TextBlocks::InMemory(content, block);
      const std::string peeked(from_file.Peek(1000));
      EXPECT_EQ(peeked, content.substr(0, 1000));  // a regular file is mapped: whatever the block
      EXPECT_EQ(std::string(in_memory.Peek(1000)), content.substr(0, 1000));
      EXPECT_EQ(from_file.TakeMapped()->text(), content) << "block " << block;
      EXPECT_EQ(in_memory.TakeMapped()->text(), content);
    }
  }
  TextBlocks started = TextBlocks::InMemory("a\nb\n", 2);
  started.Next();
  EXPECT_THROW(started.Peek(1), std::invalid_argument);
}

// Seconds with nine decimals, against printf's integer formatting as the twin: zero, each side of
// a second, the extremes of int64 and random times of both signs.
TEST(AppendSecondsFromNs, IsTheNanosecondsExactlyAsSecondsWithNineDecimals) {
  std::vector<int64_t> times = {0,
                                1,
                                -1,
                                999999999,
                                -999999999,
                                1000000000,
                                -1000000000,
                                1000000001,
                                std::numeric_limits<int64_t>::max(),
                                std::numeric_limits<int64_t>::min()};
  std::mt19937_64 rng(3);
  for (int i = 0; i < 1000; ++i) times.push_back(static_cast<int64_t>(rng()) >> (i % 60));
  for (const int64_t t_ns : times) {
    const uint64_t magnitude = t_ns < 0 ? 0 - static_cast<uint64_t>(t_ns) : t_ns;
    char expected[40];
    std::snprintf(expected, sizeof(expected), "%s%llu.%09llu", t_ns < 0 ? "-" : "",
                  static_cast<unsigned long long>(magnitude / 1000000000ULL),
                  static_cast<unsigned long long>(magnitude % 1000000000ULL));
    std::string text = "x";
    AppendSecondsFromNs(t_ns, &text);
    EXPECT_EQ(text, std::string("x") + expected) << t_ns;
  }
  std::string one;
  AppendSecondsFromNs(-1500000000, &one);
  EXPECT_EQ(one, "-1.500000000");
}

TEST(HasJpegExtension, IsJpgOrJpegInAnyCase) {
  for (const char* name : {"a.jpg", "DJI_0001.JPG", "b.Jpeg", "dir/c.JPEG", ".jpg"}) {
    EXPECT_TRUE(HasJpegExtension(name)) << name;
  }
  for (const char* name : {"a.png", "a.jpg.png", "jpg", "a.jpe", "a.jpgx", "", "a.tif"}) {
    EXPECT_FALSE(HasJpegExtension(name)) << name;
  }
}

TEST(HasPngExtension, IsPngInAnyCase) {
  for (const char* name : {"a.png", "MASK.PNG", "dir/b.Png", ".png"}) {
    EXPECT_TRUE(HasPngExtension(name)) << name;
  }
  for (const char* name : {"a.jpg", "a.png.jpg", "png", "a.pn", "a.pngx", ""}) {
    EXPECT_FALSE(HasPngExtension(name)) << name;
  }
}

TEST(FormatNumber, KeepsTextLongerThanItsStackBuffer) {
  EXPECT_EQ(FormatNumber("%.2f", 3.14159), "3.14");
  const std::string sentence(100, 'x');
  const std::string formatted = FormatNumber((sentence + " %.1f s").c_str(), 2.5);
  EXPECT_EQ(formatted, sentence + " 2.5 s");
}

// Resident memory of this process in bytes (/proc/self/statm's second field, in pages).
// Under AddressSanitizer every byte read also reads its shadow (an eighth of its size), which
// stays resident after the mapping's pages are handed back: the bounds on resident memory hold
// for the plain build only (scripts/test.sh).
size_t ResidentBytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  long pages_total = 0, pages_resident = 0;
  const bool read = f && std::fscanf(f, "%ld %ld", &pages_total, &pages_resident) == 2;
  if (f) std::fclose(f);
  return read ? static_cast<size_t>(pages_resident) * static_cast<size_t>(::sysconf(_SC_PAGESIZE))
              : 0;
}

// A 16 MiB file at path of bytes patterned by multiplier (different tests, different bytes);
// returns its content.
std::string WritePatternedFile(const std::string& path, uint32_t multiplier) {
  std::string content(16 << 20, '\0');
  for (size_t i = 0; i < content.size(); ++i)
    content[i] = static_cast<char>(static_cast<uint32_t>(i) * multiplier >> 24);
  WriteFileAtomically(path, content);
  return content;
}

TEST(MappedFile, AStreamedFileReadsWholeAndItsReleasedPagesLeaveResidentMemory) {
  test::TempDir dir;
  const std::string path = dir / "log.bin";
  const std::string content = WritePatternedFile(path, 2654435761u);
  MappedFile mapped(path, MappedFile::Paging::kStreamed);
  ASSERT_EQ(mapped.text().size(), content.size());
  const size_t before = ResidentBytes();
  ASSERT_GT(before, 0u) << "/proc/self/statm unreadable";
  // Read front to back in 1 MiB steps, handing back what was read (an odd offset: whole pages
  // only).
  size_t peak = before;
  for (size_t at = 0; at < content.size(); at += 1 << 20) {
    EXPECT_EQ(mapped.text().substr(at, 1 << 20), std::string_view(content).substr(at, 1 << 20));
    peak = std::max(peak, ResidentBytes());
    mapped.ReleaseBefore(at + (1 << 20) - 7);
  }
  mapped.ReleaseBefore(content.size());
  // Never more than a few MiB of the 16 MiB resident at once (what is handed back goes in whole
  // 2 MiB spans; the kernel maps some pages ahead of a touch), and none of it at the end.
  if (!test::kAsan) {
    EXPECT_LT(peak - before, size_t{6} << 20);
    EXPECT_LT(ResidentBytes(), before + (size_t{1} << 20));
  }
  // Released pages read again, the same bytes.
  EXPECT_EQ(mapped.text().substr(12345, 100), std::string_view(content).substr(12345, 100));
  EXPECT_EQ(mapped.text(), content);
}

// Populate maps the pages of a span ahead of the reading in one call: they are resident before
// they are touched, and the bytes are the file's.
TEST(MappedFile, APopulatedSpanIsResidentBeforeItIsRead) {
  test::TempDir dir;
  const std::string path = dir / "log.bin";
  const std::string content = WritePatternedFile(path, 2246822519u);
  MappedFile mapped(path, MappedFile::Paging::kStreamed);
  const size_t before = ResidentBytes();
  if (!mapped.Populate(0, 8 << 20)) GTEST_SKIP() << "the kernel cannot populate (Linux < 5.14)";
  EXPECT_GE(ResidentBytes(), before + (size_t{7} << 20));
  EXPECT_LT(ResidentBytes(), before + (size_t{12} << 20)) << "more than the span asked for";
  EXPECT_EQ(mapped.text().substr(0, 8 << 20), std::string_view(content).substr(0, 8 << 20));
}

TEST(MappedFile, ASecondPassHandsItsPagesBackToo) {
  // A reader in two passes (DataFlash: pass 1 for the summaries, pass 2 for the samples) reads the
  // file twice front to back; the second pass stays as small as the first.
  test::TempDir dir;
  const std::string path = dir / "log.bin";
  const std::string content = WritePatternedFile(path, 40503u);
  MappedFile mapped(path, MappedFile::Paging::kStreamed);
  const size_t before = ResidentBytes();
  for (int pass = 0; pass < 2; ++pass) {
    size_t peak = before;
    for (size_t at = 0; at < content.size(); at += 1 << 20) {
      ASSERT_EQ(mapped.text()[at + 99], content[at + 99]);
      EXPECT_EQ(mapped.text().substr(at, 1 << 20), std::string_view(content).substr(at, 1 << 20));
      peak = std::max(peak, ResidentBytes());
      mapped.ReleaseBefore(at + (1 << 20));
    }
    if (!test::kAsan) {
      EXPECT_LT(peak - before, size_t{6} << 20) << "pass " << pass;
    }
  }
}

}  // namespace
}  // namespace shutterlab
