#pragma once
// A batch on a Slurm cluster: one job array, one task per manifest item (`shutterlab batch
// MANIFEST --out DIR --item-index $SLURM_ARRAY_TASK_ID`), each making its item in the same
// resumable folder the local runner uses (batch_run.h) on a filesystem every node sees, and a
// merge job, dependent on the whole array (afterany), that writes the fleet's page. Slurm
// schedules, requeues (--requeue: a task killed with its node is run again and remakes its item)
// and accounts; nothing here schedules.

#include "estimate/batch/manifest.h"

#include <string>

namespace shutterlab {

struct SlurmBatchOptions {
  std::string executable;      // absolute: the shutterlab binary every node runs
  std::string manifest_path;   // absolute
  std::string out_dir;         // absolute, on a shared filesystem
  std::string partition;       // empty: the cluster's default
  double time_per_task_s = 0;  // 0: from the largest item (SlurmTaskSeconds)
};

struct SlurmBatchScripts {
  std::string array_script;  // sbatch --array
  std::string merge_script;  // sbatch --dependency=afterany:ARRAY
  double memory_per_task_bytes = 0;
  double seconds_per_task = 0;
  size_t tasks = 0;
};

// The two scripts. Every task asks for the largest item's memory estimate
// (EstimateBatchItemMemoryBytes) and time: one array holds one request.
SlurmBatchScripts MakeSlurmBatchScripts(const BatchManifest& manifest,
                                        const SlurmBatchOptions& options);

// A task's time limit from its item's inputs: 2 min, and 1 min per 200 MB read, times 3 for a
// slow node; a whole number of minutes.
double SlurmTaskSeconds(const BatchItem& item);

}  // namespace shutterlab
