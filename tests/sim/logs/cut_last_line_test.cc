// Every line-based gyro reader: a file cut inside its last line (copied or recorded while still
// being written) is read up to its last whole line with a `truncated` warning, while a bad line
// anywhere else stays a one-line error naming the file and the line.

#include "sim/check.h"
#include "sim/gyro_source.h"
#include "sim/logs/column_csv.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gcsv.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/raw_csv.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

constexpr int kRows = 6;

// One text format: its lines before the rows, its rows, and how it is read.
struct TextFormat {
  std::string name;
  std::string header;                 // whole lines before the rows ("" for none)
  std::function<std::string(int)> row;  // row k, without its line break
  size_t fields = 4;                  // fields a whole row has
  bool time_last = false;             // a cut inside the time makes it go backwards
  FlightLogReadOptions read;          // how ReadFlightLog reads the file
  // The rows as a stream over text in memory, in blocks of block_bytes; null: files only.
  std::function<std::unique_ptr<GyroSource>(TextBlocks)> open;
};

std::vector<TextFormat> Formats() {
  std::vector<TextFormat> formats;
  TextFormat csv;
  csv.name = "gyro.csv";
  csv.header = "t,gx,gy,gz\n";
  csv.row = [](int k) { return "1.00" + std::to_string(k) + ",0.125,-0.25,-0.5"; };
  csv.open = [](TextBlocks blocks) { return OpenGyroCsv(std::move(blocks), "mem.csv"); };
  formats.push_back(csv);

  TextFormat raw;
  raw.name = "raw";
  raw.header = "t,gx,gy,gz\n";
  raw.row = [](int k) { return "1.00" + std::to_string(k) + ",12,-345,-6789"; };
  raw.read.format = LogFormat::kRaw;
  raw.open = [options = raw.read.raw](TextBlocks blocks) {
    return OpenRawCsv(std::move(blocks), "mem.csv", options.range_dps, options.time_unit);
  };
  formats.push_back(raw);

  TextFormat gcsv;
  gcsv.name = "gcsv";
  gcsv.header = "GYROFLOW IMU LOG\nversion,1.3\nid,x\norientation,XYZ\ntscale,0.001\n"
                "gscale,0.5\nt,gx,gy,gz\n";
  gcsv.row = [](int k) { return std::to_string(1000 + k) + ",12,-345,-6789"; };
  gcsv.open = [](TextBlocks blocks) {
    return std::move(OpenGcsv(std::move(blocks), "mem.gcsv").samples);
  };
  formats.push_back(gcsv);

  // --columns 4,1,2,3 --time-unit us: the time is the last field, so a cut inside it reads as an
  // earlier time, which does not read either.
  TextFormat columns;
  columns.name = "columns";
  columns.row = [](int k) { return "0.125,-0.25,-0.5," + std::to_string(1000000 + 10 * k); };
  columns.time_last = true;
  columns.read.format = LogFormat::kColumns;
  columns.read.columns.columns = {"4", "1", "2", "3"};
  columns.read.columns.time_unit = TimeUnit::kMicroseconds;
  columns.read.columns.header = HeaderMode::kNo;
  columns.open = [options = columns.read.columns](TextBlocks blocks) {
    return std::move(OpenColumnCsv(std::move(blocks), "mem.csv", options).samples);
  };
  formats.push_back(columns);

  TextFormat blackbox;
  blackbox.name = "blackbox csv";
  blackbox.header = "loopIteration, time (us), gyroADC[0], gyroADC[1], gyroADC[2]\n";
  blackbox.row = [](int k) {
    return std::to_string(16 * k) + ", " + std::to_string(17433272 + 2000 * k) + ", 12, -345, -67";
  };
  blackbox.fields = 5;
  formats.push_back(blackbox);
  return formats;
}

std::string WholeText(const TextFormat& format) {
  std::string text = format.header;
  for (int k = 0; k < kRows; ++k) text += format.row(k) + "\n";
  return text;
}

// The cut must be left out: it lacks a field, its last field is empty or a bare sign, or (time
// last) its time is cut short. The whole line without its line break is read.
bool MustLeaveOut(const TextFormat& format, std::string_view cut) {
  if (cut == format.row(kRows - 1)) return false;
  std::vector<std::string_view> fields;
  SplitFields(cut, ',', &fields);
  if (fields.size() < format.fields) return true;
  if (format.time_last) return true;  // every cut inside the time leaves a smaller one
  return fields.back().empty() || fields.back() == "-";
}

void ExpectSamePrefix(const GyroTrace& got, const GyroTrace& whole, size_t n,
                      const std::string& where) {
  ASSERT_GE(got.size(), n) << where;
  for (size_t k = 0; k < n; ++k) {
    ASSERT_EQ(got[k].t_ns, whole[k].t_ns) << where << " sample " << k;
    ASSERT_EQ(got[k].omega_rad_s, whole[k].omega_rad_s) << where << " sample " << k;
  }
}

// What one cut copy read: the samples, and the warnings.
struct CutRead {
  GyroTrace trace;
  std::vector<LogWarning> warnings;
};

// Checks a cut copy's reading against the whole file's: every whole line read, the cut one
// either left out and said, or (when it still reads as a number) kept without a word.
void ExpectCutRead(const TextFormat& format, const CutRead& got, const GyroTrace& whole,
                   std::string_view cut, long last_line, const std::string& where,
                   size_t* left_out) {
  ExpectSamePrefix(got.trace, whole, kRows - 1, where);
  const bool said = test::AnyWarningContains(got.warnings, "truncated: line " +
                                                               std::to_string(last_line) + ":");
  if (got.trace.size() == kRows - 1) {
    ++*left_out;
    EXPECT_TRUE(said) << where << "\n" << test::JoinedWarnings(got.warnings);
    for (const LogWarning& w : got.warnings) {
      if (w.kind != "truncated") continue;
      EXPECT_EQ(w.count, std::optional<size_t>(1)) << where;
      ASSERT_TRUE(w.t_s.has_value()) << where;
      EXPECT_NEAR(*w.t_s, whole[kRows - 2].t_ns * 1e-9, 1e-9) << where;
    }
  } else {
    EXPECT_EQ(got.trace.size(), static_cast<size_t>(kRows)) << where;
    EXPECT_FALSE(MustLeaveOut(format, cut)) << where << ": '" << cut << "' was read as a sample";
    EXPECT_FALSE(said) << where;
  }
}

TEST(CutLastLine, EveryLineReaderReadsUpToTheLastWholeLineAndSaysSo) {
  test::TempDir dir;
  for (const TextFormat& format : Formats()) {
    const std::string text = WholeText(format);
    const std::string path = dir / ("whole_" + std::to_string(format.header.size()));
    WriteFileAtomically(path, text);
    const FlightLog whole = ReadFlightLog(path, format.read);
    ASSERT_EQ(whole.gyro.size(), static_cast<size_t>(kRows)) << format.name;
    const size_t last_begin = text.size() - format.row(kRows - 1).size() - 1;
    const long last_line = static_cast<long>(std::count(text.begin(), text.end(), '\n'));
    size_t left_out = 0;
    // Every cut inside the last line, and the whole last line without its line break.
    for (size_t size = last_begin + 1; size < text.size(); ++size) {
      const std::string cut_text = text.substr(0, size);
      const std::string_view cut = std::string_view(cut_text).substr(last_begin);
      const std::string where = format.name + " cut to '" + std::string(cut) + "'";
      const std::string cut_path = dir / "cut";
      WriteFileAtomically(cut_path, cut_text);
      try {
        const FlightLog log = ReadFlightLog(cut_path, format.read);
        ExpectCutRead(format, {log.gyro, log.warnings}, whole.gyro, cut, last_line, where,
                      &left_out);
      } catch (const std::exception& e) {
        ADD_FAILURE() << where << ": " << e.what();
      }
      if (!format.open) continue;
      // The streams, with the line ends at every place in their blocks.
      for (const size_t block : {size_t{5}, size_t{13}, TextBlocks::kBlockBytes}) {
        try {
          const std::unique_ptr<GyroSource> source =
              format.open(TextBlocks::InMemory(cut_text, block));
          GyroTrace trace = ReadAllSamples(source.get());
          size_t ignored = 0;
          ExpectCutRead(format, {std::move(trace), source->Warnings()}, whole.gyro, cut,
                        last_line, where + " in blocks of " + std::to_string(block), &ignored);
        } catch (const std::exception& e) {
          ADD_FAILURE() << where << " in blocks of " << block << ": " << e.what();
        }
      }
    }
    // Every cut short of the last field lacks a field and is left out.
    EXPECT_GE(left_out, format.row(kRows - 1).rfind(',') + 1) << format.name;
  }
}

TEST(CutLastLine, ABadLineBeforeTheLastIsStillAnErrorNamingFileAndLine) {
  test::TempDir dir;
  for (const TextFormat& format : Formats()) {
    std::string text = format.header;
    for (int k = 0; k < kRows; ++k) text += (k == 2 ? std::string("x,y") : format.row(k)) + "\n";
    const long bad_line = static_cast<long>(std::count(format.header.begin(),
                                                       format.header.end(), '\n')) +
                          3;
    // With the last line cut as well: the cut is forgiven, the bad line is not.
    text.resize(text.size() - 4);
    const std::string path = dir / "bad";
    WriteFileAtomically(path, text);
    try {
      ReadFlightLog(path, format.read);
      ADD_FAILURE() << format.name << ": a bad line was read";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(path + ":" + std::to_string(bad_line) + ":"),
                std::string::npos)
          << format.name << ": " << e.what();
    }
  }
}

TEST(CutLastLine, TheWarningGoesThroughTheReadAheadStreamAndBareReadersRefuse) {
  test::TempDir dir;
  const TextFormat csv = Formats().front();
  std::string text = WholeText(csv);
  text.resize(text.size() - 8);  // inside the last line's rates
  const std::string path = dir / "gyro.csv";
  WriteFileAtomically(path, text);
  FlightLogStream stream = OpenFlightLog(path);
  stream.gyro = ReadAhead(std::move(stream.gyro));
  size_t samples = 0;
  const StreamedLog streamed =
      ConsumeFlightLog(&stream, [&samples](const GyroChunk& chunk) { samples += chunk.size; });
  EXPECT_EQ(samples, static_cast<size_t>(kRows - 1));
  EXPECT_TRUE(test::AnyWarningContains(streamed.warnings, "truncated: line 7: the file ends"))
      << test::JoinedWarnings(streamed.warnings);
  // ReadGyroCsv returns a bare trace, with nowhere to say what it left out: it refuses instead.
  try {
    ReadGyroCsv(path);
    ADD_FAILURE() << "a bare reader dropped the cut line silently";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": line 7: the file ends inside it"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace shutterlab
