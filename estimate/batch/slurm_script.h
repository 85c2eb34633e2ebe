#pragma once
// A batch on a Slurm cluster: one job array, one task per manifest item (`shutterlab batch
// MANIFEST --out DIR --item-index $SLURM_ARRAY_TASK_ID`), each making its item in the same
// resumable folder the local runner uses (batch_run.h) on a filesystem every node sees, and a
// merge job, dependent on the whole array (afterany), that writes the fleet's page. Slurm
// schedules, requeues (--requeue: a task killed with its node is run again and remakes its item)
// and accounts; nothing here schedules.

#include "estimate/batch/manifest.h"

#include <string>
#include <vector>

namespace shutterlab {

struct SlurmBatchOptions {
  std::string executable;      // absolute: the shutterlab binary every node runs
  std::string manifest_path;   // absolute
  std::string out_dir;         // absolute, on a shared filesystem
  std::string partition;       // empty: the cluster's default
  double time_per_task_s = 0;  // 0: from the largest item (SlurmTaskSeconds)
};

// One job array: the items of one memory class (their estimates rounded up to 256 MiB), each
// task asking for that class's memory and the longest of its items' times.
struct SlurmArray {
  std::string name;           // the script's file name: batch.sbatch, or batch_768M.sbatch when the
                              // manifest's items fall in several classes
  std::string script;         // sbatch --array=INDICES
  std::vector<size_t> items;  // manifest indices, ascending
  double memory_bytes = 0;
  double seconds = 0;
};

struct SlurmBatchScripts {
  std::vector<SlurmArray> arrays;  // by memory, ascending
  std::string merge_script;        // sbatch --dependency=afterany:EVERY_ARRAY
  size_t tasks = 0;
};

// The scripts: one array per memory class (EstimateBatchItemMemoryBytes), so that a large
// item's request does not hold back a small one's, and the merge.
SlurmBatchScripts MakeSlurmBatchScripts(const BatchManifest& manifest,
                                        const SlurmBatchOptions& options);

// Slurm's --array list of indices: "0-3,7,9-11".
std::string SlurmArrayIndices(const std::vector<size_t>& indices);

// A task's time limit from its item's inputs: 2 min, and 1 min per 200 MB read, times 3 for a
// slow node; a whole number of minutes.
double SlurmTaskSeconds(const BatchItem& item);

}  // namespace shutterlab
