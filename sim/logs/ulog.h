#pragma once
// PX4 ULog reader (file versions 0 and 1): the best gyro trace, camera events and altitude above
// ground, parsed from the file's own format definitions ('F' messages).
//
// Spec: PX4 "ULog File Format" (docs.px4.io, dev_log/ulog_file_format); behaviour on corrupt data
// follows PX4/pyulog core.py where the spec is silent (data messages may omit trailing _padding
// fields; an unknown message type means corruption).

#include "sim/gyro_source.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/gyro_candidates.h"
#include "sim/text_file.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

// True when first_bytes begins with the ULog magic "ULog" 0x01 0x12 0x35 (needs 7 bytes or more).
bool LooksLikeULog(std::string_view first_bytes);

// Reads a .ulg file. Times: the log's boot clock (PX4 microseconds since boot) as int64 ns.
// Gyro candidates, best raw source first: sensor_gyro_fifo (int16 * scale, up to 32 samples a
// message at timestamp_sample - (n-1-i)*dt, so timestamp_sample is the newest sample's time),
// sensor_gyro (x,y,z at timestamp_sample), vehicle_angular_velocity (xyz at timestamp_sample),
// sensor_combined (gyro_rad at timestamp). Each topic instance (multi_id) is one candidate, named
// "topic.field" for instance 0 and "topic/N.field" for instance N. The one with the highest
// measured rate wins; candidates within 10% of that rate are ranked by the order above
// (internal::ChooseGyroSource in sim/logs/gyro_candidates.h, shared with the DataFlash reader).
// gyro_sources_available lists every candidate as "NAME (RATE Hz, N samples)", chosen one first.
// Camera events: camera_trigger and camera_capture (timestamp, seq).
// Altitude above ground: median of vehicle_local_position.dist_bottom where dist_bottom_valid,
// over the samples above kAirborneAltitudeM; else median of -(z - z_home) (home_position.z when
// logged, else the first local z) over the samples above kAirborneAltitudeM; a warning says which.
// Navigation: velocity from vehicle_local_position vx, vy, vz (NED) where v_xy_valid (vz where
// v_z_valid, else NaN), else from the GPS topic's vel_n_m_s, vel_e_m_s, vel_d_m_s where
// vel_ned_valid and fix_type >= 3 (a log without a valid estimate, as a bench or SITL log);
// attitude from vehicle_attitude.q (FRD body to NED), one every kAttitudeStepNs at most; the
// first instance of each that has samples.
// Dropouts ('O') become warnings; the gaps they leave show in gyro.sampling().
// Throws IoError (path, byte offset, problem) when the file is not ULog, sets an unknown
// incompatible flag, or holds no usable gyro data. Corrupt or truncated stretches are skipped
// (records_skipped, warnings) and reading resumes at the next plausible message.
FlightLog ReadULog(const std::string& path);

// The same on bytes already in memory; path is used in messages only.
FlightLog ParseULog(std::string_view bytes, const std::string& path);

// A ULog read as a stream, in memory that does not grow with the number of gyro samples. Opening
// reads the file once (pass 1): everything but the gyro samples, and of each gyro candidate only
// what choosing and cleaning it needs; `gyro` then reads the file again (pass 2) and hands on the
// chosen candidate's cleaned samples in chunks of at most chunk_samples. Together they give
// exactly what ReadULog gives (ReadULog is this stream read whole).
struct ULogStream {
  FlightLog log;                     // all but the samples (log.gyro stays empty)
  std::unique_ptr<GyroSource> gyro;  // the samples; Fraction() is the share of the file read
};
// A file, mapped and read front to back: the pages behind the parse are handed back as it goes.
// Throws IoError as ReadULog does; the source throws IoError when the file has changed (still
// being recorded, or rewritten: MappedFile::CheckUnchanged) between the passes.
ULogStream OpenULog(const std::string& path,
                    size_t chunk_samples = FillingSource::kDefaultChunkSamples);
// The same over a file mapped already (a pipe's bytes copied: TextBlocks::TakeMapped); progress
// (may be empty) is given the share of the bytes pass 1 has read as it goes.
ULogStream OpenULog(std::unique_ptr<MappedFile> file,
                    size_t chunk_samples = FillingSource::kDefaultChunkSamples,
                    const OpeningProgress& progress = {});

namespace internal {
// Bytes in memory, owned by the stream, with the limits of pass 1's candidate summaries chosen:
// small limits take the fallback (a topic instance's times held whole, with a warning) on small
// inputs (tests, fuzzing).
ULogStream OpenULogBytes(std::string bytes, const std::string& path, size_t chunk_samples,
                         const CandidateLimits& limits);
}  // namespace internal

// A vehicle below this height is taken to be on the ground when the altitude median is formed.
inline constexpr double kAirborneAltitudeM = 1.0;

}  // namespace shutterlab
