#include "core/colormap.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace penumbra {

namespace {
float mean_channel(const Color3f& c) { return (c.x + c.y + c.z) / 3.f; }
} // namespace

float robust_scale(const Image& img) {
    std::vector<float> mags;
    mags.reserve(img.pixels.size());
    for (const Color3f& c : img.pixels)
        if (std::isfinite(mean_channel(c))) mags.push_back(std::abs(mean_channel(c)));
    if (mags.empty()) return 1.f;
    const size_t k = std::min(mags.size() - 1, size_t(0.99 * double(mags.size())));
    std::nth_element(mags.begin(), mags.begin() + k, mags.end());
    return mags[k] > 0.f ? mags[k] : 1.f;
}

// Endpoints of Moreland's cool-warm map (sRGB); interpolation in sRGB, then decoded to linear.
Image diverging_colormap(const Image& img, float scale) {
    if (!(scale > 0.f)) scale = robust_scale(img);
    const Color3f blue(0.230f, 0.299f, 0.754f), red(0.706f, 0.016f, 0.150f), white(1.f);
    Image out(img.width, img.height);
    for (size_t i = 0; i < img.pixels.size(); ++i) {
        const float v = mean_channel(img.pixels[i]);
        const float t = std::isfinite(v) ? std::clamp(v / scale, -1.f, 1.f) : 0.f;
        const Color3f end = t < 0.f ? blue : red;
        const Color3f srgb = white * (1.f - std::abs(t)) + end * std::abs(t);
        out.pixels[i] = Color3f(srgb_to_linear(srgb.x), srgb_to_linear(srgb.y), srgb_to_linear(srgb.z));
    }
    return out;
}

} // namespace penumbra
