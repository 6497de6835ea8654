#include "diff/direct_boundary.h"

#include "core/distribution.h"
#include "diff/edges.h"
#include "diff/material_form.h"
#include "scene/shape_interaction.h"


namespace penumbra {

// Every discontinuity edge of the scene, sampled by length.
struct DirectBoundary::EdgeSet {
    struct SceneEdge {
        const Shape* shape;
        Edge edge;
    };
    std::vector<SceneEdge> edges;
    DiscreteDistribution by_length;
    float total_length = 0.f;
};

namespace {

using EdgeSet = DirectBoundary::EdgeSet;

std::unique_ptr<const EdgeSet> all_edges(const Scene& scene) {
    auto result = std::make_unique<EdgeSet>();
    EdgeSet& out = *result;
    std::vector<float> lengths;
    for (const auto& shape : scene.shapes)
        for (const Edge& e : discontinuity_edges(shape->mesh)) {
            const float l = norm(shape->mesh.positions[e.v1] - shape->mesh.positions[e.v0]);
            if (!(l > 0.f)) continue;
            out.edges.push_back({shape.get(), e});
            lengths.push_back(l);
            out.total_length += l;
        }
    if (!lengths.empty()) out.by_length = DiscreteDistribution(lengths);
    return result;
}

// A point on an emitter that next-event estimation could have chosen.
struct LightPoint {
    Vec3f p;
    Vec3f n; // surface normal of area lights (for offsetting rays off the emitter), zero for point lights
    const Emitter* emitter = nullptr;
    const Shape* shape = nullptr; // area lights: the material point (prim, bary) of p
    uint32_t prim = 0;
    Vec2f bary;
    float pdf = 1.f; // area density (1 for point lights), times the emitter selection probability
};

// Incident term at x from the light point (point: I/d²; area: L_e cos_y / d²), without visibility.
Color3f incident(const LightPoint& l, const Vec3f& x) {
    const Vec3f d = l.p - x;
    const float dist2 = squared_norm(d);
    if (!l.shape) return l.emitter->eval_delta(x);
    SurfaceInteraction3f y = surface_interaction<float>(*l.shape, l.prim, l.bary, MeshVertices{l.shape->mesh});
    y.wi = y.to_local(normalize(x - l.p));
    return l.emitter->eval(y) * (std::abs(dot(y.n, d)) / (dist2 * std::sqrt(dist2)));
}

// Intersection of the line from `from` through `through` with the plane of triangle `prim` of `shape`.
template <typename V> V line_plane(const V& from, const V& through, const V& p0, const V& n) {
    const V d = through - from;
    return from + d * (dot(n, p0 - from) / dot(n, d));
}

// One sample: s = the receiver point's film position, weight = the lit integrand × |ds/dA| × dℓ_D/dℓ_B / pdf,
// velocity = (x_D(θ) − x_receiver(θ)) · n_shadow (its derivative is the shadow curve's normal velocity).
BoundarySample sample_direct(const Scene& scene, const EdgeSet& edges, const MaterialForm& form, Sampler& sampler,
                           RayCounter& rays) {
    BoundarySample out;
    const Sensor& sensor = *scene.sensor;
    float u = sampler.next_1d();
    const EdgeSet::SceneEdge& se = edges.edges[edges.by_length.sample(u)];
    const float tau = u;
    const TriangleMesh& m = se.shape->mesh;
    const Vec3f a = m.positions[se.edge.v0], b = m.positions[se.edge.v1];
    const Vec3f x_b = a + (b - a) * tau;

    // A light point: point lights at their position, area lights by area.
    float u_light = sampler.next_1d(), select_pdf = 0.f;
    const Emitter* emitter = scene.sample_emitter(u_light, select_pdf);
    const Vec2f u2 = sampler.next_2d();
    if (!emitter || emitter->is_infinite()) return out;
    LightPoint light;
    light.emitter = emitter;
    if (const Shape* shape = emitter->shape()) {
        const PositionSample3f ps = shape->sample_position(u2);
        light = {ps.p, ps.n, emitter, shape, ps.prim, ps.bary, ps.pdf * select_pdf};
    } else {
        Interaction3f ref;
        ref.p = x_b;
        const auto ds = emitter->sample_direction(ref, u2).first;
        light = {ds.p, Vec3f(0.f), emitter, nullptr, 0, Vec2f(), select_pdf};
    }
    if (!is_silhouette(m, se.edge, light.p)) return out;

    // The segment light -> x_B must be clear, and its extension beyond x_B finds the receiver x_D.
    Interaction3f at_light;
    at_light.p = light.p;
    at_light.n = light.n;
    rays.rays += 2;
    Ray to_edge = at_light.spawn_ray_to(x_b);
    to_edge.tmax *= 0.999f;
    if (scene.occluded(to_edge)) return out;
    const Vec3f dir = normalize(x_b - light.p);
    const SurfaceInteraction3f recv = scene.intersect(Ray(x_b + dir * ray_offset_scale(x_b), dir));
    if (!recv.is_valid() || !recv.bsdf()) return out;
    const Vec3f x_d = recv.p;

    // The receiver point must be what the camera sees there.
    Vec2f s;
    float jacobian;
    if (!sensor.film_position(x_d, recv.n, s, jacobian)) return out;
    if (!(s.x >= 0.f && s.y >= 0.f && s.x <= sensor.film->width && s.y <= sensor.film->height)) return out;
    const Vec3f to_cam = sensor.to_sensor(x_d);
    rays.rays += 1;
    const Ray cam_ray = sensor.plugin == "orthographic" ? recv.spawn_ray(to_cam)
                                                        : recv.spawn_ray_to(sensor.to_world.apply_point(Vec3f(0.f)));
    if (scene.occluded(cam_ray)) return out;

    // The shadow curve on the receiver: tangent from a nearby edge point, normal into the shadow.
    const uint32_t* tri = &recv.shape->mesh.indices[3 * size_t(recv.prim_index)];
    const Vec3f p0 = recv.shape->mesh.positions[tri[0]];
    const float delta = 1e-3f;
    const Vec3f x_b2 = a + (b - a) * std::min(1.f, tau + delta), x_b1 = a + (b - a) * std::max(0.f, tau - delta);
    const Vec3f x_d2 = line_plane(light.p, x_b2, p0, recv.n), x_d1 = line_plane(light.p, x_b1, p0, recv.n);
    const float stretch = norm(x_d2 - x_d1) / norm(x_b2 - x_b1); // dℓ_D / dℓ_B
    if (!std::isfinite(stretch) || !(stretch > 0.f)) return out;
    Vec3f n = normalize(cross(recv.n, x_d2 - x_d1));
    const float eps = 1e-3f * norm(x_d2 - x_d1) / (2.f * delta) + 1e-5f;
    Ray probe_plus = at_light.spawn_ray_to(x_d + n * eps), probe_minus = at_light.spawn_ray_to(x_d - n * eps);
    probe_plus.tmax *= 0.999f;
    probe_minus.tmax *= 0.999f;
    rays.rays += 2;
    const bool plus_dark = scene.occluded(probe_plus), minus_dark = scene.occluded(probe_minus);
    if (plus_dark == minus_dark) return out;
    if (!plus_dark) n = n * -1.f; // n points into the shadow

    // The lit-side integrand: f_s(camera ← x_D → y) times the incident term, with the film Jacobian.
    SurfaceInteraction3f si = recv;
    si.wi = si.to_local(to_cam);
    const Color3f f = si.bsdf()->eval(BSDFContext{}, si, si.to_local(normalize(light.p - x_d)));
    const float pdf = light.pdf / edges.total_length;
    out.weight = f * incident(light, x_d) * (jacobian * stretch / pdf);
    out.s = s;

    // Velocity of the shadow curve relative to the receiver's material point, on the tape.
    const Vec3<Var> a_t = form.position(*se.shape, se.edge.v0), b_t = form.position(*se.shape, se.edge.v1);
    const Vec3<Var> xb_t = a_t + (b_t - a_t) * Var(tau);
    const Vec3<Var> y_t = light.shape ? form.vertex(surface_interaction<float>(*light.shape, light.prim, light.bary,
                                                                                  MeshVertices{light.shape->mesh})).p
                                      : Vec3<Var>(light.p);
    const Vec3<Var> q0 = form.position(*recv.shape, tri[0]), q1 = form.position(*recv.shape, tri[1]),
                    q2 = form.position(*recv.shape, tri[2]);
    const Vec3<Var> xd_t = line_plane(y_t, xb_t, q0, cross(q1 - q0, q2 - q0));
    const Vec3<Var> recv_t = form.vertex(recv).p;
    out.velocity = dot(xd_t - recv_t, Vec3<Var>(n));
    out.valid = true;
    return out;
}

constexpr uint64_t Salt = 0x94D049BB133111EBULL;

} // namespace

DirectBoundary::DirectBoundary(const Scene& scene) : scene_(scene), edges_(all_edges(scene)) {}
DirectBoundary::~DirectBoundary() = default;

Image DirectBoundary::derivative(const Parameters& params, const BoundaryOptions& options) const {
    if (edges_->edges.empty() || scene_.emitters.empty())
        return Image(scene_.sensor->film->width, scene_.sensor->film->height);
    const MaterialForm form(params);
    return boundary_derivative(scene_, params, options, Salt, [&](Sampler& sampler, RayCounter& rays) {
        return sample_direct(scene_, *edges_, form, sampler, rays);
    });
}

void DirectBoundary::gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                              std::vector<double>& gradient) const {
    if (edges_->edges.empty() || scene_.emitters.empty()) return;
    const MaterialForm form(params);
    boundary_gradient(scene_, adjoint, options, Salt, [&](Sampler& sampler, RayCounter& rays) {
        return sample_direct(scene_, *edges_, form, sampler, rays);
    }, gradient);
}

} // namespace penumbra
