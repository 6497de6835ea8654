#include "diff/psdr/boundary_segment.h"

#include "core/warp.h"
#include "diff/media_walk.h"
#include "diff/psdr/interior_media.h"
#include "render/light_medium.h"
#include "render/volume_visibility.h"
#include "scene/shape_interaction.h"

#include <algorithm>
#include <map>

namespace penumbra {

namespace {

// The vertex of face f farthest from the line (a, b): the face's apex opposite the edge.
Vec3f opposite_vertex(const TriangleMesh& m, int32_t f, const Vec3f& a, const Vec3f& b) {
    const uint32_t* i = &m.indices[3 * size_t(f)];
    const Vec3f e = normalize(b - a);
    Vec3f best = m.positions[i[0]];
    float best_d = -1.f;
    for (int k = 0; k < 3; ++k) {
        const Vec3f q = m.positions[i[k]] - a;
        const float d = squared_norm(q - e * dot(q, e));
        if (d > best_d) best_d = d, best = m.positions[i[k]];
    }
    return best;
}

// Whether face f1 lies behind face f0's plane as seen from outside the solid: a convex edge (face normals
// turned outward when the solid is wound inside out).
bool convex_edge(const SceneEdges::SceneEdge& se) {
    const TriangleMesh& m = se.shape->mesh;
    const Vec3f a = m.positions[se.edge.v0], b = m.positions[se.edge.v1];
    const float behind = dot(face_normal(m, se.edge.f0), opposite_vertex(m, se.edge.f1, a, b) - a);
    return se.inside_out ? behind > 0.f : behind < 0.f;
}

// The mesh's signed volume (divergence theorem: Σ p0 · (p1 × p2) / 6 over its faces), negative for a closed
// mesh wound inside out.
double signed_volume(const TriangleMesh& m) {
    double volume = 0;
    for (size_t f = 0; f < m.face_count(); ++f) {
        const uint32_t* i = &m.indices[3 * f];
        const Vec3f p0 = m.positions[i[0]], p1 = m.positions[i[1]], p2 = m.positions[i[2]];
        volume += double(dot(p0, cross(p1, p2)));
    }
    return volume / 6;
}

// Intersection of the line from `from` through `through` with the plane (p0, n).
template <typename V> V line_plane(const V& from, const V& through, const V& p0, const V& n) {
    const V d = through - from;
    return from + d * (dot(n, p0 - from) / dot(n, d));
}

// The source x_S0(θ) of a segment through the moving edge point x_B(θ) with direction ω: a point at infinity
// (x_B − ω, a directional light's turning with it), a delta light's moving position, a medium vertex moved by the
// volume motion, or a surface's material point; a surface source within the contact length of the receiver
// follows the receiver's contact flow (`receiver`: the interior samples x_S0 by a direction from x_D0, so the
// fixed direction from the receiver's flowed point carries it: MaterialForm::flowed_vertex).
Vec3<Var> source_position(const MaterialForm& form, const SegmentSource& source, const Vec3<Var>& xb_t,
                          const Vec3f& dir, const Vec3<Var>* receiver = nullptr) {
    const Emitter* light = source.emitter && source.emitter->is_delta() ? source.emitter : nullptr;
    if (source.infinite) return xb_t - (light ? form.light_direction(*light, dir) : Vec3<Var>(dir));
    if (source.shape) {
        const SurfaceInteraction3f hit =
            surface_interaction<float>(*source.shape, source.prim, source.bary, MeshVertices{source.shape->mesh});
        Var jacobian;
        return receiver ? form.flowed_vertex(hit, *receiver, jacobian).p : form.vertex(hit).p;
    }
    if (light) return form.light_position(*light, source.p);
    if (source.in_medium) return form.volume_motion().position(source.p, source.medium, nullptr);
    return Vec3<Var>(source.p);
}

// The receiver triangle's moving plane and the segment's velocities relative to the receiver's material point
// and (image-space first vertex) to the point where the fixed camera ray through x_D0 meets that plane.
void set_receiver_velocities(const Scene& scene, const MaterialForm& form, BoundarySegment& out) {
    const SurfaceInteraction3f& recv = out.receiver;
    const uint32_t* tri = &recv.shape->mesh.indices[3 * size_t(recv.prim_index)];
    out.plane_point = form.position(*recv.shape, tri[0]);
    out.plane_normal = cross(form.position(*recv.shape, tri[1]) - out.plane_point,
                             form.position(*recv.shape, tri[2]) - out.plane_point);
    out.velocity = out.velocity_relative_to(form, form.vertex(recv).p);
    if (form.image_space_first_vertex()) {
        const Vec3f to_camera = scene.sensor->to_sensor(recv.p);
        out.velocity_seen =
            out.velocity_relative_to(form, line_plane(Vec3<Var>(recv.p), Vec3<Var>(recv.p + to_camera),
                                                      out.plane_point, out.plane_normal));
    } else {
        out.velocity_seen = out.velocity;
    }
}

} // namespace

Contact resting_contact(const Scene& scene, const SceneEdges::SceneEdge& se, const Vec3f& x,
                        RayCounter& rays) {
    if (!se.closed || se.edge.f1 < 0) return {};
    const TriangleMesh& m = se.shape->mesh;
    const float outward = se.inside_out ? -1.f : 1.f;
    const Vec3f n[2] = {normalize(face_normal(m, se.edge.f0)) * outward,
                        normalize(face_normal(m, se.edge.f1)) * outward};
    const float probe = contact_probe(x);
    for (int k = 0; k < 2; ++k) {
        // From outside both faces, a probe along the resting face's normal onto the surface under it.
        const Vec3f down = n[k], side = n[1 - k];
        ++rays.rays;
        const SurfaceInteraction3f hit = scene.intersect(Ray(x + (side - down) * probe, down, 2.f * probe));
        if (hit.is_valid() && hit.shape != se.shape && hit.bsdf() &&
            std::abs(dot(normalize(hit.n), down)) > 0.999f)
            return {hit, side, down * -1.f};
    }
    return {};
}

BoundarySegment contact_segment(const Scene& scene, const MaterialForm& form, const EdgePoint& x_b,
                                const Contact& contact, const Vec3f& w) {
    BoundarySegment out;
    SurfaceInteraction3f recv = contact.surface;
    // The curve's normal in the receiver's plane, toward the hidden side (from the probe's point to the
    // curve).
    const Vec3f e = normalize(x_b.b - x_b.a);
    Vec3f n = normalize(cross(recv.n, e));
    if (dot(n, x_b.p - recv.p) < 0.f) n = n * -1.f;
    recv.wi = recv.to_local(w);
    out.receiver = recv;
    out.direction = w * -1.f;
    out.cos_receiver = std::abs(dot(recv.n, w));
    out.stretch = 1.f;
    out.dark_point = x_b.p + n * contact_probe(x_b.p);
    out.curve_point = x_b.p;
    out.n_dark = n;
    out.contact = true;
    const Shape& edge_shape = *x_b.edge->shape;
    const Vec3<Var> a_t = form.position(edge_shape, x_b.edge->edge.v0),
                    b_t = form.position(edge_shape, x_b.edge->edge.v1);
    out.edge_point = a_t + (b_t - a_t) * Var(x_b.tau);
    set_receiver_velocities(scene, form, out);
    out.valid = true;
    return out;
}

bool grazes(const SceneEdges::SceneEdge& se, const Vec3f& d) {
    const Edge& e = se.edge;
    if (e.f1 < 0) return true;
    const TriangleMesh& m = se.shape->mesh;
    const Vec3f a = m.positions[e.v0], b = m.positions[e.v1];
    // Both faces must lie on the same side of the plane through the edge and d (the line misses the wedge
    // between them) ...
    const Vec3f side = cross(b - a, d);
    const Vec3f u0 = opposite_vertex(m, e.f0, a, b) - a, u1 = opposite_vertex(m, e.f1, a, b) - a;
    if (!(dot(u0, side) * dot(u1, side) > 0.f)) return false;
    // ... and for a solid, that wedge must be the solid's (a convex edge: face 1 lies behind face 0).
    return !se.closed || convex_edge(se);
}

namespace {

// Azimuths about a two-face edge: the edge's axis, u0 across face 0 (azimuth 0), w = axis × u0, and face 1 at
// azimuth φ1 ∈ (−π, π); the wedge between the faces spans |φ1|.
struct EdgeAzimuths {
    Vec3f axis, u0, w;
    float phi1;
};
EdgeAzimuths edge_azimuths(const SceneEdges::SceneEdge& se) {
    const TriangleMesh& m = se.shape->mesh;
    const Vec3f a = m.positions[se.edge.v0], b = m.positions[se.edge.v1];
    const Vec3f axis = normalize(b - a);
    auto across = [&](int32_t f) {
        const Vec3f q = opposite_vertex(m, f, a, b) - a;
        return normalize(q - axis * dot(q, axis));
    };
    const Vec3f u0 = across(se.edge.f0), w = cross(axis, u0), u1 = across(se.edge.f1);
    return {axis, u0, w, std::atan2(dot(u1, w), dot(u1, u0))};
}

} // namespace

bool sample_grazing_direction(const SceneEdges::SceneEdge& se, const Vec2f& u, Vec3f& d, float& pdf) {
    const Edge& e = se.edge;
    if (e.f1 < 0) {
        d = warp::square_to_uniform_sphere(u);
        pdf = warp::square_to_uniform_sphere_pdf();
        return true;
    }
    const EdgeAzimuths az = edge_azimuths(se);
    const Vec3f &axis = az.axis, &u0 = az.u0, &w = az.w;
    const float phi1 = az.phi1, wedge = std::abs(phi1);
    if (se.closed && !convex_edge(se)) return false; // a concave edge of a solid
    const float arc = Pi - wedge;
    if (!(arc > 0.f)) return false;
    // Azimuth uniform on the two arcs (wedge, π) and (wedge + π, 2π) (mirrored for φ1 < 0), height uniform.
    const float t = u.x * 2.f * arc;
    float psi = wedge + (t < arc ? t : t - arc + Pi);
    if (phi1 < 0.f) psi = -psi;
    const float z = 2.f * u.y - 1.f, r = std::sqrt(std::max(0.f, 1.f - z * z));
    d = axis * z + (u0 * std::cos(psi) + w * std::sin(psi)) * r;
    pdf = 1.f / (4.f * arc);
    return true;
}

float grazing_direction_pdf(const SceneEdges::SceneEdge& se, const Vec3f& d) {
    if (se.edge.f1 < 0) return warp::square_to_uniform_sphere_pdf();
    if (!grazes(se, d)) return 0.f;
    const float arc = Pi - std::abs(edge_azimuths(se).phi1);
    return arc > 0.f ? 1.f / (4.f * arc) : 0.f;
}

bool sample_crease_direction(const SceneEdges::SceneEdge& se, const Vec2f& u, Vec3f& d, float& pdf) {
    const Edge& e = se.edge;
    if (e.f1 < 0 || !se.closed || !convex_edge(se)) return false;
    // The lines that enter the solid through the edge leave it toward the mirror image of the wedge,
    // azimuths (π, π + wedge) (mirrored for φ1 < 0).
    const EdgeAzimuths az = edge_azimuths(se);
    const Vec3f &axis = az.axis, &u0 = az.u0, &w = az.w;
    const float phi1 = az.phi1, wedge = std::abs(phi1);
    // A flat edge (wedge π) is no crease.
    if (!(wedge > 0.f) || !(Pi - wedge > 1e-3f)) return false;
    float psi = Pi + u.x * wedge;
    if (phi1 < 0.f) psi = -psi;
    const float z = 2.f * u.y - 1.f, r = std::sqrt(std::max(0.f, 1.f - z * z));
    d = axis * z + (u0 * std::cos(psi) + w * std::sin(psi)) * r;
    pdf = 1.f / (2.f * wedge);
    return true;
}

namespace {

EdgeSet make_edge_set(const SceneEdges& edges, std::vector<uint32_t> indices) {
    EdgeSet set;
    set.indices = std::move(indices);
    std::vector<float> lengths;
    lengths.reserve(set.indices.size());
    for (const uint32_t i : set.indices) {
        const SceneEdges::SceneEdge& se = edges.edges[i];
        lengths.push_back(norm(se.shape->mesh.positions[se.edge.v1] - se.shape->mesh.positions[se.edge.v0]));
        set.total_length += lengths.back();
    }
    if (!lengths.empty()) set.by_length = DiscreteDistribution(lengths);
    return set;
}

// Whether a shape's surface can hide part of itself from a light on or inside it: not when it is flat (only
// boundary edges) or a convex solid (closed, every edge convex).
bool can_shadow_itself(const std::vector<SceneEdges::SceneEdge>& edges, size_t first, size_t last) {
    bool flat = true, convex = true;
    for (size_t i = first; i < last; ++i) {
        const SceneEdges::SceneEdge& se = edges[i];
        if (se.edge.f1 < 0) {
            convex = false;
            continue;
        }
        flat = false;
        if (!convex_edge(se)) convex = false;
    }
    return !(flat || convex);
}

// The edges of `edges` that can cast the shadows of `emitter` (see SceneEdges::lit).
std::vector<uint32_t> shadow_edges(const SceneEdges& edges, const Emitter& emitter, const BoundingSphere& scene_bounds,
                                   const std::map<const Shape*, bool>& self_shadowing) {
    const EmitterReach reach = emitter_reach(emitter, scene_bounds);
    const BoundingSphere& light = reach.bounds;
    std::vector<uint32_t> out;
    for (uint32_t i = 0; i < edges.edges.size(); ++i) {
        const SceneEdges::SceneEdge& se = edges.edges[i];
        if (se.shape == emitter.shape() && !self_shadowing.at(se.shape)) continue;
        const TriangleMesh& m = se.shape->mesh;
        const Vec3f a = m.positions[se.edge.v0];
        bool candidate;
        if (reach.environment) {
            candidate = !se.closed || convex_edge(se); // some direction grazes it
        } else if (reach.directional) {
            candidate = grazes(se, reach.travel);
        } else {
            const auto plane_meets = [&](int32_t f) {
                const Vec3f n = face_normal(m, f);
                return std::abs(dot(n, light.center - a)) <= light.radius * norm(n);
            };
            const Vec3f from_center = a - light.center;
            candidate = plane_meets(se.edge.f0) || (se.edge.f1 >= 0 && plane_meets(se.edge.f1)) ||
                        (squared_norm(from_center) > 0.f && grazes(se, normalize(from_center)));
        }
        if (candidate) out.push_back(i);
    }
    return out;
}

} // namespace

EmitterReach emitter_reach(const Emitter& emitter, const BoundingSphere& scene_bounds) {
    EmitterReach out;
    out.environment = emitter.is_infinite() && !emitter.is_delta();
    if (const Shape* shape = emitter.shape()) {
        out.bounds = bounding_sphere(shape->mesh);
    } else if (!out.environment) {
        Interaction3f ref;
        ref.p = scene_bounds.center;
        const DirectionSample3f ds = emitter.sample_direction(ref, Vec2f(0.5f)).first;
        out.directional = emitter.is_infinite();
        if (out.directional)
            out.travel = ds.d * -1.f;
        else
            out.bounds.center = ds.p;
    }
    return out;
}

SceneEdges::SceneEdges(const Scene& scene) : media(scene_has_media(scene)) {
    std::map<const Shape*, bool> self_shadowing;
    std::vector<uint32_t> indices;
    for (const auto& shape : scene.shapes) {
        // An index-matched boundary (a pure null BSDF) does not occlude: its edges are not discontinuities.
        if (shape->bsdf && shape->bsdf->flags() == BSDFNull) continue;
        const std::vector<Edge> mesh_edges = discontinuity_edges(shape->mesh);
        const bool closed = std::none_of(mesh_edges.begin(), mesh_edges.end(), [](const Edge& e) { return e.f1 < 0; });
        const bool inside_out = closed && signed_volume(shape->mesh) < 0;
        const size_t first = edges.size();
        for (const Edge& e : mesh_edges) {
            if (!(norm(shape->mesh.positions[e.v1] - shape->mesh.positions[e.v0]) > 0.f)) continue;
            indices.push_back(uint32_t(edges.size()));
            edges.push_back({shape.get(), e, closed, inside_out});
        }
        self_shadowing[shape.get()] = can_shadow_itself(edges, first, edges.size());
    }
    all = make_edge_set(*this, std::move(indices));
    for (const auto& emitter : scene.emitters)
        lit.push_back(make_edge_set(*this, shadow_edges(*this, *emitter, scene.bounding_sphere(), self_shadowing)));
}

EdgePoint sample_edge_point(const SceneEdges& edges, const EdgeSet& set, float u) {
    EdgePoint out;
    out.edge = &edges.edges[set.indices[set.by_length.sample(u)]];
    out.tau = u;
    const TriangleMesh& m = out.edge->shape->mesh;
    out.a = m.positions[out.edge->edge.v0];
    out.b = m.positions[out.edge->edge.v1];
    out.p = out.a + (out.b - out.a) * u;
    return out;
}

namespace {

// Eqs. 47–50 for a medium vertex x_D0 on the shadow sheet: the sheet is the plane through the source src(θ) and
// the edge a(θ) b(θ) (for a source at infinity src = x_B − ω); its point along n from x_D0 is
// x_sheet = x_D0 + n λ(θ), and the normal velocity relative to the medium's material point X(p_D, θ) is that of
// (x_sheet − X(p_D, θ)) · n = λ(θ) − (X(p_D, θ) − x_D0) · n.
Var sheet_velocity(const Vec3<Var>& src, const Vec3<Var>& a, const Vec3<Var>& b, const Vec3f& x_d, const Vec3f& n,
                   const Vec3<Var>& x_material) {
    const Vec3<Var> m = cross(a - src, b - src), nv(n), xd(x_d);
    const Var lambda = dot(m, src - xd) / dot(m, nv);
    return lambda - dot(x_material - xd, nv);
}

} // namespace

FlightEnd flight_from_edge(const Scene& scene, const EdgePoint& x_b, const Vec3f& dir, const Medium* medium,
                           bool volume_vertices, Sampler& sampler, RayCounter& rays) {
    const auto own_face = [&](const FlightEnd& f) {
        return f.kind == FlightEnd::Kind::Surface && f.si.shape == x_b.edge->shape &&
               (int32_t(f.si.prim_index) == x_b.edge->edge.f0 ||
                int32_t(f.si.prim_index) == x_b.edge->edge.f1);
    };
    FlightEnd end = sample_interaction(scene, Ray(x_b.p + dir * ray_offset_scale(x_b.p), dir), medium,
                                       volume_vertices, sampler, rays);
    for (int k = 0; k < 2 && own_face(end); ++k) {
        const Color3f passed = end.weight;
        end = sample_interaction(scene, Ray(end.p + dir * ray_offset_scale(end.p), dir), end.medium,
                                 volume_vertices, sampler, rays);
        end.weight = end.weight * passed;
    }
    return own_face(end) ? FlightEnd{} : end;
}

BoundarySegment trace_boundary_segment(const Scene& scene, const SegmentContext& context,
                                       const SegmentSource& source, const EdgePoint& x_b, Sampler& sampler,
                                       RayCounter& rays, const std::optional<Contact>& contact) {
    BoundarySegment out;
    const MaterialForm& form = context.form;
    const Vec3f dir = source.infinite ? source.d : normalize(x_b.p - source.p);
    if (!source.crease && !grazes(*x_b.edge, dir)) return out;
    // Where the line through a point starts: the source, or (from infinity) beyond the scene's bounds.
    const BoundingSphere bounds = scene.bounding_sphere();
    auto origin = [&](const Vec3f& through) {
        return source.infinite ? through - dir * (2.f * (bounds.radius + norm(through - bounds.center)) + 1.f) : source.p;
    };

    // The segment source → x_B must be clear (through media and null boundaries: its transmittance, stopping
    // just short of x_B), and a free flight beyond x_B finds x_D0.
    const Medium* medium = source.edge_medium;
    Color3f tr(1.f);
    if (!source.from_edge) {
        Interaction3f at_source;
        at_source.p = source.p;
        at_source.n = source.n;
        Ray to_edge =
            source.infinite ? Ray(origin(x_b.p), dir, norm(x_b.p - origin(x_b.p))) : at_source.spawn_ray_to(x_b.p);
        to_edge.tmax *= 0.999f;
        medium = source.medium;
        tr = segment_transmittance(scene, to_edge, medium, sampler, rays, &medium);
        if (is_black(tr)) return out;
    }
    // The side the edge's faces lie on, of the plane Π through the edge and the source (the line source → x
    // grazes the edge for x on Π; points whose lines pass on the faces' side are behind them).
    const TriangleMesh& edge_mesh = x_b.edge->shape->mesh;
    const Vec3f plane_normal = cross(x_b.b - x_b.a, dir);
    const float faces_side =
        dot(opposite_vertex(edge_mesh, x_b.edge->edge.f0, x_b.a, x_b.b) - x_b.a, plane_normal);
    if (faces_side == 0.f) return out;

    // An edge lying on another surface (an object resting on it): the line enters that surface at x_B, which
    // is then x_D0 (stretch 1), on the contact curve; the hidden side lies under the object.
    if (const Contact resting = contact ? *contact : resting_contact(scene, *x_b.edge, x_b.p, rays);
        resting.valid()) {
        out = contact_segment(scene, form, x_b, resting, dir * -1.f);
        out.transmittance = tr;
        out.medium = medium;
        out.source = source;
        return out;
    }
    const FlightEnd end =
        source.crease ? sample_interaction(scene, Ray(x_b.p + dir * ray_offset_scale(x_b.p), dir), medium,
                                           context.volume_endpoints, sampler, rays)
                      : flight_from_edge(scene, x_b, dir, medium, context.volume_endpoints, sampler, rays);
    if (end.kind == FlightEnd::Kind::None || end.kind == FlightEnd::Kind::Escaped) return out;
    if (end.kind == FlightEnd::Kind::Surface && !end.si.bsdf()) return out;
    out.transmittance = tr * end.weight;
    out.medium = end.medium;
    out.direction = dir;
    const Vec3f x_d = end.p;

    // The moving edge point and source (a delta light's motion moves the apex, or turns the direction, the
    // shadow is cast from).
    const Shape& edge_shape = *x_b.edge->shape;
    const Vec3<Var> a_t = form.position(edge_shape, x_b.edge->edge.v0), b_t = form.position(edge_shape, x_b.edge->edge.v1);
    const Vec3<Var> xb_t = a_t + (b_t - a_t) * Var(x_b.tau);
    auto source_t = [&] { return source_position(form, source, xb_t, dir); };

    if (end.kind == FlightEnd::Kind::Medium) {
        // A medium vertex on the shadow sheet: its area element per dℓ(x_B) dr_D, and the normal of the sheet
        // turned toward the occluded side.
        const Vec3f e = normalize(x_b.b - x_b.a);
        const float sin_b = norm(cross(dir, e));
        out.stretch = source.infinite ? sin_b : sin_b * norm(x_d - source.p) / norm(x_b.p - source.p);
        if (!std::isfinite(out.stretch) || !(out.stretch > 0.f)) return out;
        const Vec3f n = normalize(plane_normal) * (faces_side > 0.f ? 1.f : -1.f);
        out.in_medium = true;
        out.receiver.p = x_d;
        out.cos_receiver = 1.f;
        out.dark_point = x_d + n * (1e-4f * (1.f + norm(x_d - x_b.p)));
        const Vec3<Var> src_t = source_t();
        out.velocity = sheet_velocity(src_t, a_t, b_t, x_d, n, form.volume_motion().position(x_d, end.medium, nullptr));
        // Seen directly by the camera, the medium point is parameterized along the fixed camera ray.
        out.velocity_seen =
            form.image_space_first_vertex()
                ? sheet_velocity(src_t, a_t, b_t, x_d, n,
                                 seen_medium_point(scene, form, scene.sensor->to_world.apply_point(Vec3f(0.f)), x_d))
                : out.velocity;
        out.valid = true;
        return out;
    }

    SurfaceInteraction3f recv = end.si;
    // The curve on the receiver's plane: its tangent from nearby edge points, the stretch dℓ(x_D0)/dℓ(x_B),
    // and its normal turned toward the occluded side.
    const uint32_t* tri = &recv.shape->mesh.indices[3 * size_t(recv.prim_index)];
    const Vec3f p0 = recv.shape->mesh.positions[tri[0]];
    const float delta = 1e-3f;
    const Vec3f x_b2 = x_b.a + (x_b.b - x_b.a) * std::min(1.f, x_b.tau + delta),
                x_b1 = x_b.a + (x_b.b - x_b.a) * std::max(0.f, x_b.tau - delta);
    const Vec3f x_d2 = line_plane(origin(x_b2), x_b2, p0, recv.n), x_d1 = line_plane(origin(x_b1), x_b1, p0, recv.n);
    out.stretch = norm(x_d2 - x_d1) / norm(x_b2 - x_b1);
    if (!std::isfinite(out.stretch) || !(out.stretch > 0.f)) return out;
    Vec3f n = normalize(cross(recv.n, x_d2 - x_d1));
    // The occluded side, from the geometry rather than from probe rays (which, a hair's breadth from a finely
    // tessellated silhouette and offset off the source's surface, can pass on the wrong side of the edge). The
    // lit side is lit: source → x_B → x_D0 is clear.
    const float n_side = dot(n, plane_normal);
    if (!(std::abs(n_side) > 1e-6f * norm(plane_normal))) return out;
    if ((n_side > 0.f) != (faces_side > 0.f)) n = n * -1.f;
    out.dark_point = x_d + n * (1e-3f * norm(x_d2 - x_d1) / (2.f * delta) + 1e-5f);

    recv.wi = recv.to_local(dir * -1.f);
    out.receiver = recv;
    out.cos_receiver = std::abs(dot(recv.n, dir));

    // Eqs. 47–50: the discontinuity point x_D0(θ) is where the line x_S0(θ) → x_B(θ) meets the receiver's
    // moving plane; its velocity relative to the receiver's material point, along n.
    out.edge_point = xb_t;
    out.n_dark = n;
    out.source = source;
    out.source_follows_receiver = source.shape && !source.shape->emitter && form.contact_weight(norm(source.p - x_d)) > 0.f;
    set_receiver_velocities(scene, form, out);
    out.valid = true;
    return out;
}

Var BoundarySegment::velocity_relative_to(const MaterialForm& form, const Vec3<Var>& receiver_t) const {
    if (contact)
        return dot(foot_on_plane(edge_point, plane_point, plane_normal) - receiver_t, Vec3<Var>(n_dark));
    const Vec3<Var> src_t = source_position(form, source, edge_point, direction, source_follows_receiver ? &receiver_t : nullptr);
    const Vec3<Var> xd_t = line_plane(src_t, edge_point, plane_point, plane_normal);
    return dot(xd_t - receiver_t, Vec3<Var>(n_dark));
}

float BoundarySegment::first_segment_geometry_ratio(const SurfaceInteraction3f& x_d1) const {
    if (!contact) return 1.f;
    // |cos φ_1| |cos φ_0| / r² for x_D0 at p, as |(p − x_D1) · n_1| |(p − x_D1) · n_0| / r⁴.
    const auto geometry = [&](const Vec3f& p) {
        const Vec3f d = p - x_d1.p;
        const float r2 = squared_norm(d);
        return std::abs(dot(d, x_d1.n)) * std::abs(dot(d, receiver.n)) / (r2 * r2);
    };
    const float at_probe = geometry(receiver.p);
    return at_probe > 0.f ? geometry(curve_point) / at_probe : 0.f;
}

} // namespace penumbra
