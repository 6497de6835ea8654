#include "diff/paths/adaptive_pixels.h"

#include "core/error.h"
#include "core/sampler.h"

#include <cmath>
#include <string>

namespace penumbra {

int PixelBudget::count(uint64_t seed, uint64_t pixel) const {
    const double c = expected[pixel];
    const double whole = std::floor(c);
    Sampler sampler;
    sampler.start(seed ^ 0xA5A5A5A55A5A5A5AULL, pixel, ~uint64_t(0)); // a stream no path uses
    return int(whole) + (double(sampler.next_1d()) < c - whole ? 1 : 0);
}

PixelBudget uniform_budget(int width, int height, double spp) {
    if (!(spp > 0.0)) throw Error("pixel budget: the samples per pixel must be positive, got " + std::to_string(spp));
    return {width, height, std::vector<double>(size_t(width) * size_t(height), spp)};
}

PixelBudget adaptive_budget(const Image& adjoint, double spp, double defensive) {
    if (!(spp > 0.0)) throw Error("adaptive pixel sampling: the samples per pixel must be positive, got " + std::to_string(spp));
    if (!(defensive >= 0.0 && defensive <= 1.0))
        throw Error("adaptive pixel sampling: the defensive share must be in [0, 1], got " + std::to_string(defensive));
    const size_t n = adjoint.pixels.size();
    if (n == 0) throw Error("adaptive pixel sampling: empty adjoint image");
    std::vector<double> weight(n);
    double total = 0.0;
    for (size_t j = 0; j < n; ++j) {
        const Color3f& a = adjoint.pixels[j];
        weight[j] = std::abs(double(a.x)) + std::abs(double(a.y)) + std::abs(double(a.z));
        if (!std::isfinite(weight[j])) throw Error("adaptive pixel sampling: the adjoint image has non-finite values");
        total += weight[j];
    }
    if (!(total > 0.0) && defensive == 0.0)
        throw Error("adaptive pixel sampling: the adjoint image is zero everywhere (use a defensive share > 0)");
    PixelBudget b{adjoint.width, adjoint.height, std::vector<double>(n)};
    const double uniform = total > 0.0 ? defensive : 1.0;
    for (size_t j = 0; j < n; ++j) {
        const double p = (1.0 - uniform) * (total > 0.0 ? weight[j] / total : 0.0) + uniform / double(n);
        b.expected[j] = spp * double(n) * p;
    }
    return b;
}

} // namespace penumbra
