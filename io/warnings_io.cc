#include "io/warnings_io.h"

#include <nlohmann/json.hpp>

namespace shutterlab {

nlohmann::json WarningsToJson(const std::vector<LogWarning>& warnings) {
  nlohmann::json json = nlohmann::json::array();
  for (const LogWarning& w : warnings) {
    nlohmann::json item = {{"kind", w.kind}, {"message", w.message}};
    if (w.t_s) item["t_s"] = *w.t_s;
    if (w.count) item["count"] = *w.count;
    json.push_back(std::move(item));
  }
  return json;
}

}  // namespace shutterlab
