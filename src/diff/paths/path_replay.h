// One camera path of the differential path integral (paper 002 §3-4), sampled with differential vertex
// sampling, MIS over the location of the differential vertex and next-event estimation (Eqs. 19-24 and
// Appendix B, Eqs. 37-44), and replayed for path replay backpropagation (PRB, Vicini et al. 2021; Algorithm 1):
//   pass 2 (`sample_path` with no sink) returns the path's radiance estimate L;
//   pass 3 (the same random numbers, with a sink) walks the same path again, subtracting each contribution
//   from L as it is passed, so that at vertex x_i the remainder is the radiance that arrives through the
//   sampled direction; the local derivative ∂f_i/∂θ (the BSDF evaluated with Var on a fresh local tape) is
//   handed to the sink with the weight δ · L_rest / f_i (Eq. 18). Next-event and emitted terms hand their
//   local factors (f_i toward the light, L_e) to the sink directly. Time is linear in the path length and
//   memory constant.
// All contributions are divided by the mixture density of every technique that could have produced them:
//   emitter hit after BSDF/differential sampling at x_{N-1} (Eq. 41):
//       β L_e / [(w1 + w2)_N + (w1 + w2)_{N-1} p_e / p_f(x_{N-1})]
//   next event at x_j toward x_e (Eq. 42), with p_f, p_∂f, p_e the densities of the light direction:
//       β f_j L_e / [p_f (w1 + w2 (1 − q_j)) + p_∂f q_j w2 + p_e (w1 + w2)]
// where β = Π f / p_f is the throughput (with Russian roulette's survival probabilities, which are the same
// for every technique: β does not depend on where the differential vertex is, so the roulette is accounted
// for exactly by dividing β by them).
#pragma once
#include "diff/paths/differential_vertex.h"
#include "render/emitter_hit.h"
#include "render/integrator.h"
#include "render/path_tracer.h"
#include "scene/shape.h"
#include "scene/shape_interaction.h"

#include <algorithm>
#include <type_traits>

namespace penumbra {

struct PathSamplingSettings {
    PathSettings path;         // max_depth, rr_depth, hide_emitters
    bool differential = true;  // differential vertex sampling (false: BSDF sampling, q_i = 0 everywhere)
    float q = 0.5f;            // probability that a vertex with a differential lobe becomes the differential vertex
    bool nee = true;           // next-event estimation
};

// Pass 2 has no sink.
struct NoSink {};

namespace detail {

inline Color3<Var> var_color(const Color3f& c) { return Color3<Var>(Var(c.x), Var(c.y), Var(c.z)); }
inline bool depends_on_parameters(const Color3<Var>& c) { return c.x.id >= 0 || c.y.id >= 0 || c.z.id >= 0; }
inline Vec3d to_d(const Color3f& c) { return Vec3d(c); }

// L_e of the emitter sample `ds` as seen from x, as Var (the emitter's own parameters).
inline Color3<Var> emitter_radiance(const DirectionSample3f& ds, const SurfaceInteraction3f& x) {
    const Emitter* emitter = ds.emitter;
    if (const Shape* shape = emitter->shape()) {
        SurfaceInteraction3f y = surface_interaction<float>(*shape, ds.prim, ds.bary, MeshVertices{shape->mesh});
        y.wi = y.to_local(-ds.d);
        return emitter->eval(constant_interaction(y));
    }
    if (emitter->is_delta()) return emitter->eval_delta(Vec3<Var>(x.p));
    return emitter->eval_environment(Vec3<Var>(ds.d));
}

} // namespace detail

// Returns L (pass 2). With a sink (pass 3), `L` is pass 2's value for the same random numbers, `scale` the
// per-channel factor of the path in the estimate (adjoint × camera weight / expected sample count), and the
// sink is called as sink(value, weight) right after `value` was evaluated on the cleared thread tape.
template <typename Sink>
Vec3d sample_path(const Scene& scene, Sampler& sampler, const Ray& primary, const PathSamplingSettings& s, Vec3d L,
                  const Vec3d& scale, Sink& sink, RayCounter& rays) {
    constexpr bool adjoint = !std::is_same_v<Sink, NoSink>;
    const BSDFContext ctx{TransportMode::Radiance};
    Tape& tape = Tape::current();
    tape.clear(); // has_differential_lobe() records a few nodes per vertex: keep the tape bounded by one path
    // Pass 2 accumulates into `L`; pass 3 subtracts from it (Algorithm 1, lines 5 and 21).
    const auto add = [&](const Vec3d& c) {
        if constexpr (adjoint) L -= c;
        else L += c;
    };
    if (s.path.max_depth == 0) return L;
    const unsigned max_depth = unsigned(s.path.max_depth); // -1 wraps to "infinite"

    DifferentialMIS mis;
    double mix_prev = 1.0;       // (w1 + w2) before the previous vertex
    float pdf_prev = 0.f;        // p_f of the direction sampled at the previous vertex
    bool nee_prev = false;       // next-event estimation was a technique at the previous vertex
    bool sampled_dx = false;
    Vec3d beta(1.0);
    float eta = 1.f;
    Ray ray = primary;
    ++rays.rays;
    SurfaceInteraction3f hit = scene.intersect(ray), prev_hit;

    for (unsigned depth = 0;; ++depth) {
        // Emission reached by BSDF or differential sampling (directly visible at depth 0).
        if (!(depth == 0 && s.path.hide_emitters)) {
            for_each_emitter_hit(scene, prev_hit, ray.d, hit, [&](const Emitter* e, const Color3f& Le, float p_e) {
                const double mixture = mis.mixture() + (nee_prev ? mix_prev * double(p_e) / pdf_prev : 0.0);
                const Vec3d weight = beta / mixture;
                add(weight * detail::to_d(Le));
                if constexpr (adjoint) {
                    tape.clear();
                    const Color3<Var> le = hit.is_valid() ? e->eval(constant_interaction(hit))
                                                          : e->eval_environment(Vec3<Var>(ray.d));
                    if (detail::depends_on_parameters(le)) sink(le, weight * scale);
                }
            });
        }
        if (!hit.is_valid() || depth + 1 >= max_depth) break;
        const BSDF* bsdf = hit.bsdf();
        if (!bsdf) break;
        const bool has_lobe = s.differential && bsdf->has_differential_lobe(hit);
        const double q = has_lobe ? double(s.q) : 0.0;

        // Next-event estimation (Appendix B).
        const bool nee = s.nee && bsdf->has(BSDFSmooth) && !scene.emitters.empty();
        const Vec2f u_light = sampler.next_2d();
        if (nee) {
            const auto [ds, em_weight] = scene.sample_emitter_direction(hit, u_light, true);
            ++rays.rays;
            if (!is_black(em_weight)) {
                const Vec3f wo = hit.to_local(ds.d);
                double mixture = mis.mixture(); // Eq. (42) divided by p_e; delta emitters: NEE is the only technique
                if (!ds.delta) {
                    const double p_f = bsdf->pdf(ctx, hit, wo);
                    const double p_df = has_lobe ? pdf_differential_lobe(*bsdf, ctx, hit, wo) : 0.0;
                    mixture += (p_f * (mis.w1 + mis.w2 * (1.0 - q)) + p_df * q * mis.w2) / ds.pdf;
                }
                const Color3f f = bsdf->eval(ctx, hit, wo);
                add(beta * detail::to_d(f * em_weight) / mixture);
                if constexpr (adjoint) {
                    tape.clear();
                    SurfaceInteraction<Var> si = constant_interaction(hit);
                    const Color3<Var> fv = bsdf->eval(ctx, si, Vec3<Var>(wo));
                    if (detail::depends_on_parameters(fv)) sink(fv, beta * detail::to_d(em_weight) / mixture * scale);
                    tape.clear();
                    const Color3<Var> le = detail::emitter_radiance(ds, hit);
                    if (detail::depends_on_parameters(le))
                        sink(le, beta * detail::to_d(f) / (double(ds.pdf) * mixture) * scale);
                }
            }
        }

        // BSDF or differential BSDF sampling (Algorithm 1, lines 7-11).
        const float u_dx = sampler.next_1d(), u_sign = sampler.next_1d(), u1 = sampler.next_1d();
        const Vec2f u2 = sampler.next_2d();
        BSDFSample bs;
        Color3f weight;
        float p_f;
        if (!sampled_dx && has_lobe && u_dx < s.q) {
            sampled_dx = true;
            bs = sample_differential_lobe(*bsdf, ctx, hit, u_sign, u1, u2);
            if (!(bs.pdf > 0.f)) break;
            p_f = bsdf->pdf(ctx, hit, bs.wo);
            const Color3f f = bsdf->eval(ctx, hit, bs.wo);
            if (!(p_f > 0.f) || is_black(f)) break;
            weight = f / p_f;
        } else {
            const auto sampled = bsdf->sample(ctx, hit, u1, u2);
            bs = sampled.first;
            weight = sampled.second;
            p_f = bs.pdf;
            if (is_black(weight) || !(p_f > 0.f)) break;
        }
        const bool delta_lobe = (bs.sampled_type & BSDFDelta) != 0;
        const double ratio = has_lobe && !delta_lobe ? pdf_differential_lobe(*bsdf, ctx, hit, bs.wo) / double(p_f) : 0.0;
        mix_prev = mis.mixture();
        mis.advance(q, ratio); // Algorithm 1, lines 14-15

        if constexpr (adjoint) {
            // Algorithm 1, line 29: BACKWARDGRAD(f, δL · L / f), L now being what arrives through bs.wo; at a
            // delta lobe f is its smooth factor g (scene/bsdf.h delta_weight: Fresnel times reflectance).
            tape.clear();
            SurfaceInteraction<Var> si = constant_interaction(hit);
            const Color3<Var> fv = delta_lobe ? bsdf->delta_weight(ctx, si, Vec3<Var>(bs.wo))
                                              : bsdf->eval(ctx, si, Vec3<Var>(bs.wo));
            if (detail::depends_on_parameters(fv)) {
                const Vec3d f(fv.x.v, fv.y.v, fv.z.v);
                const Vec3d w(f.x != 0.0 ? L.x / f.x : 0.0, f.y != 0.0 ? L.y / f.y : 0.0,
                              f.z != 0.0 ? L.z / f.z : 0.0);
                sink(fv, w * scale);
            }
        }

        beta *= detail::to_d(weight);
        eta *= bs.eta;
        pdf_prev = p_f;
        nee_prev = nee && !delta_lobe;
        prev_hit = hit;
        ray = hit.spawn_ray(hit.to_world(bs.wo));
        ++rays.rays;
        hit = scene.intersect(ray);

        // Russian roulette (as the path tracer: survival min(max(β) η², 0.95)); see the header comment.
        if (depth + 1 >= unsigned(s.path.rr_depth)) {
            const double survive = std::min(std::max({beta.x, beta.y, beta.z}) * eta * eta, 0.95);
            if (sampler.next_1d() >= survive) break;
            beta /= survive;
        }
    }
    return L;
}

} // namespace penumbra
