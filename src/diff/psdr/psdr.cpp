#include "diff/psdr/psdr.h"

#include "core/batch_stats.h"

#include <array>
#include <chrono>
#include <cmath>
#include <utility>

namespace penumbra {

namespace {

// Mean and standard error over batches of a boundary term (run with independent seeds).
void boundary_batches(const Scene& scene, const Parameters& params, const PsdrOptions& options, const BoundaryTerm& term,
                      int spp, uint64_t salt, Image& mean, Image& stderr_img, SampleCost& cost) {
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
        bo.first_vertex = options.interior.first_vertex;
        bo.guiding = options.guiding;
        bo.volume_endpoints = options.volume_boundary;
        bo.cost = &cost;
        batches.add(term.derivative(params, bo));
    }
    mean = batches.mean();
    if (B > 1) stderr_img = batches.standard_error();
}

// The primary, direct and indirect boundary terms connect surface points to a single center of projection:
// with a finite aperture they are refused for parameters that move geometry (diff/first_vertex.h).
void require_pinhole_terms(const Scene& scene, const Parameters& params, const PsdrOptions& options) {
    if (options.primary_spp > 0) require_pinhole(scene, params, "primary");
    if (options.direct_spp > 0) require_pinhole(scene, params, "direct");
    if (options.indirect_spp > 0) require_pinhole(scene, params, "indirect");
}

// The boundary terms of a scene with their budgets and seeds; the discontinuity edges are collected once.
class BoundaryTerms {
public:
    struct Term {
        const BoundaryTerm& estimator;
        int spp;
        uint64_t salt;
    };

    BoundaryTerms(const Scene& scene, const PsdrOptions& options)
        : edges_(scene), primary_(scene, edges_), direct_(scene, edges_), indirect_(scene, edges_), pixel_(scene),
          terms_{{{primary_, options.primary_spp, 0x2545F4914F6CDD1DULL},
                  {direct_, options.direct_spp, 0x9FB21C651E98DF25ULL},
                  {indirect_, options.indirect_spp, 0xC2B2AE3D27D4EB4FULL},
                  {pixel_, options.pixel_spp, 0x165667B19E3779F9ULL}}} {}

    // In the order of PsdrDerivative's images: primary, direct, indirect, pixel.
    const std::array<Term, 4>& terms() const { return terms_; }

private:
    SceneEdges edges_;
    PrimaryBoundary primary_;
    DirectBoundary direct_;
    IndirectBoundary indirect_;
    PixelBoundary pixel_;
    std::array<Term, 4> terms_;
};

} // namespace

PsdrDerivative psdr_derivative(const Scene& scene, const Parameters& params, const PsdrOptions& options) {
    require_pinhole_terms(scene, params, options);
    PsdrDerivative out;
    const Film& film = *scene.sensor->film;
    if (options.interior.spp > 0) {
        out.interior = render_derivative(scene, params, options.interior);
    } else {
        out.interior.derivative = Image(film.width, film.height);
        if (options.interior.batches > 1) out.interior.stderr_img = Image(film.width, film.height);
    }
    out.cost[0] = out.interior.cost;
    out.seconds[0] = out.interior.seconds;
    const BoundaryTerms boundary(scene, options);
    const std::array<std::pair<Image*, Image*>, 4> images = {{{&out.primary, &out.primary_stderr},
                                                              {&out.direct, &out.direct_stderr},
                                                              {&out.indirect, &out.indirect_stderr},
                                                              {&out.pixel, &out.pixel_stderr}}};
    for (size_t k = 0; k < images.size(); ++k) {
        const BoundaryTerms::Term& t = boundary.terms()[k];
        const auto start = std::chrono::steady_clock::now();
        boundary_batches(scene, params, options, t.estimator, t.spp, t.salt, *images[k].first, *images[k].second,
                         out.cost[k + 1]);
        out.seconds[k + 1] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    out.total = out.interior.derivative;
    const bool have_se = options.interior.batches > 1;
    if (have_se) out.total_stderr = Image(film.width, film.height);
    for (size_t i = 0; i < out.total.pixels.size(); ++i) {
        const Vec3d s(out.interior.stderr_img.pixels.empty() ? Color3f(0.f) : out.interior.stderr_img.pixels[i]);
        Vec3d variance = s * s;
        for (const auto& [mean, stderr_img] : images) {
            out.total.pixels[i] += mean->pixels[i];
            if (have_se) {
                // The estimators use independent samples: variances add.
                const Vec3d e(stderr_img->pixels[i]);
                variance += e * e;
            }
        }
        if (have_se)
            out.total_stderr.pixels[i] =
                Color3f(float(std::sqrt(variance.x)), float(std::sqrt(variance.y)), float(std::sqrt(variance.z)));
    }
    return out;
}

Gradient psdr_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const PsdrOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    require_pinhole_terms(scene, params, options);
    Gradient g;
    if (options.interior.spp > 0) g = render_gradient(scene, params, adjoint, options.interior);
    else g.values.assign(size_t(params.dimension()), 0.0);
    BoundaryOptions bo;
    bo.threads = options.interior.threads;
    bo.path = options.interior.path;
    bo.first_vertex = options.interior.first_vertex;
    bo.guiding = options.guiding;
    bo.volume_endpoints = options.volume_boundary;
    bo.cost = &g.cost;
    const BoundaryTerms boundary(scene, options);
    for (const BoundaryTerms::Term& t : boundary.terms()) {
        if (t.spp <= 0) continue;
        bo.samples_per_pixel = t.spp;
        bo.seed = options.interior.seed + t.salt;
        t.estimator.gradient(params, adjoint, bo, g.values);
    }
    g.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return g;
}

} // namespace penumbra
