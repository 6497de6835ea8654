// Shared by the bdpt tests: small scenes and statistics over independent renders. Every comparison is a
// z-score whose standard error comes from the spread of independent seeds.
#pragma once
#include "render/render.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

namespace penumbra::test {

inline std::string bdpt_sensor(const std::string& type, const std::string& lookat, float fov, int res,
                               const std::string& extra = "", const std::string& rfilter = "box") {
    return "<sensor type=\"" + type + "\"><float name=\"fov\" value=\"" + std::to_string(fov) + "\"/>" +
           extra + "<transform name=\"to_world\">" + lookat +
           "</transform><sampler type=\"independent\"><integer name=\"sample_count\" value=\"4\"/></sampler>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
           std::to_string(res) + "\"/><integer name=\"height\" value=\"" + std::to_string(res) +
           "\"/><rfilter type=\"" + rfilter + "\"/></film></sensor>";
}

inline std::string integrator_xml(const std::string& type, const std::string& params = "") {
    return "<integrator type=\"" + type + "\">" + params + "</integrator>";
}

// The image mean and the means of a 4x4 grid of blocks (channels summed), over independent renders.
struct BlockStats {
    std::vector<double> mean, stderr_; // [0]: image, [1..16]: blocks
    double seconds = 0.0;              // render time per image
    double pixel_variance = 0.0;       // per-pixel variance of one image (channel mean), averaged over pixels
};

inline BlockStats block_stats(const Scene& scene, int renders, int spp, uint64_t seed0) {
    const int n = 17;
    std::vector<std::vector<double>> values;
    std::vector<Image> images;
    BlockStats out;
    for (int r = 0; r < renders; ++r) {
        RenderOptions opt;
        opt.spp = spp;
        opt.seed = seed0 + uint64_t(r) * 7919;
        RenderStats stats;
        images.push_back(render(scene, opt, &stats));
        out.seconds += stats.seconds / renders;
        const Image& im = images.back();
        std::vector<double> v(n, 0.0);
        for (int y = 0; y < im.height; ++y)
            for (int x = 0; x < im.width; ++x) {
                const Color3f p = im.at(x, y);
                const double c = (p.x + p.y + p.z) / 3.0;
                v[0] += c / (im.width * im.height);
                const int b = 1 + (y * 4 / im.height) * 4 + x * 4 / im.width;
                v[size_t(b)] += c * 16.0 / (im.width * im.height);
            }
        values.push_back(v);
    }
    out.mean.assign(n, 0.0);
    out.stderr_.assign(n, 0.0);
    for (int i = 0; i < n; ++i) {
        double m = 0, m2 = 0;
        for (const auto& v : values)
            m += v[size_t(i)], m2 += v[size_t(i)] * v[size_t(i)];
        m /= renders;
        out.mean[size_t(i)] = m;
        out.stderr_[size_t(i)] =
            std::sqrt(std::max(0.0, (m2 / renders - m * m) * renders / (renders - 1)) / renders);
    }
    // Per-pixel variance across renders (the variance of one render's pixel estimate).
    const size_t pixels = images[0].pixels.size();
    double var = 0;
    for (size_t i = 0; i < pixels; ++i) {
        double m = 0, m2 = 0;
        for (const Image& im : images) {
            const Color3f p = im.pixels[i];
            const double c = (p.x + p.y + p.z) / 3.0;
            m += c, m2 += c * c;
        }
        m /= renders;
        var += (m2 / renders - m * m) * renders / (renders - 1);
    }
    out.pixel_variance = var / double(pixels);
    return out;
}

// z-scores of the differences between two sets of block statistics: [0] image mean, then the 16 blocks.
inline std::vector<double> z_scores(const BlockStats& a, const BlockStats& b) {
    std::vector<double> z;
    for (size_t i = 0; i < a.mean.size(); ++i) {
        const double se = std::sqrt(a.stderr_[i] * a.stderr_[i] + b.stderr_[i] * b.stderr_[i]);
        z.push_back(se > 0 ? (a.mean[i] - b.mean[i]) / se : (a.mean[i] == b.mean[i] ? 0.0 : INFINITY));
    }
    return z;
}

inline double max_abs(const std::vector<double>& v, size_t from) {
    double m = 0;
    for (size_t i = from; i < v.size(); ++i)
        m = std::max(m, std::abs(v[i]));
    return m;
}

} // namespace penumbra::test
