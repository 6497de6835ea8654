#include "diff/psdr/interior_media.h"

#include "render/volpath_tracer.h"

namespace penumbra {

Color3<Var> volumetric_camera_path(const Scene& scene, const MaterialForm& form, Sampler& sampler,
                                   const Ray& ray, const Color3f& ray_weight, const CameraFactor& camera,
                                   float escaped_weight, const PathSettings& settings, RayCounter& rays) {
    thread_local LegChain chain;
    const bool image = form.image_space_first_vertex();
    const Vec3f o0 = ray.o;
    const Vec3<Var> o = image ? Vec3<Var>(o0) : form.camera_position(o0);
    Color3f flight;
    SpectralFlights flights{SpectralMIS::PerPath, sample_hero_channel(sampler)};
    VolVertex<Var> x1;
    const ChainEnd end =
        sample_chain(scene, ray, sensor_medium(scene), flights, sampler, &chain, x1.hit, flight, rays);
    const float mean_ratio = flights.mean_ratio();
    const Color3<Var> zero(Var(0.f));
    if (end.kind == ChainEnd::Kind::Absorbed || settings.max_depth == 0) return zero;

    if (end.kind == ChainEnd::Kind::Escaped) {
        if (settings.hide_emitters) return zero;
        const Color3<Var> along = chain_weight(chain, o, o + Vec3<Var>(ray.d), true, false, true, form);
        return form.environment(scene, ray.d) * along *
               Color3<Var>(ray_weight * ((image ? 1.f : escaped_weight) / mean_ratio));
    }

    // The first vertex and its camera factor.
    x1.surface = end.kind == ChainEnd::Kind::Surface;
    x1.medium = end.medium;
    x1.wi0 = -ray.d;
    Var factor(1.f);
    if (x1.surface) {
        Ray camera_ray = ray;
        camera_ray.tmax = Infinity;
        x1.si = image ? form.ray_vertex(x1.hit, camera_ray) : form.vertex(x1.hit);
        x1.p = x1.si.p;
        x1.p0 = x1.hit.p;
        x1.si.wi = x1.si.to_local(normalize(o - x1.p));
        if (!image) factor = camera(x1.p, x1.si.n, form.jacobian(x1.hit));
    } else {
        x1.p0 = end.p;
        if (image) {
            // The piece of the fixed ray holding x1, between the moving surfaces (or the camera) around it.
            const LegPiece& piece = chain.pieces[size_t(chain.count - 1)];
            const Vec3<Var> far = o + Vec3<Var>(ray.d);
            const Vec3<Var> start =
                chain.count > 1 ? crossing_point(form, chain.pieces[size_t(chain.count - 2)].bound, o, far)
                                : o;
            if (piece.bound.is_valid()) {
                const float length0 = piece.bound.t, s = (end.distance - piece.start) / length0;
                const Vec3<Var> stop = crossing_point(form, piece.bound, o, far);
                x1.p = start + (stop - start) * Var(s);
                factor = norm(stop - start) / Var(length0 * norm(ray.d));
            } else {
                x1.p = start + Vec3<Var>(ray.d) * Var(end.distance - piece.start);
            }
        } else {
            Var jacobian;
            x1.p = form.medium_vertex(end.p, end.medium, jacobian);
            factor = camera(x1.p, normalize(o - x1.p), jacobian);
        }
    }
    const bool medium_end = !x1.surface;
    const Color3<Var> along = chain_weight(chain, o, x1.p, true, medium_end, false, form);
    Color3<Var> L(Var(0.f));
    if (x1.surface && !settings.hide_emitters)
        if (const Emitter* e = x1.hit.emitter()) L += e->eval(x1.si) / Var(mean_ratio);
    if (settings.max_depth != 1)
        L += trace_volpath_from<Var>(scene, sampler, x1, o, flights, form, settings, rays);
    return L * along * Color3<Var>(ray_weight) * factor;
}

Vec3<Var> seen_medium_point(const Scene& scene, const MaterialForm& form, const Vec3f& camera, const Vec3f& x) {
    const float dist = norm(x - camera);
    const Vec3f d = (x - camera) / dist;
    const Vec3<Var> o(camera), far(camera + d);
    const SurfaceInteraction3f before = scene.intersect(Ray(x, d * -1.f, dist));
    const SurfaceInteraction3f after = scene.intersect(Ray(x, d));
    const Vec3<Var> start = before.is_valid() ? crossing_point(form, before, o, far) : o;
    const float start0 = before.is_valid() ? dist - before.t : 0.f;
    if (!after.is_valid()) return start + Vec3<Var>(d) * Var(dist - start0);
    const Vec3<Var> stop = crossing_point(form, after, o, far);
    return start + (stop - start) * Var((dist - start0) / (dist + after.t - start0));
}

} // namespace penumbra
