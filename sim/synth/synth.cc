#include "sim/synth/synth.h"

#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/raw_csv.h"
#include "sim/logs/ulog_write.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace shutterlab {
namespace {

// Random-stream ids of the sensors (the motion uses 1 and 2, sim/synth/motion.cc).
uint64_t NoiseStream(int sensor) { return 100 + 2 * static_cast<uint64_t>(sensor); }
uint64_t TimingStream(int sensor) { return 101 + 2 * static_cast<uint64_t>(sensor); }

constexpr double kStillDefaultS = 60.0;
constexpr double kFlightDefaultS = 120.0;
// Upper bounds that keep k * 1e9 / rate and the sample count far inside int64 / memory limits.
constexpr double kMaxRateHz = 1e6;
constexpr double kMaxDurationS = 1e7;
constexpr int64_t kMaxSamples = int64_t{1} << 31;

}  // namespace

void SynthOptions::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= kMaxRateHz)
      << "rate must be in (0, " << kMaxRateHz << "] Hz, got " << rate_hz;
  SHUTTERLAB_CHECK(std::isfinite(duration_s) && duration_s >= 0 && duration_s <= kMaxDurationS)
      << "duration must be in [0, " << kMaxDurationS << "] s (0 = the profile's default), got "
      << duration_s;
  SHUTTERLAB_CHECK(std::isfinite(t0_s) && std::abs(t0_s) < 1e9)
      << "t0 must be finite, |t0| < 1e9 s";
  imu.Check();
  if (profile == MotionProfile::kSteps) steps.Check();
  if (profile == MotionProfile::kFlight) flight.Check();
  SHUTTERLAB_CHECK(NominalSampleCount() >= 2)
      << "the trace would hold fewer than 2 samples (duration " << DurationS() << " s at "
      << rate_hz << " Hz)";
  SHUTTERLAB_CHECK(NominalSampleCount() <= kMaxSamples)
      << "the trace would hold " << NominalSampleCount() << " samples (limit " << kMaxSamples
      << ")";
  if (imu.gap_period_s > 0) {
    SHUTTERLAB_CHECK(imu.gap_duration_s * rate_hz >= 1.0)
        << "gap duration " << imu.gap_duration_s << " s is shorter than one sample period at "
        << rate_hz << " Hz";
  }
}

double SynthOptions::DurationS() const {
  if (duration_s > 0) return duration_s;
  switch (profile) {
    case MotionProfile::kStill:
      return kStillDefaultS;
    case MotionProfile::kFlight:
      return kFlightDefaultS;
    case MotionProfile::kSteps:
      return Motion::Steps(steps, seed).natural_duration_s();
  }
  return kStillDefaultS;
}

int64_t SynthOptions::NominalSampleCount() const {
  // The small epsilon keeps 5 s * 3000 Hz at 15001 samples despite rounding in the product.
  return static_cast<int64_t>(std::floor(DurationS() * rate_hz + 1e-6)) + 1;
}

int64_t SynthOptions::NominalTimeNs(int64_t k) const {
  return SecondsToNs(t0_s) + std::llround(static_cast<double>(k) * 1e9 / rate_hz);
}

Motion MakeMotion(const SynthOptions& options) {
  switch (options.profile) {
    case MotionProfile::kStill:
      return Motion::Still();
    case MotionProfile::kSteps:
      return Motion::Steps(options.steps, options.seed);
    case MotionProfile::kFlight:
      return Motion::Flight(options.flight, options.DurationS(), options.seed);
  }
  return Motion::Still();
}

GyroTrace SynthesizeTrace(const SynthOptions& options, int sensor, size_t* saturated_values) {
  options.Check();
  SHUTTERLAB_CHECK(sensor >= 0 && sensor < 1000) << "sensor index must be 0..999, got " << sensor;
  const Motion motion = MakeMotion(options);
  const int64_t n = options.NominalSampleCount();
  const int64_t t0_ns = options.NominalTimeNs(0);
  ImuSimulator imu(options.imu, options.rate_hz, NoiseSource(options.seed, NoiseStream(sensor)));
  NoiseSource timing(options.seed, TimingStream(sensor));
  const double jitter_ns = options.imu.timestamp_jitter_s * 1e9;
  // Nominal intervals are floor or ceil of 1e9 / rate; a jitter below half the shorter one keeps
  // the logged timestamps non-decreasing.
  const double max_jitter_ns = std::max(0.0, std::floor(1e9 / options.rate_hz) / 2.0 - 1.0);
  const int64_t gap_period_ns =
      options.imu.gap_period_s > 0 ? SecondsToNs(options.imu.gap_period_s) : 0;
  const int64_t gap_duration_ns = SecondsToNs(options.imu.gap_duration_s);

  std::vector<GyroSample> samples;
  samples.reserve(static_cast<size_t>(n));
  for (int64_t k = 0; k < n; ++k) {
    const int64_t t_ns = options.NominalTimeNs(k);
    // Draw the noise and the jitter of every sample, even a lost one, so that gaps do not shift
    // the random streams of the samples after them.
    const Eigen::Vector3d omega = imu.Measure(motion.OmegaRadS((t_ns - t0_ns) * 1e-9));
    const double jitter =
        jitter_ns > 0 ? std::clamp(jitter_ns * timing.Normal(), -max_jitter_ns, max_jitter_ns)
                      : 0.0;
    if (gap_period_ns > 0) {
      const int64_t since_ns = t_ns - t0_ns;
      const int64_t m = since_ns / gap_period_ns;
      if (m >= 1 && since_ns - m * gap_period_ns < gap_duration_ns) continue;
    }
    samples.push_back({t_ns + std::llround(jitter), omega});
  }
  if (saturated_values) *saturated_values = imu.saturated_values();
  return GyroTrace(std::move(samples));
}

GyroTrace SynthesizeTruth(const SynthOptions& options) {
  options.Check();
  const Motion motion = MakeMotion(options);
  const int64_t n = options.NominalSampleCount();
  const int64_t t0_ns = options.NominalTimeNs(0);
  std::vector<GyroSample> samples(static_cast<size_t>(n));
  for (int64_t k = 0; k < n; ++k) {
    const int64_t t_ns = options.NominalTimeNs(k);
    samples[k] = {t_ns, motion.OmegaRadS((t_ns - t0_ns) * 1e-9)};
  }
  return GyroTrace(std::move(samples));
}

void SynthOutputOptions::Check() const {
  SHUTTERLAB_CHECK(!out_path.empty()) << "an output file is required (--out)";
  SHUTTERLAB_CHECK(out2_path != out_path) << "the second sensor's file must differ from the first";
  SHUTTERLAB_CHECK(format == LogFormat::kGyroCsv || format == LogFormat::kRaw)
      << "synth writes gyro.csv or raw counts, not " << LogFormatName(format);
  SHUTTERLAB_CHECK(!ulog || format == LogFormat::kGyroCsv) << "a ULog holds rates, not raw counts";
  SHUTTERLAB_CHECK(trigger_every_s >= 0.0) << "the trigger interval must not be negative";
  SHUTTERLAB_CHECK(trigger_every_s == 0.0 || ulog)
      << "camera triggers are written into a ULog only";
  SHUTTERLAB_CHECK(!altitude_m || ulog) << "an altitude is written into a ULog only";
}

namespace {

void WriteOne(const std::string& path, const GyroTrace& trace, const SynthOptions& options,
              const SynthOutputOptions& output) {
  if (output.ulog) {
    std::vector<CameraEvent> triggers;
    if (output.trigger_every_s > 0.0 && !trace.empty()) {
      const int64_t every_ns = SecondsToNs(output.trigger_every_s);
      for (int64_t t = trace.t_begin_ns() + every_ns; t + every_ns <= trace.t_end_ns();
           t += every_ns) {
        CameraEvent event;
        event.t_ns = t;
        event.sequence = static_cast<int64_t>(triggers.size());
        event.kind = "camera_capture";
        triggers.push_back(event);
      }
    }
    ULogWriteOptions ulog;
    ulog.altitude_above_ground_m = output.altitude_m;
    WriteULog(path, trace, triggers, ulog);
  } else if (output.format == LogFormat::kRaw) {
    WriteRawCsv(path, trace, options.imu.range_dps, output.time_unit);
  } else {
    WriteGyroCsv(path, trace);
  }
}

}  // namespace

SynthSummary WriteSynthetic(const SynthOptions& options, const SynthOutputOptions& output) {
  options.Check();
  output.Check();
  SynthSummary summary;
  size_t saturated = 0;
  const GyroTrace first = SynthesizeTrace(options, 0, &saturated);
  summary.samples = first.size();
  summary.gaps = first.sampling().gap_indices.size();
  summary.duration_s = first.DurationS();
  summary.saturated_values = saturated;
  if (options.profile == MotionProfile::kSteps) summary.turns = MakeMotion(options).turns();
  WriteOne(output.out_path, first, options, output);
  if (!output.out2_path.empty()) {
    try {
      const GyroTrace second = SynthesizeTrace(options, 1, &saturated);
      summary.saturated_values += saturated;
      WriteOne(output.out2_path, second, options, output);
    } catch (...) {
      std::remove(output.out_path.c_str());  // all or nothing across both files
      throw;
    }
  }
  return summary;
}

}  // namespace shutterlab
