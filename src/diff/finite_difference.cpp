#include "diff/finite_difference.h"

#include "core/batch_stats.h"

#include <chrono>
#include <cmath>

namespace penumbra {

FiniteDifference finite_difference(Scene& scene, Parameters& params, double h, const RenderOptions& options,
                                   int batches) {
    if (params.dimension() == 0) throw Error("finite differences: no parameter is enabled");
    if (!(h > 0.0) || !std::isfinite(h)) throw Error("finite differences: the step must be positive and finite");
    if (batches <= 0) throw Error("finite differences: batches must be positive");
    const auto start = std::chrono::steady_clock::now();
    ImageBatches estimates;
    for (int b = 0; b < batches; ++b) {
        RenderOptions o = options;
        o.seed = options.seed + 0x9E3779B97F4A7C15ULL * uint64_t(b);
        o.stratified = true; // the two sides see the same strata: what switches across an edge is nearly deterministic
        if (options.progress) o.progress = [&, b](float f) { options.progress((b + 0.5f * f) / batches); };
        params.displace(scene, +h);
        const Image plus = render(scene, o);
        if (options.progress) o.progress = [&, b](float f) { options.progress((b + 0.5f + 0.5f * f) / batches); };
        params.displace(scene, -h);
        const Image minus = render(scene, o);
        Image d(plus.width, plus.height);
        for (size_t i = 0; i < d.pixels.size(); ++i) d.pixels[i] = (plus.pixels[i] - minus.pixels[i]) / float(2.0 * h);
        estimates.add(d);
    }
    params.displace(scene, 0.0);

    FiniteDifference fd{estimates.mean(), estimates.standard_error(), 0.0, estimates.mean_standard_error(),
                        estimates.block_standard_errors()};
    fd.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return fd;
}

Comparison compare_images(const Image& test, const Image& ref, const Image& test_stderr, const Image& ref_stderr) {
    if (test.width != ref.width || test.height != ref.height)
        throw Error("compare: image sizes differ (" + std::to_string(test.width) + "x" + std::to_string(test.height) +
                    " vs " + std::to_string(ref.width) + "x" + std::to_string(ref.height) + ")");
    for (const Image* s : {&test_stderr, &ref_stderr})
        if (!s->pixels.empty() && (s->width != ref.width || s->height != ref.height))
            throw Error("compare: the standard-error image does not have the images' size");
    const bool have_se = !test_stderr.pixels.empty() || !ref_stderr.pixels.empty();
    Comparison c;
    double abs_diff = 0, abs_ref = 0, var_sum = 0, sigma_sum = 0;
    size_t outliers = 0;
    const size_t n = ref.pixels.size() * 3;
    for (size_t i = 0; i < ref.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            const double t = test.pixels[i][k], r = ref.pixels[i][k];
            abs_diff += std::abs(t - r);
            abs_ref += std::abs(r);
            c.mean_test += t;
            c.mean_ref += r;
            if (have_se) {
                const double s1 = test_stderr.pixels.empty() ? 0.0 : test_stderr.pixels[i][k];
                const double s2 = ref_stderr.pixels.empty() ? 0.0 : ref_stderr.pixels[i][k];
                const double var = s1 * s1 + s2 * s2;
                var_sum += var;
                sigma_sum += std::sqrt(var);
                if (std::abs(t - r) > 3.0 * std::sqrt(var)) ++outliers;
            }
        }
    c.relerr = abs_ref > 0 ? abs_diff / abs_ref : (abs_diff > 0 ? INFINITY : 0.0);
    c.mean_test /= double(n);
    c.mean_ref /= double(n);
    if (have_se) {
        const double se = std::sqrt(var_sum) / double(n);
        c.mean_z = se > 0 ? (c.mean_test - c.mean_ref) / se : 0.0;
        c.outlier_fraction = double(outliers) / double(n);
        // E|X| = sqrt(2/π) σ for X ~ N(0, σ²).
        c.noise_relerr = abs_ref > 0 ? std::sqrt(2.0 / M_PI) * sigma_sum / abs_ref : 0.0;
    }
    return c;
}

} // namespace penumbra
