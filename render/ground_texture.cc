#include "render/ground_texture.h"

#include "sim/check.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

// ---- Fixed point, hashing, random numbers ----------------------------------------------------

// Positions along a direction are in 1/kOne px ("sub" px) and unit vectors have length kOne. With
// sides up to kMaxSide and scene objects kept within about a frame of the image, a projection
// (x - cx) * dir.x + (y - cy) * dir.y stays well inside int32. (>> of a negative value is an
// arithmetic shift on every compiler, and C++20 requires it.)
constexpr int kOne = 1 << 14;
constexpr int kMaxSide = 16384;

// SplitMix64's finaliser: a good 64-bit mix, the same on every machine.
uint64_t Mix64(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

uint32_t Hash(int64_t a, int64_t b, uint64_t stream) {
  return static_cast<uint32_t>(
      Mix64(stream ^
            Mix64(static_cast<uint64_t>(a) * 0x9e3779b97f4a7c15ULL + static_cast<uint64_t>(b))) >>
      32);
}

// PCG32 (O'Neill): small, fast, and its output is fixed by its definition, unlike the
// std::uniform_*_distribution adaptors. Draws are one per statement (or in a braced list, which
// C++ evaluates left to right): the order of a call's arguments or a product's operands is
// unspecified, and compilers differ.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(Mix64(seed) + kIncrement) { Next(); }
  uint32_t Next() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + kIncrement;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18) ^ old) >> 27);
    const uint32_t rotation = static_cast<uint32_t>(old >> 59);
    return (xorshifted >> rotation) | (xorshifted << ((32 - rotation) & 31));
  }
  // Uniform in [lo, hi] (Lemire's multiply-shift; its bias, below (hi - lo + 1) / 2^32, does not
  // matter here).
  int Int(int lo, int hi) {
    return lo + static_cast<int>((uint64_t{Next()} * static_cast<uint64_t>(hi - lo + 1)) >> 32);
  }
  bool Percent(int percent) { return Int(0, 99) < percent; }
  int Sign() { return Percent(50) ? 1 : -1; }

 private:
  static constexpr uint64_t kIncrement = 1442695040888963407ULL;
  uint64_t state_;
};

int64_t ISqrt(int64_t n) {
  if (n <= 0) return 0;
  int64_t r = static_cast<int64_t>(std::sqrt(static_cast<double>(n)));
  while (r * r > n) --r;
  while ((r + 1) * (r + 1) <= n) ++r;
  return r;
}

// A unit vector (length kOne).
struct Dir {
  int x = kOne, y = 0;
};

Dir DirOf(int64_t dx, int64_t dy) {
  if (dx == 0 && dy == 0) return {};
  while (std::abs(dx) < (1 << 20) && std::abs(dy) < (1 << 20)) dx *= 2, dy *= 2;
  const int64_t length = ISqrt(dx * dx + dy * dy);
  return {static_cast<int>(dx * kOne / length), static_cast<int>(dy * kOne / length)};
}
Dir Perp(Dir d) { return {-d.y, d.x}; }
Dir Turn(Dir d, Dir by) {
  return DirOf(int64_t{d.x} * by.x - int64_t{d.y} * by.y,
               int64_t{d.x} * by.y + int64_t{d.y} * by.x);
}
// A direction turned from `d` by a random angle up to atan(max_tan_permille / 1000) either way:
// a random slope, normalised, so no trigonometric function (whose last bits vary by libm).
Dir Near(Rng& rng, Dir d, int max_tan_permille) {
  return Turn(d, DirOf(1000, rng.Int(-max_tan_permille, max_tan_permille)));
}

// Local coordinates around a centre: U along the axis, V across it (1/kOne px).
struct Frame {
  int cx = 0, cy = 0;
  Dir axis;
  int U(int x, int y) const { return (x - cx) * axis.x + (y - cy) * axis.y; }
  int V(int x, int y) const { return (y - cy) * axis.x - (x - cx) * axis.y; }
  cv::Point ToImage(int64_t u, int64_t v) const {
    const int64_t kOne2 = int64_t{kOne} * kOne;
    return {cx + static_cast<int>((u * axis.x - v * axis.y) / kOne2),
            cy + static_cast<int>((u * axis.y + v * axis.x) / kOne2)};
  }
  // Image box around the local rectangle |U| <= hu, |V| <= hv, with margin_px.
  cv::Rect Box(int64_t hu, int64_t hv, int margin_px) const {
    int x0 = cx, x1 = cx, y0 = cy, y1 = cy;
    for (int su : {-1, 1}) {
      for (int sv : {-1, 1}) {
        const cv::Point p = ToImage(su * hu, sv * hv);
        x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y),
        y1 = std::max(y1, p.y);
      }
    }
    return {x0 - margin_px, y0 - margin_px, x1 - x0 + 2 * margin_px + 1,
            y1 - y0 + 2 * margin_px + 1};
  }
};

// The columns [first, last] of a row where f(x) = f0 + x * slope may lie in [lo, hi], clipped to
// [0, width - 1], a pixel wider each side than exact: callers still test each pixel, this only
// skips the rest of the row.
std::pair<int, int> ColumnsWithin(int64_t f0, int64_t slope, int64_t lo, int64_t hi, int width) {
  if (slope == 0)
    return f0 >= lo && f0 <= hi ? std::make_pair(0, width - 1) : std::make_pair(0, -1);
  auto floor_div = [](int64_t a, int64_t b) {
    return a / b - ((a % b != 0) && ((a < 0) != (b < 0)));
  };
  int64_t first = floor_div(lo - f0, slope), last = floor_div(hi - f0, slope);
  if (first > last) std::swap(first, last);
  return {static_cast<int>(std::max<int64_t>(first - 1, 0)),
          static_cast<int>(std::min<int64_t>(last + 1, width - 1))};
}

// Share 0..256 of a pixel inside an edge, from its signed distance to the edge (1/kOne px,
// positive inside). soft_px = 1 is a sharp, anti-aliased edge; larger values blur it (penumbra).
int Cover(int64_t inside, int soft_px = 1) {
  const int64_t in_256ths = inside / (kOne / 256);  // a shift; the soft division only when asked
  return static_cast<int>(
      std::clamp<int64_t>((soft_px == 1 ? in_256ths : in_256ths / soft_px) + 128, 0, 256));
}

// Smooth 0..256 periodic profile (a smoothstep triangle, close to a raised cosine).
const std::array<int, 256>& WaveTable() {
  static const std::array<int, 256> table = [] {
    std::array<int, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const int tri = 255 - std::abs(2 * i - 255);  // 0 .. 255 .. 0
      t[i] = tri * tri * (3 * 255 - 2 * tri) / (255 * 255) * 256 / 255;
    }
    return t;
  }();
  return table;
}

// A pattern repeating every period along a projection (1/kOne px): crop rows, roof tiles, lines.
class Periodic {
 public:
  Periodic() = default;
  // Periods under 2 px are raised to 2 px: finer rows would only alias.
  Periodic(double period_px, uint32_t offset)
      : period_sub_(std::llround(std::max(2.0, period_px) * kOne)),
        mult_(std::llround(67108864.0 / std::max(2.0, period_px))),
        offset_(offset & 0xFFFF) {}
  // Position within the period, 0 .. 65535.
  int Phase(int64_t p) const { return static_cast<int>(((p * mult_) >> 24) + offset_) & 0xFFFF; }
  // Which period p is in.
  int64_t Cycle(int64_t p) const { return (((p * mult_) >> 24) + offset_) >> 16; }
  int Wave(int64_t p) const { return WaveTable()[Phase(p) >> 8]; }
  // Distance (1/kOne px) to the nearest period start: lines at phase 0.
  int64_t LineDistance(int64_t p) const {
    const int phase = Phase(p);
    return std::min(phase, 65536 - phase) * period_sub_ >> 16;
  }
  int64_t period_sub() const { return period_sub_; }

 private:
  int64_t period_sub_ = 2 * kOne, mult_ = 1 << 25;
  int offset_ = 0;
};

// ---- Colour ----------------------------------------------------------------------------------

struct Bgr {
  int b = 0, g = 0, r = 0;
};
constexpr Bgr Rgb(int r, int g, int b) { return {b, g, r}; }
// factor in 1/256.
Bgr Times(Bgr c, int factor) {
  return {c.b * factor / 256, c.g * factor / 256, c.r * factor / 256};
}
// weight 0..256 of b.
Bgr Mix(Bgr a, Bgr b, int weight) {
  return {a.b + (b.b - a.b) * weight / 256, a.g + (b.g - a.g) * weight / 256,
          a.r + (b.r - a.r) * weight / 256};
}
uchar Clamp8(int v) { return static_cast<uchar>(std::clamp(v, 0, 255)); }
Bgr Read(const cv::Vec3b& p) { return {p[0], p[1], p[2]}; }
void Write(cv::Vec3b& p, Bgr c) { p = cv::Vec3b(Clamp8(c.b), Clamp8(c.g), Clamp8(c.r)); }
void Blend(cv::Vec3b& p, Bgr c, int weight) {
  if (weight > 0) Write(p, Mix(Read(p), c, weight));
}
// A +-128 noise value as a brightness term of +-percent, in 1/256 (value noise mostly stays
// within +-64, so the typical swing is half of that).
int Amp(int centred, int percent) { return centred * percent / 50; }
// Tone with a per-object brightness and hue jitter.
Bgr Jitter(Rng& rng, Bgr c, int percent) {
  const int f = 256 + rng.Int(-percent, percent) * 256 / 100;
  return {c.b * (f + rng.Int(-8, 8)) / 256, c.g * (f + rng.Int(-8, 8)) / 256,
          c.r * (f + rng.Int(-8, 8)) / 256};
}

// ---- Smooth value noise ------------------------------------------------------------------------

// Random lattice values every cell_px, smoothstep-interpolated: 0..255 per pixel, precomputed for
// the whole image (one byte a pixel) because every step reads it.
class Noise {
 public:
  Noise(cv::Size size, int cell_px, uint64_t stream) : width_(size.width) {
    cell_px = std::max(cell_px, 2);
    const int lattice_w = size.width / cell_px + 2, lattice_h = size.height / cell_px + 2;
    std::vector<int> lattice(static_cast<size_t>(lattice_w) * lattice_h);
    for (int j = 0; j < lattice_h; ++j) {
      for (int i = 0; i < lattice_w; ++i) lattice[j * lattice_w + i] = Hash(i, j, stream) & 255;
    }
    std::vector<int> weight(cell_px);  // smoothstep over one cell, 0..256
    for (int o = 0; o < cell_px; ++o) {
      const int64_t t = int64_t{o} * 256 / cell_px;
      weight[o] = static_cast<int>(t * t * (3 * 256 - 2 * t) / (256 * 256));
    }
    values_.resize(static_cast<size_t>(size.width) * size.height);
    std::vector<int> between(lattice_w);  // the lattice interpolated to this row
    for (int y = 0; y < size.height; ++y) {
      const int* top = &lattice[(y / cell_px) * lattice_w];
      const int* bottom = top + lattice_w;
      const int wy = weight[y % cell_px];
      for (int i = 0; i < lattice_w; ++i) between[i] = top[i] * (256 - wy) + bottom[i] * wy;
      uint8_t* out = &values_[static_cast<size_t>(y) * width_];
      for (int x0 = 0, i = 0; x0 < size.width; x0 += cell_px, ++i) {
        const int start = between[i] * 256, step = between[i + 1] - between[i];
        const int cell_end = std::min(cell_px, size.width - x0);
        for (int o = 0; o < cell_end; ++o)
          out[x0 + o] = static_cast<uint8_t>((start + step * weight[o]) >> 16);
      }
    }
  }
  // Centred: -128 .. 127.
  int operator()(int x, int y) const {
    return int{values_[static_cast<size_t>(y) * width_ + x]} - 128;
  }

 private:
  int width_;
  std::vector<uint8_t> values_;
};

// Noise at the scales a ground surface varies on: moisture and growth patches (coarse), clumps
// and stones (medium, small), and the finest grain the camera resolves (fine, 3-4 px whatever the
// ground sample distance, so that every block has texture; finer grain would only alias).
struct Noises {
  Noise coarse, medium, small, fine;
};

// ---- The scene plan ----------------------------------------------------------------------------

struct Scale {
  double gsd_m;
  int Px(double metres) const { return std::max(1, static_cast<int>(std::lround(metres / gsd_m))); }
  int Sub(double metres) const { return static_cast<int>(std::lround(metres / gsd_m * kOne)); }
  double PxF(double metres) const { return metres / gsd_m; }
  int RandomPx(Rng& rng, double lo_m, double hi_m) const { return rng.Int(Px(lo_m), Px(hi_m)); }
};

// A random length in whole centimetres, as metres. (Whole numbers and one division: an expression
// like lo + k * 0.01 could be fused into one multiply-add on some machines and round differently.)
double Metres(Rng& rng, int lo_cm, int hi_cm) { return rng.Int(lo_cm, hi_cm) / 100.0; }

enum class Ground { kPloughed, kCereal, kRowCrop, kMeadow, kStubble, kLawn, kPaving };

struct Parcel {
  int64_t u0, u1, v0, v1;  // bounds in the layout frame, 1/kOne px
  Ground ground;
  Bgr tone;
  Dir across_rows;          // the direction crop rows alternate along
  Periodic rows, swaths;    // fine rows; wide bands (tramlines, mowing swaths)
  int line_half_gap_sub;    // tramlines: half the gap between the two tyre tracks
  int line_half_width_sub;  // tramlines: half a track's width
  int margin_sub;           // grass headland along the edges (0: none)
};

enum class RoadKind { kPaved, kTrack };

struct Road {
  Frame frame;  // U along the road, V across it
  RoadKind kind;
  int half_width_sub;  // asphalt, or the track's rutted width
  int verge_sub;       // gravel shoulder and grass beyond the half width
};

enum class Roof { kGable, kHip, kMetal, kFlat };

struct Building {
  Frame frame;  // U along the ridge
  int half_length_sub, half_width_sub;
  Roof roof;
  Bgr colour;
  int height_px;
  bool chimney;
  int chimney_u, chimney_v;  // its centre, 1/kOne px
  int radius_px() const {
    return static_cast<int>(ISqrt(int64_t{half_length_sub} * half_length_sub +
                                  int64_t{half_width_sub} * half_width_sub) /
                            kOne);
  }
};

struct Lobe {
  int dx, dy, r;  // px, from the tree centre
  // kOne * 2^16 / (2 r) and 2^24 / r^2: (r^2 - d^2) / (2 r) ~ r - d and (r^2 - d^2) / r^2 by
  // a multiply, for the per-pixel loop.
  int64_t per_2r, per_r2;
};

Lobe MakeLobe(int dx, int dy, int r) {
  return {dx, dy, r, int64_t{kOne} * 65536 / (2 * r), (int64_t{1} << 24) / (int64_t{r} * r)};
}

struct Tree {
  int cx, cy, radius_px;
  std::vector<Lobe> lobes;  // the canopy is their union: blobby, not round
  Bgr colour;
  int extent_px = 0;  // the farthest any lobe reaches from the centre
};

struct Scene {
  Frame layout;  // the fields' axis, centred on the image
  int hamlet_x, hamlet_y, hamlet_radius_px;
  Dir shadow;  // the direction shadows fall, away from the sun
  std::vector<Parcel> parcels;
  std::vector<Road> roads;  // painted in order: tracks, then the side road, the main road last
  std::vector<Building> buildings;
  std::vector<Tree> trees;
};

bool InHamlet(const Scene& scene, cv::Point p) {
  const int64_t dx = p.x - scene.hamlet_x, dy = p.y - scene.hamlet_y;
  const int64_t r = scene.hamlet_radius_px;
  return dx * dx + dy * dy < r * r;
}

// On a road's carriageway or its shoulder.
bool OnRoad(const Scene& scene, cv::Point p) {
  for (const Road& road : scene.roads) {
    if (std::abs(int64_t{road.frame.V(p.x, p.y)}) <
        int64_t{road.half_width_sub} + road.verge_sub / 2)
      return true;
  }
  return false;
}

// No road's carriageway and shoulder under any part of the footprint.
bool ClearOfRoads(const Scene& scene, const Building& b) {
  for (const Road& road : scene.roads) {
    const int64_t keep_out = int64_t{road.half_width_sub} + road.verge_sub / 2;
    int64_t lowest = INT64_MAX, highest = INT64_MIN;
    for (int su : {-1, 1}) {
      for (int sv : {-1, 1}) {
        const cv::Point p =
            b.frame.ToImage(int64_t{su} * b.half_length_sub, int64_t{sv} * b.half_width_sub);
        lowest = std::min<int64_t>(lowest, road.frame.V(p.x, p.y));
        highest = std::max<int64_t>(highest, road.frame.V(p.x, p.y));
      }
    }
    if (highest > -keep_out && lowest < keep_out) return false;
  }
  return true;
}

bool ClearOfBuildings(const Scene& scene, int x, int y, int radius_px) {
  for (const Building& b : scene.buildings) {
    const int64_t dx = x - b.frame.cx, dy = y - b.frame.cy, r = b.radius_px() + radius_px;
    if (dx * dx + dy * dy < r * r) return false;
  }
  return true;
}

// One parcel of the partition, [u0, u1) x [v0, v1) in layout units: its ground, tone, rows and
// swaths, drawn from rng (a garden in the hamlet, a field elsewhere). u_long: its long side runs
// along U.
Parcel MakeParcel(Rng& rng, const Scale& scale, const Frame& layout, int64_t u0, int64_t u1,
                  int64_t v0, int64_t v1, bool garden, bool u_long) {
  Parcel p;
  p.u0 = u0, p.u1 = u1, p.v0 = v0, p.v1 = v1;
  const int pick = rng.Int(0, 99);
  if (garden) {
    p.ground = pick < 55 ? Ground::kLawn : pick < 72 ? Ground::kPaving : Ground::kRowCrop;
  } else {
    p.ground = pick < 20   ? Ground::kPloughed
               : pick < 48 ? Ground::kCereal
               : pick < 66 ? Ground::kRowCrop
               : pick < 88 ? Ground::kMeadow
                           : Ground::kStubble;
  }
  // Rows mostly run with the parcel's long side, sometimes across it or at an angle.
  const Dir long_side = u_long ? layout.axis : Perp(layout.axis);
  const int row_pick = rng.Int(0, 99);
  p.across_rows = row_pick < 55   ? Perp(long_side)
                  : row_pick < 80 ? long_side
                                  : Near(rng, layout.axis, 1000);
  const uint32_t phase = rng.Next(), phase2 = rng.Next();
  p.margin_sub = garden ? 0 : rng.Percent(45) ? scale.Sub(Metres(rng, 30, 80)) : 0;
  switch (p.ground) {
    case Ground::kPloughed:
      p.tone = Jitter(rng, rng.Percent(50) ? Rgb(118, 92, 70) : Rgb(96, 78, 62), 8);
      p.rows = Periodic(scale.PxF(Metres(rng, 35, 55)), phase);
      break;
    case Ground::kCereal:
      p.tone = Jitter(rng, rng.Percent(50) ? Rgb(168, 160, 92) : Rgb(112, 138, 62), 6);
      p.rows = Periodic(scale.PxF(Metres(rng, 12, 17)), phase);
      p.swaths = Periodic(scale.PxF(rng.Int(18, 24)), phase2);
      p.line_half_gap_sub = scale.Sub(0.9);
      p.line_half_width_sub = scale.Sub(0.22);
      break;
    case Ground::kRowCrop:
      p.tone = Jitter(rng, garden ? Rgb(70, 118, 48) : Rgb(62, 110, 42), 8);
      p.rows = Periodic(scale.PxF(garden ? 0.35 : Metres(rng, 45, 75)), phase);
      break;
    case Ground::kMeadow:
      p.tone = Jitter(rng, Rgb(100, 112, 62), 8);
      p.swaths = Periodic(scale.PxF(Metres(rng, 200, 300)), phase2);
      break;
    case Ground::kStubble:
      p.tone = Jitter(rng, Rgb(188, 170, 118), 6);
      p.rows = Periodic(scale.PxF(0.15), phase);
      p.swaths = Periodic(scale.PxF(Metres(rng, 450, 600)), phase2);
      break;
    case Ground::kLawn:
      p.tone = Jitter(rng, Rgb(88, 114, 58), 6);
      p.swaths = Periodic(scale.PxF(Metres(rng, 80, 120)), phase2);
      break;
    case Ground::kPaving:
      p.tone = Jitter(rng, Rgb(158, 150, 138), 8);
      p.across_rows = layout.axis;
      p.rows = Periodic(scale.PxF(0.2), phase);
      p.swaths = Periodic(scale.PxF(0.3), phase2);
      break;
  }
  return p;
}

// Fields: the extended image split into rectangular strips along one farm axis (small garden
// plots within the hamlet), each with a crop and its own row direction.
void PlanParcels(Rng& rng, const Scale& scale, const cv::Size& size, Scene* scene) {
  const Frame& layout = scene->layout;
  int64_t u0 = INT64_MAX, u1 = INT64_MIN, v0 = INT64_MAX, v1 = INT64_MIN;
  for (cv::Point corner :
       {cv::Point(0, 0), cv::Point(size.width - 1, 0), cv::Point(0, size.height - 1),
        cv::Point(size.width - 1, size.height - 1)}) {
    u0 = std::min<int64_t>(u0, layout.U(corner.x, corner.y));
    u1 = std::max<int64_t>(u1, layout.U(corner.x, corner.y));
    v0 = std::min<int64_t>(v0, layout.V(corner.x, corner.y));
    v1 = std::max<int64_t>(v1, layout.V(corner.x, corner.y));
  }
  // The partition starts a random way outside the image so that a parcel edge does not line up
  // with the image border.
  u0 -= int64_t{rng.Int(2, scale.Px(20))} * kOne, v0 -= int64_t{rng.Int(2, scale.Px(15))} * kOne;
  u1 += 2 * kOne, v1 += 2 * kOne;

  struct Box {
    int64_t u0, u1, v0, v1;
  };
  std::vector<Box> todo = {{u0, u1, v0, v1}};
  while (!todo.empty()) {
    const Box box = todo.back();
    todo.pop_back();
    const cv::Point centre = layout.ToImage((box.u0 + box.u1) / 2, (box.v0 + box.v1) / 2);
    const bool garden = InHamlet(*scene, centre);
    const int64_t lu = box.u1 - box.u0, lv = box.v1 - box.v0;
    const int64_t max_short = int64_t{scale.Sub(garden ? 11 : rng.Int(18, 32))};
    const int64_t max_long = int64_t{scale.Sub(garden ? 16 : rng.Int(40, 75))};
    const bool u_long = lu >= lv;
    int split_u = -1;  // 1: cut U, 0: cut V
    if (std::min(lu, lv) > max_short) {
      split_u = u_long ? 0 : 1;
    } else if (std::max(lu, lv) > max_long) {
      split_u = u_long ? 1 : 0;
    }
    if (split_u == 1) {
      const int64_t cut = box.u0 + lu * rng.Int(35, 65) / 100;
      todo.push_back({box.u0, cut, box.v0, box.v1});
      todo.push_back({cut, box.u1, box.v0, box.v1});
      continue;
    }
    if (split_u == 0) {
      const int64_t cut = box.v0 + lv * rng.Int(35, 65) / 100;
      todo.push_back({box.u0, box.u1, box.v0, cut});
      todo.push_back({box.u0, box.u1, cut, box.v1});
      continue;
    }

    scene->parcels.push_back(
        MakeParcel(rng, scale, layout, box.u0, box.u1, box.v0, box.v1, garden, u_long));
  }
}

// Roads: a paved main road through the hamlet along the farm axis, a side road crossing it at an
// angle (paved or a farm track), and sometimes a farm track along a field edge.
void PlanRoads(Rng& rng, const Scale& scale, const cv::Size& size, Scene* scene) {
  const Dir main_axis = rng.Percent(50) ? scene->layout.axis : Perp(scene->layout.axis);
  Road main_road{{scene->hamlet_x, scene->hamlet_y, main_axis},
                 RoadKind::kPaved,
                 scale.Sub(Metres(rng, 275, 325)),
                 scale.Sub(Metres(rng, 150, 250))};

  const int along_sign = rng.Sign();
  const int along_px = along_sign * scale.RandomPx(rng, 10, 24);
  Road side_road;
  side_road.frame.cx = scene->hamlet_x + along_px * main_axis.x / kOne;
  side_road.frame.cy = scene->hamlet_y + along_px * main_axis.y / kOne;
  const int tan_permille = rng.Int(700, 5671);  // 35..80 degrees off the main road
  side_road.frame.axis = Turn(main_axis, DirOf(1000, int64_t{tan_permille} * rng.Sign()));
  if (rng.Percent(60)) {
    side_road.kind = RoadKind::kPaved;
    side_road.half_width_sub = scale.Sub(Metres(rng, 230, 270));
    side_road.verge_sub = scale.Sub(1.2);
  } else {
    side_road.kind = RoadKind::kTrack;
    side_road.half_width_sub = scale.Sub(1.6);
    side_road.verge_sub = scale.Sub(0.5);
  }

  if (rng.Percent(60)) {
    Road track;
    track.kind = RoadKind::kTrack;
    track.frame.axis = Perp(main_axis);
    const int offset_sign = rng.Sign();
    const int offset_px = offset_sign * scale.RandomPx(rng, 30, 55);
    track.frame.cx =
        std::clamp(scene->hamlet_x + offset_px * main_axis.x / kOne, -size.width, 2 * size.width);
    track.frame.cy =
        std::clamp(scene->hamlet_y + offset_px * main_axis.y / kOne, -size.height, 2 * size.height);
    track.half_width_sub = scale.Sub(1.6);
    track.verge_sub = scale.Sub(0.5);
    scene->roads.push_back(track);
  }
  scene->roads.push_back(side_road);
  scene->roads.push_back(main_road);
}

enum class BuildingKind { kHouse, kBarn, kShed };

// Size, roof and colour of a building; where it stands is up to the caller.
Building RandomBuilding(Rng& rng, const Scale& scale, BuildingKind kind) {
  Building b;
  double length_m = 0, width_m = 0, height_m = 0;
  switch (kind) {
    case BuildingKind::kHouse: {
      b.roof = rng.Percent(60) ? Roof::kGable : Roof::kHip;
      length_m = Metres(rng, 800, 1500), width_m = Metres(rng, 600, 1000), height_m = 6;
      const std::array<Bgr, 5> clay = {Rgb(166, 82, 58), Rgb(150, 96, 76), Rgb(98, 72, 62),
                                       Rgb(72, 74, 80), Rgb(120, 62, 50)};
      b.colour = Jitter(rng, clay[rng.Int(0, 4)], 6);
      break;
    }
    case BuildingKind::kBarn: {
      b.roof = Roof::kMetal;
      length_m = Metres(rng, 1400, 2400), width_m = Metres(rng, 900, 1300), height_m = 7;
      const std::array<Bgr, 3> metal = {Rgb(150, 154, 156), Rgb(126, 62, 54), Rgb(78, 102, 84)};
      b.colour = Jitter(rng, metal[rng.Int(0, 2)], 6);
      break;
    }
    case BuildingKind::kShed:
      b.roof = rng.Percent(60) ? Roof::kFlat : Roof::kMetal;
      length_m = Metres(rng, 400, 700), width_m = Metres(rng, 350, 550), height_m = 3;
      b.colour = Jitter(rng, b.roof == Roof::kFlat ? Rgb(122, 120, 114) : Rgb(146, 150, 152), 8);
      break;
  }
  b.half_length_sub = scale.Sub(length_m / 2);
  b.half_width_sub = scale.Sub(width_m / 2);
  b.height_px = scale.Px(height_m);
  b.chimney = kind == BuildingKind::kHouse && rng.Percent(70);
  b.chimney_u = b.half_length_sub / 100 * rng.Int(-60, 60);
  b.chimney_v = b.half_width_sub / 100 * rng.Int(25, 60);
  b.chimney_v *= rng.Sign();
  return b;
}

// Houses and barns along both sides of the main road within the hamlet, most square to the road,
// some turned; sheds behind some houses.
void PlanBuildings(Rng& rng, const Scale& scale, const cv::Size& size, Scene* scene) {
  const Road& main_road = scene->roads.back();
  const Dir along = main_road.frame.axis, across = Perp(along);
  const int reach_px = scene->hamlet_radius_px;
  const cv::Rect image(0, 0, size.width, size.height);
  auto place = [&](Building b, int64_t along_px, int64_t out_px, Dir axis) {
    b.frame = {scene->hamlet_x + static_cast<int>((along_px * along.x + out_px * across.x) / kOne),
               scene->hamlet_y + static_cast<int>((along_px * along.y + out_px * across.y) / kOne),
               axis};
    const bool seen =
        (b.frame.Box(b.half_length_sub, b.half_width_sub, b.height_px) & image).area() > 0;
    if (!seen || !ClearOfRoads(*scene, b) ||
        !ClearOfBuildings(*scene, b.frame.cx, b.frame.cy, b.radius_px() * 3 / 4))
      return false;
    scene->buildings.push_back(b);
    return true;
  };
  const int64_t road_edge_px = int64_t{main_road.half_width_sub + main_road.verge_sub} / kOne;
  for (int side : {-1, 1}) {
    for (int s = -reach_px + scale.RandomPx(rng, 0, 8); s < reach_px;) {
      const bool house = rng.Percent(80);
      Building b = RandomBuilding(rng, scale, house ? BuildingKind::kHouse : BuildingKind::kBarn);
      // Along the road (55%), gable end to it (25%), or turned (20%).
      const int orientation = rng.Int(0, 99);
      const bool end_on = orientation >= 55 && orientation < 80;
      Dir axis = end_on ? across : along;
      int64_t depth_px = (end_on ? b.half_length_sub : b.half_width_sub) / kOne;
      if (orientation >= 80) {
        const int turn_permille = rng.Int(140, 580);
        axis = Turn(along, DirOf(1000, turn_permille * rng.Sign()));
        depth_px = b.radius_px();
      }
      const int64_t out_px = road_edge_px + scale.RandomPx(rng, 3, 8) + depth_px;
      const bool placed = place(b, s, side * out_px, axis);
      const Building shed = RandomBuilding(rng, scale, BuildingKind::kShed);
      const int64_t shed_out_px =
          out_px + depth_px + scale.RandomPx(rng, 2, 5) + shed.half_width_sub / kOne;
      if (placed && house && rng.Percent(50))
        place(shed, s + rng.Int(-1, 1) * b.half_length_sub / kOne / 2, side * shed_out_px, along);
      s += 2 * (end_on ? b.half_width_sub : b.half_length_sub) / kOne + scale.RandomPx(rng, 3, 9);
    }
  }
}

Tree MakeTree(Rng& rng, int cx, int cy, int radius_px, Bgr colour) {
  Tree tree{cx, cy, radius_px, {}, colour};
  tree.lobes.push_back(MakeLobe(0, 0, std::max(1, radius_px * rng.Int(50, 62) / 100)));
  const int lobes = rng.Int(5, 9);
  for (int i = 0; i < lobes; ++i) {
    const int reach = radius_px * 50 / 100;
    const int dx = rng.Int(-reach, reach), dy = rng.Int(-reach, reach);
    tree.lobes.push_back(MakeLobe(dx, dy, std::max(1, radius_px * rng.Int(30, 50) / 100)));
  }
  for (const Lobe& lobe : tree.lobes) {
    const int reach_px =
        static_cast<int>(ISqrt(int64_t{lobe.dx} * lobe.dx + int64_t{lobe.dy} * lobe.dy)) + lobe.r +
        1;
    tree.extent_px = std::max(tree.extent_px, reach_px);
  }
  return tree;
}

// Trees: an avenue along the main road, garden trees in the hamlet, hedgerows along some field
// edges and a few single trees in the fields; never on a roof or the carriageway.
void PlanTrees(Rng& rng, const Scale& scale, const cv::Size& size, Scene* scene) {
  const std::array<Bgr, 5> greens = {Rgb(56, 86, 40), Rgb(72, 102, 50), Rgb(46, 72, 44),
                                     Rgb(86, 106, 56), Rgb(60, 92, 62)};
  auto add = [&](cv::Point p, int radius_px) {
    const bool near_image = p.x > -radius_px && p.y > -radius_px && p.x < size.width + radius_px &&
                            p.y < size.height + radius_px;
    if (!near_image || OnRoad(*scene, p) || !ClearOfBuildings(*scene, p.x, p.y, radius_px / 2))
      return;
    scene->trees.push_back(
        MakeTree(rng, p.x, p.y, radius_px, Jitter(rng, greens[rng.Int(0, 4)], 8)));
  };

  const Road& main_road = scene->roads.back();
  const int reach_px = size.width + size.height;
  const int first_side = rng.Sign();
  const bool both_sides = rng.Percent(35);
  const int spacing_px = scale.RandomPx(rng, 8, 12);
  for (int side : {-1, 1}) {
    if (side != first_side && !both_sides) continue;
    const int out_px = (main_road.half_width_sub + main_road.verge_sub) / kOne + scale.Px(2.5);
    for (int s = -reach_px; s < reach_px; s += spacing_px) {
      if (!rng.Percent(60)) continue;
      add(main_road.frame.ToImage(int64_t{s} * kOne, int64_t{side} * out_px * kOne),
          scale.RandomPx(rng, 2.5, 4));
    }
  }

  const double ground_m2 = size.area() * scale.gsd_m * scale.gsd_m;
  for (const Parcel& p : scene->parcels) {
    const cv::Point centre = scene->layout.ToImage((p.u0 + p.u1) / 2, (p.v0 + p.v1) / 2);
    if (InHamlet(*scene, centre)) {
      for (int i = rng.Int(0, 2); i > 0; --i) {
        const int64_t u = p.u0 + (p.u1 - p.u0) * rng.Int(10, 90) / 100;
        const int64_t v = p.v0 + (p.v1 - p.v0) * rng.Int(10, 90) / 100;
        add(scene->layout.ToImage(u, v), scale.RandomPx(rng, 2, 4.5));
      }
    } else if (rng.Percent(25)) {  // a hedgerow along one edge
      const bool along_u = rng.Percent(50);
      const int64_t step = int64_t{scale.Px(2.4)} * kOne;
      for (int64_t t = along_u ? p.u0 : p.v0; t < (along_u ? p.u1 : p.v1); t += step) {
        if (!rng.Percent(80)) continue;
        add(along_u ? scene->layout.ToImage(t, p.v0) : scene->layout.ToImage(p.u0, t),
            scale.RandomPx(rng, 1.6, 2.6));
      }
    }
  }
  for (int i = static_cast<int>(ground_m2 / 1500); i > 0; --i) {
    const cv::Point at{rng.Int(0, size.width - 1), rng.Int(0, size.height - 1)};
    add(at, scale.RandomPx(rng, 2.5, 5));
  }
}

Scene PlanScene(const GroundTextureOptions& options) {
  Rng rng(options.seed);
  const Scale scale{options.ground_sample_distance_m};
  const cv::Size size(options.width_px, options.height_px);
  Scene scene;
  scene.layout = {size.width / 2, size.height / 2, Near(rng, Dir{}, 840)};  // within +-40 degrees
  scene.hamlet_x = rng.Int(size.width / 4, size.width * 3 / 4);
  scene.hamlet_y = rng.Int(size.height / 4, size.height * 3 / 4);
  scene.hamlet_radius_px = scale.RandomPx(rng, 26, 38);
  int shadow_x = 0, shadow_y = 0;  // any direction: the sun can be anywhere
  while (shadow_x == 0 && shadow_y == 0)
    shadow_x = rng.Int(-1000, 1000), shadow_y = rng.Int(-1000, 1000);
  scene.shadow = DirOf(shadow_x, shadow_y);
  PlanRoads(rng, scale, size, &scene);
  PlanParcels(rng, scale, size, &scene);
  PlanBuildings(rng, scale, size, &scene);
  PlanTrees(rng, scale, size, &scene);
  return scene;
}

// ---- Painting ----------------------------------------------------------------------------------

Bgr Grass(Bgr tone, const Noises& n, int x, int y) {
  return Times(tone, 256 + Amp(n.coarse(x, y), 10) + Amp(n.medium(x, y), 12) +
                         Amp(n.small(x, y), 16) + Amp(n.fine(x, y), 22));
}

Bgr GroundColour(const Parcel& p, const Noises& n, int x, int y, int64_t u, int64_t v) {
  const int64_t across = int64_t{x} * p.across_rows.x + int64_t{y} * p.across_rows.y;
  const int coarse = n.coarse(x, y), medium = n.medium(x, y), small = n.small(x, y),
            fine = n.fine(x, y);
  switch (p.ground) {
    case Ground::kPloughed:
      return Times(p.tone, 256 + Amp(p.rows.Wave(across) - 128, 28) + Amp(coarse, 14) +
                               Amp(medium, 10) + Amp(small, 16) + Amp(fine, 26));
    case Ground::kCereal: {
      const int64_t track = std::abs(p.swaths.LineDistance(across) - p.line_half_gap_sub);
      return Times(p.tone, 256 + Amp(p.rows.Wave(across) - 128, 14) + Amp(coarse, 14) +
                               Amp(medium, 8) + Amp(small, 12) + Amp(fine, 22) -
                               Cover(p.line_half_width_sub - track, 2) * 70 / 256);
    }
    case Ground::kRowCrop: {
      // Plants where the row profile and the clump noise together are high: leafy, broken rows.
      const int leaf =
          std::clamp((p.rows.Wave(across) - 128) * 3 + medium * 2 + small + fine / 2 + 128, 0, 256);
      const Bgr soil = Times(Rgb(120, 102, 80), 256 + Amp(coarse, 10) + Amp(fine, 30));
      return Mix(soil, Times(p.tone, 256 + Amp(small, 24) + Amp(fine, 28)), leaf);
    }
    case Ground::kMeadow:
      return Times(Mix(p.tone, Rgb(150, 146, 84), std::clamp(coarse * 2 + 40, 0, 200)),
                   256 + Amp(p.swaths.Wave(across) - 128, 10) + Amp(medium, 12) + Amp(small, 16) +
                       Amp(fine, 26));
    case Ground::kStubble:
      return Times(p.tone, 256 + Amp(p.rows.Wave(across) - 128, 12) +
                               Amp(p.swaths.Wave(across) - 128, 10) + Amp(coarse, 8) +
                               Amp(small, 10) + Amp(fine, 24));
    case Ground::kLawn: {
      // Mowing stripes: a soft square wave.
      const int stripe = std::clamp((p.swaths.Wave(u) - 128) * 4, -128, 128);
      return Times(p.tone, 256 + Amp(stripe, 8) + Amp(medium, 8) + Amp(small, 16) + Amp(fine, 28));
    }
    case Ground::kPaving: {
      // Stones 0.2 x 0.3 m with their own shade, dark joints between them.
      const int shade = static_cast<int>(Hash(p.rows.Cycle(u), p.swaths.Cycle(v), 7) & 31) - 16;
      const int joint = std::max(Cover(kOne / 2 + kOne / 4 - p.rows.LineDistance(u)),
                                 Cover(kOne / 2 + kOne / 4 - p.swaths.LineDistance(v)));
      return Times(p.tone, 256 + shade + Amp(medium, 8) + Amp(fine, 14) - joint * 90 / 256);
    }
  }
  return p.tone;
}

void PaintFields(const Scene& scene, const Noises& n, cv::Mat3b& image) {
  const cv::Rect whole(0, 0, image.cols, image.rows);
  const Bgr headland = Rgb(110, 122, 70);
  for (const Parcel& p : scene.parcels) {
    const int64_t hu = (p.u1 - p.u0) / 2, hv = (p.v1 - p.v0) / 2;
    Frame centred = scene.layout;
    const cv::Point c = scene.layout.ToImage(p.u0 + hu, p.v0 + hv);
    centred.cx = c.x, centred.cy = c.y;
    const cv::Rect box = centred.Box(hu, hv, 2) & whole;
    for (int y = box.y; y < box.y + box.height; ++y) {
      const auto [u_first, u_last] =
          ColumnsWithin(scene.layout.U(0, y), scene.layout.axis.x, p.u0, p.u1, image.cols);
      const auto [v_first, v_last] =
          ColumnsWithin(scene.layout.V(0, y), -scene.layout.axis.y, p.v0, p.v1, image.cols);
      const int x_end = std::min({box.x + box.width - 1, u_last, v_last});
      for (int x = std::max({box.x, u_first, v_first}); x <= x_end; ++x) {
        const int64_t u = scene.layout.U(x, y), v = scene.layout.V(x, y);
        if (u < p.u0 || u >= p.u1 || v < p.v0 || v >= p.v1) continue;  // each pixel once
        Bgr colour = GroundColour(p, n, x, y, u, v);
        if (p.margin_sub > 0) {
          const int64_t edge = std::min({u - p.u0, p.u1 - u, v - p.v0, p.v1 - v});
          const int grass = Cover(p.margin_sub - edge, 3);
          if (grass > 0) colour = Mix(colour, Grass(headland, n, x, y), grass);
        }
        Write(image(y, x), colour);
      }
    }
  }
}

// A white road line: share 0..256 of the pixel, paint worn away where the medium noise is high.
int LineCover(int64_t distance, int half_width_sub, int wear_noise) {
  return Cover(half_width_sub - distance) * std::clamp(256 - (wear_noise - 30) * 6, 64, 256) / 256;
}

void PaintRoads(const Scene& scene, const Scale& scale, const Noises& n, cv::Mat3b& image) {
  const Bgr asphalt = Rgb(92, 92, 94), gravel = Rgb(150, 140, 122), verge = Rgb(112, 126, 72),
            paint = Rgb(228, 228, 218), rut = Rgb(146, 128, 102);
  const int line_half_sub = scale.Sub(0.06), edge_line_inset_sub = scale.Sub(0.4),
            shoulder_sub = scale.Sub(0.6);
  const int wheel_offset_sub = scale.Sub(0.85), wheel_half_sub = scale.Sub(0.35);
  const int rut_centre_sub = scale.Sub(0.8), rut_half_sub = scale.Sub(0.3);
  const Periodic dashes(scale.PxF(9.0), 0);  // 3 m dash, 6 m gap
  const int64_t dash_length_sub = dashes.period_sub() / 3;
  for (size_t i = 0; i < scene.roads.size(); ++i) {
    const Road& road = scene.roads[i];
    const int64_t outer_sub = int64_t{road.half_width_sub} + road.verge_sub;
    const int64_t reach_sub = outer_sub + 8 * kOne;
    for (int y = 0; y < image.rows; ++y) {
      const auto [x_first, x_last] =
          ColumnsWithin(road.frame.V(0, y), -road.frame.axis.y, -reach_sub, reach_sub, image.cols);
      for (int x = x_first; x <= x_last; ++x) {
        const int64_t from_centre = std::abs(int64_t{road.frame.V(x, y)});
        if (from_centre > reach_sub) continue;
        // Where an earlier road's carriageway is, only this road's carriageway goes over it.
        bool junction = false;
        for (size_t j = 0; j < i; ++j) {
          junction |=
              scene.roads[j].kind == RoadKind::kPaved &&
              std::abs(int64_t{scene.roads[j].frame.V(x, y)}) < scene.roads[j].half_width_sub;
        }
        const int medium = n.medium(x, y), small = n.small(x, y), fine = n.fine(x, y);
        Bgr colour;
        if (road.kind == RoadKind::kPaved) {
          const int64_t from_wheel_path =
              std::abs(std::abs(from_centre - road.half_width_sub / 2) - wheel_offset_sub);
          Bgr surface = Times(asphalt, 256 + Amp(n.coarse(x, y), 6) + Amp(medium, 8) +
                                           Amp(small, 16) + Amp(fine, 26) -
                                           Cover(wheel_half_sub - from_wheel_path, 12) * 22 / 256);
          if (!junction) {
            const int64_t along = road.frame.U(x, y);
            int dash_phase = dashes.Phase(along);  // a dash from 0 to a third
            if (dash_phase > 43690) dash_phase -= 65536;
            const int64_t into_dash =
                std::min<int64_t>(dash_phase,
                                  dash_length_sub * 65536 / dashes.period_sub() - dash_phase) *
                dashes.period_sub() / 65536;
            const int centre_line =
                std::min(LineCover(from_centre, line_half_sub, medium), Cover(into_dash));
            const int edge_line =
                LineCover(std::abs(from_centre - (road.half_width_sub - edge_line_inset_sub)),
                          line_half_sub, medium);
            surface =
                Mix(surface, Times(paint, 256 + Amp(fine, 8)), std::max(centre_line, edge_line));
          }
          const Bgr side = Mix(
              Grass(verge, n, x, y), Times(gravel, 256 + Amp(small, 20) + Amp(fine, 24)),
              Cover(road.half_width_sub + shoulder_sub + Amp(small, 30) * kOne / 64 - from_centre,
                    4));
          colour = Mix(side, surface, Cover(road.half_width_sub - from_centre));
        } else {
          const int64_t from_rut = std::abs(from_centre - rut_centre_sub);
          colour = Mix(Grass(verge, n, x, y), Times(rut, 256 + Amp(small, 18) + Amp(fine, 24)),
                       Cover(rut_half_sub + Amp(medium, 20) * kOne / 64 - from_rut, 2));
        }
        if (junction && from_centre >= road.half_width_sub) continue;
        Blend(image(y, x), colour, Cover(outer_sub - from_centre, 6));
      }
    }
  }
}

// Inward half-planes of a convex polygon.
struct Convex {
  std::vector<std::pair<Dir, cv::Point>> edges;  // inward normal, a point on the edge
  cv::Rect box;
  int CoverAt(int x, int y, int soft_px) const {
    int cover = 256;
    for (const auto& [normal, at] : edges) {
      cover = std::min(
          cover,
          shutterlab::Cover(int64_t{x - at.x} * normal.x + int64_t{y - at.y} * normal.y, soft_px));
    }
    return cover;
  }
};

// Convex hull (Andrew's monotone chain) of the points.
Convex HullOf(std::vector<cv::Point> points) {
  std::sort(points.begin(), points.end(),
            [](cv::Point a, cv::Point b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
  auto cross = [](cv::Point o, cv::Point a, cv::Point b) {
    return int64_t{a.x - o.x} * (b.y - o.y) - int64_t{a.y - o.y} * (b.x - o.x);
  };
  std::vector<cv::Point> hull;
  for (int pass = 0; pass < 2; ++pass) {
    const size_t start = hull.size();
    for (const cv::Point& p : points) {
      while (hull.size() >= start + 2 && cross(hull[hull.size() - 2], hull.back(), p) <= 0)
        hull.pop_back();
      hull.push_back(p);
    }
    hull.pop_back();
    std::reverse(points.begin(), points.end());
  }
  Convex convex;
  convex.box = cv::boundingRect(hull);
  const cv::Point centre(convex.box.x + convex.box.width / 2, convex.box.y + convex.box.height / 2);
  for (size_t i = 0; i < hull.size(); ++i) {
    const cv::Point p = hull[i], q = hull[(i + 1) % hull.size()];
    Dir normal = Perp(DirOf(q.x - p.x, q.y - p.y));
    if (int64_t{centre.x - p.x} * normal.x + int64_t{centre.y - p.y} * normal.y < 0)
      normal = {-normal.x, -normal.y};
    convex.edges.push_back({normal, p});
  }
  return convex;
}

// Calls visit(x, y) for the image pixels within reach_px of (cx, cy), row by row.
template <typename Visit>
void ForEachPixelInDisc(int cx, int cy, int reach_px, cv::Size size, Visit visit) {
  for (int y = std::max(cy - reach_px, 0); y <= std::min(cy + reach_px, size.height - 1); ++y) {
    const int half_px =
        static_cast<int>(ISqrt(int64_t{reach_px} * reach_px - int64_t{y - cy} * (y - cy)));
    for (int x = std::max(cx - half_px, 0); x <= std::min(cx + half_px, size.width - 1); ++x)
      visit(x, y);
  }
}

// Largest signed distance (1/kOne px) of (x, y) inside the tree's lobes shifted by (ox, oy), with
// a ragged, leafy outline; also how far into its lobe, 0..256 (1 at a lobe's centre).
int64_t CanopyInside(const Tree& tree, int x, int y, int ox, int oy, int ragged_noise,
                     int ragged_sub, int* depth) {
  int64_t best = INT64_MIN, best_excess = 0;
  const Lobe* best_lobe = &tree.lobes[0];
  for (const Lobe& lobe : tree.lobes) {
    const int64_t dx = x - (tree.cx + lobe.dx + ox), dy = y - (tree.cy + lobe.dy + oy);
    const int64_t excess = int64_t{lobe.r} * lobe.r - (dx * dx + dy * dy);
    const int64_t inside = excess * lobe.per_2r >> 16;  // ~ r - d near the edge
    if (inside > best) best = inside, best_excess = excess, best_lobe = &lobe;
  }
  if (depth) *depth = static_cast<int>(std::max<int64_t>(0, best_excess * best_lobe->per_r2 >> 16));
  return best + int64_t{ragged_noise} * ragged_sub / 128;
}

// Building and tree shadows darken the ground (more in red than blue: skylight fills them).
void CastShadows(const Scene& scene, const Scale& scale, const Noises& n, cv::Mat3b& image) {
  const cv::Rect whole(0, 0, image.cols, image.rows);
  cv::Mat1b shade(image.size(), uchar{0});
  for (const Building& b : scene.buildings) {
    const int length_px = b.height_px * 3 / 4;
    const int ox = length_px * scene.shadow.x / kOne, oy = length_px * scene.shadow.y / kOne;
    std::vector<cv::Point> corners;
    for (int su : {-1, 1}) {
      for (int sv : {-1, 1}) {
        const cv::Point p =
            b.frame.ToImage(int64_t{su} * b.half_length_sub, int64_t{sv} * b.half_width_sub);
        corners.push_back(p);
        corners.push_back(p + cv::Point(ox, oy));
      }
    }
    const Convex hull = HullOf(corners);
    const cv::Rect box = (hull.box + cv::Size(6, 6) - cv::Point(3, 3)) & whole;
    for (int y = box.y; y < box.y + box.height; ++y) {
      for (int x = box.x; x < box.x + box.width; ++x) {
        uchar& s = shade(y, x);
        s = std::max<uchar>(s, static_cast<uchar>(std::min(255, hull.CoverAt(x, y, 3))));
      }
    }
  }
  const int ragged_sub = scale.Sub(0.25);
  for (const Tree& tree : scene.trees) {
    const int length_px = tree.radius_px * 5 / 4;
    const int ox = length_px * scene.shadow.x / kOne, oy = length_px * scene.shadow.y / kOne;
    // Beyond the lobes, the ragged outline and the 1.5 px half penumbra nothing is shaded.
    const int reach_px = tree.extent_px + ragged_sub / kOne + 3;
    ForEachPixelInDisc(tree.cx + ox, tree.cy + oy, reach_px, image.size(), [&](int x, int y) {
      const int cover =
          Cover(CanopyInside(tree, x, y, ox, oy, n.medium(x, y), ragged_sub, nullptr), 3);
      uchar& s = shade(y, x);
      s = std::max<uchar>(s, static_cast<uchar>(std::min(255, cover)));
    });
  }
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const int s = shade(y, x);
      if (s == 0) continue;
      cv::Vec3b& p = image(y, x);
      p[0] = static_cast<uchar>(p[0] * (256 - s * 100 / 255) / 256);
      p[1] = static_cast<uchar>(p[1] * (256 - s * 116 / 255) / 256);
      p[2] = static_cast<uchar>(p[2] * (256 - s * 126 / 255) / 256);
    }
  }
}

// Roof details in pixels, worked out once for the ground sample distance.
struct RoofDetails {
  explicit RoofDetails(const Scale& scale)
      : seams(scale.PxF(1.0), 0),
        ribs(scale.PxF(0.2), 0),
        courses(scale.PxF(0.32), 0),
        tiles(scale.PxF(0.24), 0),
        seam_half_sub(scale.Sub(0.02) + kOne / 2),
        joint_half_sub(scale.Sub(0.015) + kOne / 2),
        parapet_sub(scale.Sub(0.25)),
        cap_half_sub(scale.Sub(0.14)),
        gutter_sub(scale.Sub(0.1)),
        chimney_half_sub(scale.Sub(0.35)),
        flue_half_sub(scale.Sub(0.15)),
        chimney_shadow_sub(scale.Sub(1.0)) {}
  Periodic seams, ribs, courses, tiles;  // flat-roof membrane seams, metal ribs, tile rows
  int seam_half_sub, joint_half_sub;     // (at least half a pixel, so that they show)
  int parapet_sub, cap_half_sub, gutter_sub;
  int chimney_half_sub, flue_half_sub, chimney_shadow_sub;
};

Bgr RoofColour(const Building& b, const Scene& scene, const RoofDetails& d, const Noises& n, int x,
               int y, int64_t u, int64_t v) {
  const int64_t au = std::abs(u), av = std::abs(v);
  const int64_t to_end = b.half_length_sub - au, to_eave = b.half_width_sub - av;
  const int medium = n.medium(x, y), small = n.small(x, y), fine = n.fine(x, y);
  const int weather = Amp(n.coarse(x, y), 6) + Amp(medium, 8);
  if (b.roof == Roof::kFlat) {
    const int seam = Cover(d.seam_half_sub - d.seams.LineDistance(u));
    const int parapet = Cover(d.parapet_sub - std::min(to_end, to_eave));
    return Times(b.colour, 256 + weather + Amp(small, 8) + Amp(fine, 20) - seam * 50 / 256 +
                               parapet * 40 / 256);
  }
  // Which plane the pixel is on, and how it faces the sun.
  const bool end_plane = b.roof == Roof::kHip && to_end < to_eave;
  Dir normal = end_plane ? b.frame.axis : Perp(b.frame.axis);
  const int64_t sign = end_plane ? (u >= 0 ? 1 : -1) : (v >= 0 ? 1 : -1);
  const int64_t facing =
      -sign * (int64_t{normal.x} * scene.shadow.x + int64_t{normal.y} * scene.shadow.y) / kOne;
  int light = 256 + static_cast<int>(facing * 72 / kOne);

  if (b.roof == Roof::kMetal) {
    // Corrugated sheets: ribs running down the slope, a flashing along the ridge.
    light += Amp(d.ribs.Wave(u) - 128, 16) + weather + Amp(fine, 10);
    light += Cover(d.cap_half_sub - av) * 40 / 256;
    return Times(b.colour, light);
  }
  // Tiles: courses parallel to the eave, each with a shadow line along its lower edge, and joints
  // between tiles offset by half a tile from course to course.
  const int64_t down = end_plane ? to_end : to_eave;  // distance from the eave up the slope
  const int64_t sideways = end_plane ? v : u;
  const int64_t course = d.courses.Cycle(down);
  const int course_phase = d.courses.Phase(down) >> 8;  // 0 at a course's lower edge
  const int64_t offset = (course & 1) * d.tiles.period_sub() / 2;
  const int joint = Cover(d.joint_half_sub - d.tiles.LineDistance(sideways + offset));
  const int shade = static_cast<int>(Hash(course, d.tiles.Cycle(sideways + offset), 11) & 15) - 8;
  const int course_light = course_phase < 32 ? -70 + 2 * course_phase : (course_phase - 32) / 6;
  light += course_light + shade + weather + Amp(fine, 10) - joint * 50 / 256;
  // Ridge and hip caps, and a dark line along the eaves (gutter).
  const bool on_ridge = av < d.cap_half_sub && (b.roof == Roof::kGable || to_end > to_eave);
  const bool on_hip =
      b.roof == Roof::kHip && std::abs(to_end - to_eave) < int64_t{d.cap_half_sub} * 14 / 10;
  if (on_ridge || on_hip) light = 210 + Amp(fine, 10) + weather;
  light -= Cover(d.gutter_sub - std::min(to_end, to_eave)) * 100 / 256;
  Bgr colour = Times(b.colour, light);

  if (b.chimney) {
    // A brick chimney with its flue, and its shadow on the roof.
    const int half_sub = d.chimney_half_sub, flue_half_sub = d.flue_half_sub,
              shadow_length_sub = d.chimney_shadow_sub;
    // The shadow direction in the roof's (U, V), unit length kOne.
    const int64_t shadow_u =
        (int64_t{scene.shadow.x} * b.frame.axis.x + int64_t{scene.shadow.y} * b.frame.axis.y) /
        kOne;
    const int64_t shadow_v =
        (int64_t{scene.shadow.y} * b.frame.axis.x - int64_t{scene.shadow.x} * b.frame.axis.y) /
        kOne;
    const int64_t du = u - b.chimney_u, dv = v - b.chimney_v;
    const int64_t du_shadow = du - shadow_u * shadow_length_sub / kOne,
                  dv_shadow = dv - shadow_v * shadow_length_sub / kOne;
    const int in_shadow = std::min(Cover(half_sub - std::abs(du_shadow), 2),
                                   Cover(half_sub - std::abs(dv_shadow), 2));
    colour = Times(colour, 256 - in_shadow * 110 / 256);
    const int in_chimney = std::min(Cover(half_sub - std::abs(du)), Cover(half_sub - std::abs(dv)));
    const int in_flue =
        std::min(Cover(flue_half_sub - std::abs(du)), Cover(flue_half_sub - std::abs(dv)));
    colour = Mix(colour, Times(Rgb(136, 74, 58), 256 + Amp(fine, 16)), in_chimney);
    colour = Mix(colour, Rgb(40, 34, 32), in_flue);
  }
  return colour;
}

void PaintRoofs(const Scene& scene, const Scale& scale, const Noises& n, cv::Mat3b& image) {
  const cv::Rect whole(0, 0, image.cols, image.rows);
  const RoofDetails details(scale);
  for (const Building& b : scene.buildings) {
    const cv::Rect box = b.frame.Box(b.half_length_sub, b.half_width_sub, 2) & whole;
    for (int y = box.y; y < box.y + box.height; ++y) {
      for (int x = box.x; x < box.x + box.width; ++x) {
        const int64_t u = b.frame.U(x, y), v = b.frame.V(x, y);
        const int cover =
            std::min(Cover(b.half_length_sub - std::abs(u)), Cover(b.half_width_sub - std::abs(v)));
        if (cover > 0) Blend(image(y, x), RoofColour(b, scene, details, n, x, y, u, v), cover);
      }
    }
  }
}

// Canopies: lit on the sun side, darker at each lobe's rim, leafy grain inside.
void PaintCanopies(const Scene& scene, const Scale& scale, const Noises& n, cv::Mat3b& image) {
  const int ragged_sub = scale.Sub(0.25);
  for (const Tree& tree : scene.trees) {
    const int reach_px = tree.extent_px + ragged_sub / kOne + 2;
    ForEachPixelInDisc(tree.cx, tree.cy, reach_px, image.size(), [&](int x, int y) {
      int depth = 0;
      const int cover = Cover(CanopyInside(tree, x, y, 0, 0, n.medium(x, y), ragged_sub, &depth));
      if (cover == 0) return;
      const int64_t towards_sun =
          -(int64_t{x - tree.cx} * scene.shadow.x + int64_t{y - tree.cy} * scene.shadow.y) /
          (int64_t{tree.radius_px} * kOne / 64 + 1);
      const int light = 140 + depth * 110 / 256 +
                        static_cast<int>(std::clamp<int64_t>(towards_sun, -64, 64)) +
                        Amp(n.small(x, y), 24) + Amp(n.fine(x, y), 30);
      Blend(image(y, x), Times(tree.colour, light), cover);
    });
  }
}

// A lens is never perfectly sharp: a [1 2 1] / 4 blur each way softens the drawn edges' steps
// the way optics would (integer arithmetic, borders replicated).
void SoftenLikeALens(cv::Mat3b& image) {
  const int n = image.cols * 3, h = image.rows;
  // Horizontal sums of three rows at a time (y - 1, y, y + 1), so the image is blurred in place.
  std::vector<uint16_t> sums(3 * static_cast<size_t>(n));
  auto horizontal = [&](int y) {
    const uchar* in = image.ptr<uchar>(std::clamp(y, 0, h - 1));
    uint16_t* out = &sums[static_cast<size_t>((y + 3) % 3) * n];
    auto clamped = [&](int i) {  // the border pixels stand in for their missing neighbours
      const int left = i >= 3 ? i - 3 : i, right = i + 3 < n ? i + 3 : i;
      return static_cast<uint16_t>(in[left] + 2 * in[i] + in[right]);
    };
    const int first_inner = std::min(3, n), past_inner = std::max(first_inner, n - 3);
    for (int i = 0; i < first_inner; ++i) out[i] = clamped(i);
    for (int i = first_inner; i < past_inner; ++i)
      out[i] = static_cast<uint16_t>(in[i - 3] + 2 * in[i] + in[i + 3]);
    for (int i = past_inner; i < n; ++i) out[i] = clamped(i);
  };
  horizontal(-1);
  horizontal(0);
  for (int y = 0; y < h; ++y) {
    horizontal(y + 1);
    const uint16_t* up = &sums[static_cast<size_t>((y + 2) % 3) * n];
    const uint16_t* mid = &sums[static_cast<size_t>(y % 3) * n];
    const uint16_t* down = &sums[static_cast<size_t>((y + 1) % 3) * n];
    uchar* out = image.ptr<uchar>(y);
    for (int i = 0; i < n; ++i)
      out[i] = static_cast<uchar>((up[i] + 2 * mid[i] + down[i] + 8) >> 4);
  }
}

// Sensor grain: a little per-pixel noise, mostly in brightness.
void AddGrain(uint64_t stream, cv::Mat3b& image) {
  for (int y = 0; y < image.rows; ++y) {
    cv::Vec3b* row = image[y];
    const uint32_t row_key = Hash(y, 0, stream);
    for (int x = 0; x < image.cols; ++x) {
      // lowbias32 (Wellons): one multiply-xorshift round pair is plenty for grain.
      uint32_t h = row_key + static_cast<uint32_t>(x) * 0x9e3779b9u;
      h ^= h >> 16, h *= 0x7feb352du, h ^= h >> 15, h *= 0x846ca68bu, h ^= h >> 16;
      const int grey = static_cast<int>(h & 7) + static_cast<int>((h >> 3) & 7) - 7;  // -7 .. 7
      for (int c = 0; c < 3; ++c)
        row[x][c] = Clamp8(row[x][c] + grey / 2 + static_cast<int>((h >> (8 + 2 * c)) & 3) - 1);
    }
  }
}

}  // namespace

void GroundTextureOptions::Check() const {
  SHUTTERLAB_CHECK(width_px > 0 && height_px > 0)
      << "ground texture size must be positive, got " << width_px << "x" << height_px;
  SHUTTERLAB_CHECK(width_px <= kMaxSide && height_px <= kMaxSide)
      << "ground texture sides must be at most " << kMaxSide << " px (fixed-point range), got "
      << width_px << "x" << height_px;
  // Beyond 0.2 m a pixel is wider than a crop row or a road line; below 2 mm a roof fills 5000 px.
  SHUTTERLAB_CHECK(std::isfinite(ground_sample_distance_m) && ground_sample_distance_m >= 0.002 &&
                   ground_sample_distance_m <= 0.2)
      << "ground_sample_distance_m must be in [0.002, 0.2] m, got " << ground_sample_distance_m;
}

cv::Mat MakeGroundTexture(const GroundTextureOptions& options) {
  options.Check();
  const Scale scale{options.ground_sample_distance_m};
  const cv::Size size(options.width_px, options.height_px);
  const Scene scene = PlanScene(options);
  const uint64_t stream = Mix64(options.seed ^ 0x5eed);
  const Noises noises{Noise(size, scale.Px(4.0), stream + 1),
                      Noise(size, scale.Px(0.6), stream + 2),
                      Noise(size, scale.Px(0.2), stream + 3),
                      Noise(size, std::clamp(scale.Px(0.06), 3, 4), stream + 4)};
  cv::Mat3b image(size);
  PaintFields(scene, noises, image);
  PaintRoads(scene, scale, noises, image);
  CastShadows(scene, scale, noises, image);
  PaintRoofs(scene, scale, noises, image);
  PaintCanopies(scene, scale, noises, image);
  SoftenLikeALens(image);
  AddGrain(stream + 5, image);
  // Painted in OpenCV's B, G, R order; handed over in the project's R, G, B (io/image_io.h).
  cv::Mat rgb;
  cv::cvtColor(image, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

}  // namespace shutterlab
