#include "diff/psdr/interior.h"

#include "core/stratified.h"
#include "diff/film_sample.h"
#include "diff/material_form.h"
#include "diff/pixel_driver.h"
#include "diff/psdr/interior_media.h"
#include "diff/psdr/shading_horizon.h"
#include "render/light_medium.h"


namespace penumbra {

namespace {

// The shading horizon's random numbers, apart from the warped-area estimators' auxiliary streams.
constexpr AuxiliarySalt HorizonSalt{0x2545F4914F6CDD1DULL, 0x9E6C63D0676A9A99ULL};

// One camera path of pixel (x, y) with the image-space first vertex: the film position is drawn by filter
// importance sampling, as the renderer does (stratified over the pixel's samples), and its ray stays fixed;
// x1(θ) slides along it with the surface (MaterialForm::ray_vertex). The camera factor W_j / p is the renderer's sample weight, independent of θ.
Color3<Var> sample_image_space(const Scene& scene, const MaterialForm& form, Sampler& sampler, int x, int y,
                               const PixelStratum& stratum, bool media, const BDPTPass* bdpt,
                               HorizonRule& rule, const PathSettings& settings, RayCounter& rays) {
    const Sensor& sensor = *scene.sensor;
    const Vec2f pos = sensor.film->sample_position(x, y, stratum(sampler.next_2d()));
    const auto [ray, ray_weight] = sensor.sample_ray(pos, sampler.next_2d());
    ++rays.rays;
    if (bdpt) return bidirectional_camera_path(*bdpt, form, sampler, ray, ray_weight, {}, 1.f, &rule, rays);
    if (media) return volumetric_camera_path(scene, form, sampler, ray, ray_weight, {}, 1.f, settings, rays);
    const SurfaceInteraction3f first = scene.intersect(ray);
    if (!first.is_valid())
        return settings.hide_emitters ? Color3<Var>(Var(0.f))
                                      : form.environment(scene, ray.d) * Color3<Var>(ray_weight);
    SurfaceInteraction<Var> x1 = form.ray_vertex(first, ray);
    x1.wi = x1.to_local(Vec3<Var>(ray.d * -1.f));
    return trace_path<Var>(scene, sampler, ray, first, x1, rule, settings, rays) * Color3<Var>(ray_weight);
}

// One camera path of pixel (x, y) as a function of θ: W_j(x1(θ)) L(x1 → camera) / p, with the camera factor
// W_j / p = P_j(s(θ)) |ds/dA|(θ) J(p1) / (p_s |ds/dA|(θ0)) (the pinhole importance of Eqs. 22-23 written on the
// film, P_j the normalized reconstruction filter of pixel j, s the projection of x1).
Color3<Var> sample_contribution(const Scene& scene, const MaterialForm& form, Sampler& sampler, int x, int y,
                                const PixelStratum& stratum, bool mirror, bool media, const BDPTPass* bdpt,
                                HorizonRule& rule, const PathSettings& settings, RayCounter& rays) {
    if (form.image_space_first_vertex())
        return sample_image_space(scene, form, sampler, x, y, stratum, media, bdpt, rule, settings, rays);
    const Sensor& sensor = *scene.sensor;
    const ReconstructionFilter& filter = *sensor.film->rfilter;
    const FilmSample fs = sample_film(filter, sampler, mirror);
    const Vec2f center(x + 0.5f, y + 0.5f);
    const auto [ray, ray_weight] = sensor.sample_ray(center + fs.offset, sampler.next_2d());
    ++rays.rays;
    const Vec3f camera = sensor.to_world.apply_point(Vec3f(0.f));
    if (media || bdpt) {
        // W_j / p = P_j(s(θ)) |ds/dA|(θ) J / (p_s |ds/dA|(θ0)); a medium vertex's |ds/dA| has the normal
        // toward the camera (|ds/dω| / ℓ², the volume measure).
        const CameraFactor factor = [&](const Vec3<Var>& p, const Vec3<Var>& n, const Var& jacobian) {
            const Vec3<Var> p_cam = form.to_reference_camera(p, camera);
            Vec2<Var> s;
            Var film_jacobian;
            if (!sensor.film_position(p_cam, form.direction_to_reference_camera(n), s, film_jacobian)) return Var(0.f);
            return sensor.film->filter_weight(x, y, s) * relative_change(film_jacobian * jacobian) / Var(fs.pdf);
        };
        const float escaped = sensor.film->filter_weight(x, y, center + fs.offset) / fs.pdf;
        if (bdpt)
            return bidirectional_camera_path(*bdpt, form, sampler, ray, ray_weight, factor, escaped, &rule,
                                             rays);
        return volumetric_camera_path(scene, form, sampler, ray, ray_weight, factor, escaped, settings, rays);
    }
    const SurfaceInteraction3f first = scene.intersect(ray);
    if (!first.is_valid()) {
        // The environment seen through the film is a direction: only its own rotation changes it.
        const float w = sensor.film->filter_weight(x, y, center + fs.offset) / fs.pdf;
        return settings.hide_emitters ? Color3<Var>(Var(0.f))
                                      : form.environment(scene, ray.d) * Color3<Var>(ray_weight * w);
    }

    SurfaceInteraction<Var> x1 = form.vertex(first);
    const Vec3<Var> p_cam = form.to_reference_camera(x1.p, camera);
    const Vec3<Var> n_cam = form.direction_to_reference_camera(x1.n);
    Vec2<Var> s;
    Var jacobian;
    if (!sensor.film_position(p_cam, n_cam, s, jacobian)) return Color3<Var>(Var(0.f));
    const Var P = sensor.film->filter_weight(x, y, s);
    const Var camera_factor = P * relative_change(jacobian * form.jacobian(first)) / Var(fs.pdf);

    x1.wi = x1.to_local(form.direction_from_reference_camera(sensor.to_sensor(p_cam)));
    return trace_path<Var>(scene, sampler, ray, first, x1, rule, settings, rays) * camera_factor;
}

// The interior term's samples on `loop`: sample_contribution, antithetic pairs mirrored, the film position
// stratified over the pixel's samples.
void set_interior_samples(PixelLoop& loop, std::shared_ptr<const MaterialForm> form,
                          const DiffOptions& options) {
    const Scene& scene = loop.scene;
    const bool media = scene_has_media(scene);
    const bool antithetic = options.antithetic && !form->image_space_first_vertex();
    loop.antithetic = antithetic;
    const int spp = options.spp;
    const PathSettings settings = options.path;
    const std::shared_ptr<const BDPTPass> bdpt =
        bidirectional_interior(scene, options.estimator)
            ? std::make_shared<const BDPTPass>(bidirectional_pass(scene, settings))
            : nullptr;
    const auto horizon =
        options.shading_horizon ? std::make_shared<const ShadingHorizon>(scene, loop.params) : nullptr;
    loop.tiles = per_sample([&scene, form, media, bdpt, horizon, antithetic, spp,
                             settings](Sampler& sampler, const PixelSample& s, RayCounter& rays) {
        const bool mirror = antithetic && (s.m & 1);
        const PixelStratum stratum(s.m, spp, s.seed, s.pixel);
        HorizonRule rule{
            {*form}, horizon.get(), settings, AuxiliaryRng(s.seed, s.pixel, uint64_t(s.m), HorizonSalt)};
        return sample_contribution(scene, *form, sampler, s.x, s.y, stratum, mirror, media, bdpt.get(), rule,
                                   settings, rays);
    });
}

// The results' term name and description ("interior term (unidirectional), image-space first vertex").
void describe_interior(PixelLoop& loop, const DiffOptions& options) {
    const bool bidirectional = bidirectional_interior(loop.scene, options.estimator);
    const bool image_space = image_space_first_vertex(loop.scene, loop.params, options.first_vertex);
    loop.term = "interior";
    loop.description = std::string("interior term (") + (bidirectional ? "bidirectional" : "unidirectional") +
                       "), " + (image_space ? "image-space" : "material-form") + " first vertex";
}

} // namespace

DerivativeImage render_derivative(const Scene& scene, const Parameters& params, const DiffOptions& options) {
    require_film(scene, params);
    if (bidirectional_interior(scene, options.estimator)) require_bidirectional_support(scene);
    PixelLoop loop(scene, params, options);
    set_interior_samples(loop, std::make_shared<const MaterialForm>(scene, params, options.first_vertex),
                         options);
    describe_interior(loop, options);
    return pixel_derivative(loop);
}

Gradient render_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const DiffOptions& options) {
    require_film(scene, params);
    PixelLoop loop(scene, params, options);
    const auto form = std::make_shared<const MaterialForm>(scene, params, options.first_vertex);
    if (bidirectional_interior(scene, options.estimator)) require_bidirectional_support(scene);
    set_interior_samples(loop, form, options);
    describe_interior(loop, options);
    Gradient result = pixel_gradient(loop, adjoint);
    for (const std::string& shape : form->volume_motion().omitted())
        result.warnings.push_back("the medium around '" + shape + "' does not follow its vertex_positions (" +
                                  "it touches another shape): their gradient misses the medium's motion");
    return result;
}

} // namespace penumbra
