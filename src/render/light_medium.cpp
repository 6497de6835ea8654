#include "render/light_medium.h"

#include "render/null_walk.h"
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
    constexpr NullWalkRule every_surface{.every_surface = true, .bounded = true};
    SurfaceInteraction3f hit;
    return walk_null_surfaces<every_surface>(scene, Ray(o, to_x / dist, dist), medium, rays, nullptr, hit,
                                             no_segment_action)
        .medium;
}

const Medium* emitter_medium(const Scene& scene, const Emitter& emitter, const Vec3f& origin,
                             RayCounter& rays) {
    if (emitter.medium) return emitter.medium.get();
    const Shape* shape = emitter.shape();
    if (shape && (shape->interior || shape->exterior)) return shape->exterior.get();
    return medium_at(scene, origin, rays);
}

} // namespace penumbra
