#include "sim/logs/trigger_file.h"

#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/flight_log_io.h"
#include "sim/text_file.h"

#include <cmath>
#include <set>

namespace shutterlab {
namespace {

// GPS weeks up to 9999 (the year 2171) keep week * 604800 s in int64 ns.
constexpr int64_t kMaxGpsWeek = 9999;

// Splits an MRK line on tabs, or on runs of spaces when it has no tab (a file re-saved by an
// editor); the standard-deviation field "a, b, c" then spans three tokens, which is harmless: it
// is not read.
void SplitMrk(std::string_view line, std::vector<std::string_view>* fields) {
  if (line.find('\t') != std::string_view::npos) {
    SplitFields(line, '\t', fields);
    return;
  }
  fields->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && line[i] == ' ') ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ') ++i;
    if (i > start) fields->push_back(line.substr(start, i - start));
  }
}

// "[2211]" -> 2211.
std::optional<int64_t> MrkWeek(std::string_view field) {
  if (field.size() < 3 || field.front() != '[' || field.back() != ']') return std::nullopt;
  return ParseInt(field.substr(1, field.size() - 2));
}

// "47.6436873208,Lat" -> (47.64..., "Lat").
std::optional<std::pair<double, std::string_view>> Labelled(std::string_view field) {
  const size_t comma = field.rfind(',');
  if (comma == std::string_view::npos) return std::nullopt;
  const auto value = ParseDouble(field.substr(0, comma));
  if (!value) return std::nullopt;
  return std::make_pair(*value, field.substr(comma + 1));
}

// GPS seconds of week as written ("296288.242869"), exactly to the ns: integer and fraction apart.
std::optional<int64_t> SecondsOfWeekNs(std::string_view text) {
  const size_t dot = text.find('.');
  const auto whole = ParseInt(text.substr(0, dot));
  if (!whole || *whole < 0 || *whole > kSecondsPerWeek) return std::nullopt;
  int64_t ns = 0;
  if (dot != std::string_view::npos) {
    const std::string_view fraction = text.substr(dot + 1);
    if (fraction.empty() || fraction.size() > 9 ||
        fraction.find_first_not_of("0123456789") != std::string_view::npos)
      return std::nullopt;
    for (size_t i = 0; i < 9; ++i) ns = ns * 10 + (i < fraction.size() ? fraction[i] - '0' : 0);
  }
  return *whole * kNsPerSecond + ns;
}

// One MRK line's fields into *event; the problem in words, empty when the line reads.
std::string MrkLineProblem(const std::vector<std::string_view>& fields, TriggerEvent* event) {
  if (fields.size() < 3) return "expected 'number<TAB>seconds of week<TAB>[week] ...'";
  const auto number = ParseInt(fields[0]);
  const auto tow_ns = SecondsOfWeekNs(fields[1]);
  const auto week = MrkWeek(fields[2]);
  if (!number || *number < 0) return "bad photo number '" + std::string(fields[0]) + "'";
  if (!tow_ns) return "bad GPS seconds of week '" + std::string(fields[1]) + "'";
  if (!week || *week < 0 || *week > kMaxGpsWeek)
    return "bad GPS week '" + std::string(fields[2]) + "' (expected [week])";
  event->sequence = *number;
  event->t_ns = *week * kSecondsPerWeek * kNsPerSecond + *tow_ns;
  for (size_t i = 3; i < fields.size(); ++i) {
    const auto value = Labelled(fields[i]);
    if (!value) continue;
    if (value->second == "Lat") event->latitude_deg = value->first;
    if (value->second == "Lon") event->longitude_deg = value->first;
    if (value->second == "Ellh") event->height_m = value->first;
  }
  return "";
}

// The file's last line, when the file does not end with a line break: a file cut while it was
// written or copied (a full card, a pulled cable) ends so.
bool IsCutLastLine(std::string_view text, std::string_view line) {
  return !text.empty() && text.back() != '\n' &&
         line.data() + line.size() == text.data() + text.size();
}

// A cut last line is said, not an error: kept: what it gave is read (its fields are labelled or
// whole); dropped: it did not read.
void WarnCutLastLine(long line_number, bool kept, std::vector<LogWarning>* warnings) {
  if (!kept) {
    warnings->push_back(CutLastLineWarning(line_number));
    return;
  }
  warnings->push_back(
      {"truncated", "line " + std::to_string(line_number) +
                        ": the file ends inside it (no line break, fewer fields than the first "
                        "line): read as far as it goes"});
}

void WarnOrder(const std::vector<TriggerEvent>& events, std::vector<LogWarning>* warnings) {
  size_t backwards = 0, repeated = 0;
  std::set<int64_t> seen;
  for (size_t i = 0; i < events.size(); ++i) {
    if (i > 0 && events[i].t_ns < events[i - 1].t_ns) ++backwards;
    if (events[i].sequence >= 0 && !seen.insert(events[i].sequence).second) ++repeated;
  }
  if (backwards > 0) {
    warnings->push_back({"time_backwards",
                         std::to_string(backwards) + " trigger time(s) earlier than the one before",
                         std::nullopt, backwards});
  }
  if (repeated > 0) {
    warnings->push_back({"duplicate_sequence",
                         std::to_string(repeated) + " photo number(s) given twice", std::nullopt,
                         repeated});
  }
}

// A UTC text "2026-01-13 03:04:17.875381+00:00" (ISO 8601 with ' ' or 'T'); no zone means UTC.
std::optional<int64_t> ParseUtcText(std::string_view text, std::string* problem) {
  if (text.size() < 19) {
    *problem = "'" + std::string(text) + "' is not a date and time";
    return std::nullopt;
  }
  std::string_view rest = text.substr(19), fraction, zone;
  if (!rest.empty() && rest.front() == '.') {
    size_t end = 1;
    while (end < rest.size() && rest[end] >= '0' && rest[end] <= '9') ++end;
    fraction = rest.substr(1, end - 1);
    rest = rest.substr(end);
  }
  zone = rest;
  const auto face = ParseExifDateTime(text.substr(0, 19), fraction.substr(0, 9),
                                      zone.empty() ? "Z" : zone, problem);
  if (!face) return std::nullopt;
  return face->UtcNs();
}

struct CsvColumns {
  int image = -1, time = -1;
  TriggerClock clock = TriggerClock::kLog;
  double ns_per_unit = 1e9;  // numeric time columns
  bool utc_text = false;
  std::string time_name;
};

// The columns a header names; nullopt when the first line is not a header.
std::optional<CsvColumns> HeaderColumns(const std::vector<std::string_view>& fields) {
  if (ParseDouble(fields.back())) return std::nullopt;
  CsvColumns c;
  // Log-clock columns first: they place photos without a clock relation.
  struct Time {
    const char* name;
    TriggerClock clock;
    double ns_per_unit;
    bool text;
  };
  static const Time kTimes[] = {
      {"t", TriggerClock::kLog, 1e9, false},         {"time", TriggerClock::kLog, 1e9, false},
      {"t_s", TriggerClock::kLog, 1e9, false},       {"t_ms", TriggerClock::kLog, 1e6, false},
      {"t_us", TriggerClock::kLog, 1e3, false},      {"t_ns", TriggerClock::kLog, 1.0, false},
      {"timestamp", TriggerClock::kLog, 1e3, false}, {"utc_usec", TriggerClock::kUtc, 1e3, false},
      {"utc", TriggerClock::kUtc, 0.0, true}};
  for (const Time& t : kTimes) {
    for (size_t i = 0; i < fields.size() && c.time < 0; ++i) {
      if (ToLower(fields[i]) == t.name) {
        c.time = static_cast<int>(i);
        c.clock = t.clock;
        c.ns_per_unit = t.ns_per_unit;
        c.utc_text = t.text;
        c.time_name = t.name;
      }
    }
  }
  for (size_t i = 0; i < fields.size() && c.image < 0; ++i) {
    const std::string name = ToLower(fields[i]);
    if (name == "image" || name == "name" || name == "file") c.image = static_cast<int>(i);
  }
  return c;
}

// One data row of a trigger CSV; throws IoError("PATH:LINE: problem").
TriggerEvent CsvRow(const std::vector<std::string_view>& fields, const CsvColumns& columns,
                    size_t width, const std::string& path, long n) {
  if (fields.size() != width) {
    throw IoError(IoMessage(
        path, n,
        "expected " + std::to_string(width) + " fields, got " + std::to_string(fields.size())));
  }
  const std::string_view cell = fields[columns.time];
  TriggerEvent event;
  if (columns.utc_text) {
    std::string problem;
    const auto t = ParseUtcText(cell, &problem);
    if (!t) throw IoError(IoMessage(path, n, "bad UTC time: " + problem));
    event.t_ns = *t;
  } else if (const auto whole = ParseInt(cell);
             whole && *whole > -static_cast<int64_t>(9e18 / columns.ns_per_unit) &&
             *whole < static_cast<int64_t>(9e18 / columns.ns_per_unit)) {
    event.t_ns = *whole * static_cast<int64_t>(columns.ns_per_unit);
  } else {
    const auto value = ParseDouble(cell);
    if (!value || std::abs(*value * columns.ns_per_unit) > 9e18) {
      throw IoError(IoMessage(
          path, n, "bad time '" + std::string(cell) + "' in column " + columns.time_name));
    }
    event.t_ns = std::llround(*value * columns.ns_per_unit);
  }
  if (columns.image >= 0) {
    event.name = std::string(fields[columns.image]);
    if (event.name.empty()) throw IoError(IoMessage(path, n, "empty image name"));
  }
  return event;
}

TriggerFile FromLog(const std::string& path) {
  FlightLog log = ReadFlightLog(path);
  TriggerFile file;
  file.format = log.format;
  file.clock = TriggerClock::kLog;
  file.warnings = std::move(log.warnings);
  std::string kinds;
  for (const CameraEvent& e : log.camera_events) {
    TriggerEvent event;
    event.t_ns = e.t_ns;
    event.sequence = e.sequence;
    file.events.push_back(event);
    if (kinds.find(e.kind) == std::string::npos) kinds += (kinds.empty() ? "" : ", ") + e.kind;
  }
  file.source = "camera events (" + kinds + ")";
  if (file.events.empty()) throw IoError(IoMessage(path, 0, "the log has no camera events"));
  return file;
}

}  // namespace

const char* TriggerClockName(TriggerClock clock) {
  switch (clock) {
    case TriggerClock::kLog:
      return "log clock";
    case TriggerClock::kGps:
      return "GPS time";
    case TriggerClock::kUtc:
      return "UTC";
  }
  return "log clock";
}

bool LooksLikeMrk(std::string_view text) {
  LineCursor cursor(text.substr(0, 4096));
  std::vector<std::string_view> fields;
  while (const auto line = cursor.Next()) {
    if (line->find_first_not_of(" \t") == std::string_view::npos) continue;
    SplitMrk(*line, &fields);
    return fields.size() >= 3 && ParseInt(fields[0]) && SecondsOfWeekNs(fields[1]) &&
           MrkWeek(fields[2]);
  }
  return false;
}

TriggerFile ParseMrk(std::string_view text, const std::string& path) {
  TriggerFile file;
  file.format = "mrk";
  file.clock = TriggerClock::kGps;
  file.source = "MRK exposure times (GPS time)";
  LineCursor cursor(text);
  std::vector<std::string_view> fields;
  size_t first_fields = 0;  // a whole line's field count, from the first
  while (const auto line = cursor.Next()) {
    if (line->find_first_not_of(" \t") == std::string_view::npos) continue;
    SplitMrk(*line, &fields);
    const long n = cursor.line_number();
    TriggerEvent event;
    std::string problem = MrkLineProblem(fields, &event);
    if (IsCutLastLine(text, *line)) {
      if (!problem.empty() || fields.size() < first_fields) {
        WarnCutLastLine(n, problem.empty(), &file.warnings);
        if (!problem.empty()) break;
      }
    }
    if (!problem.empty())
      throw IoError(IoMessage(path, n, problem + ", got '" + std::string(*line) + "'"));
    if (first_fields == 0) first_fields = fields.size();
    file.events.push_back(std::move(event));
  }
  if (file.events.empty()) throw IoError(IoMessage(path, 0, "no photo lines in the MRK file"));
  WarnOrder(file.events, &file.warnings);
  return file;
}

TriggerFile ParseTriggerCsv(std::string_view text, const std::string& path) {
  TriggerFile file;
  file.format = "csv";
  LineCursor cursor(text);
  std::vector<std::string_view> fields;
  std::optional<CsvColumns> columns;
  size_t width = 0;
  while (const auto line = cursor.Next()) {
    const std::string_view content = *line;
    const size_t first = content.find_first_not_of(" \t");
    if (first == std::string_view::npos || content[first] == '#') continue;
    SplitFields(content, ',', &fields);
    const long n = cursor.line_number();
    if (!columns) {
      columns = HeaderColumns(fields);
      if (columns) {
        if (columns->time < 0) {
          throw IoError(IoMessage(path, n,
                                  "the header names no time column (t, time, t_s, t_ms, t_us, "
                                  "t_ns, timestamp, utc_usec or utc): '" +
                                      std::string(content) + "'"));
        }
        width = fields.size();
        file.clock = columns->clock;
        file.source =
            "CSV column " + columns->time_name + " (" + TriggerClockName(file.clock) + ")";
        continue;
      }
      if (fields.size() > 2) {
        throw IoError(IoMessage(path, n,
                                "expected 't' or 'image,t' (seconds on the log clock) or "
                                "a header naming the columns, got '" +
                                    std::string(content) + "'"));
      }
      columns = CsvColumns{};
      columns->image = fields.size() == 2 ? 0 : -1;
      columns->time = static_cast<int>(fields.size()) - 1;
      columns->time_name = "t";
      width = fields.size();
      file.source = "CSV t (log clock)";
    }
    if (IsCutLastLine(text, content)) {
      try {
        file.events.push_back(CsvRow(fields, *columns, width, path, n));
      } catch (const IoError&) {
        WarnCutLastLine(n, false, &file.warnings);
      }
      continue;
    }
    file.events.push_back(CsvRow(fields, *columns, width, path, n));
  }
  if (file.events.empty()) throw IoError(IoMessage(path, 0, "no trigger times in the file"));
  WarnOrder(file.events, &file.warnings);
  return file;
}

GyroSync MoveTriggersToLogClock(const GyroTrace& log_gyro, const GyroTrace& clock_gyro,
                                const std::string& clock_name, TriggerFile* file) {
  SHUTTERLAB_CHECK(file->clock == TriggerClock::kLog)
      << "the triggers are on " << TriggerClockName(file->clock)
      << " already, not on a gyro's clock: give --triggers-clock only for triggers recorded "
         "beside another gyro (record's triggers file and its .gcsv)";
  GyroSyncOptions options;
  options.a_name = "the log";
  options.b_name = clock_name;
  const GyroSync sync = SyncGyros(log_gyro, clock_gyro, options);
  for (TriggerEvent& event : file->events)
    event.t_ns = SecondsToNs(ClockAFromB(sync, event.t_ns * 1e-9));
  file->source += "; on " + clock_name +
                  "'s clock, put on the log's from the motion: log clock = " + clock_name + "'s " +
                  FormatNumber("%+.6f", -sync.offset_s) + " s (+- " +
                  FormatNumber("%.2f", sync.offset_stderr_s * 1e3) + " ms)";
  return sync;
}

TriggerFile ReadTriggerFile(const std::string& path) {
  const MappedFile mapped(path);
  const std::string_view text = mapped.text();
  if (LooksLikeMrk(text)) return ParseMrk(text, path);
  LogFormat format = LogFormat::kAuto;
  try {
    format = DetectFlightLogFormat(text.substr(0, 4096), path);
  } catch (const IoError&) {
  }
  if (format == LogFormat::kULog || format == LogFormat::kDataFlash ||
      format == LogFormat::kBlackbox) {
    return FromLog(path);
  }
  return ParseTriggerCsv(text, path);
}

}  // namespace shutterlab
