#pragma once
// ArduPilot DataFlash (.bin) reader: the best gyro trace, camera events and altitude, with
// message layouts taken from the file's own FMT messages.
//
// Layout: a stream of messages 0xA3 0x95 <msg type> <payload>; type 128 is FMT (type, length
// including the 3 header bytes, name[4], format[16], labels[64]), which defines every other type.
// Format characters (ArduPilot AP_Logger/LogStructure.h): b B h H i I f d q Q n(char[4])
// N(char[16]) Z(char[64]) M(uint8 mode) c C(int16/uint16 * 0.01) e E(int32/uint32 * 0.01)
// L(int32 * 1e-7 degrees) a(int16[32]) g(float16).

#include "sim/logs/flight_log.h"

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
// Throws IoError (path, byte offset, problem) when the file is not DataFlash or has no usable gyro
// data. Corrupt stretches are skipped up to the next plausible message (records_skipped,
// warnings); a truncated tail is reported in warnings.
FlightLog ReadDataFlash(const std::string& path);

// The same on bytes already in memory; path is used in messages only.
FlightLog ParseDataFlash(std::string_view bytes, const std::string& path);

}  // namespace shutterlab
