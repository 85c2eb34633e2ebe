// `shutterlab batch`: a synthetic fleet of 51 items (synth logs with camera triggers, DJI photo
// folders, damaged items among them) run, run again, and killed with SIGKILL midway and resumed.

#include "sim/synth/synth.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/app/placed_flight.h"
#include "tests/estimate/loop/validate_fixtures.h"
#include "tests/io/photo_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;
using test::RunShutterlab;

// 51 items: 30 logs, 16 photo folders, a photo folder with its log, and 4 damaged (fewer under the
// sanitizers, where every command runs 3 to 10 times slower). The kill and Slurm tests run the
// first kKillLogs logs and the two items that fail.
constexpr int kLogs = test::kAsan ? 6 : 30, kPhotoFolders = test::kAsan ? 4 : 16;
constexpr int kItems = kLogs + kPhotoFolders + 5;
constexpr int kKillLogs = kLogs < 4 ? kLogs : 4, kKillItems = kKillLogs + 2;

// A DJI photo flying `speed_m_s` north at 60 m.
std::string FleetPhoto(double speed_m_s) {
  test::FixturePhoto p;
  p.focal_length_35mm = 24;
  p.xmp = test::DjiXmp({{"RelativeAltitude", "+60"},
                        {"FlightXSpeed", FormatNumber("%.2f", speed_m_s)},
                        {"FlightYSpeed", "0"},
                        {"FlightZSpeed", "0"}},
                       false);
  return test::JpegWithMetadata(p);
}

// The fleet: kLogs logs, kPhotoFolders photo folders and 4 damaged items (a log that is not one, a
// folder with no photos, a folder with a cut photo among whole ones, a ULog cut in half); returns
// the manifest's path.
std::string MakeFleet(const test::TempDir& dir) {
  std::string manifest = "[defaults]\nlimit = [\"5cm\", \"10cm\"]\n\n";
  for (int i = 0; i < kLogs; ++i) {
    const std::string log = "logs/f" + std::to_string(i) + ".ulg";
    fs::create_directories(dir / "logs");
    SynthOptions synth;
    synth.profile = MotionProfile::kFlight;
    synth.rate_hz = 500;
    synth.duration_s = 24;
    synth.seed = static_cast<uint64_t>(i + 1);
    synth.t0_s = 1;
    synth.flight.gust_max_dps = 10 + 3 * i;  // from calm to a gusty day
    SynthOutputOptions output;
    output.out_path = dir / log;
    output.ulog = true;
    output.trigger_every_s = 2;
    output.altitude_m = 50;
    WriteSynthetic(synth, output);
    manifest += "[[item]]\nid = \"log" + std::to_string(i) + "\"\ngroup = \"quad-" +
                std::string(1, static_cast<char>('A' + i % 3)) + "\"\nlog = \"" + log + "\"\n\n";
  }
  for (int k = 0; k < kPhotoFolders; ++k) {
    const std::string folder = "photos/p" + std::to_string(k);
    fs::create_directories(dir / folder);
    for (int j = 0; j < 3; ++j) {
      WriteFileAtomically(dir / (folder + "/DJI_000" + std::to_string(j) + ".JPG"),
                          FleetPhoto(0.5 + 9.0 * k / (kPhotoFolders - 1) + 0.2 * j));
    }
    manifest += "[[item]]\nid = \"photos" + std::to_string(k) +
                "\"\ngroup = \"mini\"\nreadout = \"20ms\"\nphotos = \"" + folder + "\"\n\n";
  }
  const int on_time_ms[5] = {0, 0, 0, 0, 0};
  test::WritePlacedFlight(dir / "placed", on_time_ms);
  manifest +=
      "[[item]]\nid = \"placed\"\nlog = \"placed/flight.ulg\"\nphotos = \"placed/photos\"\n"
      "jobs = [\"photos\", \"correct\", \"export\"]\nexport = [\"odm\"]\n\n";
  fs::create_directories(dir / "damaged/empty");
  test::WriteText(dir, "damaged/empty/notes.txt", "no photos here");
  fs::create_directories(dir / "damaged/cut");
  WriteFileAtomically(dir / "damaged/cut/DJI_0001.JPG", FleetPhoto(1));
  WriteFileAtomically(dir / "damaged/cut/DJI_0002.JPG", FleetPhoto(1).substr(0, 200));
  test::WriteText(dir, "damaged/garbage.ulg", "this is not a log");
  const std::string whole = ReadFileToString(dir / "logs/f0.ulg");
  WriteFileAtomically(dir / "damaged/half.ulg", whole.substr(0, whole.size() / 2));
  manifest +=
      "[[item]]\nid = \"garbage\"\nlog = \"damaged/garbage.ulg\"\n\n"
      "[[item]]\nid = \"empty\"\nphotos = \"damaged/empty\"\nreadout = \"20ms\"\n\n"
      "[[item]]\nid = \"cut\"\nphotos = \"damaged/cut\"\nreadout = \"20ms\"\n\n"
      "[[item]]\nid = \"half\"\nlog = \"damaged/half.ulg\"\n";
  // The kill test's: the first kKillLogs logs and the two items that fail.
  std::string first_items =
      manifest.substr(0, manifest.find("[[item]]\nid = \"log" + std::to_string(kKillLogs) + "\""));
  first_items +=
      "[[item]]\nid = \"garbage\"\nlog = \"damaged/garbage.ulg\"\n\n"
      "[[item]]\nid = \"empty\"\nphotos = \"damaged/empty\"\nreadout = \"20ms\"\n";
  test::WriteText(dir, "first_items.toml", first_items);
  return test::WriteText(dir, "fleet.toml", manifest);
}

nlohmann::json Record(const std::string& out, const std::string& id) {
  return nlohmann::json::parse(ReadFileToString(out + "/items/" + id + "/made.json"));
}

size_t ItemsWithRecords(const std::string& out) {
  size_t n = 0;
  if (!fs::exists(out + "/items")) return 0;
  for (const auto& entry : fs::directory_iterator(out + "/items"))
    n += fs::exists(entry.path() / "made.json") && entry.path().extension() != ".partial";
  return n;
}

// The processes whose command line names `text` (a fleet's folder): a killed batch's commands.
size_t ProcessesNaming(const std::string& text) {
  size_t n = 0;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    std::ifstream cmdline(entry.path() / "cmdline");
    std::string args((std::istreambuf_iterator<char>(cmdline)), std::istreambuf_iterator<char>());
    n += args.find(text) != std::string::npos && args.find("shutterlab") != std::string::npos;
  }
  return n;
}

class BatchCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fleet_ = new test::TempDir();
    manifest_ = new std::string(MakeFleet(*fleet_));
  }
  static void TearDownTestSuite() {
    delete fleet_;
    delete manifest_;
  }
  static test::TempDir* fleet_;
  static std::string* manifest_;
};
test::TempDir* BatchCli::fleet_ = nullptr;
std::string* BatchCli::manifest_ = nullptr;

TEST_F(BatchCli, FleetOfFiftyWithDamagedItemsThenARerunMakesOnlyTheFailed) {
  const std::string out = *fleet_ / "out";
  const auto r = RunShutterlab("batch " + *manifest_ + " --out " + out + " --parallel 2");
  EXPECT_EQ(r.exit_code, 2) << "an item failed: said in the exit code" << r.output;
  const std::string items = std::to_string(kItems) + " items: ";
  EXPECT_NE(r.out.find(items + std::to_string(kItems - 2) + " made, 2 failed, 0 up to date"),
            std::string::npos)
      << r.output;
  // Each failure in one line naming the item, its job and the command's own error.
  EXPECT_NE(r.out.find("failed: garbage: analyze: error: " + (*fleet_ / "damaged/garbage.ulg")),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("failed: empty: photos: error: "), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("batch: [" + std::to_string(kItems) + "/" + std::to_string(kItems) + "] "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("wrote " + out + "/: fleet.csv, fleet.html"), std::string::npos) << r.err;

  // Every item whole: its record, its inputs' hashes, each job's peak memory.
  const nlohmann::json log0 = Record(out, "log0");
  EXPECT_EQ(log0["status"], "done");
  EXPECT_EQ(log0["inputs"][0]["path"], *fleet_ / "logs/f0.ulg");
  EXPECT_EQ(log0["inputs"][0]["xxh3"].get<std::string>().size(), 16u);
  EXPECT_GT(log0["jobs"][0]["peak_memory_mib"].get<double>(), 1.0);
  if (!test::kAsan) {  // the sanitizers' shadow memory doubles a command's peak (525 MiB)
    EXPECT_LT(log0["jobs"][0]["peak_memory_mib"].get<double>(),
              log0["estimated_memory_mib"].get<double>())
        << "the estimate the memory cap and Slurm's --mem use is above what the item took";
  }
  EXPECT_TRUE(nlohmann::json::parse(ReadFileToString(out + "/items/log0/analyze/analyze.json"))
                  .contains("verdict"));
  EXPECT_EQ(Record(out, "garbage")["status"], "failed");
  EXPECT_FALSE(fs::exists(out + "/items/log0.partial"));

  // fleet.csv: a row per item; the cut photo and the cut log are said, not hidden.
  const std::string csv = ReadFileToString(out + "/fleet.csv");
  EXPECT_EQ(test::LineCount(csv), kItems + 1u);
  EXPECT_EQ(csv.rfind("id,group,input,status,judged,over_5cm_percent,over_10cm_percent,worst,", 0),
            0u);
  EXPECT_NE(csv.find("\ncut,,photos,done,1,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("1 photos could not be read"), std::string::npos);
  EXPECT_NE(csv.find("\nhalf,,log,done,"), std::string::npos) << csv;
  // The photos with their log: placed on it, corrected, exported.
  EXPECT_NE(csv.find("\nplaced,,photos + log,done,5,"), std::string::npos) << csv;
  const nlohmann::json placed = Record(out, "placed");
  EXPECT_EQ(placed["jobs"].size(), 3u);
  EXPECT_TRUE(fs::exists(out + "/items/placed/correct/correct.json"));
  EXPECT_TRUE(fs::exists(out + "/items/placed/export_odm"));
  // The last folder flies 9.5 to 9.9 m/s x 20 ms = 19-20 cm: all over 10 cm; the first 0.5-0.9
  // m/s: none.
  EXPECT_NE(
      csv.find("\nphotos" + std::to_string(kPhotoFolders - 1) + ",mini,photos,done,3,100,100,"),
      std::string::npos)
      << csv;
  EXPECT_NE(csv.find("\nphotos0,mini,photos,done,3,0,0,"), std::string::npos) << csv;
  const std::string html = ReadFileToString(out + "/fleet.html");
  EXPECT_NE(html.find("quad-B"), std::string::npos);
  EXPECT_NE(html.find("Items, the most over the largest limit first"), std::string::npos);
  EXPECT_NE(html.find("analyze: error: " + (*fleet_ / "damaged/garbage.ulg")), std::string::npos);
  test::ExpectDrawsInChromium(out + "/fleet.html", 1, "batch_fleet");

  // Run again: the failed items only; the others are up to date.
  const auto again = RunShutterlab("batch " + *manifest_ + " --out " + out);
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_NE(
      again.out.find(items + "0 made, 2 failed, " + std::to_string(kItems - 2) + " up to date"),
      std::string::npos)
      << again.output;
  // A changed input is made again, and said why.
  std::ofstream(*fleet_ / "photos/p3/DJI_0009.JPG") << FleetPhoto(3);
  const auto changed = RunShutterlab("batch " + *manifest_ + " --out " + out);
  EXPECT_NE(
      changed.out.find(items + "1 made, 2 failed, " + std::to_string(kItems - 3) + " up to date"),
      std::string::npos)
      << changed.output;
  EXPECT_NE(changed.err.find("photos3 made in "), std::string::npos) << changed.err;
  EXPECT_NE(changed.err.find("an input was added: " + (*fleet_ / "photos/p3/DJI_0009.JPG")),
            std::string::npos)
      << changed.err;
  fs::remove(*fleet_ / "photos/p3/DJI_0009.JPG");

  // --scan finds the fleet by content (the garbage log is no log; the batch's own output is
  // skipped), and its manifest reads as it is.
  const auto scan = RunShutterlab("batch --scan " + fleet_->path().string());
  ASSERT_EQ(scan.exit_code, 0) << scan.output;
  EXPECT_NE(scan.err.find("scan: " + std::to_string(kLogs + 2) + " logs, " +
                          std::to_string(kPhotoFolders + 2) + " photo folders (0 with their log)"),
            std::string::npos)
      << scan.err;
  const std::string scanned = test::WriteText(*fleet_, "scanned.toml", scan.out);
  const auto planned = RunShutterlab("batch " + scanned + " --out " + (*fleet_ / "scanned_out") +
                                     " --slurm --dry-run");
  EXPECT_NE(planned.out.find("slurm: batch.sbatch: " + std::to_string(kLogs + kPhotoFolders + 4) +
                             " tasks, each 256 MiB"),
            std::string::npos)
      << planned.output;
}

// SIGKILL midway: the items in flight are lost, none half-made, no command outlives the batch,
// and the next run makes exactly what is missing.
TEST_F(BatchCli, KilledMidwayLosesOnlyTheItemsInFlight) {
  const std::string out = *fleet_ / "killed";
  const std::string first_items = *fleet_ / "first_items.toml";
  const pid_t pid = test::SpawnShutterlab({"batch", first_items, "--out", out, "--parallel", "2"});
  ASSERT_GE(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (ItemsWithRecords(out) < 3 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the batch ended before it was killed";
  const size_t made_before = ItemsWithRecords(out);
  ASSERT_GE(made_before, 3u);
  ASSERT_LT(made_before, static_cast<size_t>(kKillItems));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(ProcessesNaming(fleet_->path().string()), 0u) << "a command outlived the batch";
  // Whole or not at all: every item folder holds its record.
  for (const auto& entry : fs::directory_iterator(out + "/items")) {
    const std::string name = entry.path().filename().string();
    if (name[0] == '.' || entry.path().extension() == ".partial") continue;
    EXPECT_TRUE(fs::exists(entry.path() / "made.json")) << name;
  }
  // The damaged items fail whenever they run, before the kill or after: f of them had.
  size_t f = 0;
  for (const char* id : {"garbage", "empty"}) f += fs::exists(out + "/items/" + id + "/made.json");
  const auto resumed = RunShutterlab("batch " + first_items + " --out " + out);
  EXPECT_EQ(resumed.exit_code, 2) << resumed.output;
  EXPECT_NE(resumed.out.find(std::to_string(kKillItems) +
                             " items: " + std::to_string(kKillLogs - made_before + f) +
                             " made, 2 failed, " + std::to_string(made_before - f) + " up to date"),
            std::string::npos)
      << "made before the kill: " << made_before << "\n"
      << resumed.output;
  EXPECT_EQ(ItemsWithRecords(out), static_cast<size_t>(kKillItems));
  for (const auto& entry : fs::directory_iterator(out + "/items"))
    EXPECT_NE(entry.path().extension(), ".partial") << entry.path();
}

// Runs a shell command, returning its standard output (its exit code in *code).
std::string Shell(const std::string& command, int* code = nullptr) {
  std::string output;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return output;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
  const int status = ::pclose(pipe);
  if (code) *code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return output;
}

// A one-node Slurm cluster on the loopback address (scripts/slurm_cluster.sh), stopped with the
// test.
class SlurmCluster {
 public:
  explicit SlurmCluster(const std::string& dir) : dir_(dir) {
    const std::string out =
        Shell(test::SourcePath("scripts/slurm_cluster.sh") + " start " + dir + " 2>&1", &code_);
    if (code_ != 0) said_ = out;
  }
  ~SlurmCluster() { Shell(test::SourcePath("scripts/slurm_cluster.sh") + " stop " + dir_); }
  bool up() const { return code_ == 0; }
  int code() const { return code_; }
  const std::string& said() const { return said_; }
  std::string conf() const { return dir_ + "/slurm.conf"; }

 private:
  std::string dir_, said_;
  int code_ = -1;
};

// Goes on only with the cluster up: without Slurm the test is skipped (failed under CI=true).
#define SHUTTERLAB_NEED_CLUSTER(cluster)                                               \
  if (!(cluster).up()) {                                                               \
    if ((cluster).code() == 77 && !test::RealDataRequired())                           \
      GTEST_SKIP() << "no Slurm here (scripts/test.sh installs slurm-wlm and munge): " \
                   << (cluster).said();                                                \
    FAIL() << "the cluster did not start: " << (cluster).said();                       \
  }

// Waits until none of the cluster's jobs is pending or running (at most 3 min).
void WaitForSlurm(const std::string& conf) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
  while (std::chrono::steady_clock::now() < deadline &&
         !Shell("SLURM_CONF=" + conf + " squeue -h").empty()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

// `batch --slurm` on a real one-node cluster: an array task per item and the merge after them; one
// task killed midway; the rerun makes what it lost.
TEST_F(BatchCli, SlurmArrayWithATaskKilledMidwayThenRerun) {
  if (test::kAsan)  // the resumed fleet runs under the sanitizers in KilledMidwayLosesOnly...
    GTEST_SKIP() << "Slurm's daemons and sbatch do the work here, not the sanitized code";
  SlurmCluster cluster(*fleet_ / "cluster");
  SHUTTERLAB_NEED_CLUSTER(cluster);
  const std::string env = "SLURM_CONF=" + cluster.conf();
  const std::string out = *fleet_ / "slurm_out";
  const std::string first_items = *fleet_ / "first_items.toml";
  // --dry-run writes the scripts and submits nothing.
  const auto dry =
      RunShutterlab("batch " + first_items + " --out " + out + " --slurm --dry-run", "", env);
  ASSERT_EQ(dry.exit_code, 0) << dry.output;
  const std::string array = ReadFileToString(out + "/slurm/batch.sbatch");
  EXPECT_NE(array.find("#SBATCH --array=0-" + std::to_string(kKillItems - 1) + "\n"),
            std::string::npos)
      << array;
  EXPECT_NE(array.find("#SBATCH --requeue\n"), std::string::npos);
  EXPECT_NE(array.find("--item-index \"$SLURM_ARRAY_TASK_ID\""), std::string::npos);
  EXPECT_TRUE(Shell(env + " squeue -h").empty());

  const auto submitted =
      RunShutterlab("batch " + first_items + " --out " + out + " --slurm", "", env);
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  EXPECT_NE(submitted.out.find("submitted: array job "), std::string::npos) << submitted.out;
  // Kill the first task seen running, with SIGKILL to the whole task.
  std::string killed;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(1);
  while (killed.empty() && std::chrono::steady_clock::now() < deadline) {
    const std::string running = Shell(env + " squeue -h -r -t R -n shutterlab-batch -o %i");
    if (!running.empty()) {
      killed = running.substr(0, running.find('\n'));
      Shell(env + " scancel --signal=KILL --full " + killed);
    }
  }
  ASSERT_FALSE(killed.empty()) << "no task was seen running";
  const int index = std::stoi(killed.substr(killed.find('_') + 1));
  const std::string id = index < kKillLogs    ? "log" + std::to_string(index)
                         : index == kKillLogs ? "garbage"
                                              : "empty";
  WaitForSlurm(cluster.conf());
  const bool killed_made = fs::exists(out + "/items/" + id + "/made.json");
  EXPECT_EQ(ItemsWithRecords(out), kKillItems - (killed_made ? 0u : 1u));
  EXPECT_TRUE(fs::exists(out + "/fleet.html")) << "the merge job ran after the array (afterany)";
  EXPECT_EQ(test::LineCount(ReadFileToString(out + "/fleet.csv")), kKillItems + 1u);

  // The rerun: every task again; those made are up to date, the killed one is made.
  const auto rerun = RunShutterlab("batch " + first_items + " --out " + out + " --slurm", "", env);
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  WaitForSlurm(cluster.conf());
  EXPECT_EQ(ItemsWithRecords(out), static_cast<size_t>(kKillItems));
  const std::string task_said =
      ReadFileToString(out + "/slurm/item_" + std::to_string(index) + ".out");
  if (!killed_made && id.rfind("log", 0) == 0) {
    EXPECT_NE(task_said.find(id + " made in "), std::string::npos) << task_said;
  }
  EXPECT_EQ(Record(out, "log0")["status"], "done");
  EXPECT_EQ(Record(out, "garbage")["status"], "failed");
  for (const auto& entry : fs::directory_iterator(out + "/items"))
    EXPECT_NE(entry.path().extension(), ".partial") << entry.path();
}

// A mixed manifest, locally and through the one-node cluster: a real clip (30 frames of the GoPro
// Karma's, chosen in the manifest) imported and validated in its item, a log, photos alone, photos
// with their log and a rendered rig dataset; the fleet's row of the clip is its validation's.
TEST(BatchMixed, AClipALogAndPhotosLocallyAndThroughSlurm) {
  if (test::kAsan)  // the clip's commands run under the sanitizers in RealClips and ImportCli
    GTEST_SKIP() << "the clip twice through import and validate: 2 min under the sanitizers";
  SHUTTERLAB_REAL_DATA(karma, "rs/gopro_karma/karma.mp4");
  test::TempDir dir;
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 500;
  synth.duration_s = 24;
  synth.t0_s = 1;
  SynthOutputOptions output;
  output.out_path = dir / "flight.ulg";
  output.ulog = true;
  output.trigger_every_s = 2;
  output.altitude_m = 50;
  WriteSynthetic(synth, output);
  fs::create_directories(dir / "photos");
  for (int j = 0; j < 3; ++j)
    WriteFileAtomically(dir / ("photos/DJI_000" + std::to_string(j) + ".JPG"), FleetPhoto(4 + j));
  test::WritePlacedFlight(dir / "placed", {0, 0, 0, 0, 0});
  fs::create_directories(dir / "rig");
  test::TempDir rig_dir;
  fs::rename(test::MakeDataset(rig_dir, {}), dir / "rig/ds");  // a rendered rig dataset
  const std::string manifest = test::WriteText(
      dir, "mixed.toml",
      "[[item]]\nid = \"karma\"\ngroup = \"gopro\"\nclip = \"" + karma +
          "\"\nstart_frame = 100\nmax_frames = 31\n\n[[item]]\nid = \"log\"\nlog = "
          "\"flight.ulg\"\n\n[[item]]\nid = \"photos\"\nphotos = \"photos\"\n\n[[item]]\nid = "
          "\"placed\"\nlog = \"placed/flight.ulg\"\nphotos = \"placed/photos\"\n\n"
          "[[item]]\nid = \"rig\"\ndataset = \"rig/ds\"\n");

  const std::string out = dir / "local";
  const auto r = RunShutterlab("batch " + manifest + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.out.find("5 items: 5 made, 0 failed, 0 up to date"), std::string::npos) << r.out;
  const nlohmann::json record = Record(out, "karma");
  ASSERT_EQ(record["jobs"].size(), 2u) << record.dump(2);
  EXPECT_EQ(record["jobs"][0]["name"], "import");
  EXPECT_EQ(record["jobs"][1]["name"], "validate");
  const std::string recipe = record["recipe"].dump();
  EXPECT_NE(recipe.find("\"--start-frame\",\"100\",\"--max-frames\",\"31\""), std::string::npos)
      << recipe;
  EXPECT_TRUE(fs::exists(out + "/items/karma/dataset/frames.csv"));
  const nlohmann::json report =
      nlohmann::json::parse(ReadFileToString(out + "/items/karma/validate/report.json"));
  EXPECT_EQ(report["frames"], 30);
  const std::string csv = ReadFileToString(out + "/fleet.csv");
  EXPECT_NE(csv.find("\nkarma,gopro,clip,done,30,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(report["verdict"]["headline"].get<std::string>()), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nlog,,log,done,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nphotos,,photos,done,3,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nplaced,,photos + log,done,5,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nrig,,dataset,done," + std::to_string(test::kStillFrames) + ","),
            std::string::npos)
      << csv;
  EXPECT_NE(ReadFileToString(out + "/fleet.html").find("items/karma/validate/validate.html"),
            std::string::npos);
  test::ExpectDrawsInChromium(out + "/fleet.html", 1, "batch_mixed");
  const auto again = RunShutterlab("batch " + manifest + " --out " + out);
  EXPECT_NE(again.out.find("5 items: 0 made, 0 failed, 5 up to date"), std::string::npos)
      << again.output;

  // The same manifest as a Slurm job array: the clip's task asks for its own memory class.
  SlurmCluster cluster(dir / "cluster");
  SHUTTERLAB_NEED_CLUSTER(cluster);
  const std::string env = "SLURM_CONF=" + cluster.conf();
  const std::string slurm_out = dir / "slurm";
  const auto submitted =
      RunShutterlab("batch " + manifest + " --out " + slurm_out + " --slurm", "", env);
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  WaitForSlurm(cluster.conf());
  EXPECT_EQ(ItemsWithRecords(slurm_out), 5u);
  const std::string slurm_csv = ReadFileToString(slurm_out + "/fleet.csv");
  EXPECT_NE(slurm_csv.find("\nkarma,gopro,clip,done,30,"), std::string::npos) << slurm_csv;
  EXPECT_NE(slurm_csv.find("\nplaced,,photos + log,done,5,"), std::string::npos) << slurm_csv;
  EXPECT_EQ(Record(slurm_out, "karma")["recipe"], record["recipe"]);
}

}  // namespace
}  // namespace shutterlab
