#include "diff/material_form.h"

#include "render/light_medium.h"

namespace penumbra {

namespace {

// Fraction of the scene's bounding radius within which a vertex follows the contact flow (docs/design.md,
// "Contacts").
constexpr float ContactFraction = 0.05f;

} // namespace

// Media keep the material flow everywhere (their walks place medium vertices by the volume motion).
float contact_length(const Scene& scene) {
    return scene_has_media(scene) ? 0.f : ContactFraction * scene.bounding_sphere().radius;
}

// χ(r) = s²(3 − 2s), s = (ℓ − r) / (ℓ/2) clamped to [0, 1]: 1 within ℓ/2, 0 beyond ℓ.
float MaterialForm::contact_weight(float r, float* derivative) const {
    if (derivative) *derivative = 0.f;
    const float l = contact_length_;
    if (!(l > 0.f) || !(r < l)) return 0.f;
    const float s = std::min(1.f, (l - r) / (0.5f * l));
    if (derivative && s < 1.f) *derivative = -6.f * s * (1.f - s) / (0.5f * l);
    return s * s * (3.f - 2.f * s);
}

SurfaceInteraction<Var> MaterialForm::ray_vertex(const SurfaceInteraction3f& hit, const Vec3<Var>& o,
                                                 const Vec3<Var>& d) const {
    const MovedVertices moved = vertices(*hit.shape);
    const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
    const Vec3<Var> p0 = moved.position(i[0]), e1 = moved.position(i[1]) - p0, e2 = moved.position(i[2]) - p0;
    const Vec3<Var> s = o - p0, q = cross(d, e2), r = cross(s, e1);
    const Var inv_det = Var(1.f) / dot(e1, q);
    const Var b1 = dot(s, q) * inv_det, b2 = dot(d, r) * inv_det;
    const Vec2<Var> bary(Var(hit.bary.x, b1.id), Var(hit.bary.y, b2.id));
    return surface_interaction<Var>(*hit.shape, hit.prim_index, bary, moved);
}

SurfaceInteraction<Var> MaterialForm::flowed_vertex(const SurfaceInteraction3f& hit, const Vec3<Var>& prev,
                                                    Var& jacobian) const {
    const Vec3f x(prev.x.v, prev.y.v, prev.z.v);
    const float r = norm(hit.p - x);
    float dchi = 0.f;
    const float chi = hit.shape->emitter ? 0.f : contact_weight(r, &dchi);
    if (chi == 0.f || !(r > 0.f)) {
        jacobian = this->jacobian(hit);
        return vertex(hit);
    }
    // The attached point: the fixed direction ω from x(θ) meets the moving triangle (Möller–Trumbore on the
    // tape) at barycentrics b_att(θ) and distance t(θ).
    const MovedVertices moved = vertices(*hit.shape);
    const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
    const Vec3<Var> p0 = moved.position(i[0]), e1 = moved.position(i[1]) - p0, e2 = moved.position(i[2]) - p0;
    const Vec3f w = (hit.p - x) / r;
    const Vec3<Var> d(w), s = prev - p0;
    const Vec3<Var> q = cross(d, e2), rq = cross(s, e1);
    const Var inv_det = Var(1.f) / dot(e1, q);
    const Var b1 = dot(s, q) * inv_det, b2 = dot(d, rq) * inv_det, t = dot(e2, rq) * inv_det;
    // Rates of change only (value 0): the attached point's barycentrics relative to the material point's.
    const Var db1 = b1 - Var(detach(b1)), db2 = b2 - Var(detach(b2));
    const Vec2<Var> bary(Var(hit.bary.x) + Var(chi) * db1, Var(hit.bary.y) + Var(chi) * db2);
    SurfaceInteraction<Var> si = surface_interaction<Var>(*hit.shape, hit.prim_index, bary, moved);

    // div V_mat, div V_att (dA = t² / |n · ω| dω at fixed ω) and ∇χ · (V_att − V_mat), χ' (y − x)/r projected on
    // the surface dotted with the displacement of the attached point from the material point.
    const Var j_mat = this->jacobian(hit);
    const Vec3<Var> n_t = cross(e1, e2);
    const Var area_per_solid_angle = t * t * norm(n_t) / abs(dot(n_t, d));
    const Var j_att = area_per_solid_angle / Var(area_per_solid_angle.v);
    Var grad = Var(0.f);
    if (dchi != 0.f) {
        const Vec3<Var> attached = p0 + e1 * b1 + e2 * b2, material = p0 + e1 * Var(hit.bary.x) + e2 * Var(hit.bary.y);
        const auto rate = [](const Vec3<Var>& v) { return v - Vec3<Var>(Vec3f(v.x.v, v.y.v, v.z.v)); };
        const Vec3<Var> displacement = rate(attached) - rate(material);
        const Vec3f n0 = normalize(Vec3f(n_t.x.v, n_t.y.v, n_t.z.v));
        const Vec3f u = w - n0 * dot(w, n0);
        grad = Var(dchi) * dot(Vec3<Var>(u), displacement);
    }
    jacobian = j_mat + Var(chi) * (j_att - j_mat) + grad;
    return si;
}

} // namespace penumbra
