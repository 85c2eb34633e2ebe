#include "sim/logs/column_csv.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <array>
#include <optional>
#include <utility>

namespace shutterlab {
namespace {

constexpr const char* kRoles[4] = {"time", "x", "y", "z"};

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// A header name without the double quotes a spreadsheet may put around it.
std::string_view Unquote(std::string_view s) {
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') return s.substr(1, s.size() - 2);
  return s;
}

// 1-based column number, or 0 when the entry is a name.
int ColumnNumber(std::string_view entry) {
  if (entry.empty() || entry.size() > 6) return 0;
  int number = 0;
  for (char c : entry) {
    if (c < '0' || c > '9') return 0;
    number = number * 10 + (c - '0');
  }
  return number == 0 ? -1 : number;  // "0": a number, but not a valid one (Check says so)
}

// Splits on the delimiter; ' ' means runs of spaces and tabs, with no empty fields.
void Split(std::string_view line, char delimiter, std::vector<std::string_view>* fields) {
  if (delimiter != ' ') {
    SplitFields(line, delimiter, fields);
    return;
  }
  fields->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) fields->push_back(line.substr(start, i - start));
  }
}

// The most frequent of ',' and ';'; else tab when the line has tabs and no spaces (a space beside a
// tab says the blanks are padding); else runs of blanks.
char DetectDelimiter(std::string_view line) {
  const long commas = std::count(line.begin(), line.end(), ',');
  const long semicolons = std::count(line.begin(), line.end(), ';');
  if (commas > 0 || semicolons > 0) return semicolons > commas ? ';' : ',';
  const bool tabs = line.find('\t') != std::string_view::npos;
  return tabs && line.find(' ') == std::string_view::npos ? '\t' : ' ';
}

std::string DelimiterName(char delimiter) {
  if (delimiter == '\t') return "tab";
  if (delimiter == ' ') return "whitespace";
  return std::string("'") + delimiter + "'";
}

// The header line for a message, cut short when long.
std::string Quoted(std::string_view line) {
  constexpr size_t kMax = 160;
  if (line.size() <= kMax) return std::string(line);
  return std::string(line.substr(0, kMax)) + "...";
}

// Where each of time, x, y, z is, and how messages call it.
struct ChosenColumns {
  std::array<size_t, 4> index{};     // 0-based field index
  std::array<std::string, 4> label;  // "column 'wx'" or "column 2"
  size_t needed_fields = 0;          // 1 + the largest index
};

ChosenColumns ResolveColumns(const ColumnCsvOptions& options,
                             const std::vector<std::string_view>* header,
                             std::string_view header_line, const std::string& path,
                             long header_line_number) {
  ChosenColumns chosen;
  for (int k = 0; k < 4; ++k) {
    const std::string& entry = options.columns[k];
    const int number = ColumnNumber(entry);
    if (number > 0) {
      chosen.index[k] = static_cast<size_t>(number - 1);
      chosen.label[k] = "column " + entry;
      if (header && chosen.index[k] < header->size())
        chosen.label[k] += " ('" + std::string(Unquote((*header)[chosen.index[k]])) + "')";
    } else {
      // A name: exact first, then case-insensitive, and it must be unique either way.
      std::optional<size_t> found;
      for (bool exact : {true, false}) {
        for (size_t i = 0; i < header->size(); ++i) {
          const std::string_view name = Unquote((*header)[i]);
          if (exact ? name != entry : ToLower(name) != ToLower(entry)) continue;
          if (found)
            throw IoError(IoMessage(
                path, header_line_number,
                "column '" + entry + "' appears twice in the header: " + Quoted(header_line)));
          found = i;
        }
        if (found) break;
      }
      if (!found)
        throw IoError(IoMessage(path, header_line_number,
                                "column '" + entry + "' (" + kRoles[k] +
                                    ") not in the header: " + Quoted(header_line)));
      chosen.index[k] = *found;
      chosen.label[k] = "column '" + entry + "'";
    }
    chosen.needed_fields = std::max(chosen.needed_fields, chosen.index[k] + 1);
  }
  return chosen;
}

// A header when a column is named, or when a chosen field of the line is not a number.
bool LooksLikeHeader(const ColumnCsvOptions& options, const std::vector<std::string_view>& fields) {
  if (options.header != HeaderMode::kAuto) return options.header == HeaderMode::kYes;
  for (const std::string& entry : options.columns) {
    const int number = ColumnNumber(entry);
    if (number <= 0) return true;
    const size_t i = static_cast<size_t>(number - 1);
    if (i < fields.size() && !ParseDouble(fields[i])) return true;
  }
  return false;
}

// The data lines, a block at a time; the first one may have been read already (no header).
class ColumnCsvSource : public FillingSource {
 public:
  ColumnCsvSource(LineReader lines, std::optional<std::string> first_row, long first_row_number,
                  ChosenColumns chosen, const ColumnCsvOptions& options, char delimiter,
                  const std::string& path, size_t chunk_samples)
      : FillingSource(chunk_samples),
        lines_(std::move(lines)),
        first_row_(std::move(first_row)),
        first_row_number_(first_row_number),
        chosen_(std::move(chosen)),
        time_unit_(options.time_unit),
        rad_s_per_unit_(options.rate_unit == RateUnit::kDegPerSecond ? kRadPerDeg : 1.0),
        delimiter_(delimiter),
        path_(path) {}

  double Fraction() const override { return lines_.Fraction(); }

 private:
  void Fill(std::vector<GyroSample>* chunk) override {
    ReserveChunk(chunk, lines_.size_bytes());
    if (first_row_) {
      chunk->push_back(ParseRow(*first_row_, first_row_number_));
      first_row_.reset();
    }
    while (chunk->size() < chunk_samples()) {
      const auto line = lines_.Next();
      if (!line) break;
      if (Trim(*line).empty()) continue;
      try {
        chunk->push_back(ParseRow(*line, lines_.line_number()));
      } catch (const IoError&) {
        if (!lines_.unterminated()) throw;
        LeaveOutCutLastLine(lines_.line_number());
      }
    }
    if (chunk->empty() && !last_t_ns()) throw IoError(IoMessage(path_, 0, "no samples"));
  }

  GyroSample ParseRow(std::string_view line, long line_number) {
    static const char* kUnitNames[] = {"s", "ms", "us", "ns"};
    Split(line, delimiter_, &fields_);
    if (fields_.size() < chosen_.needed_fields) {
      for (int k = 0; k < 4; ++k) {
        if (chosen_.index[k] < fields_.size()) continue;
        throw IoError(IoMessage(path_, line_number,
                                chosen_.label[k] + " (" + kRoles[k] + ") missing: the line has " +
                                    std::to_string(fields_.size()) + " fields split on " +
                                    DelimiterName(delimiter_)));
      }
    }
    const std::string_view time_field = fields_[chosen_.index[0]];
    const std::optional<int64_t> t_ns = ParseTimeInUnitNs(time_field, time_unit_);
    if (!t_ns)
      throw IoError(IoMessage(path_, line_number,
                              chosen_.label[0] + " (time) is not a time in " +
                                  kUnitNames[static_cast<int>(time_unit_)] + ": '" +
                                  std::string(time_field) + "'"));
    if (last_t_ns() && *t_ns < *last_t_ns())
      throw IoError(IoMessage(path_, line_number,
                              "time goes backwards: " + chosen_.label[0] + " is " +
                                  std::string(time_field) + " here and " + previous_time_ +
                                  " on line " + std::to_string(previous_line_)));
    GyroSample sample{*t_ns, {}};
    for (int k = 1; k < 4; ++k) {
      const std::string_view field = fields_[chosen_.index[k]];
      const std::optional<double> rate = ParseDouble(field);
      if (!rate)
        throw IoError(IoMessage(path_, line_number,
                                chosen_.label[k] + " (" + kRoles[k] + ") is not a number: '" +
                                    std::string(field) + "'"));
      sample.omega_rad_s[k - 1] = *rate * rad_s_per_unit_;
    }
    TakeTimeInOrder(path_, line_number, *t_ns, time_field);  // in order: checked above
    previous_time_.assign(time_field.data(), time_field.size());
    previous_line_ = line_number;
    return sample;
  }

  LineReader lines_;
  std::optional<std::string> first_row_;
  long first_row_number_;
  ChosenColumns chosen_;
  TimeUnit time_unit_;
  double rad_s_per_unit_;
  char delimiter_;
  std::string path_;
  std::string previous_time_;  // the time field of the row before, for messages
  long previous_line_ = 0;
  std::vector<std::string_view> fields_;
};

}  // namespace

void ColumnCsvOptions::Check() const {
  SHUTTERLAB_CHECK(columns.size() == 4)
      << "give four columns, time,x,y,z (header names or 1-based numbers), e.g. --columns "
         "t,gx,gy,gz or --columns 4,1,2,3 (got "
      << columns.size() << ")";
  for (const std::string& entry : columns) {
    SHUTTERLAB_CHECK(!entry.empty()) << "a column is empty";
    SHUTTERLAB_CHECK(ColumnNumber(entry) >= 0)
        << "column numbers start at 1 (got '" << entry << "')";
    SHUTTERLAB_CHECK(ColumnNumber(entry) > 0 || header != HeaderMode::kNo)
        << "column '" << entry << "' is a name, but the file has no header";
  }
  SHUTTERLAB_CHECK(delimiter == '\0' || delimiter == ',' || delimiter == ';' || delimiter == '\t' ||
                   delimiter == ' ')
      << "unknown delimiter '" << delimiter << "'";
}

std::vector<std::string> ParseColumnList(const std::string& text) {
  std::vector<std::string> columns;
  std::vector<std::string_view> fields;
  SplitFields(text, ',', &fields);
  for (std::string_view field : fields) columns.emplace_back(field);
  SHUTTERLAB_CHECK(
      columns.size() == 4 &&
      std::none_of(columns.begin(), columns.end(), [](const std::string& c) { return c.empty(); }))
      << "--columns takes four columns, time,x,y,z (header names or 1-based numbers), e.g. "
         "t,gx,gy,gz or 4,1,2,3 (got '"
      << text << "')";
  return columns;
}

char ParseDelimiter(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "auto") return '\0';
  if (lower == "," || lower == "comma") return ',';
  if (lower == ";" || lower == "semicolon") return ';';
  if (lower == "tab" || lower == "\t" || lower == "\\t") return '\t';
  if (lower == "space" || lower == "whitespace" || lower == " ") return ' ';
  SHUTTERLAB_CHECK(false) << "unknown delimiter '" << name
                          << "' (auto, comma, semicolon, tab, whitespace)";
  return '\0';
}

RateUnit ParseRateUnit(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "rad/s" || lower == "rads") return RateUnit::kRadPerSecond;
  if (lower == "deg/s" || lower == "dps") return RateUnit::kDegPerSecond;
  SHUTTERLAB_CHECK(false) << "unknown rate unit '" << name << "' (rad/s, deg/s)";
  return RateUnit::kRadPerSecond;
}

const char* RateUnitName(RateUnit unit) {
  return unit == RateUnit::kDegPerSecond ? "deg/s" : "rad/s";
}

ColumnCsvStream OpenColumnCsv(TextBlocks blocks, const std::string& path,
                              const ColumnCsvOptions& options, size_t chunk_samples) {
  options.Check();
  constexpr std::string_view kBom = "\xEF\xBB\xBF";
  LineReader lines(std::move(blocks));
  std::optional<std::string_view> line = lines.Next();
  if (line && line->substr(0, kBom.size()) == kBom) line->remove_prefix(kBom.size());
  while (line && Trim(*line).empty()) line = lines.Next();
  if (!line) throw IoError(IoMessage(path, 0, "no samples (the file is empty)"));
  ColumnCsvStream stream;
  ColumnCsvLog& log = stream.log;
  log.delimiter = options.delimiter != '\0' ? options.delimiter : DetectDelimiter(*line);
  std::vector<std::string_view> first;
  Split(*line, log.delimiter, &first);
  log.has_header = LooksLikeHeader(options, first);
  ChosenColumns chosen =
      ResolveColumns(options, log.has_header ? &first : nullptr, *line, path, lines.line_number());
  for (int k = 0; k < 4; ++k) {
    if (k > 0) log.source += ',';
    const size_t i = chosen.index[k];
    log.source +=
        log.has_header && i < first.size() ? std::string(Unquote(first[i])) : std::to_string(i + 1);
  }
  std::optional<std::string> first_row;
  if (!log.has_header) first_row = std::string(*line);
  const long first_row_number = lines.line_number();
  stream.samples = std::make_unique<ColumnCsvSource>(std::move(lines), std::move(first_row),
                                                     first_row_number, std::move(chosen), options,
                                                     log.delimiter, path, chunk_samples);
  return stream;
}

ColumnCsvLog ParseColumnCsv(std::string_view text, const std::string& path,
                            const ColumnCsvOptions& options) {
  ColumnCsvStream stream = OpenColumnCsv(TextBlocks::InMemory(text), path, options);
  stream.log.trace = ReadAllSamples(stream.samples.get());
  stream.log.warnings = stream.samples->Warnings();
  return std::move(stream.log);
}

ColumnCsvLog ReadColumnCsv(const std::string& path, const ColumnCsvOptions& options) {
  options.Check();
  ColumnCsvStream stream = OpenColumnCsv(TextBlocks::OfFile(path), path, options);
  stream.log.trace = ReadAllSamples(stream.samples.get());
  stream.log.warnings = stream.samples->Warnings();
  return std::move(stream.log);
}

}  // namespace shutterlab
