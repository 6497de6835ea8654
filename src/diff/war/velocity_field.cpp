#include "diff/war/velocity_field.h"

#include "diff/was/auxiliary_rays.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

// A tape value with value 0 and the same derivative.
Var tangent_part(const Var& v) { return Var(0.f, v.id); }

bool is_constant(const Vec3<Var>& v) { return v.x.is_constant() && v.y.is_constant() && v.z.is_constant(); }

// X(p, θ) at the material point of `hit`: the barycentric blend of its moving triangle's vertices.
Vec3<Var> material_point(const MaterialForm& form, const SurfaceInteraction3f& hit) {
    const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
    const float b1 = hit.bary.x, b2 = hit.bary.y;
    return form.position(*hit.shape, i[0]) * Var(1.f - b1 - b2) + form.position(*hit.shape, i[1]) * Var(b1) +
           form.position(*hit.shape, i[2]) * Var(b2);
}

// v_dis(q) = ∂θ X⁻¹(z, θ) for z where the ray y(θ) + t (x_O(θ) − y(θ)) meets q's moving triangle (Eqs. 7–8):
// the barycentrics of z solved on the tape (Möller–Trumbore), mapped to the reference triangle's edges.
Vec3<Var> discontinuity_velocity(const Parameters& params, const SurfaceInteraction3f& q, const Vec3<Var>& y,
                                 const Vec3<Var>& occluder) {
    const MovedVertices moved{*q.shape, params.motions(q.shape)};
    const uint32_t* i = &q.shape->mesh.indices[3 * size_t(q.prim_index)];
    const Vec3<Var> p0 = moved.position(i[0]), e1 = moved.position(i[1]) - p0, e2 = moved.position(i[2]) - p0;
    const Vec3<Var> d = occluder - y, s = y - p0;
    const Vec3<Var> a = cross(d, e2), r = cross(s, e1);
    const Var det = dot(e1, a);
    if (!(std::abs(det.v) > 1e-12f)) return Vec3<Var>(Var(0.f));
    const Var inv_det = Var(1.f) / det;
    const Var b1 = tangent_part(dot(s, a) * inv_det), b2 = tangent_part(dot(d, r) * inv_det);
    const std::vector<Vec3f>& x = q.shape->mesh.positions;
    return Vec3<Var>(x[i[1]] - x[i[0]]) * b1 + Vec3<Var>(x[i[2]] - x[i[0]]) * b2;
}

// The point of the occluder's triangle edges nearest to the ray from `origin` along the unit `direction` (in
// angle seen from the origin), moving with the mesh: near a visibility boundary the ray grazes the occluder's
// silhouette edge, and this point follows that edge (the boundary's own motion) where the hit's material
// point, on a face seen at a grazing angle, lies far along the face and moves differently.
Vec3<Var> nearest_edge_point(const MaterialForm& form, const SurfaceInteraction3f& hit, const Vec3f& origin,
                             const Vec3f& direction) {
    const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
    const std::vector<Vec3f>& x = hit.shape->mesh.positions;
    float best = Infinity, best_s = 0.f;
    int best_edge = 0;
    for (int k = 0; k < 3; ++k) {
        const Vec3f a = x[i[k]], e = x[i[(k + 1) % 3]] - a, w0 = a - origin;
        // The closest approach of the segment a + s e (s in [0, 1]) to the line origin + t direction.
        const float ee = dot(e, e), ed = dot(e, direction), denominator = ee - ed * ed;
        const float s = denominator > 1e-12f * ee
                            ? std::clamp((ed * dot(direction, w0) - dot(e, w0)) / denominator, 0.f, 1.f)
                            : 0.f;
        const Vec3f c = a + e * s - origin;
        const float length = norm(c);
        const float sine = length > 0.f ? norm(c - direction * dot(c, direction)) / length : 0.f;
        if (sine < best) best = sine, best_s = s, best_edge = k;
    }
    return form.position(*hit.shape, i[best_edge]) * Var(1.f - best_s) +
           form.position(*hit.shape, i[(best_edge + 1) % 3]) * Var(best_s);
}

// All projections of q′ along n within `reach` of the tangent plane (Fig. 10).
template <typename F>
void for_each_projection(const Scene& scene, const Vec3f& q_prime, const Vec3f& n, float reach,
                         uint64_t& rays, F&& f) {
    constexpr int MaxProjections = 8;
    Ray ray(q_prime - n * reach, n, 2.f * reach);
    for (int k = 0; k < MaxProjections; ++k) {
        ++rays;
        const SurfaceInteraction3f q = scene.intersect(ray);
        if (!q.is_valid()) return;
        f(q);
        const float step = q.t + ray_offset_scale(q.p);
        ray = Ray(ray.o + n * step, n, ray.tmax - step);
        if (!(ray.tmax > 0.f)) return;
    }
}

} // namespace

WarWeight war_weight(const Vec3f& q_minus_p, const Vec3f& p_minus_y, float boundary,
                     const WarFieldOptions& o) {
    const double sigma = o.sigma, alpha = o.exponent;
    const double r0_2 = double(squared_norm(p_minus_y));
    const double r2 = double(squared_norm(q_minus_p)) / r0_2;
    const double e = std::exp(-r2 / sigma);
    const double D = (1.0 - e) / sigma;
    const double base = std::fmax(std::pow(D, alpha) + double(boundary), 1e-300);
    const double w = 1.0 / base;
    // ∂p w = −w² α D^{α−1} (e^{−r²/σ}/σ²) ∂p r², ∂p r² = −2 ((q − p) + r² (p − y)) / r0².
    const double dw_dr2 = -w * w * alpha * std::pow(D, alpha - 1.0) * e / (sigma * sigma);
    const Vec3f dr2 = (q_minus_p + p_minus_y * float(r2)) * float(-2.0 / r0_2);
    return {w, dr2 * float(dw_dr2)};
}

WarEstimate estimate_war_field(const Vec3f& n, const Vec3f& p_minus_y, std::span<const WarAuxiliary> aux,
                               const WarFieldOptions& o) {
    const size_t count = aux.size();
    std::vector<double> w(count);
    std::vector<Vec3f> g(count);
    bool moving = false;
    for (size_t i = 0; i < count; ++i) {
        const WarWeight h = war_weight(aux[i].offset, p_minus_y, aux[i].boundary, o);
        const double inv_pdf = aux[i].pdf > 0.f ? 1.0 / double(aux[i].pdf) : 0.0;
        w[i] = h.w * inv_pdf;
        g[i] = (h.gradient - n * dot(n, h.gradient)) * float(inv_pdf); // on the tangent plane
        moving = moving || !is_constant(aux[i].velocity);
    }
    WarEstimate out{Vec3<Var>(Var(0.f)), Var(0.f)};
    if (!moving) return out;
    WarpOptions consistent;
    consistent.unbiased = false;
    // Eqs. 47 and 62: v = Σ c_i v_dis,i, ∇·v = Σ ⟨d_i, v_dis,i⟩.
    const WarpCoefficients c = warp_coefficients(w, g, consistent);
    Vec3<Var> field(Var(0.f));
    for (size_t i = 0; i < count; ++i) {
        if (is_constant(aux[i].velocity)) continue;
        field += aux[i].velocity * Var(float(c.field[i]));
        out.divergence += dot(Vec3<Var>(c.divergence[i]), aux[i].velocity);
    }
    out.velocity = field - Vec3<Var>(n) * dot(Vec3<Var>(n), field);
    return out;
}

std::vector<WarAuxiliary> sample_war_auxiliary(const WarScene& s, const SurfaceInteraction3f& hit,
                                               const WarNeighbor& y, AuxiliaryRng& rng, uint64_t& rays) {
    const WarFieldOptions& o = s.options;
    const Vec3f p = hit.p, n = normalize(hit.n);
    const float r0 = norm(p - y.reference.p);
    const float sd = o.spread * r0, reach = o.reach * r0;
    const float scale = 2.f / (o.sigma * o.sigma); // the boundary test's distance on D's scale
    const Frame3f frame(n);
    std::vector<WarAuxiliary> out;
    out.reserve(size_t(o.aux_count));
    const auto add = [&](const Vec3f& offset, float pdf_prime) {
        for_each_projection(s.scene, p + offset, n, reach, rays, [&](const SurfaceInteraction3f& q) {
            WarAuxiliary a;
            a.offset = q.p - p;
            a.pdf = pdf_prime * std::abs(dot(n, q.n)); // Eq. 46
            a.velocity = Vec3<Var>(Var(0.f));
            a.boundary = 0.f; // invisible from y
            const Ray ray = y.reference.spawn_ray_to(q.p);
            // Visibility of X(q) from y: the first occluder x″ of the segment (§3.2.2 Step 1).
            ++rays;
            const SurfaceInteraction3f occluder = s.scene.intersect(ray);
            if (occluder.is_valid()) {
                // x_O's motion: the nearest edge's (or an implicit edge's, where the occluder crosses a
                // surface).
                const ImplicitEdges* implicit = s.boundary.implicit_edges();
                const Vec3<Var> x_o = implicit && implicit->nearest(occluder, ray.o, ray.d).segment
                                          ? auxiliary_point(s.form, s.boundary, occluder, ray.o, ray.d)
                                          : nearest_edge_point(s.form, occluder, ray.o, ray.d);
                a.velocity = discontinuity_velocity(s.params, q, y.position, x_o);
            } else {
                // Visible: v_dis = 0, and B vanishes at q's own open edges and silhouettes seen from y (C.1,
                // C.2), static in material space, so that v·n = 0 there.
                a.boundary = std::min(1.f, s.boundary(q, ray.o, ray.d, scale));
            }
            out.push_back(a);
        });
    };
    for (int k = 0; k < o.aux_count; k += o.antithetic ? 2 : 1) {
        const Vec2f u = rng.next_2d();
        const float r = sd * std::sqrt(-2.f * std::log1p(-u.x)), phi = 2.f * Pi * u.y;
        const Vec3f offset = frame.s * (r * std::cos(phi)) + frame.t * (r * std::sin(phi));
        const float pdf = std::exp(-0.5f * (r * r) / (sd * sd)) / (2.f * Pi * sd * sd);
        add(offset, pdf);
        if (o.antithetic && k + 1 < o.aux_count) add(offset * -1.f, pdf);
    }
    return out;
}

SurfaceInteraction<Var> displaced_vertex(const Parameters& params, const SurfaceInteraction3f& hit,
                                         const Vec3<Var>& velocity) {
    const std::vector<Vec3f>& x = hit.shape->mesh.positions;
    const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
    const Vec3f e1 = x[i[1]] - x[i[0]], e2 = x[i[2]] - x[i[0]];
    // v = δb1 e1 + δb2 e2 (v is in the triangle's plane): the 2 × 2 normal equations.
    const float a = dot(e1, e1), b = dot(e1, e2), c = dot(e2, e2), det = a * c - b * b;
    const Var r1 = dot(Vec3<Var>(e1), velocity), r2 = dot(Vec3<Var>(e2), velocity);
    const Var db1 = (r1 * Var(c) - r2 * Var(b)) / Var(det), db2 = (r2 * Var(a) - r1 * Var(b)) / Var(det);
    const Vec2<Var> bary(Var(hit.bary.x) + db1, Var(hit.bary.y) + db2);
    return surface_interaction<Var>(*hit.shape, hit.prim_index, bary,
                                    MovedVertices{*hit.shape, params.motions(hit.shape)});
}

WarVertex war_vertex(const WarScene& s, const SurfaceInteraction3f& hit, const WarNeighbor& y,
                     AuxiliaryRng& rng, uint64_t& rays) {
    const std::vector<WarAuxiliary> aux = sample_war_auxiliary(s, hit, y, rng, rays);
    const WarEstimate e = estimate_war_field(normalize(hit.n), hit.p - y.reference.p, aux, s.options);
    WarVertex out;
    out.material = material_point(s.form, hit);
    if (is_constant(e.velocity) && e.divergence.is_constant()) {
        out.si = s.form.vertex(hit);
        out.jacobian = s.form.jacobian(hit);
    } else {
        out.si = displaced_vertex(s.params, hit, e.velocity);
        out.jacobian = s.form.jacobian(hit) * (Var(1.f) + e.divergence);
    }
    return out;
}

WarpEstimate war_direction(const WarScene& s, const WarpOptions& field, const Interaction3f& x,
                           const Vec3<Var>& position, const Vec3f& omega, AuxiliaryRng& rng, uint64_t& rays) {
    rays += uint64_t(field.aux_count);
    return estimate_warp_at(s.scene, s.form, s.boundary, WarpVertex{x, position}, omega, field, rng);
}

} // namespace penumbra
