#include "diff/pixel_boundary.h"

#include "diff/material_form.h"

namespace penumbra {

bool needs_pixel_boundary(const Scene& scene) { return scene.sensor->film->rfilter->plugin == "box"; }

namespace {

// One sample: a point s on a pixel edge (uniform over the total edge length), L(s) by path tracing, splats of
// ∓L / pdf just inside the pixels on either side, and the velocity ṡ · x̂ (or ŷ) on the tape.
BoundarySample sample_pixel_edge(const Scene& scene, const MaterialForm& form, const PathSettings& settings,
                                 Sampler& sampler, RayCounter& rays) {
    BoundarySample out;
    const Sensor& sensor = *scene.sensor;
    const int W = sensor.film->width, H = sensor.film->height;
    const float vertical = float(W + 1) * H, total = vertical + float(H + 1) * W;
    // The edge: a vertical line x = k (length H) or a horizontal line y = k (length W), and a point on it.
    const float u = sampler.next_1d() * total, v = sampler.next_1d();
    const bool is_vertical = u < vertical;
    Vec2f s, across;
    int k, extent;
    if (is_vertical) {
        k = std::min(int(u / H), W);
        s = Vec2f(float(k), v * H);
        across = Vec2f(1.f, 0.f);
        extent = W;
    } else {
        k = std::min(int((u - vertical) / W), H);
        s = Vec2f(v * W, float(k));
        across = Vec2f(0.f, 1.f);
        extent = H;
    }

    // L(s): the radiance seen through s (the same on both sides of the edge, the filter alone jumps).
    const auto [ray, ray_weight] = sensor.sample_ray(s, sampler.next_2d());
    ++rays.rays;
    const SurfaceInteraction3f hit = scene.intersect(ray);
    if (!hit.is_valid()) return out; // the environment seen directly does not move with the geometry
    const Color3f L = trace_path<float>(scene, sampler, ray, hit, hit, ReferenceGeometry{}, settings, rays);
    if (is_black(L)) return out;

    // ṡ · across for the material point seen at s.
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    Vec2<Var> s_t;
    Var jacobian;
    if (!sensor.film_position(form.to_reference_camera(form.vertex(hit).p, eye), Vec3<Var>(Vec3f(0.f, 0.f, 1.f)), s_t, jacobian))
        return out;
    const Var velocity = is_vertical ? s_t.x - Var(s.x) : s_t.y - Var(s.y);

    // The pixel before the line (outward normal +across) loses what crosses it, the one after gains it.
    const float pdf = 1.f / total, nudge = 1e-3f;
    if (k > 0) out.add_splat(s - across * nudge, L * (-1.f / pdf));
    if (k < extent) out.add_splat(s + across * nudge, L * (1.f / pdf));
    out.velocity = velocity;
    return out;
}

constexpr uint64_t Salt = 0x4CF5AD432745937FULL;

} // namespace

Image PixelBoundary::derivative(const Parameters& params, const BoundaryOptions& options) const {
    if (!needs_pixel_boundary(scene_)) return Image(scene_.sensor->film->width, scene_.sensor->film->height);
    const MaterialForm form(params);
    return boundary_derivative(scene_, params, options, Salt, [&](Sampler& sampler, RayCounter& rays) {
        return sample_pixel_edge(scene_, form, options.path, sampler, rays);
    });
}

void PixelBoundary::gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                             std::vector<double>& gradient) const {
    if (!needs_pixel_boundary(scene_)) return;
    const MaterialForm form(params);
    boundary_gradient(scene_, adjoint, options, Salt, [&](Sampler& sampler, RayCounter& rays) {
        return sample_pixel_edge(scene_, form, options.path, sampler, rays);
    }, gradient);
}

} // namespace penumbra
