// Checks a derivative image against central finite differences (common random numbers), with tolerances
// derived from standard errors estimated from 16 independent batches of each estimator:
//  - unbiasedness: |z| of the image mean < 4 (t with 15 dof: P(|t| > 4) ~ 1e-3), its standard error from the
//    spread of the batches' image means where a side measured it (check_against(DerivativeImage,
//    FiniteDifference)): a filter splats a sample over several pixels and a path carries all three channels,
//    so the pixels' errors correlate and sqrt(Σσ²)/N understates the mean's error (by ~2.4× on a gray
//    icosphere under a Gaussian filter);
//  - per 2 × 2 block: fewer than 2% of the block channels that carry at least 1% of the largest reference
//    block value beyond 4σ (expected ~0.1% if unbiased). Where only a few of the reference's samples switch
//    sides of an edge (a wide filter's tails, a silhouette crossing a pixel's corner), its batch standard
//    error underestimates its error, and a per-pixel count measures the reference's skew rather than the
//    estimator: the mean of a block is closer to normal, the floor leaves out the far tails where the
//    reference's weights are ~1e-3 of the peak, and a bias that matters still spans a block and shows;
//  - relerr = Σ|D − R| / Σ|R| below 1.5 × its pure-noise expectation sqrt(2/π) Σσ / Σ|R| (+0.02 for the
//    O(h²) truncation error of the central difference), and the same after 4 × 4 block averaging (relerr4),
//    where noise averages out and a bias does not.
#pragma once
#include "diff/finite_difference.h"
#include "diff/psdr/interior.h"
#include "diff/psdr/psdr.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace penumbra::test {

struct DiffCheck {
    Comparison comparison;
    Comparison comparison4;      // after 4 × 4 block averaging
    double noise_relerr = 0;     // expected relerr from noise alone
    double outliers_4sigma = 0;  // fraction of the significant 2 × 2 block channels beyond 4σ
    bool passes() const {
        return std::abs(comparison.mean_z) < 4.0 && outliers_4sigma < 0.02 &&
               comparison.relerr < 1.5 * noise_relerr + 0.02 &&
               comparison4.relerr < 1.5 * comparison4.noise_relerr + 0.02;
    }
};

// The standard errors of an image's k × k block means (k = 2 or 4): the per-pixel errors combined as
// independent, or, where the estimator measured the blocks' errors from its batches' block means for this
// image's size (DerivativeImage::block_stderr), the larger of the two: a filter splats a sample over
// neighbouring pixels, whose errors then correlate and the formula understates a block's error, while 16
// batches measure it with ~18% error of their own (and antithetic samples correlate pixels negatively).
inline Image block_stderr_of(const Image& image, const Image& se, const std::array<Image, 2>& measured,
                             int k) {
    Image out = block_average_stderr(se, k);
    const Image& m = measured[k == 2 ? 0 : 1];
    if (m.pixels.empty() || m.width != (image.width + k - 1) / k || m.height != (image.height + k - 1) / k)
        return out;
    if (out.pixels.empty()) return m;
    for (size_t i = 0; i < out.pixels.size(); ++i)
        out.pixels[i] = max(out.pixels[i], m.pixels[i]);
    return out;
}

inline DiffCheck check_against(const Image& d, const Image& d_se, const Image& fd, const Image& fd_se,
                               const std::array<Image, 2>& d_blocks = {},
                               const std::array<Image, 2>& fd_blocks = {}) {
    DiffCheck c;
    c.comparison = compare_images(d, fd, d_se, fd_se);
    c.comparison4 =
        compare_images(block_average(d, 4), block_average(fd, 4), block_stderr_of(d, d_se, d_blocks, 4),
                       block_stderr_of(fd, fd_se, fd_blocks, 4));
    c.noise_relerr = c.comparison.noise_relerr;
    const Image d2 = block_average(d, 2), fd2 = block_average(fd, 2);
    const Image d2_se = block_stderr_of(d, d_se, d_blocks, 2),
                fd2_se = block_stderr_of(fd, fd_se, fd_blocks, 2);
    double largest = 0;
    for (const Color3f& r : fd2.pixels) largest = std::max(largest, double(max_component(abs(r))));
    int outliers = 0, n = 0;
    for (size_t i = 0; i < fd2.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            if (std::max(std::abs(d2.pixels[i][k]), std::abs(fd2.pixels[i][k])) < 0.01 * largest) continue;
            ++n;
            const double s = std::hypot(double(d2_se.pixels[i][k]), double(fd2_se.pixels[i][k]));
            if (std::abs(d2.pixels[i][k] - fd2.pixels[i][k]) > 4.0 * s) ++outliers;
        }
    c.outliers_4sigma = n > 0 ? double(outliers) / n : 0.0;
    return c;
}

// The same check with the z of the image mean from the spread of the batches' means, and the blocks' errors
// from the batches' block means, where a side measured them
// (DerivativeImage::mean_stderr, FiniteDifference::mean_stderr): pixel errors correlate (a filter splats a
// sample over several pixels, a path carries all three channels), and sqrt(Σσ²)/N understates the mean's
// error by a factor of ~2 on such images; a stored reference keeps the per-pixel formula.
inline DiffCheck check_against(const DerivativeImage& d, const FiniteDifference& fd) {
    DiffCheck c = check_against(d.derivative, d.stderr_img, fd.derivative, fd.stderr_img, d.block_stderr,
                                fd.block_stderr);
    const double n = 3.0 * double(fd.derivative.pixels.size());
    const auto pixel_formula = [n](const Image& se) {
        double v = 0;
        for (const Color3f& s : se.pixels)
            for (int k = 0; k < 3; ++k)
                v += double(s[k]) * s[k];
        return std::sqrt(v) / n;
    };
    const double se = std::hypot(d.mean_stderr > 0 ? d.mean_stderr : pixel_formula(d.stderr_img),
                                 fd.mean_stderr > 0 ? fd.mean_stderr : pixel_formula(fd.stderr_img));
    if (se > 0) c.comparison.mean_z = (c.comparison.mean_test - c.comparison.mean_ref) / se;
    return c;
}

// psdr over 16 batches (for standard errors) with the given per-batch budgets: interior, primary, direct,
// indirect and pixel.
inline PsdrOptions batched(const Scene& scene, uint64_t seed, int interior, int primary, int direct,
                           int indirect, int pixel = 0) {
    PsdrOptions o;
    o.interior.spp = interior;
    o.interior.batches = 16;
    o.interior.seed = seed;
    o.interior.path = path_settings(scene);
    o.primary_spp = primary;
    o.direct_spp = direct;
    o.indirect_spp = indirect;
    o.pixel_spp = pixel;
    return o;
}

struct DerivativePair {
    DerivativeImage derivative;
    FiniteDifference fd;
};

// Interior derivative and finite differences for the enabled parameters, 16 batches each.
inline DerivativePair derivative_and_fd(Scene& scene, Parameters& params, int spp_derivative, int spp_fd, double h) {
    // PENUMBRA_TEST_SEED re-runs the checks with other random numbers (to see that they do not pass by luck).
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    const uint64_t seed = env ? std::strtoull(env, nullptr, 10) : 0;
    DiffOptions o;
    o.spp = spp_derivative;
    o.batches = 16;
    o.seed = 7 + 1000 * seed;
    o.path = path_settings(scene);
    RenderOptions ro;
    ro.spp = spp_fd;
    ro.seed = 1234 + 1000 * seed;
    return {render_derivative(scene, params, o), finite_difference(scene, params, h, ro, 16)};
}

// Where no finite-difference sample of any batch changed (the reference is exactly 0 with standard error 0),
// the batch standard error says nothing: the boundary terms still splat the pixel filter's tails there (the
// Gaussian reaches 2 px, and the renderer draws few samples so far out), a small but nonzero expectation. Zero
// events in N = spp × batches samples bound the reference's expectation at about ΔL / (2h N) (one switching
// sample, ΔL ≤ the largest radiance within the filter radius): that detection limit is used as the reference's
// standard error in those pixels only.
inline Image with_detection_limit(const FiniteDifference& fd, const Image& primal, double h, int samples, float radius) {
    Image err = fd.stderr_img;
    const int r = int(std::ceil(radius));
    for (int y = 0; y < err.height; ++y)
        for (int x = 0; x < err.width; ++x) {
            Color3f jump(0.f);
            for (int v = std::max(0, y - r); v <= std::min(err.height - 1, y + r); ++v)
                for (int u = std::max(0, x - r); u <= std::min(err.width - 1, x + r); ++u) jump = max(jump, primal.at(u, v));
            for (int k = 0; k < 3; ++k)
                if (err.at(x, y)[k] == 0.f && fd.derivative.at(x, y)[k] == 0.f)
                    err.at(x, y)[k] = float(jump[k] / (2.0 * h * samples));
        }
    return err;
}

// Where a visibility edge moves by a sizeable fraction of a pixel per step, the central difference has a
// truncation error comparable to its noise: it is estimated per pixel by Richardson extrapolation from the
// difference at twice the step, t = |D(2h) − D(h)| / 3 (the O(h²) error of D(h)), and added in quadrature to
// the reference's standard error `error`.
inline Image with_truncation_error(const Image& error, const FiniteDifference& fd_h, const FiniteDifference& fd_2h) {
    Image out = error;
    for (size_t i = 0; i < out.pixels.size(); ++i) {
        const Color3f t = abs(fd_2h.derivative.pixels[i] - fd_h.derivative.pixels[i]) / 3.f;
        const Color3f s = out.pixels[i];
        out.pixels[i] = Color3f(std::hypot(s.x, t.x), std::hypot(s.y, t.y), std::hypot(s.z, t.z));
    }
    return out;
}

// The dot-product test of forward against reverse mode on the same samples: ⟨a, Jv⟩ (adjoint · derivative image)
// and ⟨Jᵀa, v⟩ (gradient · direction), with Σ|a_k (Jv)_k| as the scale of their rounding differences.
struct AdjointPair {
    double forward = 0, reverse = 0, scale = 0;
};
inline AdjointPair adjoint_pair(const Image& adjoint, const Image& derivative, const std::vector<double>& gradient,
                                const std::vector<float>& direction) {
    AdjointPair p;
    for (size_t i = 0; i < adjoint.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            p.forward += double(adjoint.pixels[i][k]) * derivative.pixels[i][k];
            p.scale += std::abs(double(adjoint.pixels[i][k]) * derivative.pixels[i][k]);
        }
    for (size_t k = 0; k < direction.size(); ++k) p.reverse += gradient[k] * direction[k];
    return p;
}

inline std::string describe(const DiffCheck& c) {
    return "relerr " + std::to_string(c.comparison.relerr) + " (noise " + std::to_string(c.noise_relerr) + "), relerr4 " +
           std::to_string(c.comparison4.relerr) + " (noise " + std::to_string(c.comparison4.noise_relerr) + "), mean " +
           std::to_string(c.comparison.mean_test) + " vs fd " + std::to_string(c.comparison.mean_ref) + ", z " +
           std::to_string(c.comparison.mean_z) + ", outliers(4σ, 2x2 blocks) " + std::to_string(c.outliers_4sigma);
}

// A moving shadow: the derivative `d` and its interior term alone against central differences `fd` at step h
// (`samples` per pixel and side) whose standard error takes in the detection limit and the truncation error
// (from `fd2` at 2h). The total must match; the interior term alone must miss the shadow's motion. `label`
// names the case in the log.
inline void expect_only_the_total_matches(const std::string& label, const Scene& scene,
                                          const DerivativeImage& d, const FiniteDifference& fd,
                                          const FiniteDifference& fd2, double h, int samples) {
    const Image reference_error = with_truncation_error(
        with_detection_limit(fd, d.primal, h, samples, scene.sensor->film->rfilter->radius()), fd, fd2);
    const DiffCheck total = check_against(d.derivative, d.stderr_img, fd.derivative, reference_error);
    const DerivativeTerm& interior_term = d.term("interior");
    const DiffCheck interior =
        check_against(interior_term.derivative, interior_term.stderr_img, fd.derivative, reference_error);
    std::printf("  %s: interior+direct %s\n  interior only %s\n", label.c_str(), describe(total).c_str(),
                describe(interior).c_str());
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_FALSE(interior.passes()) << "the interior term alone must miss the moving shadow: " << describe(interior);
}

// The same against central differences computed here at h = 1e-2 and 2e-2 (16 batches of `ro`).
inline void expect_only_the_total_matches(const std::string& label, Scene& scene, Parameters& params,
                                          const DerivativeImage& d, const RenderOptions& ro) {
    const FiniteDifference fd = finite_difference(scene, params, 1e-2, ro, 16);
    const FiniteDifference fd2 = finite_difference(scene, params, 2e-2, ro, 16);
    expect_only_the_total_matches(label, scene, d, fd, fd2, 1e-2, ro.spp * 16);
}

} // namespace penumbra::test
