#pragma once
// Raw-count gyro logs of the source paper's logger (an InvenSense MPU-9250 read over SPI by a
// Raspberry Pi): one sample per line `t,gx,gy,gz[,...]`, an optional header line, gx..gz the
// sensor's int16 output registers, t in s, ms, us or ns.

#include "sim/gyro_source.h"
#include "sim/gyro_trace.h"
#include "sim/text_file.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace shutterlab {

// Time unit of a raw-count log's time column.
enum class TimeUnit { kSeconds, kMilliseconds, kMicroseconds, kNanoseconds };

// Nanoseconds per unit (1e9, 1e6, 1e3, 1).
int64_t NanosecondsPerUnit(TimeUnit unit);

// Gyro sensitivity in LSB per deg/s for a full-scale range of 250, 500, 1000 or 2000 deg/s:
// 131, 65.5, 32.8, 16.4 (MPU-9250 Product Specification rev 1.1, table 1, GYRO_FS_SEL 0..3).
// Throws std::invalid_argument naming the range otherwise.
double RawSensitivityLsbPerDps(int range_dps);

// Reads a raw-count log; rates are converted to rad/s about the sensor axes. A first line whose
// first four fields are not numbers is a header (e.g. "t,gx,gy,gz"); columns after gz are
// ignored. Throws IoError "PATH:LINE: problem" when a count is not an integer or lies outside
// int16 [-32768, 32767], a field is missing or not numeric, or the time goes backwards; throws
// std::invalid_argument for an unknown range.
GyroTrace ReadRawCsv(const std::string& path, int range_dps, TimeUnit time_unit);
// The same as a stream, parsed a block at a time as the chunks are taken; path names the file in
// messages; chunk_samples bounds each chunk.
std::unique_ptr<GyroSource> OpenRawCsv(TextBlocks blocks, const std::string& path, int range_dps,
                                       TimeUnit time_unit,
                                       size_t chunk_samples = FillingSource::kDefaultChunkSamples);

// Header of the raw-count logs we write: not gyro.csv's "t,gx,gy,gz", so that detection can tell
// counts from rad/s (a docs/FORMATS.md header always means gyro.csv).
inline constexpr const char* kRawCsvHeader = "t,gx_counts,gy_counts,gz_counts";

// Writes a raw-count log with the header kRawCsvHeader: rates quantised to the nearest count of the
// range's sensitivity; times written exactly in time_unit (integers for ns, a decimal fraction
// otherwise). A rate beyond full scale saturates at -32768 / 32767, as the sensor does. Returns the
// number of saturated values. Writes whole or not at all (IoError on failure).
size_t WriteRawCsv(const std::string& path, const GyroTrace& trace, int range_dps,
                   TimeUnit time_unit = TimeUnit::kSeconds);

// Parses a time field given in `unit` to ns. A plain decimal ("-12.345") converts exactly, so a ns
// or us clock keeps every tick even beyond 2^53 ns; an exponent form goes through double and rounds
// to the ns. nullopt when the field is not a finite number or overflows int64 ns.
std::optional<int64_t> ParseTimeInUnitNs(std::string_view field, TimeUnit unit);
// Appends t_ns in `unit`, exactly: integer part, then the fraction without trailing zeros.
void AppendTimeInUnit(int64_t t_ns, TimeUnit unit, std::string* out);

// One rate in rad/s to the nearest int16 count, saturating; *saturated set when it clipped.
int16_t RateToCount(double omega_rad_s, double lsb_per_dps, bool* saturated);

}  // namespace shutterlab
