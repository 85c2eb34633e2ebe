#pragma once
// gyro.csv rows read by their shape: where a row's non-digit bytes lie ("0.123,-0.000294,...\n":
// the point, the commas, the signs, the line break). A log writes a few shapes over and over
// (fixed decimals and their signs), so each shape's reading is worked out once, when a row of it
// is first read another way (Learn), and every later row of that shape is read with AVX2: 64
// bytes classified at once, each number's digits gathered by one shuffle and converted together,
// with no byte loop and no branch on the digits (docs/speed.md). The values are exactly what the
// byte-by-byte reading gives: the same integers and the same one correctly rounded division.

#include "sim/gyro_trace.h"

#include <cstdint>
#include <vector>

namespace shutterlab {

class GyroRowShapes {
 public:
  // Bytes that Read may load from a row's start: a row is read by shape only with this many bytes
  // of the buffer at and after it.
  static constexpr size_t kReadBytes = 80;

  // Shapes are used only on a CPU with AVX2; enabled() is false elsewhere, and Read never reads.
  GyroRowShapes();
  ~GyroRowShapes();  // where Shape is complete

  bool enabled() const { return enabled_; }
  void Disable() { enabled_ = false; }

  // The row at p (kReadBytes readable from p) read into *s when its shape is known and its values
  // are in range: the position after its '\n'. nullptr otherwise (a shape not seen, or a row no
  // shape reads: more than 64 bytes, '\r', extra columns, exponents, spaces ...), for the caller to
  // read another way.
  const char* Read(const char* p, GyroSample* s);

  // Learns the shape of the row [p, row_end) (row_end after its '\n'), just read another way,
  // when a shape can read it: "t,gx,gy,gz\n", t plain decimal digits (1 to 10 before the point, 0
  // to 9 after), each rate an optional '-' and 1 to 15 digits with or without a point, each number
  // at most 16 bytes (t: 32), the row at most 64. Stops using shapes (enabled() false) when too
  // few rows turn out to have a known one: a log whose every row differs pays the classifying for
  // nothing.
  void Learn(const char* p, const char* row_end);

 private:
  struct Shape;
  std::vector<Shape> shapes_;  // a hash table: a shape's slot by its key; key 0 is empty
  bool enabled_ = false;
  uint64_t rows_ = 0, misses_ = 0;  // rows given to Read, and those it did not read
};

}  // namespace shutterlab
