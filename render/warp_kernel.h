#pragma once
// The sampler that the renderer (render/rs_warp.h) and the corrector (render/rs_correct.h) share:
// one row of output pixels read from a source image at given source coordinates.
//
// Coordinates are source pixels, OpenCV's convention (the centre of the top-left pixel is (0, 0)).
// Bilinear sampling of integer images takes fixed-point coordinates (kSampleFracBits fractional
// bits: 1/128 px, quantisation <= 1/256 px per axis) and fixed-point weights; float images and
// bicubic sampling take float coordinates. Taps outside the source read as 0 (OpenCV's
// BORDER_CONSTANT with value 0), each tap separately.
// 8-bit RGB has SIMD paths, for maps close to a shift (rolling-shutter frames): one pixel per step
// in SSE2; where the CPU has SSE4.1 or AVX2 (checked at run time), one or two blocks of four pixels
// a step whose taps lie in one 16-byte span of two (across a row boundary, three) source rows; and
// where it has AVX-512 BW and VBMI, sixteen pixels a step whose taps lie in one 64-byte span of
// each of those rows. A block that does not fit takes the next narrower path. Every path gives the
// same bits.

#include <opencv2/core.hpp>

#include <limits>

namespace shutterlab {

enum class Interpolation { kBilinear, kBicubic };

inline constexpr int kSampleFracBits = 7;
// A coordinate with no source (a ray that misses the ground, NaN): far outside any image, so it
// samples black.
inline constexpr int kInvalidFixed = std::numeric_limits<int>::min();

// x in fixed point (round(x * 2^kSampleFracBits)); kInvalidFixed for NaN and beyond +-2^23 px.
int ToFixed(float x);

// Bilinear samples of n pixels at fixed-point (xi[k], yi[k]) from src (CV_8U or CV_16U, 1 to 4
// channels) into out: n * channels values of src's depth, interleaved.
void SampleRowFixed(const cv::Mat& src, const int* xi, const int* yi, int n, uchar* out);

// Samples of n pixels at float (xs[k], ys[k]) (NaN: no source, black): bicubic (OpenCV's A = -0.75
// kernel, float weights) for CV_8U, CV_16U and CV_32F, bilinear for CV_32F only (integer images
// take SampleRowFixed).
void SampleRowFloat(const cv::Mat& src, const float* xs, const float* ys, int n,
                    Interpolation interpolation, uchar* out);

// Fixed-point coordinates of n pixels along a line, x and y: x_out[k] = round(ax + k bx),
// y_out[k] = round(ay + k by), a and b already in fixed-point units (|a + k b| < 2^30).
void LinearFixedRows(float ax, float bx, float ay, float by, int n, int* x_out, int* y_out);

// True when every bilinear tap of the fixed-point (xi, yi) lies inside a width x height source:
// 0 <= x <= width - 1 and 0 <= y <= height - 1.
inline bool TapsInside(int xi, int yi, int width, int height) {
  return xi >= 0 && xi <= (width - 1) << kSampleFracBits && yi >= 0 &&
         yi <= (height - 1) << kSampleFracBits;
}

// Packed one bit a pixel (io/image_io.h PackedMask's order: pixel k in bit 7 - k % 8 of byte
// k / 8): set where every bilinear tap of the fixed-point (xi[k], yi[k]) lies inside a width x
// height source (0 <= x <= width - 1, 0 <= y <= height - 1). Writes (n + 7) / 8 bytes, the bits
// past n 0.
void InsideMaskBits(const int* xi, const int* yi, int n, int width, int height, uint8_t* bits);

// The 8-bit RGB sampler's paths, each giving the same bits: one pixel at a time (SSE2 or plain
// C++), and blocks of four pixels (SSE4.1), eight (AVX2) or sixteen (AVX-512 BW and VBMI).
enum class SamplerPath { kOnePixel, kSse41, kAvx2, kAvx512 };
// The widest path the sampler takes: the widest this CPU runs (checked at run time), at most the
// cap.
SamplerPath WidestSamplerPath();
// Caps the paths the kernel takes at `widest`: the sampler's, and those of LinearFixedRows (AVX2,
// AVX-512) and InsideMaskBits (AVX2), which take plain C++ below them. Tests compare every path,
// benches time them. Returns the previous cap.
SamplerPath CapSamplerPath(SamplerPath widest);

}  // namespace shutterlab
