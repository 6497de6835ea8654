#include "diff/psdr.h"

#include <chrono>
#include <cmath>

namespace penumbra {

PsdrDerivative psdr_derivative(const Scene& scene, const Parameters& params, const PsdrOptions& options) {
    PsdrDerivative out;
    out.interior = render_derivative(scene, params, options.interior);
    const Film& film = *scene.sensor->film;
    const int B = options.interior.batches;
    out.primary = Image(film.width, film.height);
    std::vector<Image> batches;
    if (options.primary_spp > 0) {
        for (int b = 0; b < B; ++b) {
            BoundaryOptions bo;
            bo.samples_per_pixel = options.primary_spp;
            bo.seed = options.interior.seed + 0x2545F4914F6CDD1DULL * uint64_t(b + 1);
            bo.threads = options.interior.threads;
            bo.path = options.interior.path;
            batches.push_back(primary_boundary_derivative(scene, params, bo));
        }
    }
    if (B > 1) out.primary_stderr = Image(film.width, film.height);
    for (size_t i = 0; i < out.primary.pixels.size() && !batches.empty(); ++i) {
        Vec3d sum(0.0), sum2(0.0);
        for (const Image& im : batches) {
            const Vec3d v(im.pixels[i]);
            sum += v;
            sum2 += v * v;
        }
        const Vec3d mean = sum / double(B);
        out.primary.pixels[i] = Color3f(mean);
        if (B > 1) {
            const Vec3d var = (sum2 / double(B) - mean * mean) * (double(B) / (B - 1));
            out.primary_stderr.pixels[i] = Color3f(float(std::sqrt(std::max(0.0, var.x) / B)),
                                                   float(std::sqrt(std::max(0.0, var.y) / B)),
                                                   float(std::sqrt(std::max(0.0, var.z) / B)));
        }
    }
    out.total = out.interior.derivative;
    for (size_t i = 0; i < out.total.pixels.size(); ++i) out.total.pixels[i] += out.primary.pixels[i];
    if (B > 1) {
        out.total_stderr = Image(film.width, film.height);
        for (size_t i = 0; i < out.total.pixels.size(); ++i) {
            const Color3f a = out.interior.stderr_img.pixels[i];
            const Color3f b = out.primary_stderr.pixels.empty() ? Color3f(0.f) : out.primary_stderr.pixels[i];
            out.total_stderr.pixels[i] = Color3f(std::hypot(a.x, b.x), std::hypot(a.y, b.y), std::hypot(a.z, b.z));
        }
    }
    return out;
}

Gradient psdr_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const PsdrOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    Gradient g = render_gradient(scene, params, adjoint, options.interior);
    if (options.primary_spp > 0) {
        BoundaryOptions bo;
        bo.samples_per_pixel = options.primary_spp;
        bo.seed = options.interior.seed + 0x2545F4914F6CDD1DULL;
        bo.threads = options.interior.threads;
        bo.path = options.interior.path;
        primary_boundary_gradient(scene, params, adjoint, bo, g.values);
    }
    g.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return g;
}

} // namespace penumbra
