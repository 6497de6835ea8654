#include "diff/primary_boundary.h"

#include "core/distribution.h"
#include "diff/material_form.h"

#include <algorithm>

namespace penumbra {

// Silhouette edges as seen from the reference camera, with their projections. Edges with an endpoint behind
// the camera are skipped.
struct PrimaryBoundary::Silhouettes {
    struct SilhouetteEdge {
        const Shape* shape;
        Edge edge;
        Vec2f s0, s1; // projected endpoints (pixels)
        float z0, z1; // depths along the view direction (perspective-correct interpolation)
    };
    std::vector<SilhouetteEdge> edges;
    DiscreteDistribution by_length;
    float total_length = 0.f;
};

namespace {

using Silhouettes = PrimaryBoundary::Silhouettes;

std::unique_ptr<const Silhouettes> find_silhouettes(const Scene& scene, const SceneEdges& edges) {
    const Sensor& sensor = *scene.sensor;
    const bool parallel = sensor.plugin == "orthographic";
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    const Vec3f forward = normalize(sensor.to_world.apply_vector(Vec3f(0.f, 0.f, 1.f)));
    auto result = std::make_unique<Silhouettes>();
    Silhouettes& out = *result;
    std::vector<float> lengths;
    for (const SceneEdges::SceneEdge& se : edges.edges) {
        const TriangleMesh& m = se.shape->mesh;
        const Edge& e = se.edge;
        if (parallel ? !is_silhouette_parallel(m, e, forward) : !is_silhouette(m, e, eye)) continue;
        const Vec3f p0 = m.positions[e.v0], p1 = m.positions[e.v1];
        Vec2f s0, s1;
        float j;
        if (!sensor.film_position(p0, forward, s0, j) || !sensor.film_position(p1, forward, s1, j)) continue;
        const float length = std::sqrt(sqr(s1.x - s0.x) + sqr(s1.y - s0.y));
        if (!(length > 0.f) || !std::isfinite(length)) continue;
        out.edges.push_back({se.shape, e, s0, s1, dot(p0 - eye, forward), dot(p1 - eye, forward)});
        lengths.push_back(length);
        out.total_length += length;
    }
    if (!lengths.empty()) out.by_length = DiscreteDistribution(lengths);
    return result;
}

// One boundary sample: film position s, the detached factor (−L_bg / pdf), and the relative normal velocity
// v = (s_edge(θ) − s_bg(θ)) · n as a tape expression (its value is ~0; its derivative is the velocity).
BoundarySample sample_boundary(const Scene& scene, const Silhouettes& sil, const MaterialForm& form, Sampler& sampler,
                               const PathSettings& settings, RayCounter& rays) {
    BoundarySample out;
    const Sensor& sensor = *scene.sensor;
    float u = sampler.next_1d();
    const Silhouettes::SilhouetteEdge& se = sil.edges[sil.by_length.sample(u)];
    const float t = u;
    const Vec2f s = se.s0 + (se.s1 - se.s0) * t;
    // The 3D edge point projecting to s (perspective-correct along the edge; affine for a parallel projection).
    const bool parallel = sensor.plugin == "orthographic";
    const float tau = parallel ? t : t * se.z0 / ((1.f - t) * se.z1 + t * se.z0);
    const Vec2f dir = se.s1 - se.s0;
    const Vec2f n2 = Vec2f(-dir.y, dir.x) / std::sqrt(dir.x * dir.x + dir.y * dir.y);

    const Vec3f p0 = se.shape->mesh.positions[se.edge.v0], p1 = se.shape->mesh.positions[se.edge.v1];
    const Vec3f x_edge = p0 + (p1 - p0) * tau;

    // Which side is the occluder (a face adjacent to the edge) and which the background behind it, probed at
    // s ± eps n2. L_bg is the limit of the background's radiance at the silhouette, but rays leaving the
    // background point start RayEpsilon-scaled offsets off its surface: a shadow ray toward a light at (or near)
    // the camera runs back along the probe and, closer to the edge than those offsets, clips the occluder and
    // reports a false shadow. The probe therefore clears the edge by twice the offset scale of the segment
    // camera–edge (which bounds the offset of any point behind the edge as seen at the edge's depth), clamped
    // to [1e-3, 0.05] pixels so that L_bg and u_bg stay the limits at the edge up to a small fraction of a pixel.
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    const float clearance = 2.f * RayEpsilon * (1.f + max_component(abs(eye)) + norm(x_edge - eye));
    const Ray center = sensor.sample_ray(s, Vec2f(0.5f)).first, side = sensor.sample_ray(s + n2, Vec2f(0.5f)).first;
    const float depth = norm(x_edge - center.o);
    const float world_per_pixel = norm(side.o + side.d * depth - (center.o + center.d * depth));
    const float eps = std::clamp(clearance / world_per_pixel, 1e-3f, 0.05f); // pixels
    const auto [ray_a, wa] = sensor.sample_ray(s + n2 * eps, sampler.next_2d());
    const auto [ray_b, wb] = sensor.sample_ray(s - n2 * eps, sampler.next_2d());
    rays.rays += 2;
    const SurfaceInteraction3f hit_a = scene.intersect(ray_a), hit_b = scene.intersect(ray_b);
    auto adjacent = [&](const SurfaceInteraction3f& h) {
        return h.is_valid() && h.shape == se.shape && (int32_t(h.prim_index) == se.edge.f0 || int32_t(h.prim_index) == se.edge.f1);
    };
    const bool a_occ = adjacent(hit_a), b_occ = adjacent(hit_b);
    if (a_occ == b_occ) return out; // hidden behind something else, or not a depth discontinuity here
    const Ray& bg_ray = a_occ ? ray_b : ray_a;
    const SurfaceInteraction3f& bg = a_occ ? hit_b : hit_a;
    const Vec2f n = a_occ ? n2 * -1.f : n2; // from the occluder toward the background
    if (bg.is_valid() && bg.t < norm(x_edge - bg_ray.o) * (1.f - 1e-4f)) return out;

    // L_bg: a path-traced estimate of the radiance seen just beyond the silhouette.
    const Color3f L_bg = trace_path<float>(scene, sampler, bg_ray, bg, bg, ReferenceGeometry{}, settings, rays);
    const float pdf = 1.f / sil.total_length;

    // Image-space velocities of the edge point (fixed barycentric position on the moving edge, Eq. 47 of paper
    // 001) and of the background's material point (Eq. 50), first order, on the tape.
    const Vec3<Var> x_e = form.position(*se.shape, se.edge.v0) +
                          (form.position(*se.shape, se.edge.v1) - form.position(*se.shape, se.edge.v0)) * Var(tau);
    const Vec3<Var> view(Vec3f(0.f, 0.f, 1.f));
    Vec2<Var> s_e, s_b(Var(s.x), Var(s.y));
    Var j;
    if (!sensor.film_position(form.to_reference_camera(x_e, eye), view, s_e, j)) return out;
    if (bg.is_valid() && !sensor.film_position(form.to_reference_camera(form.vertex(bg).p, eye), view, s_b, j)) return out;
    out.velocity = (s_e.x - s_b.x) * Var(n.x) + (s_e.y - s_b.y) * Var(n.y);
    out.add_splat(s, L_bg * (-1.f / pdf));
    return out;
}

constexpr uint64_t Salt = 0xB5AD4ECEDA1CE2A9ULL;

} // namespace

PrimaryBoundary::PrimaryBoundary(const Scene& scene, const SceneEdges& edges)
    : scene_(scene), silhouettes_(find_silhouettes(scene, edges)) {}
PrimaryBoundary::~PrimaryBoundary() = default;

Image PrimaryBoundary::derivative(const Parameters& params, const BoundaryOptions& options) const {
    if (silhouettes_->edges.empty()) return Image(scene_.sensor->film->width, scene_.sensor->film->height);
    const MaterialForm form(params);
    return boundary_derivative(scene_, params, options, Salt, [&](Sampler& sampler, RayCounter& rays) {
        return sample_boundary(scene_, *silhouettes_, form, sampler, options.path, rays);
    });
}

void PrimaryBoundary::gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                               std::vector<double>& gradient) const {
    if (silhouettes_->edges.empty()) return;
    const MaterialForm form(params);
    boundary_gradient(scene_, adjoint, options, Salt, [&](Sampler& sampler, RayCounter& rays) {
        return sample_boundary(scene_, *silhouettes_, form, sampler, options.path, rays);
    }, gradient);
}

} // namespace penumbra
