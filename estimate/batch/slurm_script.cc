#include "estimate/batch/slurm_script.h"

#include "estimate/batch/batch_plan.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

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

std::string SlurmArrayIndices(const std::vector<size_t>& indices) {
  std::string list;
  for (size_t i = 0; i < indices.size();) {
    size_t j = i;
    while (j + 1 < indices.size() && indices[j + 1] == indices[j] + 1) ++j;
    list += (list.empty() ? "" : ",") + std::to_string(indices[i]);
    if (j > i) list += "-" + std::to_string(indices[j]);
    i = j + 1;
  }
  return list;
}

SlurmBatchScripts MakeSlurmBatchScripts(const BatchManifest& manifest,
                                        const SlurmBatchOptions& options) {
  constexpr double kClassBytes = 256.0 * 1024 * 1024;
  std::map<long, SlurmArray> classes;  // by memory class
  for (size_t i = 0; i < manifest.items.size(); ++i) {
    const BatchItem& item = manifest.items[i];
    const long memory_class =
        static_cast<long>(std::ceil(EstimateBatchItemMemoryBytes(item) / kClassBytes));
    SlurmArray& array = classes[memory_class];
    array.items.push_back(i);
    array.memory_bytes = static_cast<double>(memory_class) * kClassBytes;
    array.seconds = std::max(array.seconds, SlurmTaskSeconds(item));
  }
  SlurmBatchScripts scripts;
  scripts.tasks = manifest.items.size();
  const std::string logs = options.out_dir + "/slurm";
  const std::string batch = ShellWord(options.executable) + " batch " +
                            ShellWord(options.manifest_path) + " --out " +
                            ShellWord(options.out_dir);
  for (auto& [memory_class, array] : classes) {
    if (options.time_per_task_s > 0) array.seconds = options.time_per_task_s;
    const std::string memory = std::to_string(memory_class * 256) + "M";
    array.name = classes.size() == 1 ? "batch.sbatch" : "batch_" + memory + ".sbatch";
    array.script = Header("shutterlab-batch", options, logs + "/item_%a.out") +
                   "#SBATCH --array=" + SlurmArrayIndices(array.items) + "\n" +
                   "#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1\n" + "#SBATCH --mem=" + memory +
                   "\n" + "#SBATCH --time=" + SlurmTime(array.seconds) + "\n" +
                   "#SBATCH --requeue\n"
                   "# One task per item of " +
                   options.manifest_path +
                   " (its place in it):\n"
                   "# the item's folder is made whole or not at all, so a task killed or requeued\n"
                   "# makes it again (shutterlab batch --item-index).\n"
                   "exec " +
                   batch + " --item-index \"$SLURM_ARRAY_TASK_ID\"\n";
    scripts.arrays.push_back(std::move(array));
  }
  scripts.merge_script =
      Header("shutterlab-batch-merge", options, logs + "/merge.out") +
      "#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1\n#SBATCH --mem=1024M\n"
      "#SBATCH --time=0-00:30:00\n"
      "# After every task of the arrays (afterany): the fleet's page from the items' folders.\n"
      "exec " +
      batch + " --summary-only\n";
  return scripts;
}

}  // namespace shutterlab
