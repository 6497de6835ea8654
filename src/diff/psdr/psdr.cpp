#include "diff/psdr/psdr.h"

#include "core/batch_stats.h"
#include "diff/psdr/budget.h"
#include "diff/specular_chains.h"

#include <array>
#include <chrono>
#include <cmath>
#include <utility>

namespace penumbra {

namespace {

// Mean and standard error over batches of a boundary term (run with independent seeds).
void boundary_batches(const Scene& scene, const Parameters& params, const PsdrOptions& options,
                      const BoundaryTerm& term, int spp, uint64_t salt, DerivativeTerm& out) {
    const Film& film = *scene.sensor->film;
    const int B = options.interior.batches;
    out.derivative = Image(film.width, film.height);
    if (B > 1) out.stderr_img = Image(film.width, film.height);
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
        bo.cost = &out.cost;
        batches.add(term.derivative(params, bo));
    }
    out.derivative = batches.mean();
    if (B > 1) out.stderr_img = batches.standard_error();
    out.mean_stderr = batches.mean_standard_error();
    out.block_stderr = batches.block_standard_errors();
}

// The primary, direct and indirect boundary terms connect surface points to a single center of projection:
// with a finite aperture they are refused for parameters that move geometry (diff/first_vertex.h), and so is
// a moving discontinuity that the camera sees only through delta lobes (diff/specular_chains.h).
void require_pinhole_terms(const Scene& scene, const Parameters& params, const PsdrOptions& options) {
    if (options.primary_spp > 0) require_pinhole(scene, params, "primary");
    if (options.direct_spp > 0) require_pinhole(scene, params, "direct");
    if (options.indirect_spp > 0) require_pinhole(scene, params, "indirect");
    if (options.primary_spp > 0 || options.direct_spp > 0 || options.indirect_spp > 0)
        require_no_moving_edges_behind_delta_lobes(scene, params, "psdr");
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

    // In the order of the derivative's terms after the interior: primary, direct, indirect, pixel.
    const std::array<Term, 4>& terms() const { return terms_; }

private:
    SceneEdges edges_;
    PrimaryBoundary primary_;
    DirectBoundary direct_;
    IndirectBoundary indirect_;
    PixelBoundary pixel_;
    std::array<Term, 4> terms_;
};

// "interior + boundary terms (interior 12, primary 1500, ... spp, image-space first vertex, calibrated)".
std::string describe(const PsdrOptions& options) {
    return "interior + boundary terms (" + describe_budget(options) +
           (options.calibrated ? ", calibrated)" : ")");
}

} // namespace

DerivativeImage psdr_derivative(const Scene& scene, const Parameters& params, const PsdrOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    require_pinhole_terms(scene, params, options);
    DerivativeImage out;
    std::array<DerivativeTerm, PsdrTermNames.size()> terms;
    const Film& film = *scene.sensor->film;
    if (options.interior.spp > 0) {
        DerivativeImage interior = render_derivative(scene, params, options.interior);
        terms[0] = std::move(interior.terms.front());
        out.primal = std::move(interior.primal);
        out.warnings = std::move(interior.warnings);
    } else {
        terms[0].derivative = Image(film.width, film.height);
        if (options.interior.batches > 1) terms[0].stderr_img = Image(film.width, film.height);
    }
    const BoundaryTerms boundary(scene, options);
    for (size_t k = 1; k < terms.size(); ++k) {
        const BoundaryTerms::Term& t = boundary.terms()[k - 1];
        const auto term_start = std::chrono::steady_clock::now();
        boundary_batches(scene, params, options, t.estimator, t.spp, t.salt, terms[k]);
        terms[k].seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - term_start).count();
    }
    out.derivative = terms[0].derivative;
    const bool have_se = options.interior.batches > 1;
    if (have_se) out.stderr_img = Image(film.width, film.height);
    for (size_t i = 0; i < out.derivative.pixels.size(); ++i) {
        const Vec3d s(terms[0].stderr_img.pixels.empty() ? Color3f(0.f) : terms[0].stderr_img.pixels[i]);
        Vec3d variance = s * s;
        for (size_t k = 1; k < terms.size(); ++k) {
            out.derivative.pixels[i] += terms[k].derivative.pixels[i];
            if (have_se) {
                // The estimators use independent samples: variances add.
                const Vec3d e(terms[k].stderr_img.pixels[i]);
                variance += e * e;
            }
        }
        if (have_se)
            out.stderr_img.pixels[i] = Color3f(float(std::sqrt(variance.x)), float(std::sqrt(variance.y)),
                                               float(std::sqrt(variance.z)));
    }
    const bool pixel_term = needs_pixel_boundary(scene, params, options.interior.first_vertex);
    // The terms use independent samples: variances add (of the image mean and of block means, as per pixel).
    double mean_variance = 0;
    for (size_t b = 0; b < out.block_stderr.size(); ++b) {
        Image& sum = out.block_stderr[b];
        for (const DerivativeTerm& t : terms) {
            const Image& e = t.block_stderr[b];
            if (e.pixels.empty()) continue;
            if (sum.pixels.empty()) sum = Image(e.width, e.height);
            for (size_t i = 0; i < e.pixels.size(); ++i)
                sum.pixels[i] += e.pixels[i] * e.pixels[i];
        }
        for (Color3f& v : sum.pixels)
            v = Color3f(std::sqrt(v.x), std::sqrt(v.y), std::sqrt(v.z));
    }
    for (size_t k = 0; k < terms.size(); ++k) {
        out.cost += terms[k].cost;
        mean_variance += terms[k].mean_stderr * terms[k].mean_stderr;
        terms[k].name = PsdrTermNames[k];
        if (k + 1 < terms.size() || pixel_term) out.terms.push_back(std::move(terms[k]));
    }
    out.mean_stderr = std::sqrt(mean_variance);
    out.description = describe(options);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
    g.description = describe(options);
    g.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return g;
}

} // namespace penumbra
