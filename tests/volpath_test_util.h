// Scenes and statistics shared by the volumetric integrator tests: independent renders (different seeds) give
// per-batch image means and 4x4-pixel block means, whose spread gives the standard errors every tolerance
// derives from (ptracer splats correlate neighbouring pixels, so blocks are compared, not pixels).
#pragma once
#include "render/render.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

namespace penumbra::test {

inline std::string vp_sensor(const std::string& transform, int res, const std::string& extra = "",
                             const std::string& type = "perspective") {
    return "<sensor type=\"" + type + "\">" + extra + "<transform name=\"to_world\">" + transform +
           "</transform><sampler type=\"independent\"><integer name=\"sample_count\" value=\"4\"/></sampler>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
           std::to_string(res) + "\"/><integer name=\"height\" value=\"" + std::to_string(res) +
           "\"/><rfilter type=\"box\"/></film></sensor>";
}

inline std::string vp_integrator(const std::string& type, const std::string& extra = "") {
    return "<integrator type=\"" + type + "\">" + extra + "</integrator>";
}

// Per-batch statistics: image means and block means (per channel), their mean and standard error.
struct BlockStats {
    int blocks_x = 0, blocks_y = 0;
    std::vector<double> mean, stderr_; // index (by * blocks_x + bx) * 3 + c; the last 3 entries: image mean
    double pixel_variance = 0;         // per-render pixel variance averaged over pixels and channels
    double channel_variance[3] = {0, 0, 0}; // the same per channel
};

inline BlockStats block_stats(const Scene& scene, int batches, int spp, uint64_t seed0, int block = 4) {
    const int w = scene.sensor->film->width, h = scene.sensor->film->height;
    BlockStats s;
    s.blocks_x = w / block;
    s.blocks_y = h / block;
    const size_t n = size_t(s.blocks_x * s.blocks_y + 1) * 3;
    std::vector<double> sum(n, 0.0), sum2(n, 0.0);
    std::vector<double> pix(size_t(w) * h * 3, 0.0), pix2(size_t(w) * h * 3, 0.0);
    for (int b = 0; b < batches; ++b) {
        RenderOptions opt;
        opt.spp = spp;
        opt.seed = seed0 + uint64_t(b) * 7919;
        const Image im = render(scene, opt);
        std::vector<double> v(n, 0.0);
        for (int y = 0; y < s.blocks_y * block; ++y)
            for (int x = 0; x < s.blocks_x * block; ++x)
                for (int c = 0; c < 3; ++c) {
                    const double p = im.at(x, y)[c];
                    v[size_t((y / block) * s.blocks_x + x / block) * 3 + c] += p / (block * block);
                    v[n - 3 + c] += p / (double(s.blocks_x * block) * s.blocks_y * block);
                    const size_t i = (size_t(y) * w + x) * 3 + c;
                    pix[i] += p;
                    pix2[i] += p * p;
                }
        for (size_t i = 0; i < n; ++i) {
            sum[i] += v[i];
            sum2[i] += v[i] * v[i];
        }
    }
    s.mean.resize(n);
    s.stderr_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        s.mean[i] = sum[i] / batches;
        const double var =
            std::max(0.0, (sum2[i] / batches - s.mean[i] * s.mean[i]) * batches / (batches - 1));
        s.stderr_[i] = std::sqrt(var / batches);
    }
    for (size_t i = 0; i < pix.size(); ++i) {
        const double m = pix[i] / batches;
        s.channel_variance[i % 3] +=
            std::max(0.0, (pix2[i] / batches - m * m) * batches / (batches - 1)) / (pix.size() / 3);
    }
    s.pixel_variance = (s.channel_variance[0] + s.channel_variance[1] + s.channel_variance[2]) / 3;
    return s;
}

// Agreement of two estimators: |z| of the image mean below 4, and at most one block with a channel beyond |z|
// = 4 (with 15 degrees of freedom P(|t| > 4) ~ 1.2e-3 per entry: ~0.1 expected among ~100 entries if both are
// unbiased; blocks, not channels, are counted because grey scenes correlate the channels of a block).
// Entries whose standard error is zero on both sides must agree to 1e-6. `channel` >= 0 compares that channel
// only. Returns the largest block |z|.
inline double expect_agreement(const BlockStats& a, const BlockStats& b, const std::string& what,
                               int channel = -1) {
    const size_t n = a.mean.size();
    EXPECT_EQ(n, b.mean.size());
    double max_z = 0;
    int outliers = 0, outlier_block = -1;
    for (size_t i = 0; i + 3 < n; ++i) {
        if (channel >= 0 && int(i % 3) != channel) continue;
        const double se = std::hypot(a.stderr_[i], b.stderr_[i]);
        const double d = std::abs(a.mean[i] - b.mean[i]);
        const double z = se > 0 ? d / se : (d > 1e-6 ? INFINITY : 0.0);
        max_z = std::max(max_z, z);
        if (z > 4.0 && int(i / 3) != outlier_block) {
            ++outliers;
            outlier_block = int(i / 3);
        }
        if (z > 3.5 && std::getenv("VP_VERBOSE"))
            std::printf("block %zu channel %zu: %.3e +- %.3e vs %.3e +- %.3e\n", i / 3, i % 3, a.mean[i],
                        a.stderr_[i], b.mean[i], b.stderr_[i]);
    }
    for (int c = 0; c < 3; ++c) {
        if (channel >= 0 && c != channel) continue;
        const size_t i = n - 3 + c;
        const double z = (a.mean[i] - b.mean[i]) / std::hypot(a.stderr_[i], b.stderr_[i]);
        EXPECT_LT(std::abs(z), 4.0) << what << " channel " << c << ": image mean " << a.mean[i] << " vs "
                                    << b.mean[i];
        std::printf("[ %s ] image mean z (channel %d) = %+.2f\n", what.c_str(), c, z);
    }
    EXPECT_LE(outliers, 1) << what << ": blocks beyond 4 standard errors";
    std::printf("[ %s ] max block |z| = %.2f over %zu block channels, %d blocks beyond 4\n", what.c_str(),
                max_z, channel >= 0 ? (n - 3) / 3 : n - 3, outliers);
    return max_z;
}

} // namespace penumbra::test
