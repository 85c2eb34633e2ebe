// Speed of the hot paths of a long-flight analysis, each against a reference measured in the same
// run:
//  1. reading a 30-million-line gyro.csv -> MB/s on one thread (CPU time): the streamed reader
//     (sim/logs/gyro_io OpenGyroCsv, a block at a time, what `flight` uses) and ReadGyroCsv into a
//     whole trace, against std::from_chars alone over the same buffer and istream >> double;
//  2. the same streamed reader with the parsing a chunk ahead on a second thread (wall time);
//  3. the flight analysis (estimate/paper/flight, two limits x two windows) -> samples/s, per-axis
//  and
//     vector criteria separately, against a monotonic-deque sliding range (std::deque);
//  4. `flight` end to end as the command runs it (estimate/paper/log_pipeline.h RunFlight), on one
//     thread (CPU time) and on two (wall time), to compare with scripts/pandas_flight_bench.py.
//
// Usage: analysis_bench [--lines N] [--file PATH] [--generate-only] [--streaming-only]
//                       [--flight-only] [--two-threads] [--repeat N] [--pandas]
// Generates PATH (default /tmp/shutterlab_bench_gyro.csv) when it does not exist with N lines;
// --generate-only stops there (the files for the memory measurements of docs/speed.md).
// --flight-only times only `flight` end to end per-axis on one thread, --repeat times (a quick
// A/B, and what `perf record` should look at); --pandas runs scripts/pandas_flight_bench.py on the
// same file after each of those runs (interleaved, so that both see the same load) and prints the
// ratio of the medians, CPU time against CPU time, and whether the percentages agree;
// --two-threads (implies --flight-only) also times each run as the command runs it (two threads,
// wall time), checks its counts against the one thread's, and gives that ratio too.
// A table, not Google Benchmark: one run of each step is long enough (seconds) to need no repeats.

#include "bench/bench_util.h"
#include "estimate/paper/flight.h"
#include "estimate/paper/log_pipeline.h"
#include "estimate/paper/window_stats.h"
#include "sim/bias.h"
#include "sim/integrate.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <time.h>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

// This thread's CPU time (user + system), s: on a shared machine wall time measures the neighbours.
double Now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// A multirotor-like log at 1 kHz: 5 s still, then a slow random-walk attitude rate with vibration.
// Times with 3 decimals and rates with 6, as real loggers write them (~40 bytes a line).
void GenerateCsv(const std::string& path, size_t lines) {
  std::mt19937_64 rng(20261122);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("cannot write " + path);
  std::string buffer = "t,gx,gy,gz\n";
  double w[3] = {0, 0, 0};
  char number[64];
  for (size_t i = 0; i < lines; ++i) {
    const int64_t t_ms = static_cast<int64_t>(i);
    buffer += std::to_string(t_ms / 1000);
    std::snprintf(number, sizeof(number), ".%03d", static_cast<int>(t_ms % 1000));
    buffer += number;
    for (int a = 0; a < 3; ++a) {
      if (i >= 5000) w[a] = 0.999 * w[a] + 0.003 * normal(rng);
      const double rate = 0.002 + w[a] + 0.01 * normal(rng);  // bias + motion + noise, rad/s
      const auto r =
          std::to_chars(number, number + sizeof(number), rate, std::chars_format::fixed, 6);
      buffer += ',';
      buffer.append(number, r.ptr);
    }
    buffer += '\n';
    if (buffer.size() > (1 << 22)) {
      std::fwrite(buffer.data(), 1, buffer.size(), f);
      buffer.clear();
    }
  }
  std::fwrite(buffer.data(), 1, buffer.size(), f);
  std::fclose(f);
}

// Reference reader: the classic std::ifstream >> double loop (about 80 MB/s is typical).
size_t ReadWithIstream(const std::string& path, size_t max_bytes, size_t* bytes_read) {
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  double t, x, y, z;
  char comma;
  size_t n = 0;
  std::vector<GyroSample> samples;
  while (in >> t >> comma >> x >> comma >> y >> comma >> z) {
    samples.push_back({static_cast<int64_t>(std::llround(t * 1e9)), Eigen::Vector3d(x, y, z)});
    ++n;
    if ((n & 1023) == 0 && static_cast<size_t>(in.tellg()) >= max_bytes) break;
  }
  const auto position = in.tellg();  // -1 once the stream hit the end of the file
  *bytes_read = position < 0 ? std::filesystem::file_size(path) : static_cast<size_t>(position);
  return n;
}

// Reference sliding range: the monotonic-deque algorithm with std::deque, per axis, counting the
// windows over each threshold exactly as estimate/paper/flight does.
std::vector<size_t> DequeFlagged(const PerAxisAngles& angles, int64_t window_ns,
                                 const std::vector<double>& threshold_rad, size_t* windows) {
  const auto& t = angles.t_ns;
  const size_t n = t.size();
  std::vector<double> max_range;
  for (int a = 0; a < 3; ++a) {
    const std::vector<double>& x = angles.angle_rad[a];
    std::deque<size_t> hi, lo;
    size_t e = 0, k = 0;
    for (; k < n && t[k] + window_ns <= t.back(); ++k) {
      while (e < n && t[e] < t[k] + window_ns) {
        while (!hi.empty() && x[hi.back()] <= x[e]) hi.pop_back();
        hi.push_back(e);
        while (!lo.empty() && x[lo.back()] >= x[e]) lo.pop_back();
        lo.push_back(e);
        ++e;
      }
      while (hi.front() < k) hi.pop_front();
      while (lo.front() < k) lo.pop_front();
      const double r = x[hi.front()] - x[lo.front()];
      if (a == 0)
        max_range.push_back(r);
      else
        max_range[k] = std::max(max_range[k], r);
    }
  }
  *windows = max_range.size();
  std::vector<size_t> flagged(threshold_rad.size(), 0);
  for (double r : max_range) {
    for (size_t l = 0; l < threshold_rad.size(); ++l) flagged[l] += r > threshold_rad[l];
  }
  return flagged;
}

// This process's CPU time (every thread), s.
double ProcessNow() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

double WallNow() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The streamed gyro.csv reader on its own: every chunk taken, nothing kept. Returns samples.
size_t StreamGyroCsv(const std::string& path, bool read_ahead, double* checksum) {
  std::unique_ptr<GyroSource> source = OpenGyroCsv(TextBlocks::OfFile(path), path);
  if (read_ahead) source = ReadAhead(std::move(source));
  size_t n = 0;
  for (GyroChunk chunk = source->Next(); !chunk.empty(); chunk = source->Next()) {
    n += chunk.size;
    *checksum += chunk.data[chunk.size - 1].omega_rad_s.x();
  }
  return n;
}

// `flight` as the command runs it without --auto-bias (estimate/paper/log_pipeline.h RunFlight:
// open, stream with the reader a chunk ahead on a second thread when read_ahead, audit,
// FlightStream).
FlightResult StreamedFlight(const std::string& path, const FlightOptions& options, bool read_ahead,
                            size_t* warnings) {
  LogInput input;
  input.path = path;
  input.read_ahead = read_ahead;
  FlightRun run = RunFlight(input, options);
  *warnings = run.warnings.size() - run.result.warnings.size();  // the log's, as before
  return std::move(run.result);
}

// Sections 2 and 4: the streamed reader and `flight` end to end, one thread and two.
void StreamingSections(const std::string& path, double file_mb, double t_from_chars) {
  std::printf("%-58s %10s %10s %10s\n", "streamed gyro.csv reader", "seconds", "MB/s",
              "x from_chars");
  double checksum = 0;
  for (bool read_ahead : {false, true}) {
    const double c0 = Now(), w0 = WallNow();
    const size_t n = StreamGyroCsv(path, read_ahead, &checksum);
    const double t = read_ahead ? WallNow() - w0 : Now() - c0;
    std::printf(
        "%-58s %10.3f %10.0f %10.2f   (%zu samples)\n",
        read_ahead ? "  two threads (parse a chunk ahead), wall time" : "  one thread, CPU time", t,
        file_mb / t, t_from_chars / t, n);
  }
  std::printf("(checksum %.3g)\n\n", checksum);
  std::printf("%-58s %10s %10s %10s\n", "flight end to end (streamed, as the command)", "seconds",
              "Msamples/s", "wall s");
  for (bool vector : {false, true}) {
    FlightOptions options;
    options.vector_criterion = vector;
    for (bool read_ahead : {false, true}) {
      size_t warnings = 0;
      const double c0 = Now(), p0 = ProcessNow(), w0 = WallNow();
      const FlightResult result = StreamedFlight(path, options, read_ahead, &warnings);
      const double wall = WallNow() - w0, main_s = Now() - c0, all_s = ProcessNow() - p0;
      const std::string label =
          std::string(vector ? "  per-axis + vector" : "  per-axis") +
          (read_ahead ? ", two threads, wall time" : ", one thread, CPU time");
      const double t = read_ahead ? wall : main_s;
      std::printf("%-58s %10.3f %10.1f %10.3f\n", label.c_str(), t, result.samples / t / 1e6, wall);
      if (read_ahead) {
        // On a machine whose CPU is shared and throttled the wall time measures the queue; the
        // threads' own CPU times say what the pipeline needs: its wall time on two free cores is
        // about the longer of the two.
        std::printf("%-58s %10.3f %10.1f\n", "    analysis thread, CPU time", main_s,
                    result.samples / main_s / 1e6);
        std::printf("%-58s %10.3f %10.1f\n", "    reader thread, CPU time", all_s - main_s,
                    result.samples / (all_s - main_s) / 1e6);
      }
    }
  }
  std::printf("\n");
}

// The pandas reference (scripts/pandas_flight_bench.py) on the same file: its CPU time (read_csv +
// analysis, as the script times itself) and its table, checked against ours.
struct PandasRun {
  double read_s = 0, analysis_s = 0;
  bool same_table = false;
};

PandasRun RunPandas(const std::string& path, const FlightResult& ours) {
  // From the repository root, as docs/speed.md runs it (__FILE__ may be relative to the build).
  std::string script = "scripts/pandas_flight_bench.py";
  if (!std::filesystem::exists(script)) script = bench::RepoPath(script);
  const std::string command = "/usr/bin/python3 '" + script + "' '" + path + "'";
  std::FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) throw std::runtime_error("cannot run " + command);
  std::string output;
  char line[512];
  while (std::fgets(line, sizeof(line), pipe)) output += line;
  if (pclose(pipe) != 0) throw std::runtime_error(command + " failed:\n" + output);
  PandasRun run;
  // Our rows at the script's precision, in its (sorted: limit, then window) order.
  std::vector<std::string> rows;
  for (const FlightRow& row : ours.rows) {
    char text[128];
    std::snprintf(text, sizeof(text), "%7.3f  %8.3f  %16.1f  %7zu  %15.4f", row.limit_m,
                  row.window_s, row.threshold_arcsec, row.windows, row.flagged_percent);
    rows.push_back(text);
  }
  std::sort(rows.begin(), rows.end());
  size_t matched = 0;
  size_t at = 0;
  while (at < output.size()) {
    const size_t eol = std::min(output.find('\n', at), output.size());
    const std::string text = output.substr(at, eol - at);
    std::sscanf(text.c_str(), "read_csv: %lf", &run.read_s);
    std::sscanf(text.c_str(), "per-axis analysis: %lf", &run.analysis_s);
    matched += matched < rows.size() && text == rows[matched];
    at = eol + 1;
  }
  run.same_table = matched == rows.size();
  if (run.read_s <= 0 || run.analysis_s <= 0)
    throw std::runtime_error("unexpected output of " + command + ":\n" + output);
  return run;
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// `flight` end to end, per-axis, one thread, `repeat` times (with the pandas reference after each
// when asked): the "20x pandas" figure. two_threads: each time also as the command runs it,
// the reader a chunk ahead on a second core, timed by the wall clock (pandas runs on one thread,
// so its CPU time is at most its wall time: the ratio does not flatter us).
int FlightAgainstPandas(const std::string& path, int repeat, bool pandas, bool two_threads) {
  FlightOptions options;
  options.vector_criterion = false;
  std::vector<double> ours_s, ours_wall_s, pandas_s;
  bool same = true;
  for (int r = 0; r < repeat; ++r) {
    size_t warnings = 0;
    const double c0 = Now();
    const FlightResult result = StreamedFlight(path, options, /*read_ahead=*/false, &warnings);
    ours_s.push_back(Now() - c0);
    std::printf("flight end to end, per-axis, one thread: %.3f s CPU (%.1f M samples/s)",
                ours_s.back(), result.samples / ours_s.back() / 1e6);
    if (two_threads) {
      const double w0 = WallNow();
      const FlightResult two = StreamedFlight(path, options, /*read_ahead=*/true, &warnings);
      ours_wall_s.push_back(WallNow() - w0);
      const bool same_counts = two.rows.size() == result.rows.size() &&
                               std::equal(two.rows.begin(), two.rows.end(), result.rows.begin(),
                                          [](const FlightRow& a, const FlightRow& b) {
                                            return a.windows == b.windows &&
                                                   a.flagged == b.flagged &&
                                                   a.flagged_axis == b.flagged_axis;
                                          });
      same &= same_counts;
      std::printf("; two threads %.3f s wall%s", ours_wall_s.back(),
                  same_counts ? "" : " (counts DIFFER from one thread's)");
    }
    if (pandas) {
      const PandasRun run = RunPandas(path, result);
      pandas_s.push_back(run.read_s + run.analysis_s);
      same &= run.same_table;
      std::printf("; pandas %.2f s CPU (read_csv %.2f, analysis %.2f), table %s", pandas_s.back(),
                  run.read_s, run.analysis_s, run.same_table ? "identical" : "DIFFERS");
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  std::printf("median of %d: flight %.3f s CPU", repeat, Median(ours_s));
  if (two_threads) std::printf(", two threads %.3f s wall", Median(ours_wall_s));
  if (pandas) {
    std::printf(", pandas %.2f s CPU: flight is %.1fx faster (CPU time against CPU time)",
                Median(pandas_s), Median(pandas_s) / Median(ours_s));
    if (two_threads) {
      std::printf(", %.1fx on two threads (wall time against pandas' CPU time)",
                  Median(pandas_s) / Median(ours_wall_s));
    }
  }
  std::printf("\n");
  return same ? 0 : 1;
}

// The command line: what to run and on which file.
struct BenchArgs {
  size_t lines = 30000000;
  std::string path = "/tmp/shutterlab_bench_gyro.csv";
  bool generate_only = false, streaming_only = false, flight_only = false, pandas = false,
       two_threads = false;
  int repeat = 1;
};

// Parses argv into *args; false (with the usage printed) on an unknown argument.
bool ParseBenchArgs(int argc, char** argv, BenchArgs* args) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--lines" && i + 1 < argc)
      args->lines = std::stoull(argv[++i]);
    else if (arg == "--file" && i + 1 < argc)
      args->path = argv[++i];
    else if (arg == "--generate-only")
      args->generate_only = true;
    else if (arg == "--streaming-only")
      args->streaming_only = true;
    else if (arg == "--flight-only")
      args->flight_only = true;
    else if (arg == "--pandas")
      args->pandas = true;
    else if (arg == "--two-threads")
      args->two_threads = true;
    else if (arg == "--repeat" && i + 1 < argc)
      args->repeat = std::max(1, std::stoi(argv[++i]));
    else {
      std::fprintf(stderr,
                   "usage: %s [--lines N] [--file PATH] [--generate-only] [--streaming-only] "
                   "[--flight-only] [--two-threads] [--repeat N] [--pandas]\n",
                   argv[0]);
      return false;
    }
  }
  return true;
}

// Section 1: the read steps one by one, each with its MB/s. Returns the trace read whole and
// *t_parse, std::from_chars' time over the whole buffer (the others' reference).
GyroTrace ReadingSection(const std::string& path, double file_mb, double* t_parse_out) {
  std::printf("%-58s %10s %10s\n", "read step (one thread, CPU time)", "seconds", "MB/s");
  double t0 = Now();
  const std::string text = ReadFileToString(path);
  const double t_file = Now() - t0;
  std::printf("%-58s %10.3f %10.0f\n", "ReadFileToString (whole file into memory)", t_file,
              file_mb / t_file);
  // Splitting lines and fields only (LineCursor + SplitFields, no number parsing).
  t0 = Now();
  size_t fields_seen = 0;
  {
    LineCursor cursor(text);
    std::vector<std::string_view> fields;
    while (auto line = cursor.Next()) {
      SplitFields(*line, ',', &fields);
      fields_seen += fields.size();
    }
  }
  const double t_split = Now() - t0;
  std::printf("%-58s %10.3f %10.0f\n", "LineCursor + SplitFields only", t_split, file_mb / t_split);
  // Number parsing only: std::from_chars over the whole buffer, no lines or fields kept.
  t0 = Now();
  double checksum = 0;
  {
    const char* p = text.data() + text.find('\n') + 1;
    const char* end = text.data() + text.size();
    while (p < end) {
      double v;
      const auto r = std::from_chars(p, end, v);
      checksum += v;
      p = r.ptr + 1;  // skip ',' or '\n'
    }
  }
  const double t_parse = Now() - t0;
  std::printf("%-58s %10.3f %10.0f\n", "std::from_chars whole buffer only (upper bound)", t_parse,
              file_mb / t_parse);
  // The streamed reader first, warm, as the command takes it.
  {
    double sink = 0;
    t0 = Now();
    const size_t n = StreamGyroCsv(path, false, &sink);
    const double t_stream = Now() - t0;
    std::printf("%-58s %10.3f %10.0f   <- %zu samples, %.2fx from_chars\n",
                "streamed OpenGyroCsv (sim/logs/gyro_io, what flight reads)", t_stream,
                file_mb / t_stream, n, t_parse / t_stream);
  }
  t0 = Now();
  GyroTrace trace = ReadGyroCsv(path);
  const double t_read = Now() - t0;
  std::printf("%-58s %10.3f %10.0f   <- %zu samples\n", "ReadGyroCsv (sim/gyro_io, total)", t_read,
              file_mb / t_read, trace.size());
  {
    // The trace constructor's share (validation, sorted-interval median, gap scan), on a copy.
    std::vector<GyroSample> copy = trace.samples();
    t0 = Now();
    const GyroTrace again(std::move(copy));
    const double t_construct = Now() - t0;
    std::printf("%-58s %10.3f %10.0f   (median interval %lld ns)\n",
                "  of which GyroTrace constructor (validation + sampling)", t_construct,
                file_mb / t_construct, static_cast<long long>(again.sampling().median_interval_ns));
  }
  size_t ref_bytes = 0;
  t0 = Now();
  const size_t ref_lines = ReadWithIstream(path, 200000000, &ref_bytes);
  const double t_ref = Now() - t0;
  std::printf("%-58s %10.3f %10.0f   (first %zu lines)\n", "reference: std::ifstream >> double",
              t_ref, ref_bytes / 1e6 / t_ref, ref_lines);
  std::printf("(checksum %.3g, %zu fields)\n\n", checksum, fields_seen);
  *t_parse_out = t_parse;
  return trace;
}

// Section 3: the flight analysis on the trace, per-axis and with the vector criterion, against
// the std::deque sliding range. Returns whether the counts agree.
bool FlightSection(const GyroTrace& trace) {
  double t0 = 0.0;
  FlightOptions options;  // 50 m, 5 cm and 10 cm, 10 ms and 20 ms, 20", bias 0:5
  const size_t n = trace.size();
  std::printf("%-58s %10s %10s\n", "flight step (2 limits x 2 windows, CPU time)", "seconds",
              "Msamples/s");
  options.vector_criterion = false;
  t0 = Now();
  const FlightResult axis = Flight(trace, options);
  const double t_axis = Now() - t0;
  std::printf("%-58s %10.3f %10.1f\n",
              "Flight per-axis (bias, streamed integration, ranges, counts)", t_axis,
              n / t_axis / 1e6);
  // The reference's input: the whole angle arrays (not timed against it; allocating 1 GB of fresh
  // pages is itself slow on a VM, which is why Flight streams).
  t0 = Now();
  const BiasEstimate bias = EstimateBias(trace, options.bias);
  const PerAxisAngles angles = IntegratePerAxis(trace, bias.bias_rad_s, bias.first_after);
  const double t_integrate = Now() - t0;
  std::printf("%-58s %10.3f %10.1f\n", "(reference input: bias + IntegratePerAxis, whole arrays)",
              t_integrate, n / t_integrate / 1e6);
  // Reference: std::deque monotonic queues.
  std::vector<double> threshold_rad;
  for (double limit : options.limits_m) {
    threshold_rad.push_back(std::atan(limit / options.altitude_m) +
                            options.noise_allowance_arcsec / kArcsecPerRad);
  }
  t0 = Now();
  bool counts_match = true;
  for (size_t wi = 0; wi < options.windows_s.size(); ++wi) {
    size_t windows = 0;
    const auto flagged =
        DequeFlagged(angles, SecondsToNs(options.windows_s[wi]), threshold_rad, &windows);
    for (size_t l = 0; l < flagged.size(); ++l) {
      const FlightRow& row = axis.rows[l * options.windows_s.size() + wi];
      counts_match &= row.flagged == flagged[l] && row.windows == windows;
    }
  }
  const double t_deque = Now() - t0;
  std::printf("%-58s %10.3f %10.1f   counts %s\n",
              "reference: std::deque sliding range (ranges only)", t_deque, n / t_deque / 1e6,
              counts_match ? "identical" : "DIFFER");

  options.vector_criterion = true;
  t0 = Now();
  const FlightResult both = Flight(trace, options);
  const double t_both = Now() - t0;
  std::printf("%-58s %10.3f %10.1f\n", "Flight per-axis + vector (SO(3) integration + pruning)",
              t_both, n / t_both / 1e6);
  std::printf("\n%s", FlightTable(both).c_str());
  return counts_match;
}

int Main(int argc, char** argv) {
  BenchArgs args;
  if (!ParseBenchArgs(argc, argv, &args)) return 2;
  const std::string& path = args.path;
  if (!std::filesystem::exists(path)) {
    std::printf("generating %s (%zu lines) ...\n", path.c_str(), args.lines);
    std::fflush(stdout);
    const double t0 = Now();
    GenerateCsv(path, args.lines);
    std::printf("  generated in %.1f s\n", Now() - t0);
  }
  if (args.generate_only) return 0;
  if (args.flight_only || args.pandas || args.two_threads) {
    return FlightAgainstPandas(path, args.repeat, args.pandas, args.two_threads);
  }
  const double file_mb = std::filesystem::file_size(path) / 1e6;
  std::printf("file: %s, %.1f MB\n\n", path.c_str(), file_mb);
  double t_parse = 0.0;
  const GyroTrace trace = ReadingSection(path, file_mb, &t_parse);
  StreamingSections(path, file_mb, t_parse);
  if (args.streaming_only) return 0;
  return FlightSection(trace) ? 0 : 1;
}

}  // namespace
}  // namespace shutterlab

int main(int argc, char** argv) { return shutterlab::bench::RunMain(shutterlab::Main, argc, argv); }
