#include "sim/logs/gyro_row_shapes.h"

#include "sim/text_file.h"

#include <cstring>
#include <immintrin.h>

namespace shutterlab {

// A row's reading, worked out from its shape. Each number's digits are gathered by vpshufb into
// the high end of a 16-byte lane, most significant first, zeros before them, then converted as
// one integer of 16 digits (ConvertLanes).
struct GyroRowShapes::Shape {
  alignas(32) uint8_t bytes[64];     // the row's non-digit bytes in place; 0 at digits and after it
  alignas(32) uint8_t t_digits[32];  // of the 32 bytes at the row's start: t's digits among bytes
                                     // 0-15 into lane 0, among bytes 16-31 into lane 1
  alignas(32) uint8_t xy_digits[32];  // of the 16 bytes at gx's start (lane 0), at gy's (lane 1)
  alignas(16) uint8_t z_digits[16];   // of the 16 bytes at gz's start
  alignas(32) double divisor[4];      // 10^(digits after the point) of gx, gy, gz; 1
  alignas(32) uint64_t sign[4];       // the sign bit of gx, gy, gz; 0
  uint64_t key = 0;          // bit i: byte i of the row is no digit; the highest is its '\n'
  uint64_t t_low_scale = 1;  // 10^(t's digits in lane 1)
  uint64_t t_max = 0;        // the largest of t's digits as one integer with whole seconds <= 9e9
  uint64_t t_ns_scale = 1;   // ns in a unit of t's last digit: 10^(9 - digits after the point)
  uint8_t rate_start[3] = {};
};

namespace {

constexpr int kSlotBits = 7;
constexpr size_t kRowBytes = 64;  // the longest row a shape reads, its '\n' included
// Every this many rows, shapes stop being used when more than a quarter of them had none.
constexpr uint64_t kMissCheckRows = 4096;

size_t Slot(uint64_t key) { return (key * 0x9E3779B97F4A7C15ull) >> (64 - kSlotBits); }

constexpr uint64_t Pow10(int n) {
  uint64_t v = 1;
  while (n-- > 0) v *= 10;
  return v;
}

// Where a number's digits lie in a 16-byte lane, ascending (at most 16).
struct LanePositions {
  uint8_t at[16];
  int count = 0;
  void Add(int position) { at[count++] = static_cast<uint8_t>(position); }
};

// The shuffle for one 16-byte lane: the digits at `positions` into its last bytes, in order;
// 0x80 (a zero byte) before them.
void GatherInto(uint8_t* lane, const LanePositions& positions) {
  std::memset(lane, 0x80, 16);
  std::memcpy(lane + 16 - positions.count, positions.at, positions.count);
}

// Each 16-byte lane's digits (0 to 9 a byte, most significant first) as one integer, in the low
// 64 bits of the lane.
__attribute__((target("avx2"))) inline __m256i ConvertLanes(__m256i digits) {
  const __m256i pairs = _mm256_maddubs_epi16(digits, _mm256_set1_epi16(0x010A));    // 10a + b
  const __m256i fours = _mm256_madd_epi16(pairs, _mm256_set1_epi32(0x00010064));    // 100a + b
  const __m256i packed = _mm256_packus_epi32(fours, fours);                         // to 16 bits
  const __m256i eights = _mm256_madd_epi16(packed, _mm256_set1_epi32(0x00012710));  // 10^4 a + b
  return _mm256_add_epi64(_mm256_mul_epu32(eights, _mm256_set1_epi64x(100000000)),  // 10^8 a + b
                          _mm256_srli_epi64(eights, 32));
}

__attribute__((target("avx2"))) inline uint64_t DigitMask(__m256i bytes) {
  const __m256i value = _mm256_sub_epi8(bytes, _mm256_set1_epi8('0'));
  const __m256i digit = _mm256_cmpeq_epi8(_mm256_min_epu8(value, _mm256_set1_epi8(9)), value);
  return static_cast<uint32_t>(_mm256_movemask_epi8(digit));
}

__attribute__((target("avx2"))) inline uint64_t EqualMask(__m256i a, __m256i b) {
  return static_cast<uint32_t>(_mm256_movemask_epi8(_mm256_cmpeq_epi8(a, b)));
}

}  // namespace

GyroRowShapes::GyroRowShapes() : enabled_(__builtin_cpu_supports("avx2")) {
  if (enabled_) shapes_.resize(size_t{1} << kSlotBits);
}

GyroRowShapes::~GyroRowShapes() = default;

__attribute__((target("avx2"))) const char* GyroRowShapes::Read(const char* p, GyroSample* s) {
  if (++rows_ % kMissCheckRows == 0) {
    if (misses_ * 4 > kMissCheckRows) enabled_ = false;
    misses_ = 0;
  }
  const __m256i low = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  const __m256i high = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 32));
  const uint64_t breaks =
      EqualMask(low, _mm256_set1_epi8('\n')) | EqualMask(high, _mm256_set1_epi8('\n')) << 32;
  if (breaks == 0) {  // no row in these 64 bytes (and 64 digits would give key 0, an empty slot's)
    ++misses_;
    return nullptr;
  }
  const uint64_t digits = DigitMask(low) | DigitMask(high) << 32;
  const uint64_t row = breaks ^ (breaks - 1);  // the row's bytes, its first '\n' the last
  const uint64_t key = ~digits & row;          // never 0: the '\n' is in it
  const Shape& shape = shapes_[Slot(key)];
  const uint64_t same =
      EqualMask(low, _mm256_load_si256(reinterpret_cast<const __m256i*>(shape.bytes))) |
      EqualMask(high, _mm256_load_si256(reinterpret_cast<const __m256i*>(shape.bytes + 32))) << 32;
  if (shape.key != key || (same & row) != key) {
    ++misses_;
    return nullptr;
  }
  const __m256i zero_digit = _mm256_set1_epi8('0');
  // t: all its digits as one integer, then scaled to ns.
  const __m256i t = ConvertLanes(
      _mm256_shuffle_epi8(_mm256_sub_epi8(low, zero_digit),
                          _mm256_load_si256(reinterpret_cast<const __m256i*>(shape.t_digits))));
  const uint64_t t_digits = static_cast<uint64_t>(_mm256_extract_epi64(t, 0)) * shape.t_low_scale +
                            static_cast<uint64_t>(_mm256_extract_epi64(t, 2));
  if (t_digits > shape.t_max) {
    ++misses_;
    return nullptr;
  }
  // The rates: gx and gy in one register's lanes, gz in another's first.
  const __m256i xy_bytes =
      _mm256_loadu2_m128i(reinterpret_cast<const __m128i*>(p + shape.rate_start[1]),
                          reinterpret_cast<const __m128i*>(p + shape.rate_start[0]));
  const __m256i xy = ConvertLanes(
      _mm256_shuffle_epi8(_mm256_sub_epi8(xy_bytes, zero_digit),
                          _mm256_load_si256(reinterpret_cast<const __m256i*>(shape.xy_digits))));
  const __m128i z_bytes =
      _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + shape.rate_start[2]));
  const __m256i z = ConvertLanes(_mm256_zextsi128_si256(
      _mm_shuffle_epi8(_mm_sub_epi8(z_bytes, _mm_set1_epi8('0')),
                       _mm_load_si128(reinterpret_cast<const __m128i*>(shape.z_digits)))));
  // [gx, gy, gz, 0] as integers (each below 10^15 < 2^52), to doubles exactly by the 2^52 trick,
  // then one correctly rounded division each: what ClingerDecimal computes.
  const __m256i xyz = _mm256_permute4x64_epi64(_mm256_unpacklo_epi64(xy, z), 0b11'01'10'00);
  const __m256i two52_bits = _mm256_set1_epi64x(0x4330000000000000);
  const __m256d mantissas = _mm256_sub_pd(_mm256_castsi256_pd(_mm256_or_si256(xyz, two52_bits)),
                                          _mm256_castsi256_pd(two52_bits));
  const __m256d rates = _mm256_xor_pd(_mm256_div_pd(mantissas, _mm256_load_pd(shape.divisor)),
                                      _mm256_load_pd(reinterpret_cast<const double*>(shape.sign)));
  s->t_ns = static_cast<int64_t>(t_digits * shape.t_ns_scale);
  _mm_storeu_pd(&s->omega_rad_s[0], _mm256_castpd256_pd128(rates));
  _mm_store_sd(&s->omega_rad_s[2], _mm256_extractf128_pd(rates, 1));
  return p + (64 - __builtin_clzll(key));
}

void GyroRowShapes::Learn(const char* p, const char* row_end) {
  if (!enabled_ || row_end - p > static_cast<ptrdiff_t>(kRowBytes)) return;
  Shape shape;
  std::memset(shape.bytes, 0, sizeof(shape.bytes));
  const int length = static_cast<int>(row_end - p);
  int i = 0;
  // t: 1 to 10 whole digits, a point and 0 to 9 more or none.
  LanePositions t_low, t_high;  // t's digits among bytes 0-15, among 16-31
  const auto take_t_digits = [&]() {
    int n = 0;
    for (; i < length && i < 32 && IsDecimalDigit(p[i]); ++i, ++n)
      (i < 16 ? t_low : t_high).Add(i % 16);
    return n;
  };
  const int whole = take_t_digits();
  if (whole == 0 || whole > 10) return;
  int places = 0;
  if (i < length && p[i] == '.') {
    ++i;
    places = take_t_digits();
  }
  if (places > 9 || i >= length || p[i] != ',' || i > 32) return;
  GatherInto(shape.t_digits, t_low);
  GatherInto(shape.t_digits + 16, t_high);
  shape.t_low_scale = Pow10(t_high.count);
  shape.t_max = (9'000'000'000 + 1) * Pow10(places) - 1;
  shape.t_ns_scale = Pow10(9 - places);
  // The rates: an optional '-', then digits with a point or none, 1 to 15 digits in all.
  uint8_t* const rate_digits[3] = {shape.xy_digits, shape.xy_digits + 16, shape.z_digits};
  for (int axis = 0; axis < 3; ++axis) {
    const int start = ++i;  // after the ',' before it
    const bool negative = i < length && p[i] == '-';
    i += negative;
    LanePositions positions;
    int after_point = 0;
    for (; i < length && i - start < 16 && IsDecimalDigit(p[i]); ++i) positions.Add(i - start);
    if (i < length && i - start < 16 && p[i] == '.') {
      for (++i; i < length && i - start < 16 && IsDecimalDigit(p[i]); ++i, ++after_point)
        positions.Add(i - start);
    }
    const char end = axis < 2 ? ',' : '\n';
    if (positions.count == 0 || positions.count > 15 || i >= length || p[i] != end) return;
    GatherInto(rate_digits[axis], positions);
    shape.rate_start[axis] = static_cast<uint8_t>(start);
    shape.divisor[axis] = kExactPow10[after_point];
    shape.sign[axis] = uint64_t{negative} << 63;
  }
  if (i + 1 != length) return;  // the '\n' is the row's last byte
  shape.divisor[3] = 1.0;
  shape.sign[3] = 0;
  shape.key = 0;
  for (int b = 0; b < length; ++b) {
    if (IsDecimalDigit(p[b])) continue;
    shape.key |= uint64_t{1} << b;
    shape.bytes[b] = static_cast<uint8_t>(p[b]);
  }
  shapes_[Slot(shape.key)] = shape;
}

}  // namespace shutterlab
