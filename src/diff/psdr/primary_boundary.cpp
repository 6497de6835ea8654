#include "diff/psdr/primary_boundary.h"

#include "core/distribution.h"
#include "core/interrupt.h"
#include "diff/material_form.h"
#include "diff/media_radiance.h"
#include "diff/media_walk.h"
#include "diff/psdr/boundary_segment.h"
#include "diff/psdr/shading_terminator.h"
#include "render/light_medium.h"
#include "render/volume_visibility.h"
#include "scene/texture.h"

#include <algorithm>
#include <tuple>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace penumbra {

// The edges whose image the primary term samples: silhouettes seen from the reference camera and, with the
// image-space first vertex, creases where the shading jumps (face normals, hard edges, uv seams of textured
// shapes) or where the solid hides a different half-space on either side (the horizon creases of smooth
// shading: lune_may_be_lit). Each keeps
// the part of the edge that lies in front of the camera and projects within the film (plus the filter's
// reach), with its projection. With the image-space first vertex and a perspective camera, also the triangles
// of moving smooth-normal shapes that the shading terminator crosses (diff/psdr/shading_terminator.h).
struct PrimaryBoundary::Silhouettes {
    struct SilhouetteEdge {
        const Shape* shape;
        Edge edge;
        bool crease;      // a shading discontinuity between two visible faces (not a silhouette)
        bool horizon;     // a crease of smooth shading (lune_may_be_lit), not of the shading itself
        float prior;      // sampling weight per unit length before guiding (1; a horizon crease: wedge²)
        float tau0, tau1; // the part kept: edge parameters (v0 → v1) of its ends
        Vec2f s0, s1;     // their film positions (pixels)
        float z0, z1;     // their depths along the view direction (perspective-correct interpolation)
    };
    std::vector<SilhouetteEdge> edges;
    struct TerminatorTriangle {
        const Shape* shape;
        uint32_t prim;
    };
    std::vector<float> lengths; // of the edges' images
    std::vector<TerminatorTriangle> terminators;
    std::vector<float> terminator_weights; // the triangles' image sizes (pixels)
    // Over the edges, then the terminator triangles; points are uniform along an edge's image, and b1 is
    // uniform in a triangle.
    DiscreteDistribution distribution;
    bool image_space = false;
    bool media = false; // the scene has participating media: the sides' radiances are volumetric
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

// What can shine between the planes of two faces that meet at an edge of a smooth-shaded solid. Each face
// takes light from below its own plane (its BSDF sees the interpolated normal) and the solid hides it there
// (diff/psdr/shading_horizon.h), so light arriving between the two planes reaches one side of the edge and
// not the other: the radiance jumps across the edge although the shading normals are continuous. Light that
// other surfaces reflect (paths of three or more segments), an environment and a medium's in-scattering can
// come from any direction; otherwise an emitter must reach into the wedge between the planes.
struct LuneLights {
    bool everywhere = false;
    std::vector<std::pair<const Shape*, EmitterReach>> emitters; // with their shapes (mesh lights)
};

LuneLights lune_lights(const Scene& scene, const PathSettings& path) {
    LuneLights out;
    out.everywhere = path.max_depth < 0 || path.max_depth > 2 || scene_has_media(scene);
    for (const auto& e : scene.emitters) {
        out.emitters.push_back({e->shape(), emitter_reach(*e, scene.bounding_sphere())});
        out.everywhere |= out.emitters.back().second.environment;
    }
    return out;
}

// Horizon creases flatter than this are left out: their jump is of the order of the wedge's angle squared
// (below 0.8% of the light arriving along the planes), less than the sides' own offsets resolve (each side is
// probed a few ray offsets from the edge, and a smooth gradient across that gap reads as a jump which the
// faint edge's low sampling density multiplies: a 64 x 128 sphere's 2.8° edges and its quads' near-flat
// diagonals turned a sliding ball's derivative to noise).
constexpr float MinHorizonWedge = 5.f * Pi / 180.f;

// Whether light may arrive between the planes of edge e's faces (above one, below the other), and the
// wedge's angle between them in `wedge` (radians). A mesh light does not shine on its own edges (a convex
// emitter cannot, and a concave one's light across its own creases is left out).
bool lune_may_be_lit(const LuneLights& lights, const Shape& shape, const Edge& e, float& wedge) {
    const TriangleMesh& m = shape.mesh;
    if (e.f1 < 0) return false;
    const Vec3f a = m.positions[e.v0];
    const Vec3f n0 = normalize(face_normal(m, e.f0)), n1 = normalize(face_normal(m, e.f1));
    wedge = std::acos(std::clamp(dot(n0, n1), -1.f, 1.f));
    if (!(wedge > MinHorizonWedge)) return false;
    if (lights.everywhere) return true;
    for (const auto& [emitter_shape, reach] : lights.emitters) {
        if (emitter_shape == &shape) continue;
        if (reach.directional) {
            // The light (against its rays) above one plane and below the other.
            if ((dot(n0, reach.travel) > 0.f) != (dot(n1, reach.travel) > 0.f)) return true;
            continue;
        }
        const BoundingSphere& b = reach.bounds;
        const float d0 = dot(n0, b.center - a), d1 = dot(n1, b.center - a);
        if ((d0 > -b.radius && d1 < b.radius) || (d1 > -b.radius && d0 < b.radius)) return true;
    }
    return false;
}

// The edges' sampling weights before guiding: their images' lengths times their priors.
std::vector<float> prior_weights(const Silhouettes& sil) {
    std::vector<float> w(sil.edges.size());
    for (size_t e = 0; e < w.size(); ++e)
        w[e] = sil.lengths[e] * sil.edges[e].prior;
    return w;
}

// The sampling weights: the edges' (`edge_weights`), then the terminator triangles'.
std::vector<float> all_weights(const Silhouettes& sil, std::vector<float> edge_weights) {
    edge_weights.insert(edge_weights.end(), sil.terminator_weights.begin(), sil.terminator_weights.end());
    return edge_weights;
}

// The triangles of moving shapes shaded with vertex normals whose shading terminator may be seen, weighted by
// their image size (the largest distance between their vertices' images; the film's diagonal for a triangle
// that crosses the camera plane). A triangle whose image lies beyond one side of the film box is left out.
void find_terminators(const Scene& scene, const Parameters& params, const Vec2f& lo, const Vec2f& hi,
                      Silhouettes& out) {
    const Sensor& sensor = *scene.sensor;
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    const Vec3f forward = normalize(sensor.to_world.apply_vector(Vec3f(0.f, 0.f, 1.f)));
    const float diagonal = std::hypot(hi.x - lo.x, hi.y - lo.y);
    for (const auto& shape : scene.shapes) {
        const TriangleMesh& m = shape->mesh;
        if (!params.moves(*shape) || shape->face_normals || m.normals.empty()) continue;
        for (uint32_t f = 0; f < m.face_count(); ++f) {
            if (!crosses_shading_terminator(m, f, eye)) continue;
            Vec2f s[3];
            bool projected = true;
            for (int k = 0; k < 3; ++k) {
                float j;
                const Vec3f p = m.positions[m.indices[3 * size_t(f) + k]];
                projected &= dot(p - eye, forward) > 0.f && sensor.film_position(p, forward, s[k], j);
            }
            float weight = diagonal;
            if (projected) {
                const float x0 = std::min({s[0].x, s[1].x, s[2].x}), x1 = std::max({s[0].x, s[1].x, s[2].x});
                const float y0 = std::min({s[0].y, s[1].y, s[2].y}), y1 = std::max({s[0].y, s[1].y, s[2].y});
                if (x1 < lo.x || x0 > hi.x || y1 < lo.y || y0 > hi.y) continue;
                const auto length = [&](int a, int b) { return std::hypot(s[a].x - s[b].x, s[a].y - s[b].y); };
                weight = std::max({length(1, 0), length(2, 1), length(0, 2)});
            }
            if (!(weight > 0.f) || !std::isfinite(weight)) continue;
            out.terminators.push_back({shape.get(), f});
            out.terminator_weights.push_back(weight);
        }
    }
}

std::unique_ptr<Silhouettes> find_silhouettes(const Scene& scene, const SceneEdges& edges,
                                              const Parameters& params, bool image_space,
                                              const PathSettings& path) {
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
    out.media = edges.media;
    const LuneLights lights = image_space ? lune_lights(scene, path) : LuneLights{};
    const Shape* textured_shape = nullptr; // the shape `textured` was last found for (edges come shape by shape)
    bool textured = false;
    for (const SceneEdges::SceneEdge& se : edges.edges) {
        // In image space an edge of a shape that does not move is a discontinuity that does not move.
        if (image_space && !params.moves(*se.shape)) continue;
        const TriangleMesh& m = se.shape->mesh;
        const Edge& e = se.edge;
        const bool silhouette = parallel ? is_silhouette_parallel(m, e, forward) : is_silhouette(m, e, eye);
        bool crease = false, horizon = false;
        float prior = 1.f;
        if (!silhouette) {
            if (!image_space) continue;
            if (se.shape != textured_shape) { // a uv seam is a discontinuity where a texture varies
                textured_shape = se.shape;
                textured = has_texture(*const_cast<Shape*>(se.shape), [](const Texture& t) { return !t.is_constant(); });
            }
            // A horizon crease's jump is the light in the wedge between the planes, at grazing incidence: of
            // the order of the wedge's angle squared against a silhouette's (its prior before guiding).
            float wedge = 0.f;
            if (!shading_jumps(*se.shape, e, textured)) {
                if (!lune_may_be_lit(lights, *se.shape, e, wedge)) continue;
                horizon = true;
                prior = std::min(wedge * wedge, 1.f);
            }
            // On a solid, creases between faces turned away from the camera are hidden by the solid itself.
            const Vec3f to_eye = parallel ? forward * -1.f : eye - m.positions[e.v0];
            if (se.closed && !(dot(face_normal(m, e.f0), to_eye) * (se.inside_out ? -1.f : 1.f) > 0.f))
                continue;
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
        Silhouettes::SilhouetteEdge kept;
        kept.shape = se.shape, kept.edge = e, kept.crease = crease, kept.horizon = horizon,
        kept.prior = prior;
        kept.tau0 = tau0 + (tau1 - tau0) * u0, kept.tau1 = tau0 + (tau1 - tau0) * u1;
        kept.s0 = sa + (sb - sa) * t0, kept.s1 = sa + (sb - sa) * t1;
        kept.z0 = z_a + (z_b - z_a) * u0, kept.z1 = z_a + (z_b - z_a) * u1;
        const float length = std::sqrt(sqr(kept.s1.x - kept.s0.x) + sqr(kept.s1.y - kept.s0.y));
        if (!(length > 0.f) || !std::isfinite(length)) continue;
        out.edges.push_back(kept);
        out.lengths.push_back(length);
    }
    if (image_space && sensor.projects_points() && !parallel) find_terminators(scene, params, lo, hi, out);
    if (!out.lengths.empty() || !out.terminators.empty())
        out.distribution = DiscreteDistribution(all_weights(out, prior_weights(out)));
    return result;
}

// What a probe ray next to the edge sees: the edge's own shape (near): in front of the edge, however far (next to
// a silhouette of a finely tessellated solid the adjacent face is almost parallel to the ray and is hit well in
// front of the edge), or a little behind it (a surface receding from its edge, within 2% of the edge's depth);
// something beyond the edge or nothing (far); or another shape in front of the edge (the edge is hidden there).
enum class Side { Near, Far, Front };

Side classify(const SurfaceInteraction3f& hit, const Shape& shape, float edge_distance) {
    if (!hit.is_valid()) return Side::Far;
    const bool beyond = hit.t > edge_distance * (1.f + 1e-4f);
    if (hit.shape == &shape && (!beyond || hit.t < edge_distance * 1.02f)) return Side::Near;
    return beyond ? Side::Far : Side::Front;
}

// What a camera ray sees: its first surface, crossing index-matched (null) boundaries in scenes with media.
SurfaceInteraction3f seen_surface(const Scene& scene, const Ray& ray, bool media, RayCounter& rays) {
    if (media) return first_opaque_hit(scene, ray, rays);
    ++rays.rays;
    return scene.intersect(ray);
}

// Where an edge's image crosses the film at fraction t: the film point s, the image-space normal n from side
// 1 (the edge's own surface) to side 2 (the background of a silhouette, the other face of a crease), and the
// two sides' primary rays and hits (the edge's own side: its face at the edge point, own_face()).
struct EdgeCrossing {
    bool valid = false;
    Vec2f s, n;
    bool crease = false;
    float tau = 0.f; // the edge parameter (v0 → v1) of the 3D point seen at s
    Vec3f x_edge;    // that point
    Ray ray[2];
    SurfaceInteraction3f hit[2];
    Color3f weight[2];
    // A silhouette lying on another surface (an object resting on it): side 2 is that surface next to the
    // contact curve (diff/material_form.h, contact_point). Both sides are taken at the distance δ from the
    // curve (hit[0] on the edge's face, hit[1] on the surface) and at 2δ (twice_hit, the far one seen along
    // twice_ray), for their limits at the curve (probe_contact).
    bool contact = false;
    // A horizon crease (SilhouetteEdge::horizon): both sides on their faces at δ and 2δ from the edge as
    // well (twice_hit, seen along the same probes), for the limits at the edge.
    bool extrapolate = false;
    Ray twice_ray;
    SurfaceInteraction3f twice_hit[2];
    Color3f twice_weight;
};

// Whether the probe's hit lies on a surface through the edge point x (the edge rests on it): the probe
// passing the edge meets that surface just in front of the edge.
bool rests_on(const SurfaceInteraction3f& hit, const Shape& edge_shape, const Vec3f& x) {
    return hit.is_valid() && hit.shape != &edge_shape &&
           std::abs(dot(x - hit.p, normalize(hit.n))) <= contact_probe(x);
}

// The probes' distance (pixels) from a discontinuity's image at s, seen at world point x, in image direction n
// (see cross_edge).
float probe_offset(const Sensor& sensor, const Vec3f& x, const Vec2f& s, const Vec2f& n) {
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    const float clearance = 2.f * RayEpsilon * (1.f + max_component(abs(eye)) + norm(x - eye));
    const Ray center = sensor.sample_ray(s, Vec2f(0.5f)).first, side = sensor.sample_ray(s + n, Vec2f(0.5f)).first;
    const float depth = norm(x - center.o);
    const float world_per_pixel = norm(side.o + side.d * depth - (center.o + center.d * depth));
    return std::clamp(clearance / world_per_pixel, 1e-3f, 0.05f);
}

// The radiance's limit at the edge on the side of a probe ray: the edge's own face that the ray sees next to
// the edge, at the edge point (parameter tau) moved into the face by `clearance` (at a crease: a concave
// crease's other face would otherwise lie within the offsets of the rays leaving it, at a right angle exactly
// in the offset plane; a silhouette's near side is the limit at the edge itself, where the shading terminator
// term ends its curves). The face is the one whose plane the ray meets on the face's side of the edge (its
// apex's barycentric coordinate positive) and, of two such faces (both lie on the near side of a silhouette),
// the nearer. The probe's own hit may be another face: where a mesh is seen at a grazing angle, the images of
// several edges fall within the probe offset (the ring edges of a tube seen along its length), and the probe
// sees a face one or more edges away, whose shading and lighting are not those of the edge's side.
SurfaceInteraction3f own_face(const Shape& shape, const Edge& e, float tau, const Ray& ray, float clearance) {
    const TriangleMesh& m = shape.mesh;
    const Vec3f a = m.positions[e.v0], b = m.positions[e.v1];
    int32_t seen = -1;
    float seen_t = Infinity, seen_bary[3] = {0.f, 0.f, 0.f};
    for (const int32_t f : {e.f0, e.f1}) {
        if (f < 0) continue;
        const uint32_t* i = &m.indices[3 * size_t(f)];
        const Vec3f p0 = m.positions[i[0]], e1 = m.positions[i[1]] - p0, e2 = m.positions[i[2]] - p0;
        // Möller–Trumbore without the inside test.
        const Vec3f q = cross(ray.d, e2), o = ray.o - p0, r = cross(o, e1);
        const float det = dot(e1, q);
        if (!(std::abs(det) > 0.f)) continue;
        const float t = dot(e2, r) / det, b1 = dot(o, q) / det, b2 = dot(ray.d, r) / det;
        const float bary[3] = {1.f - b1 - b2, b1, b2};
        int apex = 0;
        for (int k = 0; k < 3; ++k)
            if (!(m.positions[i[k]] == a) && !(m.positions[i[k]] == b)) apex = k;
        if (!(t > 0.f) || !(bary[apex] > 0.f) || !(t < seen_t)) continue;
        // The point's barycentrics in f: w toward the apex (its distance from the edge over the apex's, at
        // most 1/2), and (1 − w)(1 − tau), (1 − w) tau at (f's copies of) v0 and v1.
        const float height = norm(cross(m.positions[i[apex]] - a, b - a)) / norm(b - a);
        const float w = std::min(clearance / height, 0.5f);
        float at_edge[3];
        for (int k = 0; k < 3; ++k) {
            const Vec3f p = m.positions[i[k]];
            at_edge[k] = k == apex ? w : (1.f - w) * (p == a ? 1.f - tau : tau);
        }
        seen = f, seen_t = t;
        std::copy(at_edge, at_edge + 3, seen_bary);
    }
    if (seen < 0) return {};
    return shape.compute_surface_interaction(ray, seen_t, uint32_t(seen), seen_bary[1], seen_bary[2]);
}

// A silhouette resting on a surface: both sides' radiances vary steeply next to the contact curve (the
// surface sees the rising face over up to half of its directions and the face sees the surface, and a light
// near the face's plane is cut by the object's far edges), and at the curve itself rays leaving the face
// start on the surface. Each side is taken at the distances δ = contact_probe(x) (a few ray offsets, as the
// contact segments' receiver) and 2δ from the curve, and jump() extrapolates its limit at the curve
// (Richardson: 2 L(δ) − L(2δ)). With the far side at the probe offset's distance instead (up to 0.05 px,
// ~0.002 over the floor of box_on_floor.xml at 128²) the contact line's derivative read 4-6% high; with the
// near side at the curve, the edge of a box resting on another box (scenes/contact/stack.xml) saw its face
// shadowed by the surface under it, 2× the jump.
bool probe_contact(const Scene& scene, const Silhouettes::SilhouetteEdge& se, bool media, float eps,
                   EdgeCrossing& out, Sampler& sampler, RayCounter& rays) {
    const float delta = contact_probe(out.x_edge), distance = norm(out.hit[1].p - out.x_edge);
    const float offset = distance > 0.f ? eps * std::min(1.f, delta / distance) : eps;
    const Vec2f u = sampler.next_2d();
    std::tie(out.ray[1], out.weight[1]) = scene.sensor->sample_ray(out.s + out.n * offset, u);
    std::tie(out.twice_ray, out.twice_weight) = scene.sensor->sample_ray(out.s + out.n * (2.f * offset), u);
    out.hit[1] = seen_surface(scene, out.ray[1], media, rays);
    out.twice_hit[1] = seen_surface(scene, out.twice_ray, media, rays);
    out.hit[0] = own_face(*se.shape, se.edge, out.tau, out.ray[0], delta);
    out.twice_hit[0] = own_face(*se.shape, se.edge, out.tau, out.ray[0], 2.f * delta);
    return rests_on(out.hit[1], *se.shape, out.x_edge) && rests_on(out.twice_hit[1], *se.shape, out.x_edge) &&
           out.hit[0].is_valid() && out.twice_hit[0].is_valid();
}

EdgeCrossing cross_edge(const Scene& scene, const Silhouettes::SilhouetteEdge& se, bool media, float t,
                        Sampler& sampler, RayCounter& rays) {
    EdgeCrossing out;
    const Sensor& sensor = *scene.sensor;
    out.s = se.s0 + (se.s1 - se.s0) * t;
    // The 3D edge point projecting to s (perspective-correct along the edge; affine for a parallel projection).
    out.tau = se.tau0 + (se.tau1 - se.tau0) * perspective_correct(t, se.z0, se.z1, parallel_projection(sensor));
    const Vec2f dir = se.s1 - se.s0;
    const Vec2f n2 = Vec2f(-dir.y, dir.x) / std::sqrt(dir.x * dir.x + dir.y * dir.y);
    const Vec3f p0 = se.shape->mesh.positions[se.edge.v0], p1 = se.shape->mesh.positions[se.edge.v1];
    const Vec3f x_edge = p0 + (p1 - p0) * out.tau;
    out.x_edge = x_edge;

    // The two sides, probed at s ± eps n2. The radiances are the limits at the edge, but rays leaving a
    // probed point behind the edge start RayEpsilon-scaled offsets off its surface: a shadow ray toward a
    // light at (or near) the camera runs back along the probe and, closer to the edge than those offsets,
    // clips the occluder and reports a false shadow. The probe therefore clears the edge by twice the offset
    // scale of the segment camera–edge (which bounds the offset of any point behind the edge as seen at the
    // edge's depth), clamped to [1e-3, 0.05] pixels so that the radiances and velocities stay the limits at
    // the edge up to a small fraction of a pixel. The edge's own side is then evaluated on its face at the
    // edge point (own_face).
    const float eps = probe_offset(sensor, x_edge, out.s, n2);
    Side sides[2];
    for (int k = 0; k < 2; ++k) {
        std::tie(out.ray[k], out.weight[k]) = sensor.sample_ray(out.s + n2 * (k == 0 ? eps : -eps), sampler.next_2d());
        out.hit[k] = seen_surface(scene, out.ray[k], media, rays);
        sides[k] = classify(out.hit[k], *se.shape, norm(x_edge - out.ray[k].o));
    }
    out.n = n2 * -1.f; // from side 0 (probed at +eps) to side 1
    out.crease = se.crease;
    if (se.crease) {
        // A crease is seen where a side is the edge's own surface at the edge's depth (a convex ridge recedes
        // on both sides, a valley comes closer), not another part of the same shape hiding it. One side
        // suffices: next to a silhouette seen at a grazing angle the other probe may pass beyond it. Both
        // sides' radiances are the limits on the edge's two faces.
        const auto at_edge = [&](int k) {
            const float d = norm(x_edge - out.ray[k].o);
            return out.hit[k].is_valid() && out.hit[k].shape == se.shape && std::abs(out.hit[k].t - d) < 0.02f * d;
        };
        if (!at_edge(0) && !at_edge(1)) return out;
        // A horizon crease's jump is faint next to the radiance's gradient across the edge (the light it
        // takes arrives along the planes), and the sides' distance δ from the edge reads that gradient as a
        // jump of order δ: the limits at the edge are extrapolated from δ and 2δ (2 L(δ) − L(2δ)).
        const float delta = 2.f * ray_offset_scale(x_edge);
        out.extrapolate = se.horizon;
        for (int k = 0; k < 2; ++k) {
            out.hit[k] = own_face(*se.shape, se.edge, out.tau, out.ray[k], delta);
            if (out.extrapolate)
                out.twice_hit[k] = own_face(*se.shape, se.edge, out.tau, out.ray[k], 2.f * delta);
        }
        if (out.extrapolate) out.twice_ray = out.ray[1], out.twice_weight = out.weight[1];
        out.valid = out.hit[0].is_valid() && out.hit[1].is_valid() &&
                    out.hit[0].prim_index != out.hit[1].prim_index &&
                    (!out.extrapolate || (out.twice_hit[0].is_valid() && out.twice_hit[1].is_valid()));
        return out;
    }
    // A silhouette: order the sides so that the first is the edge's own (near) one, n pointing to the other.
    if (sides[0] != Side::Near) {
        std::swap(out.ray[0], out.ray[1]);
        std::swap(out.hit[0], out.hit[1]);
        std::swap(out.weight[0], out.weight[1]);
        std::swap(sides[0], sides[1]);
        out.n = n2;
    }
    if (sides[0] != Side::Near) return out;
    out.contact = sides[1] == Side::Front && rests_on(out.hit[1], *se.shape, x_edge);
    if (sides[1] != Side::Far && !out.contact) return out;
    if (out.contact) {
        out.valid = probe_contact(scene, se, media, eps, out, sampler, rays);
        return out;
    }
    out.hit[0] = own_face(*se.shape, se.edge, out.tau, out.ray[0], 0.f);
    out.valid = out.hit[0].is_valid();
    return out;
}

// The radiance seen along a camera ray up to its surface `hit`: path tracing in vacuum; in media the
// transmittance from the camera times the radiance leaving the surface (its emission unless hidden).
Color3f seen_radiance(const Scene& scene, const Ray& ray, const SurfaceInteraction3f& hit, bool media,
                      const PathSettings& settings, Sampler& sampler, RayCounter& rays) {
    if (!media) return trace_path<float>(scene, sampler, ray, hit, hit, ReferenceGeometry{}, settings, rays);
    if (!hit.is_valid()) return Color3f(0.f);
    const Medium* medium = sensor_medium(scene);
    Ray to_hit = ray;
    to_hit.tmax = hit.t * 0.999f;
    const Color3f tr = segment_transmittance(scene, to_hit, medium, sampler, rays, &medium);
    if (is_black(tr)) return tr;
    return tr * vertex_radiance(scene, {hit, ray.d * -1.f, medium}, settings.max_depth, !settings.hide_emitters,
                                settings, sampler, rays);
}

// The far side of a silhouette in media: what lies beyond the edge's depth along the far probe (Algorithm 1's
// sampleInteraction from the edge on: a medium vertex, the background surface, or the environment), times the
// transmittance from the camera to the edge.
ArrivingRadiance far_side(const Scene& scene, const EdgeCrossing& c, const Ray& ray,
                          const SurfaceInteraction3f& hit, const PathSettings& settings, Sampler& sampler,
                          RayCounter& rays) {
    const float depth = c.contact ? hit.t * (1.f - 1e-4f) : norm(c.x_edge - ray.o);
    const Medium* medium = sensor_medium(scene);
    const Color3f tr = segment_transmittance(scene, Ray(ray.o, ray.d, depth), medium, sampler, rays, &medium);
    if (is_black(tr)) return {};
    ArrivingRadiance out = arriving_radiance(scene, Ray(ray(depth), ray.d), medium, settings, sampler, rays);
    out.radiance *= tr;
    return out;
}

// The jump of the pixel integrand across the edge: L_1 − L_2 with the image-space first vertex; −L_2 in
// material form, where the edge's own side is the interior term's (its material domain is not cut).
// Path-traced estimates of the radiance seen on either side; in media the in-scattering in front of the edge,
// common to both sides, is left out (only the far side beyond the edge's depth, `far`, is estimated; in
// material form the medium's points in front of the edge are not cut either). A crease's two sides share
// their random numbers (light samples, BSDF samples), so that their difference is the jump rather than the
// noise of two estimates. At a contact, and at a horizon crease, each side is its limit at the edge (2 L(δ) −
// L(2δ)).
Color3f jump(const Scene& scene, const EdgeCrossing& c, bool image_space, bool media, const PathSettings& settings,
             Sampler& sampler, RayCounter& rays, ArrivingRadiance* far = nullptr) {
    Sampler shared = sampler;
    // A side's radiance from its probe k (0: at δ from the curve, 1: at 2δ); at a contact its limit at the
    // curve, 2 L(δ) − L(2δ), both probes with the same random numbers.
    const auto side = [&](Sampler& s, const auto& at) {
        if (!c.contact && !c.extrapolate) return at(0, s);
        Sampler twice = s;
        const Color3f once = at(0, s);
        return once * 2.f - at(1, twice);
    };
    const Color3f L_2 = side(sampler, [&](int k, Sampler& s) {
        const Ray& ray = k == 0 ? c.ray[1] : c.twice_ray;
        const SurfaceInteraction3f& hit = k == 0 ? c.hit[1] : c.twice_hit[1];
        const Color3f& weight = k == 0 ? c.weight[1] : c.twice_weight;
        if (!media)
            return trace_path<float>(scene, s, ray, hit, hit, ReferenceGeometry{}, settings, rays) * weight;
        const ArrivingRadiance a = far_side(scene, c, ray, hit, settings, s, rays);
        if (far && k == 0) *far = a;
        return a.radiance * weight;
    });
    if (!image_space) return L_2 * -1.f;
    const Color3f L_1 = side(c.crease ? shared : sampler, [&](int k, Sampler& s) {
        return seen_radiance(scene, c.ray[0], k == 0 ? c.hit[0] : c.twice_hit[0], media, settings, s, rays) *
               c.weight[0];
    });
    return L_1 - L_2;
}

// One sample of the shading terminator of a triangle (diff/psdr/shading_terminator.h; the image-space first
// vertex): the curve's points on a line b_k = u of a sweep k (diff/psdr/shading_terminator.h), and by the coarea
// formula
//   ∫_C ΔL v_n dl = ∫ du Σ_points ΔL ∂θG̃ |det ds/db| / |∂G̃/∂w|,   v_n = ∂θG̃ / |∇_s G̃|,
// with ΔL = L(G̃ > 0) − L(G̃ < 0) the limits on either side of the curve, |det ds/db| = |ds/dA| |e1 × e2|,
// and ∂θG̃ on the tape at the point where the fixed camera ray through s meets the moving triangle.
BoundarySample sample_terminator(const Scene& scene, const Silhouettes& sil, const MaterialForm& form, size_t e,
                                 float u, Sampler& sampler, const PathSettings& settings, RayCounter& rays) {
    BoundarySample out;
    const Sensor& sensor = *scene.sensor;
    const Silhouettes::TerminatorTriangle& tt = sil.terminators[e - sil.edges.size()];
    const float inv_pdf = 1.f / sil.distribution.pmf(e);
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    const TriangleMesh& m = tt.shape->mesh;
    const uint32_t* i = &m.indices[3 * size_t(tt.prim)];
    const Vec3f p0 = m.positions[i[0]], e1 = m.positions[i[1]] - p0, e2 = m.positions[i[2]] - p0;
    const Vec3f ng = cross(e1, e2);
    // One of the three sweeps at random (u's leading digit in base 3); with the balance heuristic over them, the
    // point's weight 1 / |∂G̃/∂w| becomes 3 / Σ_sweeps |∂G̃/∂w|, bounded where the curve runs along one sweep's
    // lines.
    const int sweep = std::min(int(u * 3.f), 2);
    TerminatorPoint points[2];
    const int n = shading_terminator_points(m, tt.prim, eye, sweep, u * 3.f - float(sweep), points);
    for (int k = 0; k < n; ++k) {
        const TerminatorPoint& q = points[k];
        const Vec3f x = p0 + e1 * q.bary.x + e2 * q.bary.y;
        Vec2f s;
        float j;
        const float sweeps = std::abs(q.dG_db1) + std::abs(q.dG_db2) + std::abs(q.dG_db1 - q.dG_db2);
        if (!sensor.film_position(x, normalize(ng), s, j) || !(sweeps > 0.f)) continue;
        const float ds_dA = j;
        // The curve point must be what the camera sees (a terminator on the far side of a solid lies within a few
        // percent of the near side's depth next to its silhouette): the ray through s meets this triangle first.
        const auto [ray, weight] = sensor.sample_ray(s, Vec2f(0.5f));
        const SurfaceInteraction3f center = seen_surface(scene, ray, sil.media, rays);
        if (!center.is_valid() || center.shape != tt.shape || center.prim_index != tt.prim) continue;
        // The radiance's limits on either side of the curve, on this triangle: at the curve point moved by
        // 1e-4 along ±∇G̃ in barycentric coordinates, seen from the camera. Probes through the film next to
        // the curve would see past the triangle where the dark side is a strip, narrower than their offset,
        // between the curve and a silhouette (whose near side is the limit at the edge, cross_edge).
        const float gradient = std::sqrt(sqr(q.dG_db1) + sqr(q.dG_db2));
        Color3f L[2];
        for (int side = 0; side < 2; ++side) {
            const float shift = (side == 0 ? 1e-4f : -1e-4f) / gradient;
            const float b1 = q.bary.x + q.dG_db1 * shift, b2 = q.bary.y + q.dG_db2 * shift;
            const Vec3f y = p0 + e1 * b1 + e2 * b2;
            const Ray probe(ray.o, normalize(y - ray.o));
            const SurfaceInteraction3f hit =
                tt.shape->compute_surface_interaction(probe, norm(y - ray.o), tt.prim, b1, b2);
            L[side] = seen_radiance(scene, probe, hit, sil.media, settings, sampler, rays) * weight;
        }
        // G̃ = n_s · (c − x) on the tape, at the fixed ray through s.
        const SurfaceInteraction3f hit =
            tt.shape->compute_surface_interaction(ray, norm(x - ray.o), tt.prim, q.bary.x, q.bary.y);
        const SurfaceInteraction<Var> v = form.ray_vertex(hit, ray);
        const Var G = dot(v.sh_frame.n, Vec3<Var>(eye) - v.p);
        out.add_splat(s, (L[0] - L[1]) * (ds_dA * norm(ng) * 3.f / sweeps * inv_pdf), G);
    }
    return out;
}

// One boundary sample: a point s on an edge's image, the jump there, and the normal velocity of the
// discontinuity as a tape expression (its value is ~0, its derivative the velocity):
//   image-space first vertex: (L_1 − L_2) ((s_edge(θ) − s) · n);
//   material form: −L_2 ((s_edge(θ) − s_bg(θ)) · n) for silhouettes, s_bg the background's material point.
BoundarySample sample_boundary(const Scene& scene, const Silhouettes& sil, const MaterialForm& form,
                               const BoundarySampleIndex& index, Sampler& sampler,
                               const PathSettings& settings, RayCounter& rays) {
    BoundarySample out;
    const Sensor& sensor = *scene.sensor;
    float t = index.stratified(sampler);
    const size_t e = sil.distribution.sample(t);
    if (e >= sil.edges.size()) return sample_terminator(scene, sil, form, e, t, sampler, settings, rays);
    const Silhouettes::SilhouetteEdge& se = sil.edges[e];
    const EdgeCrossing c = cross_edge(scene, se, sil.media, t, sampler, rays);
    if (!c.valid) return out;

    // Velocity of the edge point (a fixed point on the moving edge, Eq. 47 of paper 001; on a contact, its
    // motion over the surface it rests on) in image space.
    const Vec3f eye = sensor.to_world.apply_point(Vec3f(0.f));
    Vec3<Var> x_e =
        form.position(*se.shape, se.edge.v0) +
        (form.position(*se.shape, se.edge.v1) - form.position(*se.shape, se.edge.v0)) * Var(c.tau);
    if (c.contact) x_e = form.contact_point(*c.hit[1].shape, c.hit[1].prim_index, x_e);
    const Vec3<Var> view(Vec3f(0.f, 0.f, 1.f));
    Vec2<Var> s_e, s_b(Var(c.s.x), Var(c.s.y));
    Var j;
    if (!sensor.film_position(form.to_reference_camera(x_e, eye), view, s_e, j)) return out;
    ArrivingRadiance far;
    const Color3f value = jump(scene, c, sil.image_space, sil.media, settings, sampler, rays, &far);
    // Material form: the background's material point moves too (Eq. 50); in media, the far side's vertex (a
    // medium vertex by the volume motion; the environment does not move).
    if (!sil.image_space) {
        const bool surface = sil.media ? far.end.kind == FlightEnd::Kind::Surface : c.hit[1].is_valid();
        const bool medium = sil.media && far.end.kind == FlightEnd::Kind::Medium;
        if (surface || medium) {
            const Vec3<Var> x_b = medium ? form.volume_motion().position(far.end.p, far.end.medium, nullptr)
                                         : form.vertex(sil.media ? far.end.si : c.hit[1]).p;
            if (!sensor.film_position(form.to_reference_camera(x_b, eye), view, s_b, j)) return out;
        }
    }
    // Density per unit length of the film-space edge: the edge's probability over its projected length.
    const float inv_pdf = sil.lengths[e] / sil.distribution.pmf(e);
    out.add_splat(c.s, value * inv_pdf, (s_e.x - s_b.x) * Var(c.n.x) + (s_e.y - s_b.y) * Var(c.n.y));
    return out;
}

constexpr uint64_t Salt = 0xB5AD4ECEDA1CE2A9ULL, GuideSalt = 0x2127599BF4325C37ULL;

// Contrast guiding: edges are drawn with probability ∝ ½ w_e / Σw + ½ ℓ_e c_e / Σ ℓ c, a mixture of the
// prior weights w_e (the projected length ℓ_e, times a horizon crease's prior) and of ℓ_e c_e, where c_e is
// the RMS jump on the edge (the sum of the channels) measured by a pilot of a few stratified crossings per
// edge: an edge's share follows √E[jump²], the density that minimizes the variance of a sum of jumps, while
// the prior half keeps every edge's density bounded below where the pilot saw nothing. The pilot (1/16 of the
// term's samples, at most 8 crossings per edge; none when the edges it must pilot outnumber it) only shapes
// the density: its samples are not in the estimate.
void guide(const Scene& scene, Silhouettes& sil, const BoundaryOptions& options) {
    const Film& film = *scene.sensor->film;
    const uint64_t budget = uint64_t(film.width) * film.height * uint64_t(options.samples_per_pixel) / 16;
    const size_t n = sil.edges.size();
    // The edges piloted: all of them, or where they outnumber the pilot the silhouettes and shading creases
    // (the horizon creases, many and faint on a finely tessellated smooth mesh, keep their prior weights).
    std::vector<bool> piloted(n, true);
    if (budget < n)
        for (size_t e = 0; e < n; ++e)
            piloted[e] = !sil.edges[e].horizon;
    const size_t m = size_t(std::count(piloted.begin(), piloted.end(), true));
    if (!options.guiding || m < 2 || budget < m) return;
    const int per_edge = int(std::min<uint64_t>(8, budget / m));
    std::vector<float> rms(n, 0.f);
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(size_t(0), n, [&](size_t e) {
            if (!piloted[e]) return;
            check_interrupt();
            Sampler sampler;
            RayCounter rays;
            double sum2 = 0;
            for (int k = 0; k < per_edge; ++k) {
                sampler.start(options.seed ^ GuideSalt, e, uint64_t(k));
                const float t = (float(k) + sampler.next_1d()) / float(per_edge);
                const EdgeCrossing c = cross_edge(scene, sil.edges[e], sil.media, t, sampler, rays);
                if (!c.valid) continue;
                const Color3f j = jump(scene, c, sil.image_space, sil.media, options.path, sampler, rays);
                sum2 += sqr(double(j.x) + j.y + j.z);
            }
            rms[e] = float(std::sqrt(sum2 / per_edge));
        });
    });
    std::vector<float> weights = prior_weights(sil);
    double prior = 0, weighted = 0;
    for (size_t e = 0; e < n; ++e)
        if (piloted[e]) prior += weights[e], weighted += double(sil.lengths[e]) * rms[e];
    if (!(weighted > 0) || !std::isfinite(weighted)) return;
    for (size_t e = 0; e < n; ++e)
        if (piloted[e])
            weights[e] = float(0.5 * weights[e] + 0.5 * sil.lengths[e] * rms[e] * prior / weighted);
    sil.distribution = DiscreteDistribution(all_weights(sil, weights));
}

// The edges seen by the camera, with their sampling density.
std::unique_ptr<const Silhouettes> prepare(const Scene& scene, const SceneEdges& edges, const Parameters& params,
                                           const MaterialForm& form, const BoundaryOptions& options) {
    auto sil = find_silhouettes(scene, edges, params, form.image_space_first_vertex(), options.path);
    if (!sil->edges.empty()) guide(scene, *sil, options);
    return sil;
}

} // namespace

PrimaryBoundary::PrimaryBoundary(const Scene& scene, const SceneEdges& edges) : scene_(scene), edges_(edges) {}
PrimaryBoundary::~PrimaryBoundary() = default;

Image PrimaryBoundary::derivative(const Parameters& params, const BoundaryOptions& options) const {
    const MaterialForm form(scene_, params, options.first_vertex);
    const auto silhouettes = prepare(scene_, edges_, params, form, options);
    if (silhouettes->edges.empty() && silhouettes->terminators.empty())
        return Image(scene_.sensor->film->width, scene_.sensor->film->height);
    return boundary_derivative(scene_, params, options, Salt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_boundary(scene_, *silhouettes, form, index, sampler, options.path, rays);
    });
}

void PrimaryBoundary::gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                               std::vector<double>& gradient) const {
    const MaterialForm form(scene_, params, options.first_vertex);
    const auto silhouettes = prepare(scene_, edges_, params, form, options);
    if (silhouettes->edges.empty() && silhouettes->terminators.empty()) return;
    boundary_gradient(scene_, params, adjoint, options, Salt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_boundary(scene_, *silhouettes, form, index, sampler, options.path, rays);
    }, gradient);
}

} // namespace penumbra
