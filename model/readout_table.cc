#include "model/readout_table.h"

#include "sim/text_file.h"

#include <array>
#include <cstdio>
#include <limits>

namespace shutterlab {
namespace {

constexpr double kAny = std::numeric_limits<double>::infinity();

struct Row {
  const char* key;
  double readout_ms;
  double min_megapixels, max_megapixels;  // the photo mode: min <= MP < max
  const char* camera;
};

// OpenDroneMap RS_DATABASE (see the header for the commit and licence), one row per value.
constexpr std::array<Row, 35> kRows{{
    {"autel robotics xt701", 25, 0, kAny, "Autel EVO II 8K"},
    {"dji phantom vision fc200", 74, 0, kAny, "Phantom 2"},
    {"dji fc300s", 33, 0, kAny, "Phantom 3 Advanced"},
    {"dji fc300c", 33, 0, kAny, "Phantom 3 Standard"},
    {"dji fc300x", 33, 0, kAny, "Phantom 3 Professional"},
    {"dji fc330", 33, 0, kAny, "Phantom 4"},
    {"dji fc6310", 33, 0, kAny, "Phantom 4 Professional"},
    {"dji fc7203", 19, 0, 10, "Mavic Mini"},
    {"dji fc7203", 25, 10, kAny, "Mavic Mini"},
    {"dji fc2103", 32, 0, kAny, "Mavic Air"},
    {"dji fc3170", 27, 0, kAny, "Mavic Air 2"},
    {"dji fc3411", 32, 0, kAny, "Air 2S"},
    {"dji fc220", 64, 0, kAny, "Mavic Pro"},
    {"hasselblad l1d-20c", 47, 0, 17, "Mavic 2 Pro"},
    {"hasselblad l1d-20c", 56, 17, kAny, "Mavic 2 Pro"},
    {"hasselblad l2d-20c", 16.6, 0, kAny, "Mavic 3"},
    {"dji fc3682", 23, 0, kAny, "Mini 3"},
    {"dji fc3582", 26, 0, 48, "Mini 3 Pro"},
    {"dji fc3582", 60, 48, kAny, "Mini 3 Pro"},
    {"dji fc8482", 16, 0, 12, "Mini 4 Pro"},
    {"dji fc8482", 21, 12, 20, "Mini 4 Pro"},
    {"dji fc8482", 43, 20, 45, "Mini 4 Pro"},
    {"dji fc8482", 58, 45, kAny, "Mini 4 Pro"},
    {"dji fc350", 30, 0, kAny, "Inspire 1 (Zenmuse X3)"},
    {"dji mavic2-enterprise-advanced", 31, 0, kAny, "Mavic 2 Enterprise Advanced"},
    {"dji zenmuse z30", 8, 0, kAny, "Zenmuse Z30"},
    {"yuneec e90", 44, 0, kAny, "Yuneec E90"},
    {"gopro hero4 black", 30, 0, kAny, "GoPro HERO4 Black"},
    {"gopro hero8 black", 17, 0, kAny, "GoPro HERO8 Black"},
    {"teracube teracube one", 32, 0, kAny, "Teracube One"},
    {"fujifilm x-a5", 186, 0, kAny, "Fujifilm X-A5 (electronic shutter)"},
    {"fujifilm x-t2", 35, 0, kAny, "Fujifilm X-T2 (electronic shutter)"},
    {"autel robotics xl724", 29, 0, kAny, "Autel EVO Nano+"},
    {"parrot anafi", 39, 0, kAny, "Parrot Anafi"},
    {"autel robotics xt705", 30, 0, kAny, "Autel EVO II Pro"},
}};

std::string Trimmed(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && (s[a] == ' ' || s[a] == '\0')) ++a;
  while (b > a && (s[b - 1] == ' ' || s[b - 1] == '\0')) --b;
  return s.substr(a, b - a);
}

std::string ConditionText(const Row& row) {
  if (row.min_megapixels <= 0 && row.max_megapixels == kAny) return "";
  if (row.min_megapixels <= 0) return FormatNumber("< %g MP", row.max_megapixels);
  if (row.max_megapixels == kAny) return FormatNumber(">= %g MP", row.min_megapixels);
  return FormatNumber("%g", row.min_megapixels) + FormatNumber("-%g MP", row.max_megapixels);
}

}  // namespace

std::string ReadoutLookup::Citation() const {
  return "table: " + key + " (" + camera + ") " + FormatNumber("%g ms", readout_s * 1e3) +
         (condition.empty() ? "" : " for " + condition) +
         ", OpenDroneMap's rolling-shutter database (community-measured)";
}

std::string ReadoutTableKey(const std::string& make, const std::string& model) {
  return ToLower(Trimmed(make) + " " + Trimmed(model));
}

std::optional<ReadoutLookup> LookUpReadout(const std::string& make, const std::string& model,
                                           double megapixels) {
  const std::string key = ReadoutTableKey(make, model);
  for (const Row& row : kRows) {
    if (key != row.key || megapixels < row.min_megapixels || megapixels >= row.max_megapixels)
      continue;
    return ReadoutLookup{row.readout_ms * 1e-3, row.key, row.camera, ConditionText(row)};
  }
  return std::nullopt;
}

size_t ReadoutTableRows() { return kRows.size(); }

}  // namespace shutterlab
