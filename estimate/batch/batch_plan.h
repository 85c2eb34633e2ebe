#pragma once
// What a batch item runs: each job as a shutterlab command line, run in the item's own folder so
// that its outputs are relative names there and the same item plans the same commands wherever
// its folder lies (the recipe a rerun compares).

#include "estimate/batch/manifest.h"

#include <string>
#include <vector>

namespace shutterlab {

struct PlannedCommand {
  BatchJob job;
  std::string name;               // "photos", "export colmap": the job as said in progress lines
  std::vector<std::string> args;  // after the executable
  std::string stdout_path;        // relative to the item's folder; empty: into the log
  std::string log_path;           // relative: the command's stderr (and stdout when not captured)
};

// The commands of an item's jobs, in order. Inputs are absolute; outputs relative to the item's
// folder: dataset/ (a clip's import), analyze/, photos/, validate/, correct/, export_FORMAT/,
// logs/JOB.log.
std::vector<PlannedCommand> PlanBatchItem(const BatchItem& item);

// The memory one of the item's commands may take at most, in bytes, from its largest input file and
// its jobs: what the local runner keeps under its cap and what a Slurm task asks for. Measured
// peaks are in docs/batch.md.
double EstimateBatchItemMemoryBytes(const BatchItem& item);

}  // namespace shutterlab
