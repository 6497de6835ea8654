// `direct`: direct illumination only, combining emitter and BSDF samples with the power heuristic
// (Mitsuba 3's `direct`).
//
// | parameter       | type    | default         | meaning                                   |
// |-----------------|---------|-----------------|-------------------------------------------|
// | shading_samples | integer | 1               | sets both emitter_samples and bsdf_samples |
// | emitter_samples | integer | shading_samples | emitter samples per camera ray            |
// | bsdf_samples    | integer | shading_samples | BSDF samples per camera ray               |
// | hide_emitters   | boolean | false           | do not show directly visible emitters      |
#include "render/direct.h"

#include "render/emitter_hit.h"
#include "render/mis.h"

namespace penumbra {

// L = L_e + Σ_i w_lum f L_e / p_lum + Σ_j w_bsdf f L_e / p_bsdf, with sample-count-aware power heuristic weights.
void DirectIntegrator::sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out,
                              RayCounter& rays) const {
    const BSDFContext ctx{TransportMode::Radiance};
    const float total = float(settings_.emitter_samples + settings_.bsdf_samples);
    const float frac_lum = settings_.emitter_samples / total, frac_bsdf = settings_.bsdf_samples / total;
    Color3f L(0.f);
    const SurfaceInteraction3f si = scene.intersect(ray);
    if (!settings_.hide_emitters)
        for_each_emitter_hit(scene, Interaction3f(), ray.d, si, [&](const Emitter*, const Color3f& Le, float) { L += Le; });
    const BSDF* bsdf = si.is_valid() ? si.bsdf() : nullptr;
    if (!bsdf) {
        out[0] = L;
        return;
    }

    if (bsdf->has(BSDFSmooth))
        for (int i = 0; i < settings_.emitter_samples; ++i) {
            const auto [ds, em_weight] = scene.sample_emitter_direction(si, sampler.next_2d(), true);
            ++rays.rays;
            if (is_black(em_weight)) continue;
            const Vec3f wo = si.to_local(ds.d);
            const Color3f f = bsdf->eval(ctx, si, wo);
            const float w = ds.delta ? 1.f : mis_power(ds.pdf * frac_lum, bsdf->pdf(ctx, si, wo) * frac_bsdf);
            L += em_weight * f * (w / float(settings_.emitter_samples));
        }

    for (int j = 0; j < settings_.bsdf_samples; ++j) {
        const float u1 = sampler.next_1d();
        const auto [bs, weight] = bsdf->sample(ctx, si, u1, sampler.next_2d());
        if (is_black(weight)) continue;
        const Vec3f d = si.to_world(bs.wo);
        const SurfaceInteraction3f si2 = scene.intersect(si.spawn_ray(d));
        ++rays.rays;
        const bool delta = (bs.sampled_type & BSDFDelta) != 0;
        // bs and weight captured explicitly: clang before 16 cannot capture structured bindings implicitly.
        for_each_emitter_hit(
            scene, si, d, si2,
            [&, &bs = bs, &weight = weight](const Emitter*, const Color3f& Le, float emitter_pdf) {
                const float w = delta ? 1.f : mis_power(bs.pdf * frac_bsdf, emitter_pdf * frac_lum);
                L += weight * Le * (w / float(settings_.bsdf_samples));
            });
    }
    out[0] = L;
}

} // namespace penumbra
