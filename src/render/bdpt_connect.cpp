#include "render/bdpt_connect.h"

#include "render/adjoint_shading.h"
#include "render/bdpt_mis.h"
#include "render/bdpt_record.h"
#include "render/film_footprint.h"
#include "render/volume_visibility.h"

#include <algorithm>
#include <limits>

namespace penumbra {

namespace {

// f_s |cos| (surfaces, with the adjoint shading-normal correction for importance transport) or the phase
// function (media) at v, from v.wi to w_out.
Color3f scattering(const PathVertex& v, const Vec3f& w_out, TransportMode mode) {
    if (v.type == VertexType::Medium) return Color3f(v.medium->phase->eval<float>(v.wi, w_out));
    const BSDF* bsdf = v.si.bsdf();
    if (!bsdf) return Color3f(0.f);
    Color3f f = bsdf->eval(BSDFContext{mode}, v.si, v.si.to_local(w_out));
    if (mode == TransportMode::Importance) f *= adjoint_shading_correction(v.si, w_out);
    return f;
}

// A surface or medium vertex a deterministic connection can use.
bool connectible(const PathVertex& v) {
    if (v.delta || v.infinite) return false;
    if (v.type == VertexType::Medium) return true;
    const BSDF* bsdf = v.si.bsdf();
    return v.type == VertexType::Surface && bsdf && bsdf->has(BSDFSmooth);
}

// The ray from v to `target` (the whole segment when the target is a medium point, stopping just short of a
// surface target).
Ray connection_ray(const PathVertex& v, const Vec3f& target, bool target_on_surface) {
    Ray ray = ray_between(v, target);
    if (!target_on_surface) ray.tmax = norm(target - ray.o);
    return ray;
}

// The transmittance of a connection (recorded piece by piece when the sample is recorded).
Color3f connection_transmittance(BDPTContext& ctx, const Ray& ray, const Medium* medium, StrategyRecord* record) {
    return segment_transmittance(ctx.scene, ray, medium, ctx.sampler, ctx.rays, nullptr,
                                 record ? &record->connection : nullptr);
}

Interaction3f reference(const PathVertex& v) {
    Interaction3f it;
    it.p = v.p;
    it.n = v.type == VertexType::Medium ? Vec3f(0.f) : v.n;
    return it;
}

// s = 0: emission found by the camera subpath at z_{t-1} (an emitting surface or the environment).
Color3f emission_hit(BDPTContext& ctx, const std::vector<PathVertex>& camera, int t) {
    const PathVertex& pt = camera[size_t(t - 1)];
    Strategy st{0, t, nullptr, &camera};
    Color3f L(0.f);
    if (pt.infinite) {
        for (const auto& e : ctx.scene.emitters) {
            if (!e->is_infinite() || e->is_delta()) continue;
            const Color3f Le = e->eval_environment(pt.d_env);
            if (is_black(Le)) continue;
            st.emitter = e.get();
            L += pt.beta * Le * mis_weight(ctx, st);
        }
        return L;
    }
    if (pt.type != VertexType::Surface || !pt.emitter) return L;
    const Color3f Le = pt.emitter->eval(pt.si);
    if (is_black(Le)) return L;
    st.emitter = pt.emitter;
    return pt.beta * Le * mis_weight(ctx, st);
}

// s = 1: z_{t-1} connected to a fresh emitter sample.
Color3f next_event(BDPTContext& ctx, const std::vector<PathVertex>& camera, int t, StrategyRecord* record) {
    const PathVertex& pt = camera[size_t(t - 1)];
    const Vec2f u = ctx.sampler.next_2d();
    if (!connectible(pt)) return Color3f(0.f);
    const auto [ds, weight] = ctx.scene.sample_emitter_direction(reference(pt), u, false);
    if (is_black(weight)) return Color3f(0.f);
    const Color3f f = scattering(pt, ds.d, TransportMode::Radiance);
    if (is_black(f)) return Color3f(0.f);
    const Medium* medium = medium_toward(pt, ds.d);
    const bool area = ds.emitter->shape() != nullptr;
    if (record) record->light_sample = ds;
    const Color3f tr = connection_transmittance(ctx, connection_ray(pt, ds.p, area), medium, record);
    if (is_black(tr)) return Color3f(0.f);

    PathVertex light;
    light.type = VertexType::Light;
    light.emitter = ds.emitter;
    light.p = ds.p;
    light.n = area ? ds.n : Vec3f(0.f);
    light.infinite = ds.emitter->is_infinite();
    light.d_env = ds.d;
    light.pdf_fwd = light_origin_density(ctx.scene, ds.emitter, light, pt);
    Strategy st{1, t, nullptr, &camera, &light, nullptr, ds.emitter};
    std::tie(st.ff_to_light, st.ff_to_camera) = connection_free_flight(ctx, pt, light, medium);
    return pt.beta * f * weight * tr * mis_weight(ctx, st);
}

// s >= 2, t >= 2: y_{s-1} connected to z_{t-1}.
Color3f connect(BDPTContext& ctx, const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera,
                int s, int t, StrategyRecord* record) {
    const PathVertex &qs = light[size_t(s - 1)], &pt = camera[size_t(t - 1)];
    if (!connectible(qs) || !connectible(pt)) return Color3f(0.f);
    const Vec3f d = qs.p - pt.p;
    const float dist2 = squared_norm(d);
    if (!(dist2 > 0.f)) return Color3f(0.f);
    const Vec3f w = d / std::sqrt(dist2);
    const Color3f f =
        scattering(pt, w, TransportMode::Radiance) * scattering(qs, -w, TransportMode::Importance);
    if (is_black(f)) return Color3f(0.f);
    const Medium* medium = medium_toward(pt, w);
    const Color3f tr = connection_transmittance(ctx, connection_ray(pt, qs.p, qs.type == VertexType::Surface),
                                                medium, record);
    if (is_black(tr)) return Color3f(0.f);
    Strategy st{s, t, &light, &camera, nullptr, nullptr, light[0].emitter};
    std::tie(st.ff_to_light, st.ff_to_camera) = connection_free_flight(ctx, pt, qs, medium);
    return qs.beta * f * pt.beta * tr * (mis_weight(ctx, st) / dist2);
}

// t = 1: y_{s-1} connected to the sensor and splatted at its film position.
void light_tracing(BDPTContext& ctx, const std::vector<PathVertex>& light, int s, Image& splats) {
    const PathVertex& qs = light[size_t(s - 1)];
    const Vec2f u = ctx.sampler.next_2d();
    const bool endpoint = s == 1;
    if (endpoint ? !qs.emitter->shape() : !connectible(qs)) return;
    const Sensor& sensor = *ctx.scene.sensor;
    const auto [ds, importance] = sensor.sample_direction(reference(qs), u);
    if (is_black(importance)) return;
    Color3f value;
    if (endpoint) {
        // The emitter seen directly: L_e |cos θ_y| (the film importance W / d² comes from the sensor sample).
        SurfaceInteraction3f si = qs.si;
        si.wi = si.to_local(ds.d);
        value = qs.beta * qs.emitter->eval(si) * std::abs(dot(qs.n, ds.d));
    } else {
        value = qs.beta * scattering(qs, ds.d, TransportMode::Importance);
    }
    if (is_black(value)) return;
    const Medium* medium = medium_toward(qs, ds.d);
    const Color3f tr =
        segment_transmittance(ctx.scene, connection_ray(qs, ds.p, true), medium, ctx.sampler, ctx.rays);
    if (is_black(tr)) return;
    PathVertex camera;
    camera.type = VertexType::Camera;
    camera.p = ds.p;
    camera.n = Vec3f(0.f);
    Strategy st{s, 1, &light, nullptr, nullptr, &camera, light[0].emitter};
    st.camera_pdf_dir = importance.x * ds.dist * ds.dist;
    std::tie(st.ff_to_camera, st.ff_to_light) = connection_free_flight(ctx, qs, camera, medium);
    const Color3f contribution = value * importance * tr * mis_weight(ctx, st);
    if (!is_finite(contribution)) return;
    const Film& film = *sensor.film;
    for_each_pixel_in_footprint(film, ds.uv,
                                [&](int x, int y, float wf) { splats.at(x, y) += contribution * wf; });
}

} // namespace

Color3f connect_subpaths(BDPTContext& ctx, const std::vector<PathVertex>& camera,
                         const std::vector<PathVertex>& light, Image* splats) {
    const BDPTSettings& settings = ctx.settings;
    const int max_segments = settings.max_depth < 0 ? std::numeric_limits<int>::max() : settings.max_depth;
    const int n_camera = int(camera.size()), n_light = int(light.size());
    Color3f L(0.f);
    // Next-event estimation (s = 1, t >= 2) uses its own emitter sample: it does not need the light subpath.
    for (int t = 1; t <= n_camera; ++t)
        for (int s = 0; s <= std::max(n_light, 1); ++s) {
            const int segments = s + t - 1;
            if (segments < 1 || segments > max_segments || (t == 1 && (s == 0 || s > n_light))) continue;
            if (segments == 1 && settings.hide_emitters) continue;
            if (settings.strategy_s >= 0 && (s != settings.strategy_s || t != settings.strategy_t)) continue;
            if (t == 1) {
                if (ctx.sensor_connects) light_tracing(ctx, light, s, *splats);
                continue;
            }
            StrategyRecord* record = ctx.record ? &ctx.record->next(s, t) : nullptr;
            const Color3f c = s == 0   ? emission_hit(ctx, camera, t)
                              : s == 1 ? next_event(ctx, camera, t, record)
                                       : connect(ctx, light, camera, s, t, record);
            if (record) record->value = c;
            L += c;
        }
    return L;
}

} // namespace penumbra
