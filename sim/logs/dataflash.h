#pragma once
// ArduPilot DataFlash (.bin) reader: the best gyro trace, camera events and altitude, with
// message layouts taken from the file's own FMT messages.
//
// Layout: a stream of messages 0xA3 0x95 <msg type> <payload>; type 128 is FMT (type, length
// including the 3 header bytes, name[4], format[16], labels[64]), which defines every other type.
// Format characters (ArduPilot AP_Logger/LogStructure.h): b B h H i I f d q Q n(char[4])
// N(char[16]) Z(char[64]) M(uint8 mode) c C(int16/uint16 * 0.01) e E(int32/uint32 * 0.01)
// L(int32 * 1e-7 degrees) a(int16[32]) g(float16).

#include "sim/gyro_source.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/gyro_candidates.h"
#include "sim/text_file.h"

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace shutterlab {

// True when first_bytes begins with a DataFlash FMT message (0xA3 0x95 0x80); when 5 bytes or more
// are given, also the FMT-of-FMT's own type 128 and length 89.
bool LooksLikeDataFlash(std::string_view first_bytes);

// Reads a .bin file. Times: the log's boot clock (TimeUS, µs since boot) as int64 ns.
// Gyro candidates (per instance; "NAME" for instance 0, "NAME/N" otherwise), best raw first:
//  - "GYR": GyrX/GyrY/GyrZ (rad/s) at SampleUS (TimeUS when absent);
//  - "ISBD": the batch sampler, ISBH type 1 (gyro) headers; sample k of ISBD packet `seqno` is at
//    ISBH.SampleUS + (32 * seqno + k) / smp_rate, value raw / ISBH.mul rad/s, k < smp_cnt;
//  - "IMU" (and IMU2/IMU3 of old logs): GyrX/GyrY/GyrZ at TimeUS.
// The highest measured rate wins; within 10% of it, the order above decides
// (internal::ChooseGyroSource in sim/logs/gyro_candidates.h, shared with the ULog reader).
// Camera events: CAM and TRIG at TimeUS, sequence from Img when logged.
// Altitude above ground: median CAM.RelAlt (height above home at each picture) above
// kAirborneAltitudeM, when CAM has RelAlt; a warning says so.
// Navigation: velocity from the EKF (XKF1, NKF1 or EKF1 VN, VE, VD of core 0), else from the
// first GPS's 3-D fixes (Spd along GCrs, VZ down); attitude from ATT Roll, Pitch, Yaw (Z-Y-X, FRD
// body to NED), one every kAttitudeStepNs at most. Both on the boot clock (GPS only with TimeUS).
// Throws IoError (path, byte offset, problem) when the file is not DataFlash or has no usable gyro
// data. Corrupt stretches are skipped up to the next plausible message (records_skipped,
// warnings); a truncated tail is reported in warnings.
FlightLog ReadDataFlash(const std::string& path);

// The same on bytes already in memory; path is used in messages only.
FlightLog ParseDataFlash(std::string_view bytes, const std::string& path);

// A DataFlash log read in two passes over its bytes, in memory that does not grow with the number
// of gyro samples. Opening makes pass 1: everything but the samples (formats, camera events, GPS
// fixes, altitude, warnings, records_skipped), and of each gyro stream a bounded summary
// (sim/logs/gyro_candidates.h CandidateSummary) from which the stream is chosen. `samples` is pass
// 2: it parses the bytes again and hands out the chosen stream's cleaned samples in chunks of
// chunk_samples, exactly those ReadDataFlash gives; Fraction() is the share of the bytes parsed. A
// file is mapped and its pages handed back behind the parser every 8 MiB; a file that changed
// between the passes (still being recorded, or rewritten: MappedFile::CheckUnchanged) is an
// IoError naming it. A stream too disordered for
// the summary's limits is summarised again without them (memory then grows with it), said in a
// "memory" warning.
struct DataFlashStream {
  FlightLog log;  // all but the samples (log.gyro stays empty)
  std::unique_ptr<GyroSource> samples;
};
// A file, mapped; the same over a file mapped already (a pipe's bytes copied to a temporary file:
// TextBlocks::TakeMapped), where progress (may be empty) is given the share of the bytes pass 1
// has read as it goes.
DataFlashStream OpenDataFlash(const std::string& path,
                              size_t chunk_samples = FillingSource::kDefaultChunkSamples);
DataFlashStream OpenDataFlash(std::unique_ptr<MappedFile> file,
                              size_t chunk_samples = FillingSource::kDefaultChunkSamples,
                              const OpeningProgress& progress = {});
// Bytes in memory, which must outlive the stream; path is used in messages only. limits: pass 1's
// (tests and fuzzing choose small ones to reach the way without them).
DataFlashStream OpenDataFlash(std::string_view bytes, const std::string& path,
                              size_t chunk_samples = FillingSource::kDefaultChunkSamples,
                              internal::CandidateLimits limits = {});

}  // namespace shutterlab
