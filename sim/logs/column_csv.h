#pragma once
// Any delimited text file with a time column and three rate columns, read by what the user says
// about it instead of by its content: which columns (names from the header or 1-based numbers),
// the delimiter, whether there is a header, and the units of time and rate. Reads, for example, a
// phone's gyro.txt (`--columns 4,1,2,3`, no header), a PX4 ulog2csv export of sensor_combined
// (`--columns timestamp,gyro_rad[0],gyro_rad[1],gyro_rad[2] --time-unit us`) or a spreadsheet
// export (`time_ms;wx;wy;wz`).

#include "sim/gyro_source.h"
#include "sim/gyro_trace.h"
#include "sim/logs/raw_csv.h"  // TimeUnit
#include "sim/text_file.h"

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

enum class RateUnit { kRadPerSecond, kDegPerSecond };

// Whether the first non-empty line names the columns.
enum class HeaderMode { kAuto, kYes, kNo };

// What ReadColumnCsv is told about the file.
struct ColumnCsvOptions {
  // Four entries, time then x, y, z: each a 1-based column number ("4") or a header name ("wx").
  std::vector<std::string> columns;
  // ',', ';' or '\t'; ' ' splits on runs of spaces and tabs; '\0' (auto) picks from the first
  // non-empty line: the more frequent of ',' and ';'; else tab when the line has tabs and no
  // spaces; else runs of blanks.
  char delimiter = '\0';
  // kAuto: a header when a column is named, or when a chosen field of the first line is not a
  // number.
  HeaderMode header = HeaderMode::kAuto;
  TimeUnit time_unit = TimeUnit::kSeconds;
  RateUnit rate_unit = RateUnit::kRadPerSecond;
  // Throws std::invalid_argument naming the first bad field (not four columns, a column number
  // below 1, a name with header kNo, an unknown delimiter).
  void Check() const;
};

// "t,gx,gy,gz" or "4,1,2,3" -> its four entries, trimmed; throws std::invalid_argument unless
// there are four non-empty ones. A name with a comma in it cannot be given this way.
std::vector<std::string> ParseColumnList(const std::string& text);
// "auto" -> '\0'; "," / "comma"; ";" / "semicolon"; "tab" / "\t"; "space" / "whitespace" -> ' '.
// Throws std::invalid_argument naming the text otherwise.
char ParseDelimiter(const std::string& name);
// "rad/s" / "rads"; "deg/s" / "dps". Throws std::invalid_argument naming the text otherwise.
RateUnit ParseRateUnit(const std::string& name);
const char* RateUnitName(RateUnit unit);  // "rad/s", "deg/s"

// The trace and how its columns were found.
struct ColumnCsvLog {
  GyroTrace trace;     // rates in rad/s, times in the file's clock (not shifted)
  std::string source;  // the chosen columns, "time_ms,wx,wy,wz" from a header or "4,1,2,3"
  char delimiter = ',';
  bool has_header = false;
  // A last line cut inside (no line break, does not read): left out and said here
  // (CutLastLineWarning).
  std::vector<LogWarning> warnings;
};

// Reads the file (a UTF-8 byte-order mark and CRLF line ends are accepted; blank lines skipped;
// header names may be in double quotes; columns not chosen are never parsed). Throws IoError
// "PATH:LINE: problem" naming the column when a name is not in the header (quoting the header), a
// line lacks a chosen column, a field is not a number, or a time is smaller than the one before
// (naming both lines); and when the file has no sample. Throws std::invalid_argument for bad
// options (ColumnCsvOptions::Check). A last line without its line break that does not read is
// the file cut inside it: left out, with a `truncated` warning.
ColumnCsvLog ReadColumnCsv(const std::string& path, const ColumnCsvOptions& options);
// The same on text already in memory; path names it in messages.
ColumnCsvLog ParseColumnCsv(std::string_view text, const std::string& path,
                            const ColumnCsvOptions& options);
// The same as a stream: the first line and the columns are resolved at once (their errors thrown
// here), the rows a block at a time as the chunks are taken. log.trace stays empty.
struct ColumnCsvStream {
  ColumnCsvLog log;
  std::unique_ptr<GyroSource> samples;
};
ColumnCsvStream OpenColumnCsv(TextBlocks blocks, const std::string& path,
                              const ColumnCsvOptions& options);

}  // namespace shutterlab
