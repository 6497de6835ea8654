#include "diff/was/auxiliary_rays.h"

namespace penumbra {

Vec3<Var> auxiliary_point(const MaterialForm& form, const BoundaryTest& boundary, const SurfaceInteraction3f& hit,
                          const Vec3f& origin, const Vec3f& direction) {
    // y(θ) = X(p, θ) at the hit's material point: the barycentric blend of its moving triangle's vertices.
    const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
    const float b1 = hit.bary.x, b2 = hit.bary.y;
    const Vec3<Var> y = form.position(*hit.shape, i[0]) * Var(1.f - b1 - b2) +
                        form.position(*hit.shape, i[1]) * Var(b1) + form.position(*hit.shape, i[2]) * Var(b2);
    if (!boundary.implicit_edges()) return y;
    const NearestSegment nearest = boundary.implicit_edges()->nearest(hit, origin, direction);
    if (!nearest.segment) return y;
    return edge_following_point(form, hit, nearest, y, boundary.implicit_edge_factor(hit, origin, direction));
}

AuxiliarySample trace_auxiliary(const Scene& scene, const MaterialForm& form, const BoundaryTest& boundary,
                                const WarpVertex& x, const VmfSample& s, float scale) {
    AuxiliarySample a;
    a.vmf = s;
    const SurfaceInteraction3f hit = scene.intersect(x.reference.spawn_ray(s.direction));
    a.boundary = boundary(hit, x.reference.p, s.direction, scale);
    if (!hit.is_valid()) {
        a.warp = Vec3<Var>(s.direction); // an escaped ray's direction does not move with the geometry
        return a;
    }
    const Vec3<Var> d = auxiliary_point(form, boundary, hit, x.reference.p, s.direction) - x.position;
    a.warp = d / norm(d);
    return a;
}

SurfaceInteraction<Var> warped_vertex(const Parameters& params, const SurfaceInteraction3f& hit,
                                      const Vec3<Var>& origin, const Vec3<Var>& direction) {
    const MovedVertices moved{*hit.shape, params.motions(hit.shape)};
    const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
    const Vec3<Var> p0 = moved.position(i[0]), e1 = moved.position(i[1]) - p0, e2 = moved.position(i[2]) - p0;
    const Vec3<Var> s = origin - p0;
    const Vec3<Var> q = cross(direction, e2), r = cross(s, e1);
    const Var inv_det = Var(1.f) / dot(e1, q);
    const Var b1 = dot(s, q) * inv_det, b2 = dot(direction, r) * inv_det;
    // Values from the reference hit (Embree's), derivatives from the solve.
    const Vec2<Var> bary(Var(hit.bary.x, b1.id), Var(hit.bary.y, b2.id));
    return surface_interaction<Var>(*hit.shape, hit.prim_index, bary, moved);
}

} // namespace penumbra
