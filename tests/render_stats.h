// Monte Carlo statistics over independent renders (different seeds): per-pixel means and standard errors,
// and the standard error of the image mean. Every render-based tolerance in the tests derives from these.
#pragma once
#include "core/batch_stats.h"
#include "render/render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace penumbra::test {

struct BatchStats {
    Image mean, stderr_img;       // per pixel (per channel)
    double image_mean = 0.0;      // mean over pixels and channels
    double image_mean_stderr = 0.0;
};

inline BatchStats render_batches(const Scene& scene, int batches, int spp, uint64_t seed0 = 1) {
    std::vector<Image> images;
    for (int b = 0; b < batches; ++b) {
        RenderOptions opt;
        opt.spp = spp;
        opt.seed = seed0 + uint64_t(b) * 7919;
        images.push_back(render(scene, opt));
    }
    ImageBatches pixel_stats;
    for (const Image& im : images) pixel_stats.add(im);
    BatchStats s{pixel_stats.mean(), pixel_stats.standard_error()};
    std::vector<double> means;
    for (const Image& im : images) {
        double m = 0;
        for (const auto& p : im.pixels) m += p.x + p.y + p.z;
        means.push_back(m / (3.0 * im.pixels.size()));
    }
    double m = 0, m2 = 0;
    for (double v : means) {
        m += v;
        m2 += v * v;
    }
    m /= batches;
    s.image_mean = m;
    s.image_mean_stderr = std::sqrt(std::max(0.0, (m2 / batches - m * m) * batches / (batches - 1)) / batches);
    return s;
}

// The image of `scene` is bit-identical rendered with 1 and with 2 threads (same seed), is not black, and
// changes with the seed.
inline void expect_same_image_whatever_the_thread_count(const Scene& scene, const std::string& what) {
    RenderOptions one, two;
    one.spp = two.spp = 4;
    one.seed = two.seed = 42;
    one.threads = 1;
    two.threads = 2;
    const Image a = render(scene, one), b = render(scene, two);
    ASSERT_EQ(a.pixels.size(), b.pixels.size()) << what;
    double sum = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        ASSERT_EQ(a.pixels[i], b.pixels[i]) << what << ": pixel " << i;
        sum += a.pixels[i].x + a.pixels[i].y + a.pixels[i].z;
    }
    EXPECT_GT(sum, 0.0) << what << ": black image";
    RenderOptions other = one;
    other.seed = 43;
    EXPECT_NE(render(scene, other).pixels, a.pixels) << what << ": the seed must change the image";
}

} // namespace penumbra::test
