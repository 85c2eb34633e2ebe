#include "estimate/batch/batch_run.h"

#include "estimate/batch/batch_plan.h"
#include "estimate/batch/item_record.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <deque>
#include <fcntl.h>
#include <filesystem>
#include <limits>
#include <map>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace shutterlab {
namespace fs = std::filesystem;

const char* BatchItemStatusName(BatchItemStatus status) {
  switch (status) {
    case BatchItemStatus::kMade:
      return "made";
    case BatchItemStatus::kFailed:
      return "failed";
    case BatchItemStatus::kUpToDate:
      return "up to date";
    case BatchItemStatus::kBusy:
      return "busy";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc;
  ::gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

// The last line of a command's log that says something: its one-line error.
std::string LastLine(const std::string& path) {
  std::string text;
  try {
    text = ReadFileToString(path);
  } catch (const IoError&) {
    return "";
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' '))
    text.pop_back();
  const size_t start = text.find_last_of("\r\n");
  return start == std::string::npos ? text : text.substr(start + 1);
}

nlohmann::json ReadRecord(const fs::path& path) {
  try {
    return nlohmann::json::parse(ReadFileToString(path.string()));
  } catch (const std::exception&) {
    return nlohmann::json();  // none, or not one: the item is made again
  }
}

// An item being made: its commands, the one running, and what it has recorded so far.
struct ActiveItem {
  size_t index = 0;
  std::vector<PlannedCommand> plan;
  size_t running_command = 0;
  Clock::time_point command_start, item_start;
  int lock_fd = -1;
  fs::path partial, final_dir;
  nlohmann::json record;
  double estimate_bytes = 0;
  BatchItemOutcome outcome;
};

class LocalBatch {
 public:
  LocalBatch(const BatchManifest& manifest, const BatchRunOptions& options)
      : manifest_(manifest), options_(options), items_dir_(fs::path(options.out_dir) / "items") {}

  std::vector<BatchItemOutcome> Run() {
    std::error_code error;
    fs::create_directories(items_dir_, error);
    if (error)
      throw IoError(IoMessage(items_dir_.string(), 0, "cannot make it: " + error.message()));
    std::deque<size_t> queue;
    if (options_.only.empty()) {
      for (size_t i = 0; i < manifest_.items.size(); ++i) queue.push_back(i);
    } else {
      queue.assign(options_.only.begin(), options_.only.end());
    }
    progress_.total = queue.size();
    progress_.seconds_left = std::numeric_limits<double>::quiet_NaN();
    const size_t parallel = static_cast<size_t>(std::max(1, options_.parallel));
    while (!queue.empty() || !running_.empty()) {
      while (!queue.empty() && running_.size() < parallel && Fits(queue.front())) {
        const size_t index = queue.front();
        queue.pop_front();
        Begin(index);
      }
      if (running_.empty()) continue;
      WaitForOne(queue.size());
    }
    std::vector<BatchItemOutcome> outcomes;
    for (auto& [index, outcome] : outcomes_) outcomes.push_back(std::move(outcome));
    return outcomes;
  }

 private:
  bool Fits(size_t index) {
    if (running_.empty() || options_.memory_cap_bytes <= 0) return true;
    double used = 0;
    for (const auto& [pid, item] : running_) used += item.estimate_bytes;
    return used + EstimateBytes(index) <= options_.memory_cap_bytes;
  }

  // An item's memory estimate, made once: it lists the item's input files.
  double EstimateBytes(size_t index) {
    const auto [at, inserted] = estimates_.try_emplace(index, 0.0);
    if (inserted) at->second = EstimateBatchItemMemoryBytes(manifest_.items[index]);
    return at->second;
  }

  void End(ActiveItem&& item) {
    switch (item.outcome.status) {
      case BatchItemStatus::kMade:
        ++progress_.made;
        break;
      case BatchItemStatus::kFailed:
        ++progress_.failed;
        break;
      case BatchItemStatus::kUpToDate:
        ++progress_.up_to_date;
        break;
      case BatchItemStatus::kBusy:
        ++progress_.busy;
        break;
    }
    if (item.lock_fd >= 0) ::close(item.lock_fd);
    if (item.outcome.status == BatchItemStatus::kMade ||
        item.outcome.status == BatchItemStatus::kFailed) {
      made_seconds_ += item.outcome.seconds;
      ++made_count_;
    }
    progress_.running = running_.size();
    if (options_.on_item_end) options_.on_item_end(item.outcome, progress_);
    outcomes_[item.index] = std::move(item.outcome);
  }

  // Locks the item, decides whether it must be made, and starts its first command.
  void Begin(size_t index) {
    const BatchItem& spec = manifest_.items[index];
    ActiveItem item;
    item.index = index;
    item.item_start = Clock::now();
    item.outcome.id = spec.id;
    item.final_dir = items_dir_ / spec.id;
    item.partial = items_dir_ / (spec.id + ".partial");
    const std::string lock_path = (items_dir_ / ("." + spec.id + ".lock")).string();
    item.lock_fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (item.lock_fd < 0 || ::flock(item.lock_fd, LOCK_EX | LOCK_NB) != 0) {
      item.outcome.status = BatchItemStatus::kBusy;
      item.outcome.reason = "another process is making it";
      return End(std::move(item));
    }
    item.plan = PlanBatchItem(spec);
    const nlohmann::json before = ReadRecord(item.final_dir / "made.json");
    const nlohmann::json recipe = BatchItemRecipe(item.plan, options_.tool);
    std::vector<InputFileStamp> stamps;
    try {
      stamps = StampInputFiles(BatchItemInputFiles(spec), InputStampsFromRecord(before));
    } catch (const std::exception& e) {
      return Fail(std::move(item), recipe, stamps, WithoutCheckLocation(e.what()));
    }
    item.outcome.reason = options_.force ? "--force" : BatchItemStaleReason(before, recipe, stamps);
    if (item.outcome.reason.empty()) {
      item.outcome.status = BatchItemStatus::kUpToDate;
      return End(std::move(item));
    }
    std::error_code error;
    fs::remove_all(item.partial, error);  // what a killed run left
    fs::remove_all(item.final_dir.string() + ".old", error);
    fs::create_directories(item.partial / "logs", error);
    if (error) return Fail(std::move(item), recipe, stamps, "cannot make " + item.partial.string());
    item.record = {{"format", "shutterlab-batch-item/1"},
                   {"id", spec.id},
                   {"reason", item.outcome.reason},
                   {"started_utc", UtcNow()},
                   {"recipe", recipe},
                   {"inputs", InputStampsJson(stamps)},
                   {"jobs", nlohmann::json::array()}};
    item.estimate_bytes = EstimateBytes(index);
    item.record["estimated_memory_mib"] = item.estimate_bytes / (1024.0 * 1024);
    Launch(std::move(item));
  }

  // An item that failed before any command ran: recorded in its folder as failed.
  void Fail(ActiveItem&& item, const nlohmann::json& recipe,
            const std::vector<InputFileStamp>& stamps, const std::string& error) {
    item.record = {{"format", "shutterlab-batch-item/1"},
                   {"id", item.outcome.id},
                   {"started_utc", UtcNow()},
                   {"recipe", recipe},
                   {"inputs", InputStampsJson(stamps)},
                   {"jobs", nlohmann::json::array()}};
    std::error_code ignored;
    fs::remove_all(item.partial, ignored);
    fs::create_directories(item.partial, ignored);
    item.outcome.error = error;
    Finish(std::move(item));
  }

  void Launch(ActiveItem&& item) {
    const PlannedCommand& command = item.plan[item.running_command];
    std::error_code ignored;
    if (!command.stdout_path.empty())
      fs::create_directories((item.partial / command.stdout_path).parent_path(), ignored);
    item.command_start = Clock::now();
    const pid_t pid = Spawn(command, item.partial);
    if (pid < 0) {
      item.outcome.error =
          command.name + ": cannot start " + options_.executable + ": " + std::strerror(errno);
      return Finish(std::move(item));
    }
    running_.emplace(pid, std::move(item));
  }

  // fork and exec the command in `folder`, its output in its files. The child is killed when this
  // process dies (PR_SET_PDEATHSIG), so a killed batch leaves no command writing into a folder
  // the next run will remove.
  pid_t Spawn(const PlannedCommand& command, const fs::path& folder) {
    std::vector<std::string> args = {options_.executable};
    args.insert(args.end(), command.args.begin(), command.args.end());
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    const std::string folder_text = folder.string();
    const std::string log_path = command.log_path;
    const std::string stdout_path = command.stdout_path;
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid != 0) return pid;
    // The child: only async-signal-safe calls until exec.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(137);
    if (::chdir(folder_text.c_str()) != 0) ::_exit(126);
    const int log = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int out =
        stdout_path.empty() ? log : ::open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int null = ::open("/dev/null", O_RDONLY);
    if (log < 0 || out < 0 || null < 0) ::_exit(126);
    ::dup2(null, 0);
    ::dup2(out, 1);
    ::dup2(log, 2);
    ::execv(argv[0], argv.data());
    const char* message = "batch: cannot run the shutterlab executable\n";
    (void)!::write(2, message, std::strlen(message));
    ::_exit(127);
  }

  void WaitForOne(size_t queued) {
    int status = 0;
    struct rusage usage;
    const pid_t pid = ::wait4(-1, &status, 0, &usage);
    if (pid < 0) {
      if (errno == EINTR) return;
      throw IoError(std::string("batch: waiting for a command failed: ") + std::strerror(errno));
    }
    const auto at = running_.find(pid);
    if (at == running_.end()) return;  // not ours
    ActiveItem item = std::move(at->second);
    running_.erase(at);
    const PlannedCommand& command = item.plan[item.running_command];
    const double peak_bytes = static_cast<double>(usage.ru_maxrss) * 1024.0;
    item.outcome.peak_memory_bytes = std::max(item.outcome.peak_memory_bytes, peak_bytes);
    const int exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    item.record["jobs"].push_back({{"name", command.name},
                                   {"exit_code", exit_code},
                                   {"seconds", SecondsSince(item.command_start)},
                                   {"peak_memory_mib", peak_bytes / 1048576.0},
                                   {"log", command.log_path}});
    if (exit_code != 0) {
      std::string said = LastLine((item.partial / command.log_path).string());
      if (WIFSIGNALED(status))
        said = "killed by signal " + std::to_string(WTERMSIG(status)) +
               (said.empty() ? "" : " (" + said + ")");
      item.outcome.error =
          command.name + ": " + (said.empty() ? "exit code " + std::to_string(exit_code) : said);
      return Finish(std::move(item), queued);
    }
    if (++item.running_command < item.plan.size()) return Launch(std::move(item));
    Finish(std::move(item), queued);
  }

  // Records the item and swaps its folder in whole (rename, or an atomic exchange with the old).
  void Finish(ActiveItem&& item, size_t queued = 0) {
    item.outcome.status =
        item.outcome.error.empty() ? BatchItemStatus::kMade : BatchItemStatus::kFailed;
    item.outcome.seconds = SecondsSince(item.item_start);
    item.record["status"] = item.outcome.error.empty() ? "done" : "failed";
    item.record["error"] = item.outcome.error;
    item.record["seconds"] = item.outcome.seconds;
    item.record["peak_memory_mib"] = item.outcome.peak_memory_bytes / 1048576.0;
    item.record["finished_utc"] = UtcNow();
    try {
      WriteFileAtomically((item.partial / "made.json").string(), item.record.dump(2) + "\n");
      SwapIn(item.partial, item.final_dir);
    } catch (const std::exception& e) {
      item.outcome.status = BatchItemStatus::kFailed;
      item.outcome.error = WithoutCheckLocation(e.what());
    }
    const double per_item =
        (made_seconds_ + item.outcome.seconds) / static_cast<double>(made_count_ + 1);
    progress_.seconds_left =
        per_item * (static_cast<double>(queued) + 0.5 * static_cast<double>(running_.size())) /
        std::max(1, options_.parallel);
    End(std::move(item));
  }

  // A filesystem without renameat2's flags (NFS, where a cluster's items may lie) gets two
  // renames: the old folder aside, the new one in; a kill between them leaves ID.old, which the
  // next run's item removes with its stale ID.partial.
  static void SwapIn(const fs::path& partial, const fs::path& final_dir) {
    const auto fail = [&] {
      throw IoError(
          IoMessage(final_dir.string(), 0,
                    std::string("cannot put the item in place: ") + std::strerror(errno)));
    };
    if (::renameat2(AT_FDCWD, partial.c_str(), AT_FDCWD, final_dir.c_str(), RENAME_NOREPLACE) == 0)
      return;
    std::error_code ignored;
    if (errno == EINVAL) {
      const fs::path old = final_dir.string() + ".old";
      fs::remove_all(old, ignored);
      if (fs::exists(final_dir) && ::rename(final_dir.c_str(), old.c_str()) != 0) fail();
      if (::rename(partial.c_str(), final_dir.c_str()) != 0) fail();
      fs::remove_all(old, ignored);
      return;
    }
    if (errno != EEXIST ||
        ::renameat2(AT_FDCWD, partial.c_str(), AT_FDCWD, final_dir.c_str(), RENAME_EXCHANGE) != 0)
      fail();
    fs::remove_all(partial, ignored);  // now the old one
  }

  const BatchManifest& manifest_;
  const BatchRunOptions& options_;
  fs::path items_dir_;
  std::map<pid_t, ActiveItem> running_;
  std::map<size_t, BatchItemOutcome> outcomes_;
  std::map<size_t, double> estimates_;  // EstimateBytes's, by item index
  BatchProgress progress_;
  double made_seconds_ = 0;
  size_t made_count_ = 0;
};

}  // namespace

std::vector<BatchItemOutcome> RunBatch(const BatchManifest& manifest,
                                       const BatchRunOptions& options) {
  return LocalBatch(manifest, options).Run();
}

}  // namespace shutterlab
