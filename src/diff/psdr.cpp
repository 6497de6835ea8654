#include "diff/psdr.h"

#include "core/batch_stats.h"

#include <chrono>
#include <cmath>

namespace penumbra {

namespace {

// Mean and standard error over batches of a boundary estimator (run with independent seeds).
template <typename Estimator>
void boundary_batches(const Scene& scene, const PsdrOptions& options, int spp, uint64_t salt, const Estimator& estimate,
                      Image& mean, Image& stderr_img) {
    const Film& film = *scene.sensor->film;
    const int B = options.interior.batches;
    mean = Image(film.width, film.height);
    if (B > 1) stderr_img = Image(film.width, film.height);
    if (spp <= 0) return;
    ImageBatches batches;
    for (int b = 0; b < B; ++b) {
        BoundaryOptions bo;
        bo.samples_per_pixel = spp;
        bo.seed = options.interior.seed + salt * uint64_t(b + 1);
        bo.threads = options.interior.threads;
        bo.path = options.interior.path;
        batches.add(estimate(bo));
    }
    mean = batches.mean();
    if (B > 1) stderr_img = batches.standard_error();
}

constexpr uint64_t PrimarySalt = 0x2545F4914F6CDD1DULL, DirectSalt = 0x9FB21C651E98DF25ULL,
                   IndirectSalt = 0xC2B2AE3D27D4EB4FULL, PixelSalt = 0x165667B19E3779F9ULL;

} // namespace

PsdrDerivative psdr_derivative(const Scene& scene, const Parameters& params, const PsdrOptions& options) {
    PsdrDerivative out;
    out.interior = render_derivative(scene, params, options.interior);
    boundary_batches(scene, options, options.primary_spp, PrimarySalt,
                     [&, primary = PrimaryBoundary(scene)](const BoundaryOptions& bo) { return primary.derivative(params, bo); },
                     out.primary, out.primary_stderr);
    boundary_batches(scene, options, options.direct_spp, DirectSalt,
                     [&, direct = DirectBoundary(scene)](const BoundaryOptions& bo) { return direct.derivative(params, bo); },
                     out.direct, out.direct_stderr);
    boundary_batches(scene, options, options.indirect_spp, IndirectSalt,
                     [&, indirect = IndirectBoundary(scene)](const BoundaryOptions& bo) { return indirect.derivative(params, bo); },
                     out.indirect, out.indirect_stderr);
    boundary_batches(scene, options, needs_pixel_boundary(scene) ? options.pixel_spp : 0, PixelSalt,
                     [&, pixel = PixelBoundary(scene)](const BoundaryOptions& bo) { return pixel.derivative(params, bo); },
                     out.pixel, out.pixel_stderr);
    const Film& film = *scene.sensor->film;
    out.total = Image(film.width, film.height);
    const bool have_se = options.interior.batches > 1;
    if (have_se) out.total_stderr = Image(film.width, film.height);
    for (size_t i = 0; i < out.total.pixels.size(); ++i) {
        out.total.pixels[i] = out.interior.derivative.pixels[i] + out.primary.pixels[i] + out.direct.pixels[i] +
                              out.indirect.pixels[i] + out.pixel.pixels[i];
        if (have_se) {
            // The estimators use independent samples: variances add.
            const Vec3d a(out.interior.stderr_img.pixels[i]), b(out.primary_stderr.pixels[i]), c(out.direct_stderr.pixels[i]),
                d(out.indirect_stderr.pixels[i]), e(out.pixel_stderr.pixels[i]);
            const Vec3d v = a * a + b * b + c * c + d * d + e * e;
            out.total_stderr.pixels[i] = Color3f(float(std::sqrt(v.x)), float(std::sqrt(v.y)), float(std::sqrt(v.z)));
        }
    }
    return out;
}

Gradient psdr_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const PsdrOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    Gradient g = render_gradient(scene, params, adjoint, options.interior);
    BoundaryOptions bo;
    bo.threads = options.interior.threads;
    bo.path = options.interior.path;
    if (options.primary_spp > 0) {
        bo.samples_per_pixel = options.primary_spp;
        bo.seed = options.interior.seed + PrimarySalt;
        PrimaryBoundary(scene).gradient(params, adjoint, bo, g.values);
    }
    if (options.direct_spp > 0) {
        bo.samples_per_pixel = options.direct_spp;
        bo.seed = options.interior.seed + DirectSalt;
        DirectBoundary(scene).gradient(params, adjoint, bo, g.values);
    }
    if (options.indirect_spp > 0) {
        bo.samples_per_pixel = options.indirect_spp;
        bo.seed = options.interior.seed + IndirectSalt;
        IndirectBoundary(scene).gradient(params, adjoint, bo, g.values);
    }
    if (options.pixel_spp > 0 && needs_pixel_boundary(scene)) {
        bo.samples_per_pixel = options.pixel_spp;
        bo.seed = options.interior.seed + PixelSalt;
        PixelBoundary(scene).gradient(params, adjoint, bo, g.values);
    }
    g.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return g;
}

} // namespace penumbra
