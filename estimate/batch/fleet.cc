#include "estimate/batch/fleet.h"

#include "estimate/report/html_report.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>

namespace shutterlab {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double NumberAt(const json& object, const char* key) {
  if (!object.is_object()) return kNaN;
  const auto at = object.find(key);
  return at != object.end() && at->is_number() ? at->get<double>() : kNaN;
}

std::string TextAt(const json& object, const char* key) {
  if (!object.is_object()) return "";
  const auto at = object.find(key);
  return at != object.end() && at->is_string() ? at->get<std::string>() : "";
}

// "5 cm": a limit as the tables say it.
std::string LimitText(double limit_m) {
  char text[32];
  std::snprintf(text, sizeof text, "%g cm", limit_m * 100);
  return text;
}

// One image's D and its flags, whatever command judged it.
struct Judged {
  std::string name;
  double d_m;
  std::map<double, bool> over;  // limit (m) -> over it
};

// The share over each limit and the worst three, from the judged images.
void Summarise(std::vector<Judged> judged, FleetRow* row) {
  judged.erase(
      std::remove_if(judged.begin(), judged.end(), [](const Judged& j) { return j.over.empty(); }),
      judged.end());
  row->judged = judged.size();
  if (judged.empty()) return;
  for (const auto& [limit, over] : judged.front().over) row->limits_m.push_back(limit);
  for (const double limit : row->limits_m) {
    size_t over = 0;
    for (const Judged& j : judged) over += j.over.count(limit) && j.over.at(limit);
    row->share_over.push_back(static_cast<double>(over) / static_cast<double>(judged.size()));
  }
  std::sort(judged.begin(), judged.end(), [](const Judged& a, const Judged& b) {
    return (std::isnan(b.d_m) ? -1 : b.d_m) < (std::isnan(a.d_m) ? -1 : a.d_m);
  });
  for (size_t i = 0; i < judged.size() && i < 3 && std::isfinite(judged[i].d_m); ++i)
    row->worst.emplace_back(judged[i].name, judged[i].d_m);
}

std::map<double, bool> Flags(const json& flagged) {
  std::map<double, bool> over;
  if (!flagged.is_object()) return over;
  for (const auto& [key, value] : flagged.items()) {
    if (!value.is_boolean()) return {};  // not judged at this limit: not judged
    over[std::strtod(key.c_str(), nullptr)] = value.get<bool>();
  }
  return over;
}

void AddWarnings(const json& warnings, FleetRow* row) {
  if (!warnings.is_array()) return;
  for (const json& w : warnings) {
    const std::string text = w.is_string() ? w.get<std::string>() : TextAt(w, "message");
    if (!text.empty()) row->warnings.push_back(text);
  }
}

// analyze LOG --json (and the analyze part of analyze --photos LOG --json).
void ReadAnalyze(const json& doc, FleetRow* row) {
  row->verdict = TextAt(doc.value("verdict", json()), "line");
  const json camera = doc.value("camera", json());
  row->readout_s = NumberAt(camera, "readout_s");
  row->readout_source = "given";
  row->camera = "from --camera";
  for (const json& assumption : doc.value("assumptions", json::array())) {
    if (TextAt(assumption, "what") == "readout") row->readout_source = "assumed";
    if (TextAt(assumption, "what") == "camera")
      row->camera = TextAt(assumption, "taken") + " (assumed)";
  }
  AddWarnings(doc.value("warnings", json()), row);
  std::vector<Judged> judged;
  for (const json& image : doc.value("images", json::array())) {
    if (!image.value("in_trace", false)) continue;
    judged.push_back({TextAt(image, "name"), NumberAt(image, "D_full_m"),
                      Flags(image.value("flagged", json()))});
  }
  Summarise(std::move(judged), row);
}

// The most common of a set of texts (a folder's camera, its readout), and how many differ.
std::string MostCommon(const std::vector<std::string>& texts) {
  std::map<std::string, size_t> counts;
  for (const std::string& text : texts) ++counts[text];
  const auto best =
      std::max_element(counts.begin(), counts.end(),
                       [](const auto& a, const auto& b) { return a.second < b.second; });
  if (best == counts.end()) return "";
  return best->first +
         (counts.size() > 1 ? " (and " + std::to_string(counts.size() - 1) + " other)" : "");
}

// analyze --photos --json's photos object.
void ReadPhotos(const json& photos, FleetRow* row) {
  if (row->verdict.empty()) row->verdict = TextAt(photos.value("summary", json()), "line");
  std::vector<std::string> cameras, readouts;
  std::map<std::string, size_t> missing;
  std::vector<Judged> judged;
  size_t unreadable = 0;
  for (const json& p : photos.value("photos", json::array())) {
    if (p.contains("error")) {
      ++unreadable;
      continue;
    }
    cameras.push_back(TextAt(p, "make") + " " + TextAt(p, "model"));
    const double readout_s = NumberAt(p, "readout_s");
    readouts.push_back(std::isfinite(readout_s) ? QuantityText(readout_s * 1e3, "ms") + " from " +
                                                      TextAt(p, "readout_origin")
                                                : "none");
    for (const json& m : p.value("missing", json::array()))
      if (m.is_string()) ++missing[m.get<std::string>()];
    const double rotation_m = NumberAt(p, "D_rotation_m");
    const double translation_m = NumberAt(p, "D_translation_m");
    judged.push_back({TextAt(p, "name"),
                      (std::isfinite(rotation_m) ? rotation_m : 0) + translation_m,
                      Flags(p.value("flagged", json()))});
  }
  row->camera = MostCommon(cameras);
  row->readout_source = MostCommon(readouts);
  if (!readouts.empty()) row->readout_s = kNaN;
  if (unreadable) row->warnings.push_back(std::to_string(unreadable) + " photos could not be read");
  for (const auto& [what, count] : missing)
    row->warnings.push_back(std::to_string(count) + " photos without " + what);
  Summarise(std::move(judged), row);
}

void ReadValidate(const json& report, FleetRow* row) {
  const json verdict = report.value("verdict", json());
  row->verdict = TextAt(verdict, "level") + ": " + TextAt(verdict, "headline");
  row->judged = report.value("frames", size_t{0});
  AddWarnings(report.value("warnings", json()), row);
}

FleetRow ReadRow(const BatchItem& item, const fs::path& out) {
  FleetRow row;
  row.id = item.id;
  row.group = item.group;
  row.readout_s = kNaN;
  row.has_gyro = !item.log.empty() || !item.clip.empty() || !item.dataset.empty();
  row.input = !item.clip.empty()      ? "clip"
              : !item.dataset.empty() ? "dataset"
              : !item.photos.empty()  ? (item.log.empty() ? "photos" : "photos + log")
                                      : "log";
  const fs::path dir = out / "items" / item.id;
  json record;
  try {
    record = json::parse(ReadFileToString((dir / "made.json").string()));
  } catch (const std::exception&) {
    row.status = "not made";
    return row;
  }
  row.status = TextAt(record, "status");
  row.error = TextAt(record, "error");
  if (row.status != "done") return row;  // what its jobs wrote may be half: not read
  const auto read = [&](const char* file, auto reader) {
    const fs::path path = dir / file;
    if (!fs::exists(path)) return false;
    try {
      reader(json::parse(ReadFileToString(path.string())));
    } catch (const std::exception& e) {
      row.warnings.push_back(std::string(file) +
                             " could not be read: " + WithoutCheckLocation(e.what()));
    }
    return true;
  };
  const auto link = [&](const char* page) {
    if (row.report.empty() && fs::exists(dir / page))
      row.report = (fs::path("items") / item.id / page).string();
  };
  read("validate/report.json", [&](const json& j) { ReadValidate(j, &row); });
  read("analyze/analyze.json", [&](const json& j) { ReadAnalyze(j, &row); });
  read("photos/photos.json", [&](const json& j) {
    if (j.contains("images")) ReadAnalyze(j, &row);  // with a log: analyze's, photos within
    row.limits_m.clear(), row.share_over.clear(), row.worst.clear();
    ReadPhotos(j.contains("images") ? j.value("photos", json()) : j, &row);
  });
  link("photos/report.html");
  link("analyze/report.html");
  link("validate/validate.html");
  return row;
}

}  // namespace

std::vector<FleetRow> ReadFleet(const BatchManifest& manifest, const std::string& out_dir) {
  std::vector<FleetRow> rows;
  for (const BatchItem& item : manifest.items) rows.push_back(ReadRow(item, out_dir));
  return rows;
}

namespace {

// The share over the largest limit, -1 when not judged: the order of the "first" list.
double WorstShare(const FleetRow& row) {
  return row.share_over.empty() ? -1 : row.share_over.back();
}

std::string Percent(double share) {
  char text[16];
  std::snprintf(text, sizeof text, "%.0f%%", share * 100);
  return text;
}

// The largest share over the largest limit of any item: whether the page needs attention.
double WorstShareOfAll(const std::vector<FleetRow>& rows) {
  double worst = -1;
  for (const FleetRow& row : rows) worst = std::max(worst, WorstShare(row));
  return worst;
}

}  // namespace

std::vector<std::string> FleetAdvice(const std::vector<FleetRow>& rows) {
  std::vector<const FleetRow*> ranked;
  for (const FleetRow& row : rows)
    if (row.status == "done" && WorstShare(row) > 0) ranked.push_back(&row);
  std::stable_sort(ranked.begin(), ranked.end(), [](const FleetRow* a, const FleetRow* b) {
    return WorstShare(*a) > WorstShare(*b);
  });
  std::vector<std::string> advice;
  for (size_t i = 0; i < ranked.size() && i < 5; ++i) {
    const FleetRow& row = *ranked[i];
    std::string line = row.id + ": " + Percent(WorstShare(row)) + " of its " +
                       std::to_string(row.judged) + " images over " +
                       LimitText(row.limits_m.back());
    if (!row.worst.empty()) {
      line += " (worst " + row.worst.front().first + ", " +
              QuantityText(std::round(row.worst.front().second * 1000) / 10, "cm") + ")";
    }
    line += row.has_gyro
                ? ": correct its images first (its gyro gives the rotation part: shutterlab "
                  "correct)"
                : ": no gyro log, so only the translation part can be corrected (ODM's "
                  "--rolling-shutter does that); fly it again slower or higher if that is not "
                  "enough";
    advice.push_back(line);
  }
  size_t failed = 0;
  for (const FleetRow& row : rows) failed += row.status == "failed";
  if (failed) {
    advice.push_back(std::to_string(failed) +
                     " item(s) failed: their lines are in the table below; fix the input and run "
                     "the batch again (it makes only what failed or changed)");
  }
  if (advice.empty()) advice.push_back("no item has images over its limits");
  return advice;
}

namespace {

// RFC 4180: a field with a comma, quote or line break is quoted, its quotes doubled.
std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// Every limit any row was judged at, ascending: the table's columns.
std::vector<double> AllLimits(const std::vector<FleetRow>& rows) {
  std::vector<double> limits;
  for (const FleetRow& row : rows)
    limits.insert(limits.end(), row.limits_m.begin(), row.limits_m.end());
  std::sort(limits.begin(), limits.end());
  limits.erase(std::unique(limits.begin(), limits.end()), limits.end());
  return limits;
}

double ShareAt(const FleetRow& row, double limit_m) {
  for (size_t i = 0; i < row.limits_m.size() && i < row.share_over.size(); ++i)
    if (row.limits_m[i] == limit_m) return row.share_over[i];
  return kNaN;
}

std::string WorstText(const FleetRow& row) {
  std::string text;
  for (const auto& [name, d_m] : row.worst)
    text +=
        (text.empty() ? "" : "; ") + name + " " + QuantityText(std::round(d_m * 1000) / 10, "cm");
  return text;
}

std::string ReadoutText(const FleetRow& row) {
  if (std::isnan(row.readout_s)) return row.readout_source;
  return QuantityText(row.readout_s * 1e3, "ms") + " (" + row.readout_source + ")";
}

std::string FleetCsv(const std::vector<FleetRow>& rows, const std::vector<double>& limits) {
  std::string csv = "id,group,input,status,judged";
  for (const double limit : limits) {
    char name[48];
    std::snprintf(name, sizeof name, ",over_%gcm_percent", limit * 100);
    csv += name;
  }
  csv += ",worst,readout,camera,warnings,verdict,error,report\n";
  for (const FleetRow& row : rows) {
    csv += CsvField(row.id) + "," + CsvField(row.group) + "," + CsvField(row.input) + "," +
           row.status + "," + std::to_string(row.judged);
    for (const double limit : limits) {
      const double share = ShareAt(row, limit);
      csv += "," +
             (std::isnan(share) ? std::string() : QuantityText(std::round(share * 1000) / 10, ""));
    }
    std::string warnings;
    for (const std::string& w : row.warnings) warnings += (warnings.empty() ? "" : "; ") + w;
    csv += "," + CsvField(WorstText(row)) + "," + CsvField(ReadoutText(row)) + "," +
           CsvField(row.camera) + "," + CsvField(warnings) + "," + CsvField(row.verdict) + "," +
           CsvField(row.error) + "," + CsvField(row.report) + "\n";
  }
  return csv;
}

// Per group: its flights, and the least, median and largest share over each limit.
void AddGroupTable(const std::vector<FleetRow>& rows, const std::vector<double>& limits,
                   HtmlPage* page) {
  std::map<std::string, std::vector<const FleetRow*>> groups;
  for (const FleetRow& row : rows)
    groups[row.group.empty() ? "(no group)" : row.group].push_back(&row);
  std::vector<std::string> header = {"group", "items", "items judged"};
  for (const double limit : limits)
    header.push_back("over " + LimitText(limit) + ": least / median / most");
  std::vector<std::vector<std::string>> table;
  for (const auto& [group, members] : groups) {
    size_t judged = 0;
    for (const FleetRow* row : members) judged += row->judged > 0;
    std::vector<std::string> cells = {group, std::to_string(members.size()),
                                      std::to_string(judged)};
    for (const double limit : limits) {
      std::vector<double> shares;
      for (const FleetRow* row : members)
        if (!std::isnan(ShareAt(*row, limit))) shares.push_back(ShareAt(*row, limit));
      if (shares.empty()) {
        cells.push_back("");
        continue;
      }
      const auto [least, most] = std::minmax_element(shares.begin(), shares.end());
      cells.push_back(Percent(*least) + " / " + Percent(Median(shares)) + " / " + Percent(*most));
    }
    table.push_back(std::move(cells));
  }
  page->Heading("By group (drone or camera)");
  page->Table(header, table);
}

void AddItemTable(const std::vector<FleetRow>& rows, const std::vector<double>& limits,
                  HtmlPage* page) {
  std::vector<const FleetRow*> order;
  for (const FleetRow& row : rows) order.push_back(&row);
  std::stable_sort(order.begin(), order.end(), [](const FleetRow* a, const FleetRow* b) {
    return WorstShare(*a) > WorstShare(*b);
  });
  std::vector<std::string> header = {"item", "group", "input", "status", "judged"};
  for (const double limit : limits) header.push_back("over " + LimitText(limit));
  header.insert(header.end(),
                {"worst", "readout", "camera", "warnings", "verdict or error", "report"});
  std::vector<std::vector<std::string>> table;
  for (const FleetRow* row : order) {
    std::vector<std::string> cells = {row->id, row->group, row->input, row->status,
                                      std::to_string(row->judged)};
    for (const double limit : limits) {
      const double share = ShareAt(*row, limit);
      cells.push_back(std::isnan(share) ? "" : Percent(share));
    }
    std::string warnings;
    for (const std::string& w : row->warnings) warnings += (warnings.empty() ? "" : "; ") + w;
    cells.insert(cells.end(), {WorstText(*row), ReadoutText(*row), row->camera, warnings,
                               row->error.empty() ? row->verdict : row->error, row->report});
    table.push_back(std::move(cells));
  }
  page->Heading("Items, the most over the largest limit first");
  page->Table(header, table, true);
}

// Each judged item's share over each limit, items ranked by the largest limit's share.
void AddShareChart(const std::vector<FleetRow>& rows, const std::vector<double>& limits,
                   HtmlPage* page) {
  std::vector<const FleetRow*> judged;
  for (const FleetRow& row : rows)
    if (!row.share_over.empty()) judged.push_back(&row);
  if (judged.empty() || limits.empty()) return;
  std::stable_sort(judged.begin(), judged.end(), [](const FleetRow* a, const FleetRow* b) {
    return WorstShare(*a) > WorstShare(*b);
  });
  Chart chart;
  chart.title = "Share of each item's images over each limit";
  chart.x_label = "item, ranked (1 = the most over the largest limit)";
  chart.y_label = "images over the limit (%)";
  chart.kind = ChartKind::kPoints;
  chart.integer_x = true;
  chart.clip_outliers = false;
  for (size_t i = 0; i < judged.size(); ++i) chart.x.push_back(static_cast<double>(i + 1));
  for (const double limit : limits) {
    std::vector<double> y;
    for (const FleetRow* row : judged) y.push_back(ShareAt(*row, limit) * 100);
    chart.series.emplace_back("over " + LimitText(limit), std::move(y));
  }
  page->AddChart(chart);
}

}  // namespace

std::vector<std::string> WriteFleetSummary(const std::vector<FleetRow>& rows,
                                           const std::string& out_dir) {
  const std::vector<double> limits = AllLimits(rows);
  std::map<std::string, size_t> by_status;
  for (const FleetRow& row : rows) ++by_status[row.status];
  std::string counts;
  for (const auto& [status, count] : by_status)
    counts += (counts.empty() ? "" : ", ") + std::to_string(count) + " " + status;

  HtmlPage page("Fleet: " + std::to_string(rows.size()) + " items");
  const bool problem = by_status.count("failed") > 0;
  const std::vector<std::string> advice = FleetAdvice(rows);
  page.BeginBox(problem ? "problem" : WorstShareOfAll(rows) > 0 ? "attention" : "ok");
  page.Paragraph(std::to_string(rows.size()) + " items: " + counts + ". First:");
  page.List(advice);
  page.EndBox();
  AddShareChart(rows, limits, &page);
  AddGroupTable(rows, limits, &page);
  AddItemTable(rows, limits, &page);
  std::string links;
  for (const FleetRow& row : rows) {
    if (!row.report.empty())
      links += "<li><a href=\"" + EscapeHtml(row.report) + "\">" + EscapeHtml(row.id) + "</a></li>";
  }
  if (!links.empty()) {
    page.Heading("Each item's own page");
    page.RawHtml("<ul>" + links + "</ul>");
  }
  page.Paragraph(
      "Each item's folder is items/ID: made.json says what made it (inputs, options, "
      "tool) and how each job ended; logs/ holds each command's own output.");
  const std::string csv_path = (fs::path(out_dir) / "fleet.csv").string();
  const std::string html_path = (fs::path(out_dir) / "fleet.html").string();
  WriteFileAtomically(csv_path, FleetCsv(rows, limits));
  page.Write(html_path);
  return {csv_path, html_path};
}

}  // namespace shutterlab
