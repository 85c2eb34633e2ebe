#pragma once
// The raw gyro dump of a phone capture app (the lhaippp/gyro-video-stabilization recordings'
// gyro_dump.txt, the file their gyro.txt and framestamp.txt were made from): one gyro sample per
// line, `frameid:N gyro:K x X y Y z Z ts T` (rates in rad/s about the sensor's axes, T in
// microseconds on the device clock), among start-of-frame lines `SOF T, frameNum :N exp time E`.
// Each frame's batch repeats the last sample of the batch before it: a sample whose time and
// rates equal the one before is left out, and counted in a `repeated_sample` warning.

#include "sim/gyro_source.h"
#include "sim/text_file.h"

#include <memory>
#include <string>
#include <string_view>

namespace shutterlab {

// Whether text (a file's start) is such a dump: its first non-empty line is a gyro line
// (`frameid:`) or a start-of-frame line (`SOF `).
bool LooksLikeGyroDump(std::string_view first_bytes);

// The dump's samples, parsed a block at a time as the chunks are taken; path names the file in
// messages. Start-of-frame lines are skipped. Throws IoError "PATH:LINE: problem" on a gyro line of
// another shape, a value that is not a number, or a time going backwards; a last line cut short
// (no line break) is left out with a `truncated` warning.
std::unique_ptr<GyroSource> OpenGyroDump(
    TextBlocks blocks, const std::string& path,
    size_t chunk_samples = FillingSource::kDefaultChunkSamples);

}  // namespace shutterlab
