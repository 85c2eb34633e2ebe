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

// Parses the data lines from the cursor on.
std::vector<GyroSample> ParseRows(LineCursor* cursor, std::optional<std::string_view> line,
                                  const ChosenColumns& chosen, const ColumnCsvOptions& options,
                                  char delimiter, const std::string& path, size_t expected_rows) {
  const double rad_s_per_unit = options.rate_unit == RateUnit::kDegPerSecond ? kRadPerDeg : 1.0;
  const char* unit_name[] = {"s", "ms", "us", "ns"};
  std::vector<GyroSample> samples;
  samples.reserve(expected_rows);
  // Fewer page faults on a long log (sim/text_file.h): it costs more than parsing otherwise.
  AdviseHugePages(samples.data(), expected_rows * sizeof(GyroSample));
  std::vector<std::string_view> fields;
  std::string_view previous_time;
  long previous_line = 0;
  for (; line; line = cursor->Next()) {
    if (Trim(*line).empty()) continue;
    const long line_number = cursor->line_number();
    Split(*line, delimiter, &fields);
    if (fields.size() < chosen.needed_fields) {
      for (int k = 0; k < 4; ++k) {
        if (chosen.index[k] < fields.size()) continue;
        throw IoError(IoMessage(path, line_number,
                                chosen.label[k] + " (" + kRoles[k] + ") missing: the line has " +
                                    std::to_string(fields.size()) + " fields split on " +
                                    DelimiterName(delimiter)));
      }
    }
    const std::string_view time_field = fields[chosen.index[0]];
    const std::optional<int64_t> t_ns = ParseTimeInUnitNs(time_field, options.time_unit);
    if (!t_ns)
      throw IoError(IoMessage(path, line_number,
                              chosen.label[0] + " (time) is not a time in " +
                                  unit_name[static_cast<int>(options.time_unit)] + ": '" +
                                  std::string(time_field) + "'"));
    if (!samples.empty() && *t_ns < samples.back().t_ns)
      throw IoError(IoMessage(path, line_number,
                              "time goes backwards: " + chosen.label[0] + " is " +
                                  std::string(time_field) + " here and " +
                                  std::string(previous_time) + " on line " +
                                  std::to_string(previous_line)));
    GyroSample sample{*t_ns, {}};
    for (int k = 1; k < 4; ++k) {
      const std::string_view field = fields[chosen.index[k]];
      const std::optional<double> rate = ParseDouble(field);
      if (!rate)
        throw IoError(IoMessage(path, line_number,
                                chosen.label[k] + " (" + kRoles[k] + ") is not a number: '" +
                                    std::string(field) + "'"));
      sample.omega_rad_s[k - 1] = *rate * rad_s_per_unit;
    }
    samples.push_back(sample);
    previous_time = time_field;
    previous_line = line_number;
  }
  if (samples.empty()) throw IoError(IoMessage(path, 0, "no samples"));
  return samples;
}

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

ColumnCsvLog ParseColumnCsv(std::string_view text, const std::string& path,
                            const ColumnCsvOptions& options) {
  options.Check();
  constexpr std::string_view kBom = "\xEF\xBB\xBF";
  if (text.substr(0, kBom.size()) == kBom) text.remove_prefix(kBom.size());
  LineCursor cursor(text);
  std::optional<std::string_view> line = cursor.Next();
  while (line && Trim(*line).empty()) line = cursor.Next();
  if (!line) throw IoError(IoMessage(path, 0, "no samples (the file is empty)"));
  ColumnCsvLog log;
  log.delimiter = options.delimiter != '\0' ? options.delimiter : DetectDelimiter(*line);
  std::vector<std::string_view> first;
  Split(*line, log.delimiter, &first);
  log.has_header = LooksLikeHeader(options, first);
  const ChosenColumns chosen =
      ResolveColumns(options, log.has_header ? &first : nullptr, *line, path, cursor.line_number());
  for (int k = 0; k < 4; ++k) {
    if (k > 0) log.source += ',';
    const size_t i = chosen.index[k];
    log.source +=
        log.has_header && i < first.size() ? std::string(Unquote(first[i])) : std::to_string(i + 1);
  }
  if (log.has_header) line = cursor.Next();
  // Rows from the length of the first lines, a quarter over, so that the vector never re-copies.
  const std::string_view rest =
      line ? text.substr(static_cast<size_t>(line->data() - text.data())) : std::string_view();
  const size_t probe = std::min<size_t>(rest.size(), 4096);
  const size_t probe_lines =
      std::max<size_t>(1, std::count(rest.begin(), rest.begin() + probe, '\n'));
  const size_t expected_rows = rest.size() / std::max<size_t>(1, probe / probe_lines) * 5 / 4 + 16;
  log.trace =
      GyroTrace(ParseRows(&cursor, line, chosen, options, log.delimiter, path, expected_rows));
  return log;
}

ColumnCsvLog ReadColumnCsv(const std::string& path, const ColumnCsvOptions& options) {
  options.Check();
  const MappedFile file(path);
  return ParseColumnCsv(file.text(), path, options);
}

}  // namespace shutterlab
