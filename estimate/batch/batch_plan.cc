#include "estimate/batch/batch_plan.h"

#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace shutterlab {
namespace {

void AddIf(std::vector<std::string>* args, const char* option, const std::string& value) {
  if (value.empty()) return;
  args->push_back(option);
  args->push_back(value);
}

// The options every analysis of the item shares: its camera and the values it overrides.
void AddCameraOptions(const BatchItem& item, bool with_triggers, std::vector<std::string>* args) {
  AddIf(args, "--camera", item.camera);
  AddIf(args, "--lens-profile", item.lens_profile);
  if (std::isfinite(item.readout_s))
    AddIf(args, "--readout", QuantityText(item.readout_s * 1e3, "ms"));
  if (std::isfinite(item.altitude_m)) AddIf(args, "--altitude", QuantityText(item.altitude_m, "m"));
  if (with_triggers) AddIf(args, "--triggers", item.triggers);
}

void AddLimits(const BatchItem& item, std::vector<std::string>* args) {
  if (item.limits_m.empty()) return;
  std::string text;
  for (const double limit : item.limits_m)
    text += (text.empty() ? "" : ",") + QuantityText(limit * 100, "cm");
  AddIf(args, "--limit", text);
}

PlannedCommand Command(BatchJob job, std::string name, std::vector<std::string> args,
                       std::string stdout_path = "") {
  std::string log = name;
  std::replace(log.begin(), log.end(), ' ', '_');
  return {job, std::move(name), std::move(args), std::move(stdout_path), "logs/" + log + ".log"};
}

}  // namespace

std::vector<PlannedCommand> PlanBatchItem(const BatchItem& item) {
  std::vector<PlannedCommand> plan;
  const std::string dataset = item.clip.empty() ? item.dataset : "dataset";
  const auto has = [&](BatchJob job) {
    return std::find(item.jobs.begin(), item.jobs.end(), job) != item.jobs.end();
  };
  for (const BatchJob job : item.jobs) {
    std::vector<std::string> args;
    switch (job) {
      case BatchJob::kImport:
        args = {"import", item.clip, "--out", "dataset"};
        AddIf(&args, "--lens-profile", item.lens_profile);
        if (item.start_frame >= 0)
          args.insert(args.end(), {"--start-frame", std::to_string(item.start_frame)});
        if (item.max_frames >= 0)
          args.insert(args.end(), {"--max-frames", std::to_string(item.max_frames)});
        plan.push_back(Command(job, "import", args));
        break;
      case BatchJob::kAnalyze:
        args = {"analyze", item.log, "--out", "analyze", "--json"};
        AddCameraOptions(item, true, &args);
        AddLimits(item, &args);
        plan.push_back(Command(job, "analyze", args, "analyze/analyze.json"));
        break;
      case BatchJob::kPhotos:
        args = {"analyze"};
        if (!item.log.empty()) args.push_back(item.log);
        args.insert(args.end(), {"--photos", item.photos, "--out", "photos", "--json"});
        AddCameraOptions(item, !item.log.empty(), &args);
        AddLimits(item, &args);
        plan.push_back(Command(job, "photos", args, "photos/photos.json"));
        break;
      case BatchJob::kValidate:
        args = {"validate", dataset, "--report", "validate/report.json", "--out", "validate"};
        AddIf(&args, "--lens-profile", item.lens_profile);
        AddLimits(item, &args);
        plan.push_back(Command(job, "validate", args, "validate/validate.txt"));
        break;
      case BatchJob::kCorrect:
        if (has(BatchJob::kValidate)) {
          args = {"correct", dataset,   "--report", "validate/report.json",
                  "--out",   "correct", "--json"};
        } else {
          args = {"correct", item.log, "--photos", item.photos, "--out", "correct", "--json"};
          AddCameraOptions(item, true, &args);
        }
        plan.push_back(Command(job, "correct", args, "correct/correct.json"));
        break;
      case BatchJob::kExport:
        for (const std::string& format : item.exports) {
          const std::string source =
              has(BatchJob::kPhotos) ? "photos/photos.json" : "validate/report.json";
          args = {"export", source, "--to", format, "--out", "export_" + format, "--json"};
          plan.push_back(Command(job, "export " + format, args, "export_" + format + ".json"));
        }
        break;
    }
  }
  return plan;
}

double EstimateBatchItemMemoryBytes(const BatchItem& item) {
  double largest_file_bytes = 0;
  for (const std::string& file : BatchItemInputFiles(item)) {
    std::error_code error;
    const auto bytes = std::filesystem::file_size(file, error);
    if (!error) largest_file_bytes = std::max(largest_file_bytes, static_cast<double>(bytes));
  }
  // A command's fixed part (its libraries, OpenCV's pools, and the codecs module's 130 MB where it
  // reads images: analyze's peak is 55 MiB on a 3 MB log and 57 MiB on a 64 MB one, docs/batch.md),
  // what the logs' readers map, and a decoded photo or frame for every compressed byte of the
  // largest file (a JPEG compresses about 8:1; correct and validate hold several frames at once).
  // Slurm's requests round it up to 256 MiB anyway.
  constexpr double kFixedBytes = 200.0 * 1024 * 1024;
  const bool decodes_images = std::any_of(item.jobs.begin(), item.jobs.end(), [](BatchJob job) {
    return job == BatchJob::kCorrect || job == BatchJob::kValidate || job == BatchJob::kImport;
  });
  return kFixedBytes + largest_file_bytes * (decodes_images ? 32 : 2);
}

}  // namespace shutterlab
