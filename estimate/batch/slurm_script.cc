#include "estimate/batch/slurm_script.h"

#include "estimate/batch/batch_plan.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace shutterlab {
namespace {

// A word for a bash script: single-quoted, its own single quotes closed and escaped.
std::string ShellWord(const std::string& text) {
  std::string quoted = "'";
  for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// Slurm's time format, D-HH:MM:SS.
std::string SlurmTime(double seconds) {
  const long total = static_cast<long>(std::ceil(seconds));
  char text[32];
  std::snprintf(text, sizeof text, "%ld-%02ld:%02ld:%02ld", total / 86400, total / 3600 % 24,
                total / 60 % 60, total % 60);
  return text;
}

std::string Header(const std::string& name, const SlurmBatchOptions& options,
                   const std::string& output) {
  std::string header = "#!/bin/bash\n#SBATCH --job-name=" + name + "\n";
  if (!options.partition.empty()) header += "#SBATCH --partition=" + options.partition + "\n";
  header += "#SBATCH --output=" + output + "\n";
  return header;
}

}  // namespace

double SlurmTaskSeconds(const BatchItem& item) {
  double bytes = 0;
  for (const std::string& file : BatchItemInputFiles(item)) {
    std::error_code error;
    const auto size = std::filesystem::file_size(file, error);
    if (!error) bytes += static_cast<double>(size);
  }
  return std::ceil(3 * (120 + 60 * bytes / 200e6) / 60) * 60;
}

SlurmBatchScripts MakeSlurmBatchScripts(const BatchManifest& manifest,
                                        const SlurmBatchOptions& options) {
  SlurmBatchScripts scripts;
  scripts.tasks = manifest.items.size();
  for (const BatchItem& item : manifest.items) {
    scripts.memory_per_task_bytes =
        std::max(scripts.memory_per_task_bytes, EstimateBatchItemMemoryBytes(item));
    scripts.seconds_per_task = std::max(scripts.seconds_per_task, SlurmTaskSeconds(item));
  }
  if (options.time_per_task_s > 0) scripts.seconds_per_task = options.time_per_task_s;
  const std::string logs = options.out_dir + "/slurm";
  const std::string batch = ShellWord(options.executable) + " batch " +
                            ShellWord(options.manifest_path) + " --out " +
                            ShellWord(options.out_dir);
  const long memory_mib = static_cast<long>(std::ceil(scripts.memory_per_task_bytes / 1048576.0));
  scripts.array_script =
      Header("shutterlab-batch", options, logs + "/item_%a.out") + "#SBATCH --array=0-" +
      std::to_string(scripts.tasks - 1) + "\n" + "#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1\n" +
      "#SBATCH --mem=" + std::to_string(memory_mib) + "M\n" +
      "#SBATCH --time=" + SlurmTime(scripts.seconds_per_task) + "\n" +
      "#SBATCH --requeue\n"
      "# One task per item of " +
      options.manifest_path +
      ": the item's folder is made whole or\n"
      "# not at all, so a task killed or requeued makes it again (shutterlab batch --item-index).\n"
      "exec " +
      batch + " --item-index \"$SLURM_ARRAY_TASK_ID\"\n";
  scripts.merge_script =
      Header("shutterlab-batch-merge", options, logs + "/merge.out") +
      "#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1\n#SBATCH --mem=1024M\n"
      "#SBATCH --time=0-00:30:00\n"
      "# After every task of the array (afterany): the fleet's page from the items' folders.\n"
      "exec " +
      batch + " --summary-only\n";
  return scripts;
}

}  // namespace shutterlab
