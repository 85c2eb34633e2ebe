#pragma once
// Runs a manifest's items on this machine: each item's commands (batch_plan.h) one after another
// in a folder of its own, up to `parallel` items at once under a memory cap, each command a child
// process of the shutterlab executable. An item is made whole or not at all: it is made in
// OUT/items/ID.partial and swapped into OUT/items/ID with its made.json (item_record.h) only when
// it ends, so killing the batch at any moment (SIGKILL too: the commands die with it) loses only
// the items in flight, which the next run makes again. An item being made by another process (a
// Slurm task, a second batch) is locked (flock on OUT/items/.ID.lock) and skipped.

#include "estimate/batch/manifest.h"

#include <functional>
#include <string>
#include <vector>

namespace shutterlab {

enum class BatchItemStatus {
  kMade,      // every job ended well
  kFailed,    // a job failed: the item's folder holds what it wrote and why (made.json "error")
  kUpToDate,  // made before from the same inputs, options and tool: not made again
  kBusy,      // another process is making it
};
const char* BatchItemStatusName(BatchItemStatus status);

struct BatchItemOutcome {
  std::string id;
  BatchItemStatus status = BatchItemStatus::kFailed;
  std::string reason;  // why it was made ("not made yet", "an input changed: PATH", "--force")
  std::string error;   // a failed item's one line: "JOB: what the command said"
  double seconds = 0;
  double peak_memory_bytes = 0;  // the largest of its commands' peak resident memory
};

struct BatchProgress {
  size_t total = 0, made = 0, failed = 0, up_to_date = 0, busy = 0, running = 0;
  double seconds_left = 0;  // NaN until an item has been made in this run
};

struct BatchRunOptions {
  std::string executable;  // the shutterlab binary the commands run
  std::string tool;        // its version, recorded ("shutterlab 0.1")
  std::string out_dir;
  int parallel = 1;             // items at once
  double memory_cap_bytes = 0;  // the items' estimated memory together stays under it; <= 0: none
  bool force = false;           // make every item again
  std::vector<size_t> only;     // the items to run, by index (a Slurm task's); empty: all
  // Called as each item ends (and for those up to date or busy), with the counts so far.
  std::function<void(const BatchItemOutcome&, const BatchProgress&)> on_item_end;
};

// Runs the items; returns their outcomes in manifest order (those in `only`, when given). Throws
// IoError when OUT cannot be made.
std::vector<BatchItemOutcome> RunBatch(const BatchManifest& manifest,
                                       const BatchRunOptions& options);

}  // namespace shutterlab
