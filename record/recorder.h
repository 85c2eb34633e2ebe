#pragma once
// `shutterlab record`: gyro samples from one or two sensors' FIFOs, and camera trigger edges, on
// one clock, written without ever pausing the reads.
//
// Threads: one reader reads every sensor's FIFO (record/gyro_driver.h) at dithered instants a
// fraction of the FIFO's fill time apart, stamps each sample from the FIFO counts
// (record/fifo_clock.h) and pushes it into that sensor's ring (record/sample_ring.h); it
// never waits for anything but its next read. One writer drains the rings every 20 ms into each
// sensor's file; a slow write (an SD card's garbage collection) only fills the ring. A trigger
// thread collects GPIO edges (record/trigger_source.h). Everything the reader could not read
// is a gap with its time and the samples it cost, counted and written into the log:
//   fifo_overflow  the FIFO filled between two reads (the reader was late)
//   bad_data       a FIFO count or packet the configuration cannot give (a bus error)
//   missed_read    an SPI transfer failed
//   part_reset     WHO_AM_I or the configuration read back wrong (a brown-out, a loose wire); the
//                  part is configured again
//   buffer_full    the ring was full (the writer was slower for longer than the ring holds)
// The samples a gap cost are counted from the fitted sample clock: the index of the first sample
// after the gap is the number the part had produced by then.
//
// Output per sensor: a Gyroflow .gcsv (record/record_output.h) with the raw counts, the
// settings, the still bias, the clock fit and every gap in its header; the camera triggers in a
// file `analyze --triggers` reads. Times are seconds from the recorder's start on its clock, the
// same for every file of one recording. Each file is written whole at the end (the samples go to a
// temporary file beside it while recording): a stop by SIGINT or SIGTERM (RecorderOptions::stop)
// still gives whole files; a crash leaves the temporary files and no output.

#include "record/clock.h"
#include "record/recording.h"

#include <vector>

namespace shutterlab {

// Configures every sensor (throws IoError for a wrong WHO_AM_I before anything is written), records
// until the duration or *stop, and writes the files. Throws IoError when a file cannot be written,
// or when a sensor recorded no sample (stopped before its first); no output is left then.
RecordSummary Record(const std::vector<RecordSensor>& sensors, const RecorderOptions& options,
                     Clock& clock);

}  // namespace shutterlab
