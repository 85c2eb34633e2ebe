// `shutterlab batch MANIFEST --out DIR`: every flight, clip and dataset of a manifest through its
// jobs, in parallel on this machine, resumable; then DIR/fleet.html and fleet.csv
// (estimate/batch/).

#include "app/command.h"
#include "estimate/batch/batch_run.h"
#include "estimate/batch/fleet.h"
#include "estimate/batch/manifest.h"
#include "estimate/batch/manifest_scan.h"
#include "estimate/batch/slurm_script.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <unistd.h>

namespace shutterlab::app {
namespace {

struct BatchCommand {
  std::string manifest_path, out_dir, scan_dir;
  int parallel = 0;
  double memory_cap_bytes = 0;
  bool force = false, json = false;
  // A cluster: write (and unless dry_run submit) the Slurm array; a task runs one item.
  bool slurm = false, dry_run = false, summary_only = false;
  std::string slurm_partition;
  double slurm_time_s = 0;
  int item_index = -1;
};

std::string ThisExecutable() {
  char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof path - 1);
  if (n <= 0) throw std::runtime_error("batch: cannot find its own executable (/proc/self/exe)");
  return std::string(path, static_cast<size_t>(n));
}

double PhysicalMemoryBytes() {
  return static_cast<double>(::sysconf(_SC_PHYS_PAGES)) *
         static_cast<double>(::sysconf(_SC_PAGESIZE));
}

std::string MiB(double bytes) { return FormatNumber("%.0f", bytes / 1048576.0) + " MiB"; }

// One line per item that was made or failed, as it ends (stderr: stdout may be --json).
void SayItemEnd(const BatchItemOutcome& item, const BatchProgress& p) {
  if (item.status == BatchItemStatus::kUpToDate) return;
  const size_t ended = p.made + p.failed + p.up_to_date + p.busy;
  std::string line =
      "batch: [" + std::to_string(ended) + "/" + std::to_string(p.total) + "] " + item.id + " ";
  switch (item.status) {
    case BatchItemStatus::kMade:
      line += "made in " + FormatNumber("%.1f", item.seconds) + " s (peak " +
              MiB(item.peak_memory_bytes) + "; " + item.reason + ")";
      break;
    case BatchItemStatus::kFailed:
      line += "failed: " + item.error;
      break;
    default:
      line += BatchItemStatusName(item.status) + std::string(": ") + item.reason;
  }
  line += "; " + std::to_string(p.failed) + " failed, " + std::to_string(p.running) + " running";
  if (std::isfinite(p.seconds_left) && p.running + (p.total - ended) > 0)
    line += ", about " + FormatNumber("%.0f", p.seconds_left) + " s left";
  std::cerr << line << "\n";
}

nlohmann::json OutcomesJson(const std::vector<BatchItemOutcome>& outcomes) {
  nlohmann::json items = nlohmann::json::array();
  for (const BatchItemOutcome& o : outcomes) {
    items.push_back({{"id", o.id},
                     {"status", BatchItemStatusName(o.status)},
                     {"reason", o.reason},
                     {"error", o.error},
                     {"seconds", o.seconds},
                     {"peak_memory_mib", o.peak_memory_bytes / 1048576.0}});
  }
  return items;
}

// Runs a command line of the cluster's tools (sbatch) and returns its standard output; a tool that
// is missing or refuses is one line naming it.
std::string RunSlurmTool(const std::string& command) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) throw IoError("batch --slurm: cannot run " + command);
  std::string output;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int status = ::pclose(pipe);
  while (!output.empty() && output.back() == '\n') output.pop_back();
  if (status != 0) {
    throw IoError("batch --slurm: '" + command + "' failed: " +
                  (output.empty() ? "is Slurm installed (sbatch on PATH)?" : output));
  }
  return output;
}

// Writes OUT/slurm/batch.sbatch (one array per memory class: batch_768M.sbatch, ...) and
// merge.sbatch and, unless --dry-run, submits them: the arrays, then the merge after them all.
void RunOnSlurm(const BatchManifest& manifest, const BatchCommand& command) {
  namespace fs = std::filesystem;
  SlurmBatchOptions options;
  options.executable = ThisExecutable();
  options.manifest_path = fs::absolute(command.manifest_path).string();
  options.out_dir = fs::absolute(command.out_dir).lexically_normal().string();
  options.partition = command.slurm_partition;
  options.time_per_task_s = command.slurm_time_s;
  const SlurmBatchScripts scripts = MakeSlurmBatchScripts(manifest, options);
  const std::string folder = options.out_dir + "/slurm";
  fs::create_directories(folder);
  std::vector<std::string> written;
  for (const SlurmArray& array : scripts.arrays) {
    written.push_back(folder + "/" + array.name);
    WriteFileAtomically(written.back(), array.script);
    std::cout << "slurm: " << array.name << ": " << array.items.size() << " tasks, each "
              << MiB(array.memory_bytes) << " and " << FormatNumber("%.0f", array.seconds / 60)
              << " min at most\n";
  }
  const std::string merge_path = folder + "/merge.sbatch";
  WriteFileAtomically(merge_path, scripts.merge_script);
  written.push_back(merge_path);
  SayWritten(folder, written);
  if (command.dry_run) {
    std::cout << "not submitted (--dry-run): sbatch --parsable each array, then sbatch "
                 "--dependency=afterany:ARRAY_JOB_IDS "
              << merge_path << "\n";
    return;
  }
  std::string array_ids;
  for (size_t i = 0; i + 1 < written.size(); ++i) {
    const std::string job = RunSlurmTool("sbatch --parsable '" + written[i] + "'");
    array_ids += ":" + job.substr(0, job.find(';'));
  }
  const std::string merge_job =
      RunSlurmTool("sbatch --parsable --dependency=afterany" + array_ids + " '" + merge_path + "'");
  std::cout << "submitted: array job" << (scripts.arrays.size() > 1 ? "s " : " ")
            << array_ids.substr(1) << " (" << scripts.tasks << " tasks), merge job "
            << merge_job.substr(0, merge_job.find(';')) << " writes " << options.out_dir
            << "/fleet.html after " << (scripts.arrays.size() > 1 ? "them" : "it") << "\n";
}

// The fleet's page from the items' folders as they are (the merge job's, or any time).
void WriteSummary(const BatchManifest& manifest, const BatchCommand& command) {
  const std::vector<FleetRow> rows = ReadFleet(manifest, command.out_dir);
  const std::vector<std::string> written = WriteFleetSummary(rows, command.out_dir);
  if (!command.json) {
    std::cout << "first:\n";
    for (const std::string& line : FleetAdvice(rows)) std::cout << "  " << line << "\n";
  }
  SayWritten(command.out_dir, written);
}

// --scan: the manifest on stdout, what was found on stderr.
void Scan(const BatchCommand& command) {
  const ManifestScan scan = ScanForManifest(command.scan_dir);
  std::cout << scan.toml;
  std::cerr << "scan: " << scan.logs << " logs, " << scan.photo_folders << " photo folders ("
            << scan.paired << " with their log), " << scan.clips << " clips, " << scan.datasets
            << " datasets; save it in " << command.scan_dir
            << ", review it, then: shutterlab batch MANIFEST --out OUT\n";
}

int Run(const BatchCommand& command) {
  if (!command.scan_dir.empty()) {
    Scan(command);
    return 0;
  }
  if (command.manifest_path.empty() || command.out_dir.empty())
    throw std::invalid_argument(
        "batch needs MANIFEST and --out DIR (or --scan DIR to write a manifest)");
  const BatchManifest manifest = ReadBatchManifest(command.manifest_path);
  if (command.slurm) {
    RunOnSlurm(manifest, command);
    return 0;
  }
  if (command.summary_only) {
    WriteSummary(manifest, command);
    return 0;
  }
  if (command.item_index >= static_cast<int>(manifest.items.size())) {
    throw IoError(IoMessage(command.manifest_path, 0,
                            "--item-index " + std::to_string(command.item_index) + ": it holds " +
                                std::to_string(manifest.items.size()) + " items (0 to " +
                                std::to_string(manifest.items.size() - 1) + ")"));
  }
  BatchRunOptions options;
  options.executable = ThisExecutable();
  options.tool = kShutterlabVersion;
  options.out_dir = command.out_dir;
  options.parallel = command.parallel > 0
                         ? command.parallel
                         : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  options.memory_cap_bytes =
      command.memory_cap_bytes > 0 ? command.memory_cap_bytes : 0.8 * PhysicalMemoryBytes();
  options.force = command.force;
  options.on_item_end = SayItemEnd;
  if (command.item_index >= 0) {
    options.only = {static_cast<size_t>(command.item_index)};
    options.parallel = 1;
    const std::vector<BatchItemOutcome> outcomes = RunBatch(manifest, options);
    return outcomes.front().status == BatchItemStatus::kFailed ? 2 : 0;
  }
  std::cerr << "batch: " << manifest.items.size() << " items, " << options.parallel
            << " at once, memory cap " << MiB(options.memory_cap_bytes) << "\n";
  const std::vector<BatchItemOutcome> outcomes = RunBatch(manifest, options);
  const std::vector<FleetRow> rows = ReadFleet(manifest, command.out_dir);
  const std::vector<std::string> written = WriteFleetSummary(rows, command.out_dir);
  size_t counts[4] = {0, 0, 0, 0};
  for (const BatchItemOutcome& o : outcomes) ++counts[static_cast<int>(o.status)];
  if (command.json) {
    std::cout << JsonText(nlohmann::json{{"format", "batch/1"},
                                         {"out", command.out_dir},
                                         {"items", OutcomesJson(outcomes)},
                                         {"fleet", written}})
              << "\n";
  } else {
    std::cout << manifest.items.size() << " items: " << counts[0] << " made, " << counts[1]
              << " failed, " << counts[2] << " up to date, " << counts[3] << " busy\n";
    for (const BatchItemOutcome& o : outcomes)
      if (o.status == BatchItemStatus::kFailed)
        std::cout << "failed: " << o.id << ": " << o.error << "\n";
    std::cout << "first:\n";
    for (const std::string& line : FleetAdvice(rows)) std::cout << "  " << line << "\n";
  }
  SayWritten(command.out_dir, written);
  return counts[static_cast<int>(BatchItemStatus::kFailed)] > 0 ? 2 : 0;
}

const CommandRegistration kBatchRegistration(97, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "batch",
      "run a manifest's flights, clips and datasets (docs/FORMATS.md \"Batch manifest\") through "
      "their jobs, resumably, and write one page for the fleet (DIR/fleet.html, fleet.csv)");
  auto command = std::make_shared<BatchCommand>();
  auto* manifest = cmd->add_option("MANIFEST", command->manifest_path, "the manifest (TOML)")
                       ->check(CLI::ExistingFile);
  auto* out = cmd->add_option("--out", command->out_dir,
                              "the batch's folder: items/ID per item, fleet.html, fleet.csv (a "
                              "rerun makes only what is new, changed or failed)");
  cmd->add_option("--scan", command->scan_dir,
                  "print a manifest of what this folder tree holds (logs, photo folders with "
                  "their log, clips, datasets, found by content) to review before running it")
      ->check(CLI::ExistingDirectory)
      ->excludes(manifest)
      ->excludes(out);
  cmd->add_option("--parallel", command->parallel, "items at once (0: the cores)")
      ->check(CLI::NonNegativeNumber);
  AddQuantityOption(cmd, "--memory-cap", &command->memory_cap_bytes, "B", "GiB",
                    "the running items' estimated memory together stays under this (0: 80% of "
                    "this machine's)");
  cmd->add_flag("--force", command->force, "make every item again");
  auto* slurm =
      cmd->add_flag("--slurm", command->slurm,
                    "on a Slurm cluster: write OUT/slurm/batch.sbatch (an array, one task "
                    "per item) and merge.sbatch (the fleet's page after it) and submit "
                    "both; OUT must be on a filesystem every node sees");
  cmd->add_option("--slurm-partition", command->slurm_partition, "the partition to submit to")
      ->needs(slurm);
  AddQuantityOption(cmd, "--slurm-time", &command->slurm_time_s, "s", "min",
                    "each task's time limit (0: from the largest item's inputs)")
      ->needs(slurm);
  cmd->add_flag("--dry-run", command->dry_run, "with --slurm: write the scripts, do not submit")
      ->needs(slurm);
  cmd->add_option("--item-index", command->item_index,
                  "make only the item at this 0-based place in the manifest (a Slurm array "
                  "task's $SLURM_ARRAY_TASK_ID); no fleet page")
      ->check(CLI::NonNegativeNumber)
      ->excludes(slurm);
  cmd->add_flag("--summary-only", command->summary_only,
                "only write fleet.html and fleet.csv from the items' folders as they are")
      ->excludes(slurm);
  cmd->add_flag("--json", command->json, "print each item's outcome as JSON (batch/1)");
  return std::function<void()>([command] {
    const int code = Run(*command);
    if (code != 0) std::exit(code);
  });
});

}  // namespace
}  // namespace shutterlab::app
