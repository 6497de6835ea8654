#include "render/bdpt_sample.h"

#include "render/bdpt_connect.h"
#include "render/light_medium.h"
#include "scene/sensors/sensor_common.h"

#include <algorithm>
#include <limits>

namespace penumbra {

namespace {

// A path of at most max_depth segments has max_depth + 1 camera vertices (z_0 on the sensor, s = 0) and
// max_depth light vertices (t >= 1).
size_t max_vertices(int max_depth, size_t endpoints) {
    return max_depth < 0 ? std::numeric_limits<size_t>::max() : size_t(max_depth) + endpoints;
}

// Infinite lights emit from a disk of the scene's bounding sphere, enlarged as the emitters do.
BoundingSphere emission_bounds(const Scene& scene) {
    BoundingSphere bounds = scene.bounding_sphere();
    bounds.radius = std::max(RayEpsilon, bounds.radius * (1.f + RayEpsilon));
    return bounds;
}

} // namespace

BDPTPass::BDPTPass(const Scene& s, const BDPTSettings& bdpt, bool light_tracing)
    : scene(s), settings(bdpt), has_media(scene_has_media(s)),
      sensor_connects(light_tracing && dynamic_cast<const MeterSensor*>(s.sensor.get()) == nullptr),
      bounds(emission_bounds(s)), max_camera(max_vertices(bdpt.max_depth, 1)),
      max_light(max_vertices(bdpt.max_depth, 0)) {}

Color3f BDPTSample::render(const BDPTPass& pass, Sampler& sampler, RayCounter& rays, const Ray& ray,
                           const Vec2f& u_aperture, Image& splats) {
    return trace(pass, sampler, rays, ray, u_aperture, &splats, nullptr);
}

void BDPTSample::trace_recorded(const BDPTPass& pass, Sampler& sampler, RayCounter& rays, const Ray& ray) {
    record.clear();
    trace(pass, sampler, rays, ray, Vec2f(0.5f), nullptr, &record);
}

Color3f BDPTSample::trace(const BDPTPass& pass, Sampler& sampler, RayCounter& rays, const Ray& ray,
                          const Vec2f& u_aperture, Image* splats, BDPTRecord* recorded) {
    BDPTContext ctx{pass.scene,     pass.settings,        sampler,     rays,
                    pass.has_media, pass.sensor_connects, pass.bounds, recorded};
    camera_subpath(ctx, ray, u_aperture, camera, pass.max_camera);
    light_subpath(ctx, light, pass.max_light);
    return connect_subpaths(ctx, camera, light, splats);
}

} // namespace penumbra
