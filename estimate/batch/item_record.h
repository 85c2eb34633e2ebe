#pragma once
// What made a batch item (its folder's made.json, docs/FORMATS.md "Batch output"): the commands,
// the tool, every input file's size, modification time and content hash, and how each job ended.
// A rerun compares it with what the item would be made from now and redoes the item only when
// something differs or it failed.

#include "estimate/batch/batch_plan.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab {

struct InputFileStamp {
  std::string path;  // absolute
  uint64_t bytes = 0;
  int64_t mtime_ns = 0;
  std::string xxh3;  // XXH3-64 of the content, 16 hex digits
};

// The stamps of `files`. A file whose path, size and modification time equal a stamp in
// `previous` keeps that stamp's hash (as git's index and make trust them), so a rerun reads only
// what changed; every other file is hashed. Throws IoError naming a file that cannot be read.
std::vector<InputFileStamp> StampInputFiles(const std::vector<std::string>& files,
                                            const std::vector<InputFileStamp>& previous = {});

// XXH3-64 of a file's content as 16 hex digits. Throws IoError.
std::string FileXxh3(const std::string& path);

// The part of an item's record that decides whether it must be made again: the tool and the
// commands (with every option).
nlohmann::json BatchItemRecipe(const std::vector<PlannedCommand>& plan, const std::string& tool);

nlohmann::json InputStampsJson(const std::vector<InputFileStamp>& stamps);
// The stamps of a made.json; empty when it holds none or is not one.
std::vector<InputFileStamp> InputStampsFromRecord(const nlohmann::json& record);

// Why an item must be made again ("" when its record says it is up to date): no record, it failed,
// the tool or a command changed, an input was added, removed or changed (named).
std::string BatchItemStaleReason(const nlohmann::json& record, const nlohmann::json& recipe,
                                 const std::vector<InputFileStamp>& inputs);

}  // namespace shutterlab
