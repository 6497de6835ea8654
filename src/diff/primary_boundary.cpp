#include "diff/primary_boundary.h"

#include "core/distribution.h"
#include "diff/material_form.h"
#include "scene/texture.h"

#include <algorithm>

namespace penumbra {

// The edges whose image the primary term samples: silhouettes seen from the reference camera and, with the
// image-space first vertex, creases of meshes shaded with face normals (the shading jumps there). Each keeps
// the part of the edge that lies in front of the camera and projects within the film (plus the filter's
// reach), with its projection.
struct PrimaryBoundary::Silhouettes {
    struct SilhouetteEdge {
        const Shape* shape;
        Edge edge;
        bool crease;      // a shading discontinuity between two visible faces (not a silhouette)
        float tau0, tau1; // the part kept: edge parameters (v0 → v1) of its ends
        Vec2f s0, s1;     // their film positions (pixels)
        float z0, z1;     // their depths along the view direction (perspective-correct interpolation)
    };
    std::vector<SilhouetteEdge> edges;
    DiscreteDistribution by_length;
    float total_length = 0.f;
    bool image_space = false;
};

namespace {

using Silhouettes = PrimaryBoundary::Silhouettes;

bool parallel_projection(const Sensor& sensor) { return sensor.plugin == "orthographic"; }

// Position along the projected segment (fraction t of s0 → s1) to position along the 3D segment.
float perspective_correct(float t, float z0, float z1, bool parallel) {
    return parallel ? t : t * z0 / ((1.f - t) * z1 + t * z0);
}

// Liang–Barsky: the parameter range [t0, t1] of a → b inside the box [lo, hi]²; false if empty.
bool clip_to_box(const Vec2f& a, const Vec2f& b, const Vec2f& lo, const Vec2f& hi, float& t0, float& t1) {
    t0 = 0.f;
    t1 = 1.f;
    const float d[2] = {b.x - a.x, b.y - a.y}, p[2] = {a.x, a.y}, l[2] = {lo.x, lo.y}, h[2] = {hi.x, hi.y};
    for (int k = 0; k < 2; ++k) {
        if (d[k] == 0.f) {
            if (p[k] < l[k] || p[k] > h[k]) return false;
            continue;
        }
        float ta = (l[k] - p[k]) / d[k], tb = (h[k] - p[k]) / d[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 < t1;
}

// Whether the shape's appearance varies with uv (a texture that is not constant), so that a uv seam is a
// discontinuity.
class TextureFinder final : public ParamVisitor {
public:
    void put(const std::string&, float*, int, int*, bool) override {}
    void put_object(const std::string&, Object* object) override {
        if (!object || found) return;
        if (const auto* texture = dynamic_cast<const Texture*>(object); texture && !texture->is_constant()) found = true;
        object->traverse(*this);
    }
    bool found = false;
};

// Whether the shading jumps across an edge between two faces: face normals, or vertex normals (or, on a
// textured shape, uvs) that differ between the faces' copies of the edge's vertices (a hard edge or a seam).
bool shading_jumps(const Shape& shape, const Edge& e, bool textured) {
    const TriangleMesh& m = shape.mesh;
    if (shape.face_normals || m.normals.empty()) return true;
    const uint32_t* f1 = &m.indices[3 * size_t(e.f1)];
    for (const uint32_t v : {e.v0, e.v1}) {
        // f1's copy of v: the vertex at the same position (positions were merged to find the edge).
        for (int k = 0; k < 3; ++k) {
            const uint32_t w = f1[k];
            if (w == v || !(m.positions[w] == m.positions[v])) continue;
            if (squared_norm(m.normals[w] - m.normals[v]) > 1e-8f) return true;
            if (textured && !m.uvs.empty() && !(m.uvs[w] == m.uvs[v])) return true;
        }
    }
    return false;
}

std::unique_ptr<const Silhouettes> find_silhouettes(const Scene& scene, const SceneEdges& edges, const Parameters& params,
                                                    bool image_space) {
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    const bool parallel = parallel_projection(sensor);
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    const Vec3f forward = normalize(sensor.to_world.apply_vector(Vec3f(0.f, 0.f, 1.f)));
    const float r = film.rfilter->radius();
    const Vec2f lo(-r, -r), hi(film.width + r, film.height + r);
    const float near = std::max(sensor.near_clip, 1e-4f);
    auto result = std::make_unique<Silhouettes>();
    Silhouettes& out = *result;
    out.image_space = image_space;
    std::vector<float> lengths;
    const Shape* textured_shape = nullptr; // the shape `textured` was last found for (edges come shape by shape)
    bool textured = false;
    for (const SceneEdges::SceneEdge& se : edges.edges) {
        // In image space an edge of a shape that does not move is a discontinuity that does not move.
        if (image_space && params.motions(se.shape).empty() && se.shape->vertex_param_index < 0) continue;
        const TriangleMesh& m = se.shape->mesh;
        const Edge& e = se.edge;
        const bool silhouette = parallel ? is_silhouette_parallel(m, e, forward) : is_silhouette(m, e, eye);
        bool crease = false;
        if (!silhouette) {
            if (!image_space) continue;
            if (se.shape != textured_shape) {
                TextureFinder finder;
                const_cast<Shape*>(se.shape)->traverse(finder);
                textured_shape = se.shape;
                textured = finder.found;
            }
            if (!shading_jumps(*se.shape, e, textured)) continue;
            // On a solid, creases between faces turned away from the camera are hidden by the solid itself.
            const Vec3f to_eye = parallel ? forward * -1.f : eye - m.positions[e.v0];
            if (se.closed && !(dot(face_normal(m, e.f0), to_eye) > 0.f)) continue;
            crease = true;
        }
        const Vec3f p0 = m.positions[e.v0], p1 = m.positions[e.v1];
        // The part in front of the near plane, then the part over the film.
        const float za = dot(p0 - eye, forward), zb = dot(p1 - eye, forward);
        float tau0 = 0.f, tau1 = 1.f;
        if (za < near && zb < near) continue;
        if (za < near) tau0 = (near - za) / (zb - za);
        if (zb < near) tau1 = (near - za) / (zb - za);
        const Vec3f a = p0 + (p1 - p0) * tau0, b = p0 + (p1 - p0) * tau1;
        Vec2f sa, sb;
        float j;
        if (!sensor.film_position(a, forward, sa, j) || !sensor.film_position(b, forward, sb, j)) continue;
        const float z_a = dot(a - eye, forward), z_b = dot(b - eye, forward);
        float t0, t1;
        if (!clip_to_box(sa, sb, lo, hi, t0, t1)) continue;
        const float u0 = perspective_correct(t0, z_a, z_b, parallel), u1 = perspective_correct(t1, z_a, z_b, parallel);
        Silhouettes::SilhouetteEdge kept{se.shape, e, crease, tau0 + (tau1 - tau0) * u0, tau0 + (tau1 - tau0) * u1,
                                         sa + (sb - sa) * t0, sa + (sb - sa) * t1, z_a + (z_b - z_a) * u0,
                                         z_a + (z_b - z_a) * u1};
        const float length = std::sqrt(sqr(kept.s1.x - kept.s0.x) + sqr(kept.s1.y - kept.s0.y));
        if (!(length > 0.f) || !std::isfinite(length)) continue;
        out.edges.push_back(kept);
        lengths.push_back(length);
        out.total_length += length;
    }
    if (!lengths.empty()) out.by_length = DiscreteDistribution(lengths);
    return result;
}

// What a probe ray next to the edge sees: the edge's own surface (near), something beyond the edge or nothing
// (far), or something in front of it (the edge is hidden there).
enum class Side { Near, Far, Front };

Side classify(const SurfaceInteraction3f& hit, const Shape& shape, float edge_distance) {
    if (!hit.is_valid()) return Side::Far;
    // A grazing surface next to a silhouette is seen a little in front of the edge (for a smooth solid of
    // radius R, by ~√(2Rδ) at a distance δ from the silhouette): a 2% band counts as the edge's own surface.
    if (hit.shape == &shape && std::abs(hit.t - edge_distance) < 0.02f * edge_distance) return Side::Near;
    if (hit.t > edge_distance * (1.f + 1e-4f)) return Side::Far;
    return Side::Front;
}

// One boundary sample: a point s on an edge's image, the radiance on either side, and the normal velocity of the
// discontinuity as a tape expression (its value is ~0, its derivative the velocity).
//   image-space first vertex: (L_a − L_b) ((s_edge(θ) − s) · n), n pointing from side a to side b (for a
//     silhouette a is the occluder; for a crease either face);
//   material form: −L_bg ((s_edge(θ) − s_bg(θ)) · n) for silhouettes, the occluder's own side being the
//     interior term's (its material domain is not cut).
BoundarySample sample_boundary(const Scene& scene, const Silhouettes& sil, const MaterialForm& form,
                               const BoundarySampleIndex& index, Sampler& sampler, const PathSettings& settings,
                               RayCounter& rays) {
    BoundarySample out;
    const Sensor& sensor = *scene.sensor;
    float u = index.stratified(sampler);
    const Silhouettes::SilhouetteEdge& se = sil.edges[sil.by_length.sample(u)];
    const float t = u;
    const Vec2f s = se.s0 + (se.s1 - se.s0) * t;
    // The 3D edge point projecting to s (perspective-correct along the edge; affine for a parallel projection).
    const float tau = se.tau0 + (se.tau1 - se.tau0) * perspective_correct(t, se.z0, se.z1, parallel_projection(sensor));
    const Vec2f dir = se.s1 - se.s0;
    const Vec2f n2 = Vec2f(-dir.y, dir.x) / std::sqrt(dir.x * dir.x + dir.y * dir.y);

    const Vec3f p0 = se.shape->mesh.positions[se.edge.v0], p1 = se.shape->mesh.positions[se.edge.v1];
    const Vec3f x_edge = p0 + (p1 - p0) * tau;

    // The two sides, probed at s ± eps n2. The radiances are the limits at the edge, but rays leaving a probed
    // point start RayEpsilon-scaled offsets off its surface: a shadow ray toward a light at (or near) the camera
    // runs back along the probe and, closer to the edge than those offsets, clips the occluder and reports a
    // false shadow. The probe therefore clears the edge by twice the offset scale of the segment camera–edge
    // (which bounds the offset of any point behind the edge as seen at the edge's depth), clamped to
    // [1e-3, 0.05] pixels so that the radiances and velocities stay the limits at the edge up to a small
    // fraction of a pixel.
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    const float clearance = 2.f * RayEpsilon * (1.f + max_component(abs(eye)) + norm(x_edge - eye));
    const Ray center = sensor.sample_ray(s, Vec2f(0.5f)).first, side = sensor.sample_ray(s + n2, Vec2f(0.5f)).first;
    const float depth = norm(x_edge - center.o);
    const float world_per_pixel = norm(side.o + side.d * depth - (center.o + center.d * depth));
    const float eps = std::clamp(clearance / world_per_pixel, 1e-3f, 0.25f); // pixels
    const auto [ray_a, wa] = sensor.sample_ray(s + n2 * eps, sampler.next_2d());
    const auto [ray_b, wb] = sensor.sample_ray(s - n2 * eps, sampler.next_2d());
    rays.rays += 2;
    const SurfaceInteraction3f hit_a = scene.intersect(ray_a), hit_b = scene.intersect(ray_b);
    const Side side_a = classify(hit_a, *se.shape, norm(x_edge - ray_a.o)), side_b = classify(hit_b, *se.shape, norm(x_edge - ray_b.o));
    // Order the sides so that the first is the edge's own (near) one; n points from it to the other.
    const bool a_first = side_a == Side::Near;
    const Side first = a_first ? side_a : side_b, second = a_first ? side_b : side_a;
    const Vec2f n = a_first ? n2 * -1.f : n2;
    const Ray &ray_1 = a_first ? ray_a : ray_b, &ray_2 = a_first ? ray_b : ray_a;
    const SurfaceInteraction3f &hit_1 = a_first ? hit_a : hit_b, &hit_2 = a_first ? hit_b : hit_a;
    const Color3f w_1 = a_first ? wa : wb, w_2 = a_first ? wb : wa;
    if (first != Side::Near) return out;
    if (se.crease ? !(second == Side::Near && hit_1.prim_index != hit_2.prim_index) : second != Side::Far) return out;

    // Velocity of the edge point (a fixed point on the moving edge, Eq. 47 of paper 001) in image space.
    const Vec3<Var> x_e = form.position(*se.shape, se.edge.v0) +
                          (form.position(*se.shape, se.edge.v1) - form.position(*se.shape, se.edge.v0)) * Var(tau);
    const Vec3<Var> view(Vec3f(0.f, 0.f, 1.f));
    Vec2<Var> s_e;
    Var j;
    if (!sensor.film_position(form.to_reference_camera(x_e, eye), view, s_e, j)) return out;
    const float inv_pdf = sil.total_length;

    // Radiance on the second side, a path-traced estimate (the background of a silhouette).
    const Color3f L_2 = trace_path<float>(scene, sampler, ray_2, hit_2, hit_2, ReferenceGeometry{}, settings, rays) * w_2;
    if (sil.image_space) {
        const Color3f L_1 = trace_path<float>(scene, sampler, ray_1, hit_1, hit_1, ReferenceGeometry{}, settings, rays) * w_1;
        out.add_splat(s, (L_1 - L_2) * inv_pdf, (s_e.x - Var(s.x)) * Var(n.x) + (s_e.y - Var(s.y)) * Var(n.y));
        return out;
    }
    // Material form: the background's material point moves too (Eq. 50).
    Vec2<Var> s_b(Var(s.x), Var(s.y));
    if (hit_2.is_valid() && !sensor.film_position(form.to_reference_camera(form.vertex(hit_2).p, eye), view, s_b, j)) return out;
    out.add_splat(s, L_2 * -inv_pdf, (s_e.x - s_b.x) * Var(n.x) + (s_e.y - s_b.y) * Var(n.y));
    return out;
}

constexpr uint64_t Salt = 0xB5AD4ECEDA1CE2A9ULL;

} // namespace

PrimaryBoundary::PrimaryBoundary(const Scene& scene, const SceneEdges& edges) : scene_(scene), edges_(edges) {}
PrimaryBoundary::~PrimaryBoundary() = default;

Image PrimaryBoundary::derivative(const Parameters& params, const BoundaryOptions& options) const {
    const MaterialForm form(scene_, params, options.first_vertex);
    const auto silhouettes = find_silhouettes(scene_, edges_, params, form.image_space_first_vertex());
    if (silhouettes->edges.empty()) return Image(scene_.sensor->film->width, scene_.sensor->film->height);
    return boundary_derivative(scene_, params, options, Salt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_boundary(scene_, *silhouettes, form, index, sampler, options.path, rays);
    });
}

void PrimaryBoundary::gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                               std::vector<double>& gradient) const {
    const MaterialForm form(scene_, params, options.first_vertex);
    const auto silhouettes = find_silhouettes(scene_, edges_, params, form.image_space_first_vertex());
    if (silhouettes->edges.empty()) return;
    boundary_gradient(scene_, adjoint, options, Salt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_boundary(scene_, *silhouettes, form, index, sampler, options.path, rays);
    }, gradient);
}

} // namespace penumbra
