#include "render/light_medium.h"

#include "render/volume_visibility.h"

namespace penumbra {

bool scene_has_media(const Scene& scene) {
    if (sensor_medium(scene)) return true;
    for (const auto& shape : scene.shapes)
        if (shape->interior || shape->exterior) return true;
    for (const auto& emitter : scene.emitters)
        if (emitter->medium) return true;
    return false;
}

const Medium* medium_at(const Scene& scene, const Vec3f& x, RayCounter& rays) {
    const Medium* medium = sensor_medium(scene);
    const Vec3f o = scene.sensor->to_world.apply_point(Vec3f(0.f));
    const Vec3f to_x = x - o;
    const float dist = norm(to_x);
    if (!(dist > 0.f)) return medium;
    Ray ray(o, to_x / dist, dist);
    // A bound on the surfaces crossed guards against rays stuck on coincident surfaces.
    for (int crossing = 0; crossing < 256; ++crossing) {
        ++rays.rays;
        const SurfaceInteraction3f si = scene.intersect(ray);
        if (!si.is_valid()) break;
        medium = target_medium(*si.shape, si.n, ray.d, medium);
        ray = ray_beyond(ray, si);
        if (!(ray.tmax > 0.f)) break;
    }
    return medium;
}

const Medium* emitter_medium(const Scene& scene, const Emitter& emitter, const Vec3f& origin,
                             RayCounter& rays) {
    if (emitter.medium) return emitter.medium.get();
    const Shape* shape = emitter.shape();
    if (shape && (shape->interior || shape->exterior)) return shape->exterior.get();
    return medium_at(scene, origin, rays);
}

} // namespace penumbra
