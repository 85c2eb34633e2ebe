#pragma once
// Reads back what estimate/report/html_report.h embeds in a page, for the report tests.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace shutterlab::test {

// The JSON blocks of the page's charts, in page order, parsed.
inline std::vector<nlohmann::json> ChartBlocks(const std::string& html) {
  std::vector<nlohmann::json> blocks;
  const std::string open = "class=\"chart-data\"";
  for (size_t at = html.find(open); at != std::string::npos; at = html.find(open, at + 1)) {
    const size_t begin = html.find('>', at) + 1;
    const size_t end = html.find("</script>", begin);
    blocks.push_back(nlohmann::json::parse(html.substr(begin, end - begin)));
  }
  return blocks;
}

// True when the page loads nothing from outside: no src/href to a URL, no CSS url() or @import.
inline bool SelfContained(const std::string& html) {
  for (const char* bad : {"src=\"http", "src='http", "href=\"http", "href='http", "src=\"//",
                          "href=\"//", "url(http", "url(//", "@import"}) {
    if (html.find(bad) != std::string::npos) return false;
  }
  return true;
}

}  // namespace shutterlab::test
