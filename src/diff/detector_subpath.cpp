#include "diff/detector_subpath.h"

#include "render/adjoint_shading.h"

namespace penumbra {

namespace {

// Whether the camera sees the point p (on a surface with normal n).
bool camera_sees(const Scene& scene, const Vec3f& p, const Vec3f& n, RayCounter& rays) {
    const Sensor& sensor = *scene.sensor;
    Interaction3f at;
    at.p = p;
    at.n = n;
    ++rays.rays;
    return !scene.occluded(sensor.plugin == "orthographic" ? at.spawn_ray(sensor.to_sensor(p))
                                                           : at.spawn_ray_to(sensor.to_world.apply_point(Vec3f(0.f))));
}

// The camera's importance at `si` in film measure, times the adjoint BSDF toward the camera.
bool connect_to_camera(const Scene& scene, const SurfaceInteraction3f& si, CameraConnection& out, RayCounter& rays) {
    const Sensor& sensor = *scene.sensor;
    float jacobian;
    if (!sensor.film_position(si.p, si.n, out.s, jacobian)) return false;
    const float r = sensor.film->rfilter->radius(); // border pixels' filters reach r beyond the film
    if (!(out.s.x >= -r && out.s.y >= -r && out.s.x <= sensor.film->width + r && out.s.y <= sensor.film->height + r))
        return false;
    const Vec3f to_cam = sensor.to_sensor(si.p);
    const float cos_cam = std::abs(dot(si.n, to_cam));
    if (!(cos_cam > 0.f)) return false;
    if (!camera_sees(scene, si.p, si.n, rays)) return false;
    const Color3f f = si.bsdf()->eval(BSDFContext{TransportMode::Importance}, si, si.to_local(to_cam)) *
                      adjoint_shading_correction(si, to_cam);
    out.weight = f * (jacobian / cos_cam);
    return !is_black(out.weight);
}

} // namespace

void detector_connections(const Scene& scene, const SurfaceInteraction3f& x_d0, const Vec3f& dark_point, int t_min,
                          int t_max, const PathSettings& settings, Sampler& sampler, RayCounter& rays,
                          DetectorConnections& out) {
    const BSDFContext ctx{TransportMode::Importance};
    SurfaceInteraction3f si = x_d0;
    Color3f throughput(1.f);
    for (int t = 0; t_max < 0 || t <= t_max; ++t) {
        const BSDF* bsdf = si.bsdf();
        if (!bsdf) return;
        if (t >= t_min && bsdf->has(BSDFSmooth)) {
            CameraConnection c;
            if (connect_to_camera(scene, si, c, rays) && (t > 0 || camera_sees(scene, dark_point, si.n, rays))) {
                c.weight *= throughput;
                c.t = t;
                out.items[out.count++] = c;
                if (out.count == DetectorConnections::Capacity) return;
            }
        }
        if (t == t_max) return;
        const float u1 = sampler.next_1d();
        const auto [bs, weight] = bsdf->sample(ctx, si, u1, sampler.next_2d());
        if (is_black(weight)) return;
        const Vec3f d = si.to_world(bs.wo);
        throughput *= weight * adjoint_shading_correction(si, d);
        ++rays.rays;
        si = scene.intersect(si.spawn_ray(d));
        if (!si.is_valid()) return;
        if (t + 1 >= settings.rr_depth) {
            const float q = std::min(max_component(throughput), 0.95f);
            if (sampler.next_1d() >= q) return;
            throughput /= q;
        }
    }
}

} // namespace penumbra
