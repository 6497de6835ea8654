#include "diff/psdr/budget.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

constexpr int Terms = 5;          // interior, primary, direct, indirect, pixel
constexpr int PilotBatches = 4;
constexpr uint64_t PilotSalt = 0x5851F42D4C957F2DULL;

// A term's variance and cost per sample per pixel, from the pilot.
struct TermStats {
    double variance = 0, cost = 0;
    bool active = false; // the term traced rays (it applies to this scene)
};

int& term_spp(PsdrOptions& o, int k) {
    switch (k) {
    case 0: return o.interior.spp;
    case 1: return o.primary_spp;
    case 2: return o.direct_spp;
    case 3: return o.indirect_spp;
    default: return o.pixel_spp;
    }
}

// Samples per pixel of the pilot (per batch): 1/16 of the budget over its batches.
int pilot_spp(int spp) { return std::max(1, spp / (16 * PilotBatches)); }

// s_k ∝ √(V_k / c_k) with Σ c_k s_k = spp Σ_active c_k; a term whose pilot saw no variance keeps the pilot's
// share (its events may be rare), the interior at least one sample per pixel and batch (it gives the primal).
PsdrOptions allocate(const PsdrOptions& base, const std::array<TermStats, Terms>& stats, int spp, int batches) {
    double budget = 0, norm = 0;
    for (const TermStats& t : stats)
        if (t.active) budget += spp * t.cost, norm += std::sqrt(t.variance * t.cost);
    PsdrOptions o = base;
    o.calibrated = true;
    const int minimum = std::max(1, pilot_spp(spp) * PilotBatches / batches);
    for (int k = 0; k < Terms; ++k) {
        const TermStats& t = stats[size_t(k)];
        int per_batch = 0;
        if (t.active) {
            const double total = norm > 0 && t.variance > 0 ? std::sqrt(t.variance / t.cost) * budget / norm : 0.0;
            per_batch = std::max(minimum, int(std::lround(total / batches)));
        }
        term_spp(o, k) = k == 0 ? std::max(1, per_batch) : per_batch;
    }
    return o;
}

PsdrOptions pilot_options(const PsdrOptions& base, int spp) {
    PsdrOptions o = base;
    o.interior.seed = base.interior.seed ^ PilotSalt;
    o.interior.progress = nullptr;
    for (int k = 0; k < Terms; ++k) term_spp(o, k) = pilot_spp(spp);
    return o;
}

// Σ over pixels and channels of stderr² × (samples per pixel over all batches): the per-sample variance.
double per_sample_variance(const Image& stderr_img, int samples_per_pixel) {
    double v = 0;
    for (const Color3f& s : stderr_img.pixels) v += double(s.x) * s.x + double(s.y) * s.y + double(s.z) * s.z;
    return v * samples_per_pixel;
}

using Stats = std::array<TermStats, Terms>;

// Forward mode: one pilot of every term in PilotBatches batches.
Stats derivative_stats(const Scene& scene, const Parameters& params, const PsdrOptions& base, int spp) {
    PsdrOptions pilot = pilot_options(base, spp);
    pilot.interior.batches = PilotBatches;
    const DerivativeImage d = psdr_derivative(scene, params, pilot);
    const int samples = pilot_spp(spp) * PilotBatches;
    Stats stats; // a term that does not apply (pixel) keeps zero statistics: inactive
    for (size_t k = 0; k < d.terms.size(); ++k) {
        const DerivativeTerm& t = d.terms[k];
        stats[k] = {per_sample_variance(t.stderr_img, samples), t.cost.units() / samples, t.cost.rays > 0};
    }
    return stats;
}

// Reverse mode: each term alone, in independent batches: the variance of its gradient vector.
Stats gradient_stats(const Scene& scene, const Parameters& params, const Image& adjoint, const PsdrOptions& base, int spp) {
    Stats stats;
    const int per_batch = pilot_spp(spp), samples = per_batch * PilotBatches;
    for (int k = 0; k < Terms; ++k) {
        PsdrOptions pilot = pilot_options(base, spp);
        for (int j = 0; j < Terms; ++j) term_spp(pilot, j) = j == k ? per_batch : 0;
        std::vector<double> sum, sum2;
        SampleCost cost;
        for (int b = 0; b < PilotBatches; ++b) {
            pilot.interior.seed = (base.interior.seed ^ PilotSalt) + 0x9E3779B97F4A7C15ULL * uint64_t(b + 1);
            const Gradient g = psdr_gradient(scene, params, adjoint, pilot);
            if (sum.empty()) sum.assign(g.values.size(), 0.0), sum2.assign(g.values.size(), 0.0);
            for (size_t i = 0; i < g.values.size(); ++i) sum[i] += g.values[i], sum2[i] += g.values[i] * g.values[i];
            cost += g.cost;
        }
        // Unbiased variance of a batch's gradient, times its samples per pixel: the per-sample variance.
        double variance = 0;
        for (size_t i = 0; i < sum.size(); ++i) {
            const double m = sum[i] / PilotBatches;
            variance += std::max(0.0, (sum2[i] / PilotBatches - m * m) * PilotBatches / (PilotBatches - 1.0));
        }
        stats[size_t(k)] = {variance * per_batch, cost.units() / samples, cost.rays > 0};
    }
    return stats;
}

// The variance × cost of the optimal split, (Σ_k √(V_k c_k))²: what a parameterization costs at its best.
double optimal_variance_cost(const Stats& stats) {
    double sum = 0;
    for (const TermStats& t : stats)
        if (t.active) sum += std::sqrt(t.variance * t.cost);
    return sum * sum;
}

// The split of the better first-vertex parameterization. With a static camera both apply (diff/first_vertex.h)
// and image space is usually far less noisy, but not always: where a moving surface meets another moving with
// it (two planes at a right angle, translating together), the image-space vertex stays put while the next one
// moves with its surface, and the segment between them changes as 1/distance near the contact, a heavy tail the
// material form (both moving together) does not have. Both are piloted and the lower optimal variance × cost
// wins; an explicit choice in `base` is kept.
template <typename StatsOf>
PsdrOptions choose_and_allocate(const Scene& scene, const Parameters& params, const PsdrOptions& base, int spp,
                                int batches, const StatsOf& stats_of) {
    PsdrOptions chosen = base;
    const bool both = base.interior.first_vertex == FirstVertex::Auto &&
                      image_space_first_vertex(scene, params, FirstVertex::Auto);
    chosen.interior.first_vertex = image_space_first_vertex(scene, params, base.interior.first_vertex)
                                       ? FirstVertex::ImageSpace
                                       : FirstVertex::Material;
    Stats stats = stats_of(chosen);
    if (both) {
        PsdrOptions material = base;
        material.interior.first_vertex = FirstVertex::Material;
        const Stats material_stats = stats_of(material);
        if (optimal_variance_cost(material_stats) < optimal_variance_cost(stats)) chosen = material, stats = material_stats;
    }
    return allocate(chosen, stats, spp, batches);
}

} // namespace

PsdrOptions psdr_budget(const Scene& scene, const Parameters& params, const PsdrOptions& base, int spp) {
    if (spp <= 0) throw Error("the sample budget must be positive");
    return choose_and_allocate(scene, params, base, spp, std::max(1, base.interior.batches),
                               [&](const PsdrOptions& o) { return derivative_stats(scene, params, o, spp); });
}

PsdrOptions psdr_gradient_budget(const Scene& scene, const Parameters& params, const Image& adjoint,
                                 const PsdrOptions& base, int spp) {
    if (spp <= 0) throw Error("the sample budget must be positive");
    PsdrOptions base1 = base;
    base1.interior.batches = 1;
    return choose_and_allocate(scene, params, base1, spp, 1,
                               [&](const PsdrOptions& o) { return gradient_stats(scene, params, adjoint, o, spp); });
}

std::string describe_budget(const PsdrOptions& o) {
    const int b = std::max(1, o.interior.batches);
    const char* form = o.interior.first_vertex == FirstVertex::ImageSpace ? ", image-space first vertex"
                       : o.interior.first_vertex == FirstVertex::Material ? ", material-form first vertex"
                                                                          : "";
    return "interior " + std::to_string(o.interior.spp * b) + ", primary " + std::to_string(o.primary_spp * b) +
           ", direct " + std::to_string(o.direct_spp * b) + ", indirect " + std::to_string(o.indirect_spp * b) +
           ", pixel " + std::to_string(o.pixel_spp * b) + " spp" + form;
}

} // namespace penumbra
