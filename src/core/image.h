// RGB float images and their file formats: OpenEXR (linear), PNG/JPEG/BMP/TGA/HDR (stb).
#pragma once
#include "core/vector.h"

#include <cstdint>
#include <string>
#include <vector>

namespace penumbra {

struct Image {
    int width = 0, height = 0;
    std::vector<Color3f> pixels; // row-major, top row first

    Image() = default;
    Image(int w, int h, const Color3f& fill = Color3f(0.f)) : width(w), height(h), pixels(size_t(w) * h, fill) {}
    Color3f& at(int x, int y) { return pixels[size_t(y) * width + x]; }
    const Color3f& at(int x, int y) const { return pixels[size_t(y) * width + x]; }
};

// The largest image read_image accepts by default: 2^28 pixels (16384 x 16384; a 16k x 8k environment map is
// half of it), 3 GiB as float RGB. The size in a file's header is checked before anything is allocated for it.
constexpr int64_t MaxImagePixels = int64_t(1) << 28;

// Reads EXR (linear) or an 8-bit/HDR format via stb; 8-bit images are converted from sRGB to linear when
// `srgb_to_linear` is set (Mitsuba's `raw=false`). Throws Error naming the file on failure, and for images of
// more than `max_pixels` pixels.
// The image averaged over k × k blocks (partial blocks at the right and bottom edges averaged over what they
// hold), and its standard error from per-pixel standard errors (pixels independent). Noise averages out over
// a block while a bias does not: relerr after 4 × 4 block averaging ("relerr4") is the accuracy measure of
// the estimator suite.
Image block_average(const Image& image, int k);
Image block_average_stderr(const Image& stderr_img, int k);

Image read_image(const std::string& path, bool srgb_to_linear = true, int64_t max_pixels = MaxImagePixels);
// Writes by extension: .exr (32-bit float RGB) or .png (sRGB-encoded, clamped 8-bit). The file is written to a
// temporary name and renamed, so a failed write never leaves a partial file. Throws Error on failure.
void write_image(const std::string& path, const Image& image);
// Writes an 8-bit PNG of `channels` (1: gray, 2: gray + alpha, 3: RGB, 4: RGBA) interleaved values per pixel:
// color channels clamped and sRGB-encoded, alpha clamped and stored linearly. Throws Error on failure.
void write_png(const std::string& path, int width, int height, int channels,
               const std::vector<float>& values);

// Linear sRGB (Rec. 709 primaries, D65 white) to CIE 1931 XYZ.
Color3f srgb_to_xyz(const Color3f& rgb);

float srgb_to_linear(float v);
float linear_to_srgb(float v);

} // namespace penumbra
