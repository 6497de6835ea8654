#include "diff/boundary_segment.h"

#include "core/warp.h"
#include "scene/shape_interaction.h"

#include <algorithm>

namespace penumbra {

SceneEdges::SceneEdges(const Scene& scene) {
    std::vector<float> lengths;
    for (const auto& shape : scene.shapes) {
        const std::vector<Edge> mesh_edges = discontinuity_edges(shape->mesh);
        const bool closed = std::none_of(mesh_edges.begin(), mesh_edges.end(), [](const Edge& e) { return e.f1 < 0; });
        for (const Edge& e : mesh_edges) {
            const float l = norm(shape->mesh.positions[e.v1] - shape->mesh.positions[e.v0]);
            if (!(l > 0.f)) continue;
            edges.push_back({shape.get(), e, closed});
            lengths.push_back(l);
            total_length += l;
        }
    }
    if (!lengths.empty()) by_length = DiscreteDistribution(lengths);
}

EdgePoint sample_edge_point(const SceneEdges& edges, float u) {
    EdgePoint out;
    out.edge = &edges.edges[edges.by_length.sample(u)];
    out.tau = u;
    const TriangleMesh& m = out.edge->shape->mesh;
    out.a = m.positions[out.edge->edge.v0];
    out.b = m.positions[out.edge->edge.v1];
    out.p = out.a + (out.b - out.a) * u;
    return out;
}

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

// Intersection of the line from `from` through `through` with the plane (p0, n).
template <typename V> V line_plane(const V& from, const V& through, const V& p0, const V& n) {
    const V d = through - from;
    return from + d * (dot(n, p0 - from) / dot(n, d));
}

} // namespace

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
    return !se.closed || dot(face_normal(m, e.f0), u1) < 0.f;
}

bool sample_grazing_direction(const SceneEdges::SceneEdge& se, const Vec2f& u, Vec3f& d, float& pdf) {
    const Edge& e = se.edge;
    if (e.f1 < 0) {
        d = warp::square_to_uniform_sphere(u);
        pdf = warp::square_to_uniform_sphere_pdf();
        return true;
    }
    const TriangleMesh& m = se.shape->mesh;
    const Vec3f a = m.positions[e.v0], b = m.positions[e.v1];
    const Vec3f axis = normalize(b - a);
    auto across = [&](int32_t f) {
        const Vec3f q = opposite_vertex(m, f, a, b) - a;
        return normalize(q - axis * dot(q, axis));
    };
    // Azimuths about the edge: face 0 at 0, face 1 at φ1 ∈ (−π, π); the wedge between them spans |φ1|.
    const Vec3f u0 = across(e.f0), w = cross(axis, u0), u1 = across(e.f1);
    const float phi1 = std::atan2(dot(u1, w), dot(u1, u0)), wedge = std::abs(phi1);
    if (se.closed && !(dot(face_normal(m, e.f0), u1) < 0.f)) return false; // a concave edge of a solid
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

BoundarySegment trace_boundary_segment(const Scene& scene, const MaterialForm& form, const SegmentSource& source,
                                       const EdgePoint& x_b, RayCounter& rays) {
    BoundarySegment out;
    const Vec3f dir = source.infinite ? source.d : normalize(x_b.p - source.p);
    if (!grazes(*x_b.edge, dir)) return out;
    // Where the line through a point starts: the source, or (from infinity) beyond the scene's bounds.
    const BoundingSphere bounds = scene.bounding_sphere();
    auto origin = [&](const Vec3f& through) {
        return source.infinite ? through - dir * (2.f * (bounds.radius + norm(through - bounds.center)) + 1.f) : source.p;
    };
    // A shadow ray from the source to `target`, stopping just short of it (from infinity: from beyond the bounds).
    Interaction3f at_source;
    at_source.p = source.p;
    at_source.n = source.n;
    auto blocked = [&](const Vec3f& target) {
        Ray ray = source.infinite ? Ray(origin(target), dir, norm(target - origin(target))) : at_source.spawn_ray_to(target);
        ray.tmax *= 0.999f;
        ++rays.rays;
        return scene.occluded(ray);
    };

    // The segment source → x_B must be clear, and its extension beyond x_B finds the receiver x_D0.
    if (blocked(x_b.p)) return out;
    ++rays.rays;
    SurfaceInteraction3f recv = scene.intersect(Ray(x_b.p + dir * ray_offset_scale(x_b.p), dir));
    if (!recv.is_valid() || !recv.bsdf()) return out;
    const Vec3f x_d = recv.p;

    // The curve on the receiver's plane: its tangent from nearby edge points, the stretch dℓ(x_D0)/dℓ(x_B),
    // and its normal turned toward the occluded side (found by two probe rays from the source).
    const uint32_t* tri = &recv.shape->mesh.indices[3 * size_t(recv.prim_index)];
    const Vec3f p0 = recv.shape->mesh.positions[tri[0]];
    const float delta = 1e-3f;
    const Vec3f x_b2 = x_b.a + (x_b.b - x_b.a) * std::min(1.f, x_b.tau + delta),
                x_b1 = x_b.a + (x_b.b - x_b.a) * std::max(0.f, x_b.tau - delta);
    const Vec3f x_d2 = line_plane(origin(x_b2), x_b2, p0, recv.n), x_d1 = line_plane(origin(x_b1), x_b1, p0, recv.n);
    out.stretch = norm(x_d2 - x_d1) / norm(x_b2 - x_b1);
    if (!std::isfinite(out.stretch) || !(out.stretch > 0.f)) return out;
    Vec3f n = normalize(cross(recv.n, x_d2 - x_d1));
    const float eps = 1e-3f * norm(x_d2 - x_d1) / (2.f * delta) + 1e-5f;
    // From infinity the probes start on the receiver (offset along its normal) and look back along −d.
    auto probe_dark = [&](const Vec3f& target) {
        if (!source.infinite) return blocked(target);
        Interaction3f at;
        at.p = target;
        at.n = recv.n;
        ++rays.rays;
        return scene.occluded(at.spawn_ray(dir * -1.f));
    };
    const bool plus_dark = probe_dark(x_d + n * eps), minus_dark = probe_dark(x_d - n * eps);
    if (plus_dark == minus_dark) return out;
    if (!plus_dark) n = n * -1.f;
    out.dark_point = x_d + n * eps;

    recv.wi = recv.to_local(dir * -1.f);
    out.receiver = recv;
    out.cos_receiver = std::abs(dot(recv.n, dir));

    // Eqs. 47–50: the discontinuity point x_D0(θ) is where the line x_S0(θ) → x_B(θ) meets the receiver's
    // moving plane; its velocity relative to the receiver's material point, along n.
    const Shape& edge_shape = *x_b.edge->shape;
    const Vec3<Var> a_t = form.position(edge_shape, x_b.edge->edge.v0), b_t = form.position(edge_shape, x_b.edge->edge.v1);
    const Vec3<Var> xb_t = a_t + (b_t - a_t) * Var(x_b.tau);
    const Vec3<Var> src_t =
        source.infinite ? xb_t - Vec3<Var>(dir)
        : source.shape  ? form.vertex(surface_interaction<float>(*source.shape, source.prim, source.bary,
                                                                 MeshVertices{source.shape->mesh})).p
                        : Vec3<Var>(source.p);
    const Vec3<Var> q0 = form.position(*recv.shape, tri[0]), q1 = form.position(*recv.shape, tri[1]),
                    q2 = form.position(*recv.shape, tri[2]);
    const Vec3<Var> xd_t = line_plane(src_t, xb_t, q0, cross(q1 - q0, q2 - q0));
    out.velocity = dot(xd_t - form.vertex(recv).p, Vec3<Var>(n));
    out.valid = true;
    return out;
}

} // namespace penumbra
