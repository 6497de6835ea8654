#include "diff/psdr/shading_horizon.h"

#include "scene/shape_interaction.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

// Whether `target` is visible from `origin` (shadow-ray epsilon short of it).
bool unoccluded(const Scene& scene, const Vec3f& origin, const Vec3f& target, RayCounter& rays) {
    const Vec3f d = target - origin;
    const float dist = norm(d);
    ++rays.rays;
    return !scene.occluded(Ray(origin, d / dist, dist * (1.f - 1e-3f)));
}

// V₊ − V₋: the visibility of the point (or, when `target` is null, of the direction d) from just above and
// just below the tangent plane (n) at x.
float visibility_jump(const Scene& scene, const Vec3f& x, const Vec3f& n, const Vec3f* target, const Vec3f& d,
                      RayCounter& rays) {
    const Vec3f offset = n * ray_offset_scale(x);
    float jump = 0.f;
    for (const float side : {1.f, -1.f}) {
        const Vec3f o = x + offset * side;
        bool clear;
        if (target) {
            clear = unoccluded(scene, o, *target, rays);
        } else {
            ++rays.rays;
            clear = !scene.occluded(Ray(o, d));
        }
        if (clear) jump += side;
    }
    return jump;
}

// The direction at angle 2π u on the great circle of the plane with normal n.
Vec3f circle_direction(const Vec3f& n, float u) {
    Vec3f t, b;
    coordinate_system(n, t, b);
    const float phi = 2.f * Pi * u;
    return t * std::cos(phi) + b * std::sin(phi);
}

// The chord where the plane (x, n) crosses triangle `prim`: its end points and their barycentrics (b1, b2).
bool chord(const TriangleMesh& mesh, uint32_t prim, const Vec3f& x, const Vec3f& n, Vec3f p[2], Vec2f b[2]) {
    const uint32_t* i = &mesh.indices[3 * size_t(prim)];
    const Vec3f v[3] = {mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]]};
    const Vec2f bary[3] = {Vec2f(0.f, 0.f), Vec2f(1.f, 0.f), Vec2f(0.f, 1.f)};
    const float s[3] = {dot(n, v[0] - x), dot(n, v[1] - x), dot(n, v[2] - x)};
    int found = 0;
    for (int k = 0; k < 3 && found < 2; ++k) {
        const int l = (k + 1) % 3;
        if ((s[k] > 0.f) == (s[l] > 0.f)) continue;
        const float t = s[k] / (s[k] - s[l]);
        p[found] = v[k] + (v[l] - v[k]) * t;
        b[found] = bary[k] + (bary[l] - bary[k]) * t;
        ++found;
    }
    return found == 2;
}

} // namespace

ShadingHorizon::ShadingHorizon(const Scene& scene, const Parameters& params)
    : scene_(scene), params_(params) {
    for (const auto& shape : scene.shapes)
        moving_ = moving_ || params.moves(*shape);
    for (const auto& e : scene.emitters) {
        if (const Shape* shape = e->shape())
            area_.push_back({e.get(), shape, bounding_sphere(shape->mesh)});
        else if (e->is_infinite() && !e->is_delta())
            environments_.push_back(e.get());
    }
}

std::optional<Color3<Var>> ShadingHorizon::sample(const MaterialForm& form, const BSDF& bsdf,
                                                  const SurfaceInteraction3f& hit,
                                                  const SurfaceInteraction<Var>& si, unsigned depth,
                                                  const PathSettings& settings, AuxiliaryRng& rng,
                                                  RayCounter& rays) const {
    std::optional<Color3<Var>> out;
    const auto add = [&out](const std::optional<Color3<Var>>& term) {
        if (term) out = out ? *out + *term : *term;
    };
    // Flat shading: the BSDF vanishes on the plane (normal and bump maps reject directions below the shading
    // frame's horizon too, scene/bsdfs/perturbed_frame.h).
    if (std::abs(dot(hit.sh_frame.n, hit.n)) > 1.f - 1e-6f) return out;
    const Vec3f n = hit.n;
    // The area lights whose bounds the plane cuts: one of them, uniformly.
    const auto cut_by_plane = [&](const AreaLight& l) {
        return std::abs(dot(n, l.bounds.center - hit.p)) < l.bounds.radius;
    };
    const int cut = int(std::count_if(area_.begin(), area_.end(), cut_by_plane));
    if (cut > 0) {
        int pick = std::min(int(rng.next_1d() * float(cut)), cut - 1);
        for (const AreaLight& l : area_)
            if (cut_by_plane(l) && pick-- == 0) {
                add(area_light(form, bsdf, hit, si, l, float(cut), rng.next_2d(), rays));
                break;
            }
    }
    for (const Emitter* e : environments_)
        add(environment(bsdf, hit, si, *e, rng.next_1d(), rays));
    // Paths through z have depth + 2 segments to z's next vertex and beyond: a path traced from z with the
    // segments left (its first segment is x → z; z's own emission hidden).
    PathSettings reflected = settings;
    reflected.hide_emitters = true;
    if (settings.max_depth >= 0) reflected.max_depth = settings.max_depth - int(depth) - 1;
    if (moving_ && (reflected.max_depth < 0 || reflected.max_depth >= 2))
        add(surfaces(form, bsdf, hit, si, reflected, rng, rays));
    return out;
}

std::optional<Color3<Var>> ShadingHorizon::area_light(const MaterialForm& form, const BSDF& bsdf,
                                                      const SurfaceInteraction3f& hit,
                                                      const SurfaceInteraction<Var>& si,
                                                      const AreaLight& light, float weight, const Vec2f& u,
                                                      RayCounter& rays) const {
    const TriangleMesh& mesh = light.shape->mesh;
    const Vec3f n = hit.n;
    const uint32_t triangles = uint32_t(mesh.indices.size() / 3);
    // C_x by length: the chords of the light's triangles.
    Vec3f p[2];
    Vec2f b[2];
    float total = 0.f;
    for (uint32_t t = 0; t < triangles; ++t)
        if (chord(mesh, t, hit.p, n, p, b)) total += norm(p[1] - p[0]);
    if (!(total > 0.f)) return std::nullopt;
    float target = u.x * total;
    uint32_t prim = triangles;
    for (uint32_t t = 0; t < triangles && prim == triangles; ++t) {
        if (!chord(mesh, t, hit.p, n, p, b)) continue;
        const float length = norm(p[1] - p[0]);
        if (target < length || t + 1 == triangles)
            prim = t;
        else
            target -= length;
    }
    if (prim == triangles) return std::nullopt;
    const Vec2f bary = b[0] + (b[1] - b[0]) * u.y;
    SurfaceInteraction3f y = surface_interaction<float>(*light.shape, prim, bary, MeshVertices{mesh});
    const Vec3f to_light = y.p - hit.p;
    const float dist2 = squared_norm(to_light);
    if (!(dist2 > 0.f)) return std::nullopt;
    const Vec3f w = to_light / std::sqrt(dist2);
    y.wi = y.to_local(w * -1.f);
    const BSDFContext ctx{TransportMode::Radiance};
    const Color3f g =
        bsdf.eval(ctx, hit, hit.to_local(w)) * light.emitter->eval(y) * (std::abs(dot(y.n, w)) / dist2);
    const float gradient = norm(n - y.n * dot(n, y.n));
    if (is_black(g) || !(gradient > 1e-6f)) return std::nullopt;
    const float jump = visibility_jump(scene_, hit.p, n, &y.p, w, rays);
    if (jump == 0.f) return std::nullopt;

    // s(θ) = n_g(θ) · (y(θ) − x(θ)) with the light point at its material point.
    const uint32_t* i = &mesh.indices[3 * size_t(prim)];
    const Vec3<Var> y_t = form.position(*light.shape, i[0]) * Var(1.f - bary.x - bary.y) +
                          form.position(*light.shape, i[1]) * Var(bary.x) +
                          form.position(*light.shape, i[2]) * Var(bary.y);
    const Var s = dot(normalize(si.n), y_t - si.p);
    return Color3<Var>(g * (jump * weight * total / gradient)) * (s - Var(detach(s)));
}

std::optional<Color3<Var>> ShadingHorizon::environment(const BSDF& bsdf, const SurfaceInteraction3f& hit,
                                                       const SurfaceInteraction<Var>& si,
                                                       const Emitter& emitter, float u,
                                                       RayCounter& rays) const {
    const Vec3f w = circle_direction(hit.n, u);
    const BSDFContext ctx{TransportMode::Radiance};
    const Color3f g = bsdf.eval(ctx, hit, hit.to_local(w)) * emitter.eval_environment(w);
    if (is_black(g)) return std::nullopt;
    const float jump = visibility_jump(scene_, hit.p, hit.n, nullptr, w, rays);
    if (jump == 0.f) return std::nullopt;
    // s(θ) = n_g(θ) · ω: the interior integrates the environment over fixed world directions (its rotation
    // slides the radiance over them), so only the plane moves.
    const Var s = dot(normalize(si.n), Vec3<Var>(w));
    return Color3<Var>(g * (jump * 2.f * Pi)) * (s - Var(detach(s)));
}

std::optional<Color3<Var>> ShadingHorizon::surfaces(const MaterialForm& form, const BSDF& bsdf,
                                                    const SurfaceInteraction3f& hit,
                                                    const SurfaceInteraction<Var>& si,
                                                    const PathSettings& reflected, AuxiliaryRng& rng,
                                                    RayCounter& rays) const {
    const Vec3f w = circle_direction(hit.n, rng.next_1d());
    const BSDFContext ctx{TransportMode::Radiance};
    const Color3f f = bsdf.eval(ctx, hit, hit.to_local(w));
    if (is_black(f)) return std::nullopt;
    const Vec3f offset = hit.n * ray_offset_scale(hit.p);
    rays.rays += 2;
    const Ray grazing(hit.p + offset, w);
    const SurfaceInteraction3f z = scene_.intersect(grazing);
    if (!z.is_valid() || !z.bsdf() || (!params_.moves(*hit.shape) && !params_.moves(*z.shape)))
        return std::nullopt;
    // Below the plane the ray must enter the vertex's own solid (it leaves through the inside of a face),
    // where nothing is reflected toward x; an open sheet lets it through, and the light is continuous there.
    const SurfaceInteraction3f below = scene_.intersect(Ray(hit.p - offset, w));
    if (!below.is_valid() || below.shape != hit.shape || !(dot(below.n, w) > 0.f)) return std::nullopt;
    Sampler path_sampler;
    path_sampler.start(rng.next_u64(), 0, 0);
    const Color3f reflected_radiance =
        trace_path<float>(scene_, path_sampler, grazing, z, z, ReferenceGeometry{}, reflected, rays);
    const float r = norm(z.p - hit.p);
    const Color3f g = f * reflected_radiance * (2.f * Pi / r);
    if (is_black(g) || !std::isfinite(max_component(g))) return std::nullopt;
    // s(θ) = n_g(θ) · (z(θ) − x(θ)) with z placed as the interior places a vertex reached from x (its
    // material point, or the contact flow's near x).
    Var jacobian;
    const Var s = dot(normalize(si.n), form.flowed_vertex(z, si.p, jacobian).p - si.p);
    return Color3<Var>(g) * (s - Var(detach(s)));
}

} // namespace penumbra
