// `path`: unidirectional path tracer with next-event estimation and MIS (Mitsuba 3's `path`).
//
// | parameter      | type    | default | meaning                                                    |
// |----------------|---------|---------|------------------------------------------------------------|
// | max_depth      | integer | -1      | longest path depth (-1 = infinite, 1 = visible emitters)    |
// | rr_depth       | integer | 5       | depth at which Russian roulette starts                     |
// | hide_emitters  | boolean | false   | do not show directly visible emitters                      |
#include "render/path.h"

#include "render/emitter_hit.h"
#include "render/mis.h"

namespace penumbra {

PathIntegrator::PathIntegrator(const Properties& props) {
    max_depth_ = int(props.get_int("max_depth", -1));
    rr_depth_ = int(props.get_int("rr_depth", 5));
    hide_emitters_ = props.get_bool("hide_emitters", false);
    if (max_depth_ < -1) props.raise("max_depth", "must be -1 (infinite) or non-negative");
    if (rr_depth_ <= 0) props.raise("rr_depth", "must be positive");
}

// Estimates L(x, ω) = L_e + ∫ f L cos dω with BSDF sampling and emitter sampling combined by the power heuristic.
void PathIntegrator::sample(const Scene& scene, Sampler& sampler, const Ray& primary, Color3f* out,
                            RayCounter& rays) const {
    out[0] = Color3f(0.f);
    if (max_depth_ == 0) return;
    const BSDFContext ctx{TransportMode::Radiance};
    const unsigned max_depth = unsigned(max_depth_); // -1 wraps to "infinite"
    Color3f L(0.f), throughput(1.f);
    float eta = 1.f;
    Ray ray = primary;
    SurfaceInteraction3f prev_si;
    float prev_bsdf_pdf = 1.f;
    bool prev_bsdf_delta = true;

    for (unsigned depth = 0;; ++depth) {
        const SurfaceInteraction3f si = scene.intersect(ray);

        // Emission reached by BSDF sampling (or directly visible), MIS-weighted against emitter sampling.
        if (!(depth == 0 && hide_emitters_))
            for_each_emitter_hit(scene, prev_si, ray.d, si, [&](const Color3f& Le, float emitter_pdf) {
                const float w = prev_bsdf_delta ? 1.f : mis_power(prev_bsdf_pdf, emitter_pdf);
                L += throughput * Le * w;
            });
        if (!si.is_valid()) break;
        if (depth + 1 >= max_depth) break;
        const BSDF* bsdf = si.bsdf();
        if (!bsdf) break;

        // Next-event estimation.
        if (bsdf->has(BSDFSmooth) && !scene.emitters.empty()) {
            const auto [ds, em_weight] = scene.sample_emitter_direction(si, sampler.next_2d(), true);
            ++rays.rays;
            if (!is_black(em_weight)) {
                const Vec3f wo = si.to_local(ds.d);
                const Color3f f = bsdf->eval(ctx, si, wo);
                const float w = ds.delta ? 1.f : mis_power(ds.pdf, bsdf->pdf(ctx, si, wo));
                L += throughput * em_weight * f * w;
            }
        } else {
            sampler.next_2d(); // keep the sample stream aligned across materials
        }

        // BSDF sampling.
        const float u1 = sampler.next_1d();
        const auto [bs, weight] = bsdf->sample(ctx, si, u1, sampler.next_2d());
        if (is_black(weight)) break;
        throughput *= weight;
        eta *= bs.eta;
        prev_si = si;
        prev_bsdf_pdf = bs.pdf;
        prev_bsdf_delta = (bs.sampled_type & BSDFDelta) != 0;
        ray = si.spawn_ray(si.to_world(bs.wo));
        ++rays.rays;

        // Russian roulette (Mitsuba 3: survival probability min(max(throughput)·eta², 0.95)).
        if (depth + 1 >= unsigned(rr_depth_)) {
            const float q = std::min(max_component(throughput) * eta * eta, 0.95f);
            if (sampler.next_1d() >= q) break;
            throughput /= q;
        }
    }
    out[0] = L;
}

} // namespace penumbra
