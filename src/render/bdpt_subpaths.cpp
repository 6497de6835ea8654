#include "render/bdpt_subpaths.h"

#include "core/warp.h"
#include "render/adjoint_shading.h"
#include "render/bdpt_record.h"
#include "render/light_medium.h"
#include "render/medium_sampling.h"
#include "render/null_walk.h"
#include "render/volume_visibility.h"

#include <cmath>

namespace penumbra {

namespace {

// A straight piece of a segment between two vertices, in one medium (segments cross null surfaces).
struct Piece {
    const Medium* medium;
    Vec3f o, d;
    float length;
};

float pass_density(const Piece& q) {
    return q.medium ? free_flight_pdf(*q.medium, q.o, q.d, q.length, false) : 1.f;
}

// The free-flight factors of a segment made of `pieces` (in order from a to b): the density of the outcome
// "passed every piece, then stopped at b" (scattered at b if b is a medium vertex), and the same walked from
// b to a.
std::pair<float, float> segment_free_flight(const std::vector<Piece>& pieces, bool a_in_medium,
                                            bool b_in_medium) {
    float fwd = 1.f, rev = 1.f;
    for (size_t k = 0; k < pieces.size(); ++k) {
        const Piece& q = pieces[k];
        if (!q.medium) continue;
        const bool last = k + 1 == pieces.size(), first = k == 0;
        const float pass = pass_density(q);
        fwd *= last && b_in_medium ? free_flight_pdf(*q.medium, q.o, q.d, q.length, true) : pass;
        rev *= first && a_in_medium ? free_flight_pdf(*q.medium, q.o + q.d * q.length, -q.d, q.length, true)
                                    : pass;
    }
    return {fwd, rev};
}

// Extends `path` from its last vertex along `ray` (sampled with solid-angle density pdf_dir, or the disk
// density from an infinite light), in `medium`, with throughput beta (pbrt-v3's RandomWalk with media).
void random_walk(BDPTContext& ctx, Ray ray, const Medium* medium, Color3f beta, float pdf_dir,
                 TransportMode mode, std::vector<PathVertex>& path, size_t max_vertices) {
    std::vector<LegChain>* chains =
        ctx.record ? (mode == TransportMode::Radiance ? &ctx.record->camera : &ctx.record->light) : nullptr;
    const BDPTContext& c = ctx;
    const BSDFContext bsdf_ctx{mode};
    thread_local std::vector<Piece> pieces;
    float eta = 1.f;
    const float start = max_component(beta), rr_scale = start > 0.f ? 1.f / start : 1.f;
    while (path.size() < max_vertices) {
        // Follow the ray to the next vertex, through null surfaces, sampling free flights.
        pieces.clear();
        bool scattered = false, absorbed = false;
        Vec3f scatter_p;
        LegChain* chain = nullptr;
        if (chains) {
            if (chains->size() <= path.size()) chains->resize(path.size() + 1);
            chain = &(*chains)[path.size()];
        }
        SurfaceInteraction3f hit;
        const NullWalk w = walk_null_surfaces<NullWalkRule{.hit_after_bound_ends = true}>(
            c.scene, ray, medium, ctx.rays, chain, hit,
            [&](const Medium* m, const Ray& r, float tmax, FlightRecord* record) {
                if (m) {
                    const FreeFlightSample ff = sample_free_flight(*m, r.o, r.d, tmax, ctx.sampler, record);
                    beta *= ff.weight;
                    absorbed = ff.event == FreeFlightSample::Event::Absorbed || is_black(beta);
                    if (absorbed) return false;
                    if (ff.event == FreeFlightSample::Event::Scattered) {
                        pieces.push_back({m, r.o, r.d, ff.t});
                        scattered = true;
                        scatter_p = ff.p;
                        return false;
                    }
                }
                pieces.push_back({m, r.o, r.d, tmax});
                return true;
            });
        if (absorbed) return;
        medium = w.medium;
        ray = w.ray;
        const size_t prev_index = path.size() - 1;
        PathVertex v;
        v.medium = medium;
        v.beta = beta;
        v.wi = -ray.d;
        std::tie(v.ff_fwd, v.ff_rev) =
            segment_free_flight(pieces, path[prev_index].type == VertexType::Medium, scattered);
        if (scattered) {
            v.type = VertexType::Medium;
            v.p = scatter_p;
            v.n = Vec3f(0.f);
        } else if (!hit.is_valid()) {
            // An escaped camera ray: the environment's endpoint (light subpaths simply end).
            if (mode == TransportMode::Importance) return;
            v.type = VertexType::Light;
            v.infinite = true;
            v.d_env = ray.d;
            v.p = ray.o + ray.d * (2.f * c.bounds.radius + norm(ray.o - c.bounds.center));
            v.n = Vec3f(0.f);
            v.pdf_fwd = pdf_dir;
            path.push_back(v);
            return;
        } else {
            v.type = VertexType::Surface;
            v.si = hit;
            v.p = hit.p;
            v.n = hit.n;
            v.emitter = hit.emitter();
        }
        v.pdf_fwd = to_area_density(path[prev_index], v, pdf_dir, v.ff_fwd);
        path.push_back(v);
        PathVertex& cur = path.back();
        if (path.size() >= max_vertices) return;

        // Sample the next direction; the reverse density goes to the previous vertex.
        Vec3f wo;
        float pdf_rev_dir = 0.f;
        if (cur.type == VertexType::Medium) {
            const PhaseFunction& phase = *medium->phase;
            std::tie(wo, pdf_dir) = phase.sample(cur.wi, ctx.sampler.next_2d());
            if (!(pdf_dir > 0.f)) return;
            pdf_rev_dir = phase.pdf(wo, cur.wi);
            ray = Ray(cur.p, wo);
        } else {
            const BSDF* bsdf = cur.si.bsdf();
            const float u1 = ctx.sampler.next_1d();
            const Vec2f u2 = ctx.sampler.next_2d();
            if (!bsdf) {
                cur.delta = true; // no BSDF: nothing connects here
                return;
            }
            const auto [bs, weight] = bsdf->sample(bsdf_ctx, cur.si, u1, u2);
            if (is_black(weight)) return;
            wo = cur.si.to_world(bs.wo);
            beta *= weight;
            if (mode == TransportMode::Importance)
                beta *= adjoint_shading_correction(cur.si, wo);
            else
                eta *= bs.eta;
            if (bs.sampled_type & BSDFDelta) {
                cur.delta = true;
                cur.eta = bs.eta;
                pdf_dir = 0.f;
            } else {
                pdf_dir = bs.pdf;
                SurfaceInteraction3f swapped = cur.si;
                swapped.wi = bs.wo;
                pdf_rev_dir =
                    bsdf->pdf(BSDFContext{mode == TransportMode::Radiance ? TransportMode::Importance
                                                                          : TransportMode::Radiance},
                              swapped, cur.si.wi);
            }
            medium = target_medium(*cur.si.shape, cur.n, wo, medium);
            ray = cur.si.spawn_ray(wo);
        }
        path[prev_index].pdf_rev = to_area_density(cur, path[prev_index], pdf_rev_dir, cur.ff_rev);

        // Russian roulette: Mitsuba 3's survival probability min(max(beta) eta², 0.95), with beta relative to
        // the subpath's starting throughput (a light subpath starts at L_e / p, which would keep q at 0.95).
        if (path.size() - 1 >= size_t(c.settings.rr_depth)) {
            const float q = std::min(max_component(beta) * rr_scale * eta * eta, 0.95f);
            if (ctx.sampler.next_1d() >= q) return;
            beta /= q;
        }
    }
}

} // namespace

Vec3f direction_to(const PathVertex& from, const PathVertex& to) {
    return to.infinite ? to.d_env : normalize(to.p - from.p);
}

float to_area_density(const PathVertex& from, const PathVertex& to, float pdf_dir, float ff) {
    if (to.infinite) return pdf_dir;
    if (from.infinite) return pdf_dir * ff * (to.on_surface() ? std::abs(dot(to.n, from.d_env)) : 1.f);
    const Vec3f w = to.p - from.p;
    const float dist2 = squared_norm(w);
    if (!(dist2 > 0.f)) return 0.f;
    float pdf = pdf_dir * ff / dist2;
    if (to.on_surface()) pdf *= std::abs(dot(to.n, w)) / std::sqrt(dist2);
    return pdf;
}

float scattering_density(const PathVertex& v, const Vec3f& w_prev, const PathVertex& next, float ff,
                         TransportMode mode) {
    const Vec3f w_next = direction_to(v, next);
    float pdf = 0.f;
    if (v.type == VertexType::Medium) {
        pdf = v.medium->phase->pdf(w_prev, w_next);
    } else {
        const BSDF* bsdf = v.si.bsdf();
        if (!bsdf) return 0.f;
        SurfaceInteraction3f si = v.si;
        si.wi = si.to_local(w_prev);
        pdf = bsdf->pdf(BSDFContext{mode}, si, si.to_local(w_next));
    }
    return to_area_density(v, next, pdf, ff);
}

float light_origin_density(const Scene& scene, const Emitter* emitter, const PathVertex& v,
                           const PathVertex& next) {
    const float selection = 1.f / float(scene.emitters.size());
    if (const Shape* shape = emitter->shape()) return selection * shape->pdf_position();
    if (emitter->flags() & EmitterDeltaPosition) return selection;
    if (emitter->flags() & EmitterDeltaDirection) return 0.f;
    // An infinite light: the solid-angle density with which emitter sampling at `next` picks its direction.
    DirectionSample3f ds;
    ds.d = v.d_env;
    ds.dist = Infinity;
    ds.emitter = emitter;
    Interaction3f ref;
    ref.p = next.p;
    return scene.pdf_emitter_direction(ref, ds);
}

float light_emission_density(const BDPTContext& ctx, const Emitter* emitter, const PathVertex& v,
                             const PathVertex& next, float ff) {
    if (v.infinite) {
        const float r = ctx.bounds.radius;
        return to_area_density(v, next, 1.f / (Pi * r * r), ff);
    }
    const Vec3f w = normalize(next.p - v.p);
    float pdf_dir = 0.f;
    if (emitter->shape())
        pdf_dir = std::max(dot(v.n, w), 0.f) * InvPi;
    else
        pdf_dir = emitter->pdf_emission_direction(w);
    return to_area_density(v, next, pdf_dir, ff);
}

const Medium* medium_toward(const PathVertex& v, const Vec3f& d) {
    if (v.type == VertexType::Surface) return target_medium(*v.si.shape, v.si.n, d, v.medium);
    return v.medium;
}

Ray ray_between(const PathVertex& v, const Vec3f& target) {
    Interaction3f it;
    it.p = v.p;
    it.n = v.type == VertexType::Medium ? Vec3f(0.f) : v.n;
    return it.spawn_ray_to(target);
}

std::pair<float, float> connection_free_flight(BDPTContext& ctx, const PathVertex& a, const PathVertex& b,
                                               const Medium* medium) {
    if (!ctx.has_media) return {1.f, 1.f};
    thread_local std::vector<Piece> pieces;
    pieces.clear();
    SurfaceInteraction3f hit;
    walk_null_surfaces<NullWalkRule{.bounded = true}>(
        ctx.scene, ray_between(a, b.p), medium, ctx.rays, nullptr, hit,
        [&](const Medium* m, const Ray& r, float end, FlightRecord*) {
            pieces.push_back({m, r.o, r.d, end});
            return true;
        });
    return segment_free_flight(pieces, a.type == VertexType::Medium, b.type == VertexType::Medium);
}

void camera_subpath(BDPTContext& ctx, const Ray& ray, const Vec2f& u_aperture, std::vector<PathVertex>& path,
                    size_t max_vertices) {
    path.clear();
    if (max_vertices == 0) return;
    PathVertex camera;
    camera.type = VertexType::Camera;
    camera.p = ray.o;
    camera.n = Vec3f(0.f);
    path.push_back(camera);
    random_walk(ctx, ray, sensor_medium(ctx.scene), Color3f(1.f), 0.f, TransportMode::Radiance, path,
                max_vertices);
    if (path.size() < 2) return;
    // The density of z_1: the sensor's importance W(ω) is the density of primary directions (film positions
    // uniform over the image); sample_direction() from z_1 with the same lens sample returns W / d².
    PathVertex& z1 = path[1];
    Interaction3f ref;
    ref.p = z1.infinite ? ray.o + ray.d : z1.p;
    const auto [ds, weight] = ctx.scene.sensor->sample_direction(ref, u_aperture);
    const float pdf_dir = weight.x * ds.dist * ds.dist;
    if (!z1.infinite) path[0].p = ds.p;
    z1.pdf_fwd = to_area_density(path[0], z1, pdf_dir, z1.ff_fwd);
}

void light_subpath(BDPTContext& ctx, std::vector<PathVertex>& path, size_t max_vertices) {
    path.clear();
    const Scene& scene = ctx.scene;
    if (max_vertices == 0 || scene.emitters.empty()) return;
    float u_select = ctx.sampler.next_1d(), selection = 0.f;
    const Emitter* emitter = scene.sample_emitter(u_select, selection);
    const Vec2f u_position = ctx.sampler.next_2d(), u_direction = ctx.sampler.next_2d();

    PathVertex light;
    light.type = VertexType::Light;
    light.emitter = emitter;
    light.n = Vec3f(0.f);
    Ray ray;
    Color3f beta;
    float pdf_dir = 0.f;
    const Medium* medium = nullptr;
    if (const Shape* shape = emitter->shape()) {
        // Area light: a uniform point, a cosine-weighted direction on the front side.
        const PositionSample3f ps = shape->sample_position(u_position);
        const Vec3f local = warp::square_to_cosine_hemisphere(u_direction);
        SurfaceInteraction3f si;
        si.p = ps.p;
        si.n = ps.n;
        si.uv = ps.uv;
        si.sh_frame = Frame3f(ps.n);
        si.wi = local;
        si.shape = shape;
        si.prim_index = ps.prim;
        si.bary = ps.bary;
        const Vec3f d = si.to_world(local);
        light.si = si;
        light.p = ps.p;
        light.n = ps.n;
        light.pdf_fwd = selection * ps.pdf;
        light.beta = Color3f(1.f / light.pdf_fwd);
        pdf_dir = local.z * InvPi;
        if (!(pdf_dir > 0.f)) return;
        beta = emitter->eval(si) * (Pi / light.pdf_fwd);
        ray = si.spawn_ray(d);
        medium = ctx.has_media ? emitter_medium(ctx.scene, *emitter, ray.o, ctx.rays) : nullptr;
    } else if (emitter->flags() & EmitterDeltaPosition) {
        // Point, spot, projector: the emitter's own ray sampling, whose direction density it reports.
        Color3f weight;
        std::tie(ray, weight) = emitter->sample_ray(u_position, u_direction);
        light.p = ray.o;
        light.pdf_fwd = selection;
        light.beta = Color3f(1.f / selection);
        pdf_dir = emitter->pdf_emission_direction(ray.d);
        beta = weight / selection;
        medium = ctx.has_media ? emitter_medium(ctx.scene, *emitter, ray.o, ctx.rays) : nullptr;
    } else {
        // Infinite lights (pbrt, Mitsuba): the emitter's direction sampling, then an origin uniform on the
        // disk of the scene's bounding sphere perpendicular to it, upstream of the scene.
        Interaction3f center;
        center.p = ctx.bounds.center;
        const auto [ds, weight] = emitter->sample_direction(center, u_direction);
        if (is_black(weight)) return;
        const float r = ctx.bounds.radius;
        const Vec2f disk = warp::square_to_uniform_disk_concentric(u_position);
        const Vec3f origin =
            ctx.bounds.center + (Frame3f(ds.d).to_world(Vec3f(disk.x, disk.y, 0.f)) + ds.d) * r;
        ray = Ray(origin, -ds.d);
        light.infinite = true;
        light.d_env = ds.d;
        light.p = origin;
        light.pdf_fwd = ds.delta ? 0.f : selection * ds.pdf;
        light.beta = Color3f(1.f / selection);
        pdf_dir = 1.f / (Pi * r * r);
        beta = weight * (Pi * r * r / selection);
        medium = ctx.has_media ? emitter_medium(ctx.scene, *emitter, ray.o, ctx.rays) : nullptr;
    }
    light.medium = medium;
    path.push_back(light);
    if (is_black(beta)) return;
    random_walk(ctx, ray, medium, beta, pdf_dir, TransportMode::Importance, path, max_vertices);
}

} // namespace penumbra
